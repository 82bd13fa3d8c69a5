/* The C entry point of solve_lcp: converters._lcpfast.Solver.

   solve_lcp(M, q) on a small problem is a few hundred nanoseconds of compiled work; called from Python, the
   checks, the two output arrays and the result object had cost about 2 us more. Results are recycled once
   nothing but the Solver's pool refers to them (take_free): up to POOL results stay alive after the caller has
   dropped them (a weak reference to one of their arrays may outlive the caller's last reference; such an
   array is never written again). A Solver is callable as
   solve_lcp is and takes exactly the problems of solve_lcp's thin path (converters/lcp/solve.py): float64
   C-contiguous M (k x k) and q (k), 0 < k <= k_max, the defaults for max_iter, time_limit and the options,
   any method but enum, a Python float tol in range, a bool fast_paths, and neither PCSUITE_TIME_LIMIT nor
   PCSUITE_MAX_MEMORY set. It checks them, allocates z and w, calls the compiled solve (converters.lcp.engine.
   solve_raw, compiled ahead of time into this module: the same source as every other path), and builds the
   LCPResult, with the thin path's very branches. Any other call, and every answer the thin path hands to
   Python (not solved within the first slice of work, auto's messages that need formatting, NaN or inf in M or
   q), goes to the Python functions it was given: one source of truth for every check and message.

   Built by python -m converters.build_kernels (build_fast) with numba's helper functions (_helperlib.c: the
   compiled code calls its frexp, ldexp and reshape), and loaded only when current (converters/compiled.py). */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <time.h>
#include <structmember.h>

#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include "_numba_common.h"
#define NUMBA_EXPORT_FUNC(_rettype) VISIBILITY_HIDDEN _rettype
#define NUMBA_EXPORT_DATA(_vartype) VISIBILITY_HIDDEN _vartype
#define PYCC_COMPILING
#include "_helperlib.c"

/* _helperlib.c declares these for numba's hashing; the compiled solve does not hash */
int64_t _numba_hashsecret_siphash_k0;
int64_t _numba_hashsecret_siphash_k1;
int64_t _numba_hashsecret_djbx33a_suffix;

/* The compiled solve's arrays are views of the caller's memory (no meminfo): the reference counting numba
   emits never reaches zero, so its destructor is never called. */
VISIBILITY_HIDDEN void NRT_MemInfo_call_dtor(void *meminfo) { (void)meminfo; abort(); }

/* numba's calling convention: the status (0: returned; else an exception, described in *excinfo), the value
   through the first pointer. Arguments as in converters.lcp.engine.solve_raw. */
typedef struct { char *a; int32_t b; char *c; char *d; int32_t e; } excinfo_t;
extern int32_t pcsuite_lcp_solve_raw(int64_t *answer, excinfo_t **excinfo, double *M, double *q, double *z,
                                     double *w, int64_t k, int64_t method, double tol, int64_t max_iter,
                                     int64_t fast_paths, double *opts, int64_t n_opts, int64_t budget, double *mbuf,
                                     double *buf, int64_t n_buf, int64_t *ibuf, int64_t n_ibuf, double *out);

/* solve_once's answers and solve_raw's layout (converters/lcp/state.py, engine.py: checked at construction) */
enum { ONCE_SOLVED = 0, ONCE_CLOSED_FORM = 1, ONCE_OTHER = 2, RAW_WORKSPACE = -1, RAW_BAD_OPTIONS = -2 };
enum { RAW_ITERATIONS = 0, RAW_ERR, RAW_USED, RAW_RULE, RAW_STAGES, RAW_INFO_X, RAW_OUT_SIZE };
#define MAX_METHODS 16
/* Results kept for recycling: a loop that drops or rebinds its result each call finds one free in two. */
#define POOL 4
/* auto's messages kept, by what they say (the method used, the stages, the eigenvalue's bits, k) */
#define MESSAGES 8
typedef struct { int64_t used, stages, k; uint64_t eig; PyObject *text; } Message;
/* LCPResult's fields, in the order of the slot descriptors the Solver is given */
enum { F_Z, F_W, F_STATUS, F_ERR, F_ITERATIONS, F_METHOD, F_MESSAGE, F_SOLUTIONS, N_FIELDS };

/* The workspace, shared by every call (the GIL is held throughout: one solve at a time), grown when needed. */
static double *work_m = NULL;      /* k x k: M normalised */
static Py_ssize_t n_work_m = 0;
static double *work_f = NULL;
static int64_t n_work_f = 0;
static int64_t *work_i = NULL;
static int64_t n_work_i = 0;

typedef struct {
    PyObject_HEAD
    vectorcallfunc vectorcall;
    PyObject *dict;           /* __doc__, __wrapped__, __name__, ... (functools.update_wrapper) */
    PyObject *python;         /* solve_lcp in Python: every call the fast path does not take */
    PyObject *after_once;     /* (M, q, code, tol, fast_paths, started) -> LCPResult: the sliced solve */
    PyObject *auto_message;   /* (used, stages, eig or None, k) -> str */
    PyObject *result_type;    /* LCPResult: a class with __slots__ */
    Py_ssize_t offsets[N_FIELDS];   /* where each field's slot is in an LCPResult */
    PyObject *solved;         /* "solved" */
    PyObject *empty;          /* "" */
    PyObject *names;          /* method names, by code */
    PyObject *auto_labels;    /* "auto:<method>", by code */
    PyObject *closed_forms;   /* "closed form (<rule>)", by rule */
    PyObject *closed_label;   /* "auto:closed form" */
    PyObject *environ;        /* os.environ._data */
    uint64_t environ_version; /* its version when neither limit was set in it */
    int environ_seen;
    PyObject *time_key, *memory_key;
    PyObject *opts;           /* the default options (a float64 array) */
    Py_ssize_t n_methods, n_rules, auto_code, enum_code;
    int64_t once_max_iter[MAX_METHODS], pgs_gave_way[MAX_METHODS];
    double tol_default, tol_low, tol_high;
    Py_ssize_t k_max;
    int64_t budget;
    PyObject *pool[POOL];     /* results handed out recently, recycled once nothing else refers to them */
    int pool_next;            /* the entry a new result replaces when every one is in use */
    Message messages[MESSAGES];
    int messages_next;
} Solver;

static PyObject *s_method, *s_tol, *s_fast_paths, *s_max_iter, *s_time_limit;

static int
grow(int64_t need_f, int64_t need_i)
{
    if (need_f > n_work_f) {
        double *f = PyMem_RawRealloc(work_f, (size_t)need_f * sizeof(double));
        if (f == NULL) return -1;
        work_f = f;
        n_work_f = need_f;
    }
    if (need_i > n_work_i) {
        int64_t *i = PyMem_RawRealloc(work_i, (size_t)need_i * sizeof(int64_t));
        if (i == NULL) return -1;
        work_i = i;
        n_work_i = need_i;
    }
    return 0;
}

/* A float64 array the thin path takes: exactly numpy.ndarray, float64 in native order, C-contiguous, aligned. */
static inline int
plain(PyObject *o, int ndim)
{
    if (!PyArray_CheckExact(o)) return 0;
    PyArrayObject *a = (PyArrayObject *)o;
    return PyArray_NDIM(a) == ndim && PyArray_TYPE(a) == NPY_DOUBLE && PyArray_ISNOTSWAPPED(a)
           && PyArray_IS_C_CONTIGUOUS(a) && PyArray_ISALIGNED(a);
}

static inline int
is_name(PyObject *name, PyObject *interned)
{
    return name == interned || (PyUnicode_Check(name) && PyUnicode_Compare(name, interned) == 0);
}

/* An environment variable set to something (os.environ._data holds bytes). -1 on error. */
static int
set_in_environ(Solver *s, PyObject *key)
{
    PyObject *value = PyDict_GetItemWithError(s->environ, key);
    if (value == NULL) return PyErr_Occurred() ? -1 : 0;
    return !PyBytes_Check(value) || PyBytes_GET_SIZE(value) > 0;
}

/* Whether PCSUITE_TIME_LIMIT or PCSUITE_MAX_MEMORY is set (1), or looking failed (-1: the Python path then
   raises it again). Looked up only when os.environ has changed since the last look (CPython < 3.12 numbers
   every change of a dict: ma_version_tag). */
static int
limits_set(Solver *s)
{
#if PY_VERSION_HEX < 0x030C0000
    uint64_t version = ((PyDictObject *)s->environ)->ma_version_tag;
    if (s->environ_seen && version == s->environ_version) return 0;
#endif
    int set = set_in_environ(s, s->time_key);
    if (set == 0) set = set_in_environ(s, s->memory_key);
    if (set < 0) {
        PyErr_Clear();
        return 1;
    }
#if PY_VERSION_HEX < 0x030C0000
    s->environ_seen = set == 0;
    s->environ_version = version;
#endif
    return set;
}

/* time.monotonic()'s clock on Linux. Read when a solve goes on in Python after the first slice of work: its
   deadline (the default 20 s; a limit set in the environment takes the Python path from the start) then
   counts from the end of that slice, a few milliseconds late at most. */
static double
monotonic(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);      /* time.monotonic's clock on Linux */
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

#define FIELD(s, r, f) (*(PyObject **)((char *)(r) + (s)->offsets[f]))

/* A result of the pool that nothing but the pool refers to, with a new reference (so a call made while this one
   runs, by a destructor say, cannot take it too); NULL when every one is in use. CPython recycles its floats,
   lists and frames the same way: allocating and freeing two arrays, a list and the result was a third of a
   small solve's time. Nothing can see a recycled object: only the pool refers to it. */
static PyObject *
take_free(Solver *s)
{
    for (int i = 0; i < POOL; i++) {
        PyObject *r = s->pool[i];
        if (r != NULL && Py_REFCNT(r) == 1) return Py_NewRef(r);
    }
    return NULL;
}

/* An array of a free result that can hold the next answer: nothing else refers to it (no view, no weak
   reference, no buffer), and it is still what solve_lcp made (k float64s, owned, writeable). */
static inline int
reusable_array(PyObject *o, npy_intp k)
{
    if (o == NULL || Py_REFCNT(o) != 1 || !plain(o, 1)) return 0;
    PyArrayObject *a = (PyArrayObject *)o;
    return PyArray_DIM(a, 0) == k && PyArray_CHKFLAGS(a, NPY_ARRAY_OWNDATA | NPY_ARRAY_WRITEABLE)
           && PyArray_BASE(a) == NULL && ((PyArrayObject_fields *)a)->weakreflist == NULL;
}

/* The LCPResult of a solved problem, built as answer.make_result builds it (object.__new__, then each field's
   slot, at the offsets its member descriptors give), or ``held`` (a free result of the pool) given the new
   fields. Every field is set before the old values are released: their destructors may run Python code. */
static PyObject *
result(Solver *s, PyObject *held, PyObject *z, PyObject *w, double err, int64_t iterations, PyObject *method,
       PyObject *message)
{
    PyTypeObject *type = (PyTypeObject *)s->result_type;
    PyObject *solutions = NULL;
    if (held != NULL) {
        PyObject *old = FIELD(s, held, F_SOLUTIONS);
        if (old != NULL && Py_REFCNT(old) == 1 && PyList_CheckExact(old) && PyList_GET_SIZE(old) == 0)
            solutions = Py_NewRef(old);
    }
    if (solutions == NULL) solutions = PyList_New(0);
    PyObject *e = PyFloat_FromDouble(err), *it = PyLong_FromLongLong(iterations);
    PyObject *r = (e == NULL || it == NULL || solutions == NULL) ? NULL
                  : held != NULL ? Py_NewRef(held) : type->tp_alloc(type, 0);
    if (r == NULL) {
        Py_XDECREF(e);
        Py_XDECREF(it);
        Py_XDECREF(solutions);
        return NULL;
    }
    PyObject *values[N_FIELDS] = {Py_NewRef(z), Py_NewRef(w), Py_NewRef(s->solved), e, it, Py_NewRef(method),
                                  Py_NewRef(message), solutions};
    PyObject *old[N_FIELDS];
    for (int f = 0; f < N_FIELDS; f++) {       /* a new object's slots are NULL */
        old[f] = FIELD(s, r, f);
        FIELD(s, r, f) = values[f];
    }
    if (held == NULL) {                       /* into the pool: an empty entry, else the oldest one's place */
        int i = 0;
        while (i < POOL && s->pool[i] != NULL) i++;
        if (i == POOL) {
            i = s->pool_next;
            s->pool_next = (s->pool_next + 1) % POOL;
        }
        PyObject *out = s->pool[i];
        s->pool[i] = Py_NewRef(r);
        Py_XDECREF(out);
    }
    for (int f = 0; f < N_FIELDS; f++) Py_XDECREF(old[f]);
    return r;
}

/* auto's message after other methods of its plan gave way: the Python function's words (it is pure), kept in the
   Solver by their arguments: calling it through its lru_cache had cost a third of a k = 4 solve. */
static PyObject *
auto_words(Solver *s, Py_ssize_t used, int64_t stages, double eig, Py_ssize_t k)
{
    uint64_t bits = 0x7ff8000000000000ULL;       /* NaN: no eigenvalue computed */
    if (eig == eig) memcpy(&bits, &eig, sizeof(bits));
    for (int i = 0; i < MESSAGES; i++) {
        Message *m = &s->messages[i];
        if (m->text != NULL && m->used == used && m->stages == stages && m->eig == bits && m->k == k)
            return Py_NewRef(m->text);
    }
    PyObject *eig_o = eig == eig ? PyFloat_FromDouble(eig) : Py_NewRef(Py_None);
    if (eig_o == NULL) return NULL;
    PyObject *text = PyObject_CallFunction(s->auto_message, "nLOn", used, (long long)stages, eig_o, k);
    Py_DECREF(eig_o);
    if (text == NULL || !PyUnicode_CheckExact(text)) return text;
    Message *m = &s->messages[s->messages_next];
    s->messages_next = (s->messages_next + 1) % MESSAGES;
    PyObject *old = m->text;
    m->used = used;
    m->stages = stages;
    m->k = k;
    m->eig = bits;
    m->text = Py_NewRef(text);
    Py_XDECREF(old);
    return text;
}

static PyObject *
solver_call(PyObject *self, PyObject *const *args, size_t nargsf, PyObject *kwnames)
{
    Solver *s = (Solver *)self;
    Py_ssize_t nargs = PyVectorcall_NARGS(nargsf);
    PyObject *method = NULL, *tol_o = NULL, *fast_o = NULL;
    if (nargs < 2 || nargs > 4) goto python;
    if (nargs >= 3) method = args[2];
    if (nargs >= 4) tol_o = args[3];
    if (kwnames != NULL) {
        Py_ssize_t n = PyTuple_GET_SIZE(kwnames);
        for (Py_ssize_t i = 0; i < n; i++) {
            PyObject *name = PyTuple_GET_ITEM(kwnames, i), *value = args[nargs + i];
            if (is_name(name, s_method) && method == NULL) method = value;
            else if (is_name(name, s_tol) && tol_o == NULL) tol_o = value;
            else if (is_name(name, s_fast_paths) && fast_o == NULL) fast_o = value;
            else if ((is_name(name, s_max_iter) || is_name(name, s_time_limit)) && value == Py_None) continue;
            else goto python;      /* options, a repeated argument, anything else: Python says what it takes */
        }
    }
    PyObject *Mo = args[0], *qo = args[1];
    if (!plain(Mo, 2) || !plain(qo, 1)) goto python;
    PyArrayObject *M = (PyArrayObject *)Mo, *q = (PyArrayObject *)qo;
    npy_intp k = PyArray_DIM(q, 0);
    if (k <= 0 || k > s->k_max || PyArray_DIM(M, 0) != k || PyArray_DIM(M, 1) != k) goto python;
    Py_ssize_t code = s->auto_code;
    if (method != NULL) {
        if (!PyUnicode_CheckExact(method)) goto python;
        for (code = 0; code < s->n_methods; code++)
            if (is_name(method, PyTuple_GET_ITEM(s->names, code))) break;
        if (code == s->n_methods || code == s->enum_code) goto python;
    }
    double tol = s->tol_default;
    if (tol_o != NULL) {
        if (!PyFloat_CheckExact(tol_o)) goto python;
        tol = PyFloat_AS_DOUBLE(tol_o);
        if (!(s->tol_low <= tol && tol <= s->tol_high)) goto python;
    }
    int fast_paths = 1;
    if (fast_o != NULL) {
        if (fast_o != Py_True && fast_o != Py_False) goto python;
        fast_paths = fast_o == Py_True;
    }
    if (limits_set(s)) goto python;              /* a time or memory limit (or an error): Python reads it */

    PyObject *held = take_free(s), *z = NULL, *w = NULL;
    if (held != NULL) {
        if (reusable_array(FIELD(s, held, F_Z), k)) z = Py_NewRef(FIELD(s, held, F_Z));
        if (reusable_array(FIELD(s, held, F_W), k)) w = Py_NewRef(FIELD(s, held, F_W));
    }
    if (z == NULL) z = PyArray_EMPTY(1, &k, NPY_DOUBLE, 0);
    if (w == NULL && z != NULL) w = PyArray_EMPTY(1, &k, NPY_DOUBLE, 0);
    if (w == NULL) {
        Py_XDECREF(z);
        Py_XDECREF(held);
        return NULL;
    }
    PyArrayObject *opts = (PyArrayObject *)s->opts;
    if (k * k > n_work_m) {
        double *m = PyMem_RawRealloc(work_m, (size_t)(k * k) * sizeof(double));
        if (m == NULL) {
            Py_DECREF(z);
            Py_DECREF(w);
            Py_XDECREF(held);
            return PyErr_NoMemory();
        }
        work_m = m;
        n_work_m = k * k;
    }
    double out[RAW_OUT_SIZE];
    int64_t answer = RAW_WORKSPACE;
    int32_t status = 0;
    while (answer == RAW_WORKSPACE) {
        excinfo_t *excinfo = NULL;
        status = pcsuite_lcp_solve_raw(&answer, &excinfo, (double *)PyArray_DATA(M), (double *)PyArray_DATA(q),
                                       (double *)PyArray_DATA((PyArrayObject *)z),
                                       (double *)PyArray_DATA((PyArrayObject *)w), (int64_t)k, (int64_t)code, tol,
                                       s->once_max_iter[code], fast_paths, (double *)PyArray_DATA(opts),
                                       (int64_t)PyArray_DIM(opts, 0), s->budget, work_m, work_f, n_work_f, work_i,
                                       n_work_i, out);
        if (status != 0) break;
        if (answer == RAW_WORKSPACE && grow((int64_t)out[0], (int64_t)out[1]) < 0) {
            Py_DECREF(z);
            Py_DECREF(w);
            Py_XDECREF(held);
            return PyErr_NoMemory();
        }
    }
    PyObject *r = NULL;
    if (status == 0 && answer == ONCE_SOLVED) {
        Py_ssize_t used = (Py_ssize_t)out[RAW_USED];
        int64_t stages = (int64_t)out[RAW_STAGES];
        if (code != s->auto_code) {
            r = result(s, held, z, w, out[RAW_ERR], (int64_t)out[RAW_ITERATIONS], PyTuple_GET_ITEM(s->names, code),
                       s->empty);
        }
        else if (used >= 0 && used < s->n_methods) {
            PyObject *message;
            if (stages == ((int64_t)1 << (4 * used)) || stages == s->pgs_gave_way[used]) {
                message = Py_NewRef(s->empty);
            }
            else {
                message = auto_words(s, used, stages, out[RAW_INFO_X], (Py_ssize_t)k);
            }
            if (message != NULL) {
                r = result(s, held, z, w, out[RAW_ERR], (int64_t)out[RAW_ITERATIONS],
                           PyTuple_GET_ITEM(s->auto_labels, used), message);
                Py_DECREF(message);
            }
        }
        else {
            PyErr_SetString(PyExc_SystemError, "solve_lcp: the compiled solve named no method");
        }
    }
    else if (status == 0 && answer == ONCE_CLOSED_FORM) {
        Py_ssize_t rule = (Py_ssize_t)out[RAW_RULE];
        if (rule >= 0 && rule < s->n_rules) {
            r = result(s, held, z, w, out[RAW_ERR], 0,
                       code == s->auto_code ? s->closed_label : PyTuple_GET_ITEM(s->names, code),
                       PyTuple_GET_ITEM(s->closed_forms, rule));
        }
        else {
            PyErr_SetString(PyExc_SystemError, "solve_lcp: the compiled solve named no closed form");
        }
    }
    else if (status == 0 && answer == ONCE_OTHER) {
        /* not solved within the first slice of work, or not solved: the sliced solve, as the thin path does */
        r = PyObject_CallFunction(s->after_once, "OOndOd", Mo, qo, code, tol, fast_paths ? Py_True : Py_False,
                                  monotonic());
    }
    Py_DECREF(z);
    Py_DECREF(w);
    Py_XDECREF(held);
    if (r != NULL || PyErr_Occurred()) return r;
    /* NaN or inf in M or q, or an exception inside the compiled code: Python's checks say what is wrong */
python:
    return PyObject_Vectorcall(s->python, args, nargsf, kwnames);
}

static PyObject *
solver_new(PyTypeObject *type, PyObject *args, PyObject *kwargs)
{
    Solver *s;
    PyObject *python, *after_once, *auto_message, *result_type, *slots, *solved, *empty, *names, *auto_labels;
    PyObject *closed_forms, *closed_label, *environ, *time_key, *memory_key, *opts, *once_max_iter, *pgs_gave_way;
    double tol_default, tol_low, tol_high;
    Py_ssize_t k_max, auto_code, enum_code;
    long long budget;
    if (kwargs != NULL && PyDict_GET_SIZE(kwargs) > 0) {
        PyErr_SetString(PyExc_TypeError, "Solver takes positional arguments only");
        return NULL;
    }
    if (!PyArg_ParseTuple(args, "OOOOO!UUO!O!O!UO!O!O!O!O!O!dddnnnL:Solver", &python, &after_once, &auto_message,
                          &result_type, &PyTuple_Type, &slots, &solved, &empty, &PyTuple_Type, &names,
                          &PyTuple_Type, &auto_labels, &PyTuple_Type, &closed_forms, &closed_label, &PyDict_Type,
                          &environ, &PyBytes_Type, &time_key, &PyBytes_Type, &memory_key, &PyArray_Type, &opts,
                          &PyTuple_Type, &once_max_iter,
                          &PyTuple_Type, &pgs_gave_way, &tol_default, &tol_low, &tol_high, &k_max, &auto_code,
                          &enum_code, &budget))
        return NULL;
    Py_ssize_t n = PyTuple_GET_SIZE(names);
    if (!PyType_Check(result_type) || n < 1 || n > MAX_METHODS || PyTuple_GET_SIZE(auto_labels) != n
        || PyTuple_GET_SIZE(once_max_iter) != n || PyTuple_GET_SIZE(pgs_gave_way) != n
        || auto_code < 0 || auto_code >= n || enum_code < 0 || enum_code >= n || k_max < 1
        || !PyArray_Check(opts) || !plain(opts, 1)) {
        PyErr_SetString(PyExc_ValueError, "Solver: inconsistent configuration");
        return NULL;
    }
    if (PyTuple_GET_SIZE(slots) != N_FIELDS || ((PyTypeObject *)result_type)->tp_dictoffset != 0) {
        PyErr_SetString(PyExc_ValueError, "Solver: LCPResult must have __slots__, one per field");
        return NULL;
    }
    Py_ssize_t offsets[N_FIELDS];
    for (Py_ssize_t i = 0; i < N_FIELDS; i++) {
        PyObject *descr = PyTuple_GET_ITEM(slots, i);
        if (!Py_IS_TYPE(descr, &PyMemberDescr_Type) || PyDescr_TYPE(descr) != (PyTypeObject *)result_type
            || ((PyMemberDescrObject *)descr)->d_member->type != T_OBJECT_EX) {
            PyErr_SetString(PyExc_ValueError, "Solver: each field must be a slot of LCPResult");
            return NULL;
        }
        offsets[i] = ((PyMemberDescrObject *)descr)->d_member->offset;
    }
    /* everything read before the object exists: a conversion may run Python code (__index__) */
    int64_t max_iters[MAX_METHODS], gave_way[MAX_METHODS];
    for (Py_ssize_t i = 0; i < n; i++) {
        if (!PyLong_CheckExact(PyTuple_GET_ITEM(once_max_iter, i))
            || !PyLong_CheckExact(PyTuple_GET_ITEM(pgs_gave_way, i))
            || !PyUnicode_Check(PyTuple_GET_ITEM(names, i)) || !PyUnicode_Check(PyTuple_GET_ITEM(auto_labels, i))) {
            PyErr_SetString(PyExc_ValueError, "Solver: method names and labels must be str, limits int");
            return NULL;
        }
        max_iters[i] = PyLong_AsLongLong(PyTuple_GET_ITEM(once_max_iter, i));
        gave_way[i] = PyLong_AsLongLong(PyTuple_GET_ITEM(pgs_gave_way, i));
        if (PyErr_Occurred()) return NULL;
    }
    s = (Solver *)type->tp_alloc(type, 0);
    if (s == NULL) return NULL;
    memcpy(s->offsets, offsets, sizeof(offsets));
    memcpy(s->once_max_iter, max_iters, (size_t)n * sizeof(int64_t));
    memcpy(s->pgs_gave_way, gave_way, (size_t)n * sizeof(int64_t));
    s->vectorcall = solver_call;
    s->python = Py_NewRef(python);
    s->after_once = Py_NewRef(after_once);
    s->auto_message = Py_NewRef(auto_message);
    s->result_type = Py_NewRef(result_type);
    s->solved = Py_NewRef(solved);
    s->empty = Py_NewRef(empty);
    s->names = Py_NewRef(names);
    s->auto_labels = Py_NewRef(auto_labels);
    s->closed_forms = Py_NewRef(closed_forms);
    s->closed_label = Py_NewRef(closed_label);
    s->environ = Py_NewRef(environ);
    s->time_key = Py_NewRef(time_key);
    s->memory_key = Py_NewRef(memory_key);
    s->opts = Py_NewRef(opts);
    s->n_methods = n;
    s->n_rules = PyTuple_GET_SIZE(closed_forms);
    s->auto_code = auto_code;
    s->enum_code = enum_code;
    s->tol_default = tol_default;
    s->tol_low = tol_low;
    s->tol_high = tol_high;
    s->k_max = k_max;
    s->budget = budget;
    return (PyObject *)s;
}

static int
solver_traverse(Solver *s, visitproc visit, void *arg)
{
    Py_VISIT(s->dict);
    Py_VISIT(s->python);
    Py_VISIT(s->after_once);
    Py_VISIT(s->auto_message);
    Py_VISIT(s->result_type);
    Py_VISIT(s->solved);
    Py_VISIT(s->empty);
    Py_VISIT(s->names);
    Py_VISIT(s->auto_labels);
    Py_VISIT(s->closed_forms);
    Py_VISIT(s->closed_label);
    Py_VISIT(s->environ);
    Py_VISIT(s->time_key);
    Py_VISIT(s->memory_key);
    Py_VISIT(s->opts);
    for (int i = 0; i < POOL; i++) Py_VISIT(s->pool[i]);
    for (int i = 0; i < MESSAGES; i++) Py_VISIT(s->messages[i].text);
    return 0;
}

static int
solver_clear(Solver *s)
{
    Py_CLEAR(s->dict);
    Py_CLEAR(s->python);
    Py_CLEAR(s->after_once);
    Py_CLEAR(s->auto_message);
    Py_CLEAR(s->result_type);
    Py_CLEAR(s->solved);
    Py_CLEAR(s->empty);
    Py_CLEAR(s->names);
    Py_CLEAR(s->auto_labels);
    Py_CLEAR(s->closed_forms);
    Py_CLEAR(s->closed_label);
    Py_CLEAR(s->environ);
    Py_CLEAR(s->time_key);
    Py_CLEAR(s->memory_key);
    Py_CLEAR(s->opts);
    for (int i = 0; i < POOL; i++) Py_CLEAR(s->pool[i]);
    for (int i = 0; i < MESSAGES; i++) Py_CLEAR(s->messages[i].text);
    return 0;
}

static void
solver_dealloc(Solver *s)
{
    PyObject_GC_UnTrack(s);
    solver_clear(s);
    Py_TYPE(s)->tp_free((PyObject *)s);
}

static PyObject *
solver_repr(Solver *s)
{
    return s->python == NULL ? PyUnicode_FromString("<solve_lcp>") : PyObject_Repr(s->python);
}

/* pickled by name, as a function is: the module's attribute of the same qualified name */
static PyObject *
solver_reduce(Solver *s, PyObject *unused)
{
    (void)unused;
    if (s->python == NULL) {
        PyErr_SetString(PyExc_TypeError, "solve_lcp's C entry point is not set up");
        return NULL;
    }
    return PyObject_GetAttrString(s->python, "__qualname__");
}

static PyMethodDef solver_methods[] = {
    {"__reduce__", (PyCFunction)solver_reduce, METH_NOARGS, NULL},
    {NULL, NULL, 0, NULL}};

static PyGetSetDef solver_getset[] = {
    {"__dict__", PyObject_GenericGetDict, PyObject_GenericSetDict, NULL, NULL},
    {NULL, NULL, NULL, NULL, NULL}};

static PyTypeObject SolverType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "converters._lcpfast.Solver",
    .tp_basicsize = sizeof(Solver),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC | Py_TPFLAGS_HAVE_VECTORCALL,
    .tp_doc = "solve_lcp with its thin path in C (see converters/lcp/_fast.c)",
    .tp_new = solver_new,
    .tp_dealloc = (destructor)solver_dealloc,
    .tp_traverse = (traverseproc)solver_traverse,
    .tp_clear = (inquiry)solver_clear,
    .tp_call = PyVectorcall_Call,
    .tp_vectorcall_offset = offsetof(Solver, vectorcall),
    .tp_dictoffset = offsetof(Solver, dict),
    .tp_repr = (reprfunc)solver_repr,
    .tp_methods = solver_methods,
    .tp_getset = solver_getset,
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_lcpfast",
                                    "The C entry point of solve_lcp (converters/lcp/_fast.c).", -1, NULL};

PyMODINIT_FUNC
PyInit__lcpfast(void)
{
    import_array();
    if (PyType_Ready(&SolverType) < 0) return NULL;
#define INTERN(var, text) if ((var = PyUnicode_InternFromString(text)) == NULL) return NULL
    INTERN(s_method, "method");
    INTERN(s_tol, "tol");
    INTERN(s_fast_paths, "fast_paths");
    INTERN(s_max_iter, "max_iter");
    INTERN(s_time_limit, "time_limit");
    PyObject *m = PyModule_Create(&module);
    if (m == NULL) return NULL;
    if (PyModule_AddObjectRef(m, "Solver", (PyObject *)&SolverType) < 0
        || PyModule_AddIntConstant(m, "RAW_OUT_SIZE", RAW_OUT_SIZE) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
