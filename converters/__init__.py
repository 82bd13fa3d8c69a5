"""pcsuite's converters package: problems, methods, models and analysis (see the README's Layout)."""
import os

from . import kernel_cache

#: The BLAS's own threads, one per process unless the user's environment says otherwise. The matrices here are small
#: (the states of a circuit: a few to a few tens) and a multithreaded BLAS spends more waking its threads than
#: multiplying: a 5 x 5 matrix exponential took 418 us with OpenBLAS 0.3.31's threads on two busy cores and 34 us on
#: one, and the test suite three times as long. Parallel work (sweeps, bifurcation diagrams) runs in processes. A
#: BLAS loaded later (scipy.linalg's own) reads the variable when it loads; one loaded already is limited by
#: threadpoolctl.
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
if not any(os.environ.get(name) for name in BLAS_THREAD_VARIABLES):
    os.environ["OPENBLAS_NUM_THREADS"] = os.environ["MKL_NUM_THREADS"] = "1"
    from threadpoolctl import threadpool_limits
    threadpool_limits(limits=1, user_api="blas")

kernel_cache.refresh()   # before any compiled kernel loads its cache (see converters.kernel_cache)
