"""Hostile and absurd input: one clear line and a non-zero exit, within a bound on CPU time and memory, nothing written
outside the output directory; every flag acts or is refused; no worker outlives a killed command; a kill at any
instant never leaves a partial output in place of a good one."""
import json
import os
import random
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from validation.cli import main

PCSUITE = [sys.executable, "-m", "validation.cli"]
ROOT = Path(__file__).resolve().parents[2]
#: CPU seconds a hostile command may spend (its work, whatever else the machine runs: a loaded machine stretches
#: wall time, not this), and wall seconds after which it counts as hung.
TIME_BOUND_S = 30.0
HUNG_S = 4 * TIME_BOUND_S
MEMORY_BOUND_KB = 1 << 20          # 1 GiB, as ru_maxrss (KiB) of the command and every process it waited for

#: Runs one command and reports its exit code, the CPU time of it and every process it waited for, and the largest
#: resident set among them (a fresh small process, so the bounds measure the command, not this test's process).
WRAPPER = """
import json, resource, subprocess, sys
try:
    proc = subprocess.run(sys.argv[2:], capture_output=True, text=True, timeout=float(sys.argv[1]))
    code, out, err = proc.returncode, proc.stdout, proc.stderr
except subprocess.TimeoutExpired as exc:
    code, out, err = "timeout", "", str(exc)
usage = resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps({"code": code, "out": out, "err": err, "cpu": usage.ru_utime + usage.ru_stime,
                  "maxrss_kb": usage.ru_maxrss}))
"""


def bounded(argv, cwd, env=None):
    """(code, stdout, stderr, CPU seconds, max RSS in KiB) of ``pcsuite argv`` run in ``cwd`` (``env``: variables
    added); code "timeout" when it ran HUNG_S wall seconds."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), **(env or {})}
    done = subprocess.run([sys.executable, "-c", WRAPPER, str(HUNG_S), *PCSUITE, *map(str, argv)],
                          cwd=cwd, capture_output=True, text=True, env=env)
    result = json.loads(done.stdout)
    return result["code"], result["out"], result["err"], result["cpu"], result["maxrss_kb"]


def tree(directory: Path) -> dict:
    return {str(p.relative_to(directory)): p.stat().st_size for p in directory.rglob("*") if p.is_file()}


def scene(text: str) -> str:
    return 'converter = "buck"\n' + text


def dat_header(n: int) -> str:
    return f"{n}\n0\n{n} {n}\n{n} {n}\n1 0 0 1\n"


#: Every case of the hostile-input audit: (id, argv, files to create in the run's directory, what the one
#: stderr line must contain). Each runs in a fresh directory ``work`` inside ``tmp_path``; ``OUT`` there is the
#: only place a command may write.
FUZZ = [
    # tracebacks before
    ("t-end-1e-300", ["simulate", "buck", "--t-end", "1e-300"], {}, "t_end must be at least one step"),
    ("event-h-1e-18", ["simulate", "buck", "--method", "event", "--h", "1e-18"], {}, "--max-memory"),
    ("out-proc", ["simulate", "buck", "--periods", "2", "--out", "/proc/x.csv"], {}, "--out /proc/x.csv"),
    ("out-dev-full", ["simulate", "buck", "--periods", "2", "--out", "/dev/full/x.csv"], {}, "--out /dev/full/x.csv"),
    ("compare-plot-proc", ["compare", "buck", "--plot", "/proc/x.png"], {}, "--plot /proc/x.png"),
    ("gdcm-h-0", ["gdcm", "buck", "--h", "0"], {}, "h must be positive"),
    ("gdcm-h-1e-18", ["gdcm", "buck", "--h", "1e-18"], {}, "--max-memory"),
    ("gdcm-map-out-proc", ["gdcm-map", "buck", "--no-spice", "--out", "/proc/m"], {}, "--out /proc/m"),
    ("scene-description-5", ["report", "s.toml", "--out", "OUT"], {"s.toml": scene("description = 5\n")},
     "description"),
    ("dat-n-1e6", ["lcp", "solve", "big.dat"], {"big.dat": dat_header(10 ** 6)}, "--max-memory"),
    # memory without bounds before
    ("h-1e-12", ["simulate", "buck", "--h", "1e-12"], {}, "--max-memory"),
    ("h-1e-11", ["simulate", "buck", "--h", "1e-11"], {}, "--max-memory"),
    ("compare-h-1e-12", ["compare", "buck", "--h", "1e-12"], {}, "--max-memory"),
    ("event-h-1e-13", ["simulate", "buck", "--method", "event", "--h", "1e-13"], {}, "--max-memory"),
    ("gdcm-map-size", ["gdcm-map", "buck", "--size", "1000000", "1000000"], {}, "--size N_D must be in [2, 1000]"),
    ("dat-n-50000", ["lcp", "solve", "n.dat"], {"n.dat": dat_header(50_000)}, "--max-memory"),
    ("dat-dev-zero", ["lcp", "solve", "/dev/zero"], {}, "regular file"),
    ("smc-spice-1s", ["simulate", "boost", "--control", "smc", "--method", "spice", "--t-end", "1"], {},
     "--max-memory"),
    # hangs before
    ("spice-t-end-1e9", ["simulate", "buck", "--method", "spice", "--t-end", "1e9"], {}, "--max-memory"),
    ("spice-periods-1e5", ["simulate", "buck", "--method", "spice", "--periods", "100000"], {}, "--max-memory"),
    ("smc-spice-band", ["simulate", "boost", "--control", "smc", "--method", "spice", "-p", "band=1e-12"], {},
     "--max-memory"),
    ("smc-spice-t-end-1e9", ["simulate", "boost", "--control", "smc", "--method", "spice", "--t-end", "1e9"], {},
     "--max-memory"),
    ("scene-tiny-tmax", ["report", "s.toml", "--out", "OUT"],
     {"s.toml": scene("[methods.spice]\ntmax_fraction = 1e-12\n")}, "tmax_fraction"),
    ("mech-t-end-1e9", ["mech", "simulate", "friction", "--t-end", "1e9"], {}, "--max-memory"),
    ("mech-h-1e-12", ["mech", "simulate", "friction", "--method", "moreau", "--h", "1e-12"], {}, "--max-memory"),
    ("murty-max-iter-1e12", ["lcp", "solve", "murty.dat", "--method", "murty", "--max-iter", "1000000000000"],
     {"murty.dat": None}, "max_iter"),
    ("murty-time-limit", ["lcp", "solve", "murty.dat", "--method", "murty", "--max-iter", "1000000000",
                          "--no-fast-paths"], {"murty.dat": None}, "time limit of 20 s"),   # pivots, not substitution
    # accepted but suspect before
    ("space", ["simulate", "buck", "-p", "L=10 u"], {}, "L must be a number with no space inside"),
    ("full-width", ["simulate", "buck", "-p", "L=１０u"], {}, "L must be a number typed in plain ASCII"),
    ("f-sw-1e300", ["simulate", "buck", "-p", "f_sw=1e300"], {}, "f_sw (switching frequency) must be within"),
    ("f-sw-1e-300", ["simulate", "buck", "-p", "f_sw=1e-300"], {}, "f_sw (switching frequency) must be within"),
    ("L-1e300", ["simulate", "buck", "-p", "L=1e300"], {}, "L (inductance) must be within"),
    # the second audit (tracebacks, flags ignored, wrong answers, unbounded processes)
    ("scheduler-tls", ["sweep", "buck", "--grid", "D=0.1:0.9:3", "--scheduler", "tls://127.0.0.1:1", "--out", "OUT"],
     {}, "scheduler must be a Dask address tcp://HOST:PORT with PORT in [1, 65535]"),
    ("scheduler-port", ["sweep", "buck", "--grid", "D=0.1:0.9:3", "--scheduler", "tcp://h:99999999", "--out", "OUT"],
     {}, "got 'tcp://h:99999999'"),
    ("scheduler-inproc", ["sweep", "buck", "--grid", "D=0.1:0.9:3", "--scheduler", "inproc://x", "--out", "OUT"], {},
     "scheduler must be a Dask address"),
    ("scene-deep-nesting", ["report", "s.toml", "--out", "OUT"], {"s.toml": scene("L = " + "[" * 1000 + "]" * 1000 + "\n")},
     "nested too deeply"),
    ("sweep-h-fraction-0", ["sweep", "buck", "--grid", "D=0.1:0.9:3", "--h-fraction", "0", "--out", "OUT"], {},
     "h_fraction (h / T) must be in (0, 1); got 0.0"),
    ("sweep-workers-1e5", ["sweep", "buck", "--grid", "D=0.1:0.9:3", "--workers", "100000", "--out", "OUT"], {},
     "--workers must be an integer in [1, 64]; got 100000"),
    ("bifurcation-workers", ["bifurcation", "buck", "--param", "A=1:2", "--workers", "1000"], {},
     "--workers must be an integer in [1, 64]; got 1000"),
    ("report-workers", ["report", "default", "--out", "OUT", "--workers", "65"], {},
     "--workers must be an integer in [1, 64]; got 65"),
    ("smooth-eps-1e5", ["simulate", "buck", "--method", "smooth", "--eps", "1e5"], {},
     "eps must be in [1e-08, 0.1]; got 100000.0"),
    ("smooth-eps-1e-300", ["simulate", "buck", "--method", "smooth", "--eps", "1e-300"], {}, "eps must be in"),
    ("netlist-t-end-1e308", ["netlist", "buck", "--t-end", "1e308", "--out", "OUT.cir"], {}, "--max-memory"),
    ("netlist-t-end-1e-30", ["netlist", "buck", "--t-end", "1e-30"], {},
     "t_end must be at least one switching period (1e-05 s)"),
    # --time-limit accepted and ignored before: a command that is one run stops at it
    ("mech-time-limit", ["mech", "simulate", "stick-slip", "--t-end", "1e5", "--time-limit", "2"], {},
     "the run did not finish within the time limit of 2 s (--time-limit)"),
    ("event-time-limit", ["simulate", "buck", "--method", "event", "--t-end", "5", "--h", "9e-6", "--time-limit", "2"],
     {}, "the run did not finish within the time limit of 2 s (--time-limit)"),
    # the alarm fired inside an event period run that Newton shooting called, and Newton took it for a trial outside
    # the map's domain and carried on: a 10 ps mode (10 pH, 1 ohm) ran past 100 s at --time-limit 5
    ("event-steady-time-limit", ["simulate", "ps.cir", "--steady", "--method", "event", "--time-limit", "2"],
     {"ps.cir": "peak detector through 10 pH and 1 ohm\n.param f=100k T={1/f} e={1e-3/f}\n"
                "Vs a 0 PULSE(-10 10 {T/2-e/2} {e} {e} {T/2-e} {T})\nR1 a b 1\nL1 b c 10p\nD1 c out DMOD\n"
                "C1 out 0 1u\nR2 out 0 1k\n.model DMOD D\n.tran {T/1000} {100*T}\n.end\n"},
     # whichever comes first: the limit, or the crossing search's bound on substeps (2.4e7 for one 5 us stretch)
     ("the run did not finish within the time limit of 2 s (--time-limit)",
      "the stiffest mode's time constant is about 8.33e-13 s, so crossing 5e-06 s takes 2.4e+07 substeps")),
    ("bifurcation-time-limit", ["bifurcation", "buck", "--param", "A=1:2", "--time-limit", "5"], {},
     "--time-limit bounds ngspice runs and LCP solves; this command runs neither"),
    ("param-twice", ["simulate", "buck", "-p", "Vin=1", "-p", "Vin=2"], {}, "-p Vin is given twice (Vin=1 and Vin=2)"),
    ("param-underflow", ["simulate", "buck", "-p", "Vin=1e-400"], {}, "Vin must be 0 or at least 5e-324 in magnitude"),
    # a path escape before
    ("scene-name-escape", ["report", "s.toml", "--out", "OUT"], {"s.toml": scene('name = "../../../../escaped"\n')},
     "name"),
    # the third audit: exponents and integers beyond any float (tracebacks before)
    ("param-exponent-huge", ["simulate", "buck", "-p", "L=1e99999999999999999999"], {},
     "L must be a finite number, at most 1.8e308 in magnitude; got '1e99999999999999999999'"),
    ("param-exponent-tiny", ["simulate", "buck", "-p", "L=1e-99999999999999999999"], {},
     "L must be 0 or at least 5e-324 in magnitude"),
    ("h-exponent-huge", ["simulate", "buck", "--h", "1e99999999999999999999"], {}, "h must be a finite number"),
    ("t-end-exponent-huge", ["simulate", "buck", "--t-end", "1e99999999999999999999"], {},
     "t_end must be a finite number"),
    ("sweep-grid-exponent-huge", ["sweep", "buck", "--grid", "D=0.1:1e99999999999999999999:3", "--out", "OUT"], {},
     "D stop must be a finite number"),
    ("scene-quoted-exponent-huge", ["report", "s.toml", "--out", "OUT"],
     {"s.toml": scene('[params]\nL = "1e99999999999999999999"\n')}, "[params]: L must be a finite number"),
    ("max-memory-1e400", ["simulate", "buck", "--max-memory", "1e400"], {},
     "--max-memory must be in [16 MiB, 1 TiB]; got '1e400'"),
    ("max-memory-exponent-5000-digits", ["simulate", "buck", "--max-memory", "1e" + "9" * 5000], {},
     "--max-memory must be in [16 MiB, 1 TiB]"),
    ("scene-int-400-digits", ["report", "s.toml", "--out", "OUT"], {"s.toml": scene("[params]\nD = " + "1" * 400 + "\n")},
     "[params]: D must be a finite number, at most 1.8e308 in magnitude; got an integer of 400 digits"),
    ("scene-periods-400-digits", ["report", "s.toml", "--out", "OUT"],
     {"s.toml": scene("[run]\nperiods = " + "1" * 400 + "\n")},
     "[run] periods must be an integer in [1, 100000]; got an integer of 400 digits"),
    # 5,000-digit integers: Python's "Exceeds the limit (4300 digits)", naming nothing, before
    ("scene-int-5000-digits", ["report", "s.toml", "--out", "OUT"],
     {"s.toml": scene("[run]\nperiods = " + "1" * 5000 + "\n")}, "scene s.toml [run] periods: an integer of 5000 digits"),
    ("scene-param-5000-digits", ["report", "s.toml", "--out", "OUT"],
     {"s.toml": scene("[params]\nD = -" + "1" * 5000 + "\n")}, "scene s.toml [params] D: an integer of 5000 digits"),
    ("sweep-count-5000-digits", ["sweep", "buck", "--grid", "D=0.1:0.9:" + "1" * 5000, "--out", "OUT"], {},
     "--grid D: COUNT must be an integer in [1, 10,000,000]; got '11111111111111111111...1111111111 (5000 characters)'"),
    ("dat-n-5000-digits", ["lcp", "solve", "n.dat"], {"n.dat": "1" * 5000 + "\n0\n1 1\n1 1\n1\n-1\n"},
     "n must be an integer of at most 18 digits; got one of 5000 digits"),
    # .dat numbers in other scripts' digits, or split by a space that is not ASCII (read as two numbers before)
    ("dat-arabic-indic-digit", ["lcp", "solve", "x.dat"], {"x.dat": "\u0661\n0\n1 1\n1 1\n1\n-1\n"},
     "token '\u0661' at position 1 (line 1) is not an integer"),
    ("dat-fullwidth-digit-in-q", ["lcp", "solve", "x.dat"], {"x.dat": "1\n0\n1 1\n1 1\n1\n-\uff11\n"},
     "token '-\uff11' at position 8 (line 6) is not a finite number"),
    ("dat-no-break-space-in-number", ["lcp", "solve", "x.dat"], {"x.dat": "2\n0\n2 2\n2 2\n1 0 0 1\n-1\u00a0000 2\n"},
     "token '-1\\xa0000' at position 11 (line 6) is not a finite number"),
    ("dat-escape-in-name", ["lcp", "solve", "e\x1b[2J.dat"], {"e\x1b[2J.dat": "x\n"},
     "pcsuite: error: 'e\\x1b[2J.dat': token 'x' at position 1 (line 1) is not an integer (reading n)"),
    # a file option's missing directory was created silently before; a path is shown quoted when it is not printable
    ("out-missing-directory", ["simulate", "buck", "--periods", "2", "--out", "nodir/x.csv"], {},
     "--out nodir/x.csv: its directory nodir does not exist"),
    ("out-newline-in-path", ["simulate", "buck", "--periods", "2", "--out", "a\nb/x.csv"], {},
     "--out 'a\\nb/x.csv': its directory 'a\\nb' does not exist"),
    ("plot-escape-in-path", ["simulate", "buck", "--periods", "2", "--plot", "/proc/\x1b[2Jx.png"], {},
     "--plot '/proc/\\x1b[2Jx.png': cannot write in /proc"),
    ("netlist-missing-directory", ["netlist", "buck", "--out", "nodir/x.cir"], {},
     "--out nodir/x.cir: its directory nodir does not exist"),
]


def murty_file() -> str:
    """A 300 x 300 problem on which Murty's least-index pivoting takes exponentially many pivots (M upper
    triangular with 2 on the diagonal and 4 above it, q = -1: Murty's own example, 2^n - 1 pivots)."""
    import numpy as np
    n = 300
    M = np.triu(np.full((n, n), 4.0), 1) + 2.0 * np.eye(n)
    q = -np.ones(n)
    return f"{n}\n0\n{n} {n}\n{n} {n}\n" + "\n".join(" ".join(f"{v:g}" for v in col) for col in M.T) + "\n" + \
        " ".join(f"{v:g}" for v in q) + "\n"


@pytest.fixture(scope="module")
def fuzz_results(tmp_path_factory):
    """Every FUZZ case, two at a time, each in its own directory (the table's evidence, collected once)."""
    base = tmp_path_factory.mktemp("fuzz")
    murty = murty_file()

    def one(case):
        name, argv, files, _ = case
        outer = base / name
        work = outer / "work"
        work.mkdir(parents=True)
        for file, text in files.items():
            (work / file).write_text(murty if text is None else text)
        before = tree(outer)
        result = bounded(argv, work)
        return name, (*result, before, tree(outer), outer)

    with ThreadPoolExecutor(2) as pool:
        return dict(pool.map(one, FUZZ))


@pytest.mark.parametrize("name,argv,files,expected", FUZZ, ids=[case[0] for case in FUZZ])
@pytest.mark.slow
def test_each_hostile_case_gets_one_clear_line_quickly_and_in_bounded_memory(fuzz_results, name, argv, files, expected):
    code, out, err, cpu, maxrss_kb, before, after, outer = fuzz_results[name]
    lines = [line for line in err.splitlines() if line.strip()]
    assert code not in (0, "timeout"), (code, err)
    assert "Traceback" not in err and "Traceback" not in out
    assert len(lines) == 1 and lines[0].startswith("pcsuite:"), err
    assert any(said in lines[0] for said in ((expected,) if isinstance(expected, str) else expected)), lines[0]
    assert cpu < TIME_BOUND_S, cpu
    assert maxrss_kb < MEMORY_BOUND_KB, maxrss_kb
    assert after == before                                    # nothing written anywhere, OUT included
    assert not (outer.parent / "escaped").exists() and not (outer / "escaped").exists()


@pytest.mark.slow
def test_no_file_is_written_outside_out_whatever_a_scene_contains(tmp_path):
    """A valid user scene whose strings carry quotes, brackets and ../ runs; everything it writes is under --out."""
    work = tmp_path / "a" / "b" / "work"
    work.mkdir(parents=True)
    (work / "nasty.toml").write_text('converter = "buck"\nname = "ok-name"\n'
                                     'description = "../../x\' onerror=\'alert(1)\' <script>&"\n'
                                     'suites = ["mine"]\n[params]\nD = "0.4"\n[run]\nperiods = 30\nwindow = 10\n')
    before = tree(tmp_path)
    code, out, err, _, _ = bounded(["report", "nasty.toml", "--out", "OUT", "--workers", "1"], work)
    assert code in (0, 1), err
    new = {path for path in tree(tmp_path) if path not in before}
    assert new and all(path.startswith("a/b/work/OUT/") for path in new), sorted(new)
    page = (work / "OUT" / "index.html").read_text()
    assert "<script>" not in page and "onerror='" not in page


#: Flags that would be ignored in a combination: each is refused with one line naming the flag (issue 22's table).
IGNORED = [
    (["simulate", "buck", "--method", "spice", "--periods", "0"], "periods must be an integer >= 1; got 0"),
    (["simulate", "buck", "--method", "spice", "--periods", "-1"], "periods must be an integer >= 1; got -1"),
    (["simulate", "buck", "--method", "spice", "--h", "1e-8"], "--h does not apply to --method spice"),
    (["simulate", "buck", "--method", "spice", "--theta", "7"], "--theta does not apply to --method spice"),
    (["simulate", "buck", "--method", "spice", "--eps", "1e-3"], "--eps does not apply to --method spice"),
    (["simulate", "buck", "--method", "spice", "--steady", "--steady-tol", "1e-3"],
     "--steady-tol does not apply to --method spice"),
    (["simulate", "buck", "--steady-tol", "1e-3"], "--steady-tol applies with --steady only"),
    (["simulate", "buck", "--rtol", "1e-4", "--steady-tol", "1e-3"], "give either --rtol or --steady-tol"),
    (["simulate", "boost", "--control", "smc", "--theta", "2"], "theta must be in [0.5, 1]; got 2.0"),
    (["simulate", "boost", "--control", "smc-implicit", "--method", "event"], "use --method lcp"),
    (["simulate", "boost", "--control", "smc", "--steady"], "--steady needs a fixed switching period"),
    (["simulate", "boost", "--control", "smc", "--method", "spice", "--steady"],
     "--steady needs a fixed switching period"),
    (["simulate", "buck", "--steady-tol", "inf", "--steady"], "steady_tol must be a number"),
    (["simulate", "buck", "--steady-tol", "nan", "--steady"], "steady_tol must be a number"),
    (["simulate", "buck", "--steady-tol", "0", "--steady"], "steady_tol must be in [1e-14, 1) (relative; Newton aims "
                                                            "at a tenth of it); got 0.0"),
    (["simulate", "buck", "--steady-tol", "1e-15", "--steady"], "steady_tol must be in [1e-14, 1)"),   # "tol ... 1e-16"
    (["simulate", "buck", "--t-end", "1e9"], "a shorter --t-end"),
    (["compare", "buck", "--t-end", "nan"], "--t-end applies to --control smc"),
    (["compare", "buck", "--t-end", "1e9"], "--t-end applies to --control smc"),
    (["compare", "boost", "--control", "smc", "--t-end", "1m"], "t_end must be at least 0.004 s"),
    (["compare", "boost", "--control", "smc", "--start", "rest"], "--start applies to PWM comparisons"),
    (["gdcm-map", "buck", "--workers", "0"], "--workers must be an integer in [1, 64]; got 0"),
    (["gdcm-map", "buck", "--workers", "-5"], "--workers must be an integer in [1, 64]; got -5"),
    (["gdcm-map", "buck", "--no-spice", "--workers", "2"], "--workers sets the ngspice processes"),
    (["bench", "--only", "stability", "--periods", "5"], "--periods sets the trade-off"),
    (["bench", "--only", "stability", "--quick"], "--quick sets the trade-off"),
    (["sweep", "buck", "--grid", "D=0.2:0.8:3", "--seed", "3"], "--seed sets the Latin hypercube"),
    (["sweep", "buck", "--grid", "D=0.2:0.8:3", "--method", "spice", "--h-fraction", "0.01"],
     "--h-fraction does not apply to --method spice"),
    (["sweep", "buck", "--grid", "D=0.2:0.8:3", "--method", "event", "--h-fraction", "0.01"],
     "--h-fraction sets the lcp stepper's step"),
    (["sweep", "buck", "--grid", "D=0.2:0.8:3", "--steady", "--periods", "5"], "--periods does not apply with --steady"),
    (["sweep", "buck", "--grid", "D=0.2:0.8:3", "--scheduler", "serial", "--workers", "2"],
     "--workers sets the local processes"),
    (["bifurcation", "buck", "--param", "Vin=20:36", "--points", "0", "--record", "5"],
     "--record sets the brute-force diagram"),
    (["lcp", "solve", "x.dat", "--tol", "10"], "tol must be in [1e-16, 0.01]"),
    (["lcp", "solve", "x.dat", "--method", "enum", "--max-iter", "5"], "max_iter does not apply to method 'enum'"),
    (["mech", "bifurcations", "friction", "--param", "omega=2.85:2.95", "--points", "0", "--workers", "2"],
     "--workers must be >= 1 and needs the diagram"),
    (["mech", "bifurcations", "friction", "--param", "omega=2.85:2.95", "--points", "100000000"],
     "--points must be an integer in [0, 100000]"),
    (["mech", "bifurcations", "stick-slip", "--param", "k2=1:2", "--points", "0"],     # printed nothing, exit 0
     "--points must be an integer in [2, 100000] for the stick-slip (its study is the brute-force diagram); got 0"),
    (["mech", "bifurcations", "cam-follower", "--param", "rpm=100:200", "--workers", "1000"],
     "--workers must be an integer in [1, 64]; got 1000"),
    (["sweep", "buck", "--grid", "D=0.2:0.8", "--lhs", "3", "--seed", "-1"],      # numpy's words, no flag, before
     "--seed must be an integer >= 0; got -1"),
    (["sweep", "buck", "--grid", "R=5:200:40:log", "--lhs", "50"],                 # COUNT silently dropped before
     "--grid R: COUNT does not apply with --lhs (the hypercube draws its N points over START:STOP); give "
     "R=START:STOP[:log]; got 'R=5:200:40:log'"),
    (["bifurcation", "boost", "--param", "D=0.2:0.5", "--points", "0"],     # the default control, not given
     "--control voltage-mode is available for buck only (boost takes --control pwm, smc, smc-implicit, "
     "peak-current, valley-current, current-loop, voltage-loop)"),
    (["report", ""], "TARGET must be a suite (bench, bifurcation, default, gdcm, lcp, mechanics, thermal), a scene file "
                     "FILE.toml or a directory of them; got ''"),                 # read as '.' before
    # the third audit: accepted and ignored before
    (["list", "--time-limit", "5"], "--time-limit bounds ngspice runs and LCP solves; this command runs neither"),
    (["mech", "list", "--time-limit", "5"], "--time-limit bounds ngspice runs and LCP solves; this command runs neither"),
    (["netlist", "buck", "--time-limit", "5"], "--time-limit bounds ngspice runs and LCP solves; this command runs neither"),
    (["gdcm-map", "buck", "--no-spice", "--size", "3", "3", "--time-limit", "5"],
     "--time-limit bounds ngspice runs and LCP solves; this command runs neither"),
    (["bifurcation", "buck", "--param", "Vin=20:36", "--points", "0", "--state", "iL"],
     "--state sets the brute-force diagram; --points 0 asks for continuation only"),
    (["bifurcation", "buck", "--param", "Vin=20:36", "-p", "Vin=25", "--points", "0"],
     "Vin is both swept (--param) and fixed (-p); give it once"),
    (["mech", "bifurcations", "friction", "--param", "omega=2.85:2.95", "-p", "omega=2.9"],
     "omega is both swept (--param) and fixed (-p); give it once"),
    (["sweep", "buck", "--grid", "D=0.2:0.8:3", "--seed", "0"],
     "--seed sets the Latin hypercube; it does not apply without --lhs (got --seed 0)"),
]

#: A number that does not parse: the one line names the flag, the range and the text (argparse named no range).
UNPARSABLE = [
    (["bench", "--periods", "x"], "argument --periods: must be an integer in [2, 100,000]; got 'x'"),
    (["bifurcation", "buck", "--param", "Vin=20:30", "--max-period", "x"],
     "argument --max-period: must be an integer >= 1; got 'x'"),
    (["bifurcation", "buck", "--param", "Vin=20:30", "--points", "1.5"], "argument --points: must be an integer >= 0; got '1.5'"),
    (["bifurcation", "buck", "--param", "Vin=20:30", "--transient", "x"],
     "argument --transient: must be an integer >= 0; got 'x'"),
    (["bifurcation", "buck", "--param", "Vin=20:30", "--record", "x"], "argument --record: must be an integer >= 2; got 'x'"),
    (["bifurcation", "buck", "--param", "Vin=20:30", "--workers", "x"],
     "argument --workers: must be an integer in [1, 64]; got 'x'"),
    (["bode", "buck", "--input", "duty", "--points", "x"], "argument --points: must be an integer in [1, 100,000]; got 'x'"),
    (["gdcm-map", "buck", "--size", "3", "x"], "argument --size: must be an integer in [2, 1,000]; got 'x'"),
    (["gdcm-map", "buck", "--workers", "2.0"], "argument --workers: must be an integer in [1, 64]; got '2.0'"),
    (["lcp", "solve", "x.dat", "--tol", "small"], "argument --tol: must be a number in [1e-16, 0.01]; got 'small'"),
    (["lcp", "solve", "x.dat", "--max-iter", "1e3"],
     "argument --max-iter: must be an integer in [1, 1,000,000,000]; got '1e3'"),
    (["mech", "simulate", "friction", "--periods", "x"], "argument --periods: must be an integer >= 1; got 'x'"),
    (["mech", "bifurcations", "friction", "--param", "omega=2.85:2.95", "--points", "x"],
     "argument --points: must be an integer in [0, 100,000]; got 'x'"),
    (["mech", "bifurcations", "friction", "--param", "omega=2.85:2.95", "--workers", "x"],
     "argument --workers: must be an integer in [1, 64]; got 'x'"),
    (["report", "lcp", "--workers", "many"], "argument --workers: must be an integer in [1, 64]; got 'many'"),
    (["simulate", "buck", "--periods", "nan"], "argument --periods: must be an integer >= 1; got 'nan'"),
    (["sweep", "buck", "--grid", "D=0.2:0.8", "--lhs", "x"], "argument --lhs: must be an integer in [1, 10,000,000]; got 'x'"),
    (["sweep", "buck", "--grid", "D=0.2:0.8", "--seed", "x"], "argument --seed: must be an integer >= 0; got 'x'"),
    (["sweep", "buck", "--tolerance", "C=5%", "--samples", "x"],
     "argument --samples: must be an integer in [1, 10,000,000]; got 'x'"),
    (["sweep", "buck", "--grid", "D=0.2:0.8:3", "--periods", "x"], "argument --periods: must be an integer >= 1; got 'x'"),
    (["sweep", "buck", "--grid", "D=0.2:0.8:3", "--h-fraction", "1/200"],
     "argument --h-fraction: must be a number in (0, 1); got '1/200'"),
    (["sweep", "buck", "--grid", "D=0.2:0.8:3", "--rtol", "x"], "argument --rtol: must be a number in [1e-10, 0.1]; got 'x'"),
    (["sweep", "buck", "--grid", "D=0.2:0.8:3", "--workers", "x"], "argument --workers: must be an integer in [1, 64]; got 'x'"),
    (["sweep", "buck", "--grid", "D=0.2:0.8:3", "--chunk", "x"], "argument --chunk: must be an integer >= 1; got 'x'"),
]


#: An empty path (an unset variable in ``--out "$OUT"``) had been read as the current directory.
EMPTY_PATHS = [
    ["bench", "--out", ""], ["bifurcation", "buck", "--param", "Vin=20:30", "--diagram", ""],
    ["bode", "buck", "--input", "duty", "--plot", ""],
    ["compare", "buck", "--plot", ""], ["gdcm-map", "buck", "--out", ""], ["lcp", "solve", ""],
    ["mech", "simulate", "friction", "--out", ""], ["mech", "bifurcations", "friction", "--param", "omega=2.85:2.95",
                                                      "--diagram", ""],
    ["netlist", "buck", "--out", " "], ["report", "lcp", "--out", ""], ["simulate", "buck", "--out", ""],
    ["simulate", "buck", "--plot", ""], ["simulate", "buck", "--steady", "--thermal", ""],
    ["sweep", "buck", "--grid", "D=0.2:0.8:3", "--out", ""],
    ["sensitivity", "buck", "--plot", ""], ["view", ""], ["view", "run.parquet", "--out", ""],
]


def _flag(argv):
    """The option an EMPTY_PATHS case gives empty (a positional: its name)."""
    return "file" if argv[:2] == ["lcp", "solve"] else "path" if argv == ["view", ""] else argv[-2]


@pytest.mark.parametrize("argv", EMPTY_PATHS, ids=[" ".join(a) for a in EMPTY_PATHS])
def test_an_empty_path_is_refused_not_read_as_the_current_directory(capsys, tmp_path, monkeypatch, argv):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as stop:
        main(argv)
    flag = _flag(argv)
    assert stop.value.code == 2 and capsys.readouterr().err == f"pcsuite: error: argument {flag}: must be a path; got {argv[-1]!r}\n"
    assert list(tmp_path.iterdir()) == []


def test_every_path_option_refuses_an_empty_path():
    import argparse
    from pathlib import Path

    from validation.cli import build_parser
    paths = set()

    def walk(parser, path):
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, child in action.choices.items():
                    walk(child, path + (name,))
            else:
                assert action.type is not Path, (path, action.option_strings)
                if getattr(action.type, "__name__", "") == "given_path":
                    paths.add((path, (action.option_strings or [action.dest])[0]))
    walk(build_parser(), ())
    table = {(tuple(a[:2] if a[0] in ("lcp", "mech") else a[:1]), _flag(a)) for a in EMPTY_PATHS}
    assert table == paths and len(paths) == 17


@pytest.mark.parametrize("argv,message", UNPARSABLE, ids=[" ".join(a) for a, _ in UNPARSABLE])
def test_a_number_that_does_not_parse_gets_one_line_with_the_range(capsys, tmp_path, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as stop:                 # argparse's exit, with the project's one line
        main(argv)
    out, err = capsys.readouterr()
    assert stop.value.code == 2 and out == "" and err == f"pcsuite: error: {message}\n"
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("flag", ["--periods", "--lhs"])
def test_a_5000_digit_option_is_named_with_its_range_and_its_length(capsys, tmp_path, monkeypatch, flag):
    """Python's "Exceeds the limit (4300 digits)" is a ValueError: the option was named, then all 5,000 digits."""
    monkeypatch.chdir(tmp_path)
    argv = ["sweep", "buck", "--grid", "D=0.2:0.8", flag, "1" * 5000]
    with pytest.raises(SystemExit) as stop:
        main(argv)
    err = capsys.readouterr().err
    within = {"--periods": ">= 1", "--lhs": "in [1, 10,000,000]"}[flag]
    assert stop.value.code == 2 and err == (f"pcsuite: error: argument {flag}: must be an integer {within}; got "
                                            "'11111111111111111111...1111111111 (5000 characters)'\n")


def test_every_integer_and_real_option_names_its_range_when_its_value_does_not_parse():
    import argparse

    from validation.cli import build_parser
    bare, typed = set(), set()

    def walk(parser, path):
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, child in action.choices.items():
                    walk(child, path + (name,))
            elif action.type in (int, float):
                bare.add((path, action.option_strings[0]))
            elif getattr(action.type, "__name__", "") == "typed":      # common.integer / common.number
                typed.add((path, action.option_strings[0]))
    walk(build_parser(), ())
    assert bare == set()
    table = {(tuple(argv[:2] if argv[0] in ("lcp", "mech") else argv[:1]), message.split()[1].rstrip(":"))
             for argv, message in UNPARSABLE}
    assert table == typed and len(typed) == 24              # every such option has its row below


@pytest.mark.parametrize("argv,message", IGNORED, ids=[" ".join(a) for a, _ in IGNORED])
def test_every_flag_acts_or_is_refused_with_one_line(capsys, tmp_path, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "x.dat").write_text("1\n0\n1 1\n1 1\n1\n-1\n")
    start = time.process_time()
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1, err
    assert time.process_time() - start < 10.0               # CPU seconds: refused before anything long runs
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.dat"]


def test_pcsuite_alone_says_a_command_is_needed_on_stderr_with_the_usage(capsys):
    """Nothing on stderr and exit 2 before: the help went to stdout, as if asked for, with a failing status."""
    with pytest.raises(SystemExit) as stop:
        main([])
    out, err = capsys.readouterr()
    assert stop.value.code == 2 and out == ""
    assert len(err.splitlines()) == 1 and err.startswith("pcsuite: error: a command is required: usage: pcsuite "), err
    assert "simulate" in err and "pcsuite --help" in err


@pytest.mark.slow
def test_pcsuite_time_limit_stops_a_one_run_command_as_the_flag_does(tmp_path):
    """PCSUITE_TIME_LIMIT bounded ngspice runs and LCP solves only: a long event run went on past it."""
    argv = ["simulate", "buck", "--method", "event", "--t-end", "5", "--h", "9e-6"]
    code, out, err, cpu, _ = bounded(argv, tmp_path, env={"PCSUITE_TIME_LIMIT": "2"})
    assert code == 2 and "Traceback" not in err, (code, err)
    assert err == ("pcsuite: error: the run did not finish within the time limit of 2 s (PCSUITE_TIME_LIMIT); raise "
                   "it, or ask for a shorter run (--t-end, --periods) or a coarser one\n")
    assert cpu < 15.0 and list(tmp_path.iterdir()) == []     # the whole run: minutes of CPU


@pytest.mark.parametrize("argv", [["simulate", "buck", "--periods", "2"], ["list"]], ids=["simulate", "list"])
def test_a_memory_limit_variable_beyond_any_float_is_one_line_naming_it(tmp_path, argv):
    """PCSUITE_MAX_MEMORY=1e400 raised OverflowError where a command checked memory (a traceback), and was
    ignored by those that check none: it is read before anything runs, as PCSUITE_TIME_LIMIT is."""
    code, out, err, _, _ = bounded(argv, tmp_path, env={"PCSUITE_MAX_MEMORY": "1e400"})
    assert (code, out) == (2, ""), (code, err)
    assert err == "pcsuite: error: PCSUITE_MAX_MEMORY must be in [16 MiB, 1 TiB]; got '1e400'\n"


def test_gdcm_h_acts(ngspice):
    """--h reaches the stepper (it used to arrive as a string and fail for every value)."""
    from validation.gdcm import gdcm_check
    coarse, fine = gdcm_check("buck", {}, h="1e-7"), gdcm_check("buck", {}, h="1e-8")
    assert coarse["held_fraction"]["lcp"] != fine["held_fraction"]["lcp"]
    assert fine["held_fraction"]["lcp"] == pytest.approx(0.3107, abs=2e-3)


def _descendants(pid: int) -> list[int]:
    import psutil
    try:
        return [child.pid for child in psutil.Process(pid).children(recursive=True)]
    except psutil.NoSuchProcess:
        return []


def _alive(pids) -> list[int]:
    import psutil
    out = []
    for pid in pids:
        try:
            if psutil.Process(pid).status() != psutil.STATUS_ZOMBIE:
                out.append(pid)
        except psutil.NoSuchProcess:
            pass
    return out


@pytest.mark.parametrize("argv,workers", [(["report", "default", "--out", "OUT"], 3),
                                          (["compare", "boost", "--control", "smc", "--t-end", "60m"], 1)],
                         ids=["report", "compare"])
def test_sigkill_leaves_no_pcsuite_or_ngspice_process_behind(ngspice, tmp_path, argv, workers):
    """SIGKILL of a command with ngspice workers: 2 s later none of its processes is alive."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen([*PCSUITE, *argv], cwd=tmp_path, env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)
    seen: set[int] = set()
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and proc.poll() is None:     # until its workers (and theirs) are running
        seen |= set(_descendants(proc.pid))
        if len(seen) >= workers:
            break
        time.sleep(0.1)
    time.sleep(0.3)
    seen |= set(_descendants(proc.pid))
    assert proc.poll() is None and len(seen) >= workers, (proc.poll(), seen)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    time.sleep(2.0)
    assert _alive(seen) == []


@pytest.mark.slow
def test_kill_9_at_random_instants_never_leaves_a_partial_output(tmp_path):
    """10 kills at random instants of `simulate --out`: the file is always the old one or a complete new one,
    and the next run leaves no temporary behind."""
    import pyarrow.parquet as pq
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    target = tmp_path / "w.parquet"
    argv = [*PCSUITE, "simulate", "buck", "--out", str(target)]
    subprocess.run([*argv, "--periods", "10"], check=True, env=env, capture_output=True)
    old = target.read_bytes()
    start = time.monotonic()
    subprocess.run([*argv, "--periods", "3000"], check=True, env=env, capture_output=True)
    full = time.monotonic() - start
    new = target.read_bytes()
    rng = random.Random(20261124)
    outcomes = []
    for _ in range(10):
        target.write_bytes(old)
        proc = subprocess.Popen([*argv, "--periods", "3000"], env=env, stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)
        time.sleep(rng.uniform(0.0, 1.2 * full))
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        data = target.read_bytes()
        assert data in (old, new)
        pq.read_table(target)                               # a whole Parquet file
        outcomes.append("new" if data == new and proc.returncode == -9 else "old")
    subprocess.run([*argv, "--periods", "10"], check=True, env=env, capture_output=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["w.parquet"]       # temporaries of the kills are gone


def rc_ladder(stages: int) -> str:
    lines = [f"a {stages}-stage RC ladder", "V1 n0 0 PULSE(0 1 0 1n 1n 5u 10u)"]
    for i in range(stages):
        lines += [f"R{i + 1} n{i} n{i + 1} 1", f"C{i + 1} n{i + 1} 0 1n"]
    return "\n".join(lines + [f"D1 n{stages} out DIDEAL", "C0 out 0 1u", "R0 out 0 1k", ".model DIDEAL D",
                              ".tran 10n 100u", ".end"]) + "\n"


@pytest.mark.slow
def test_the_time_limit_stops_a_netlist_while_it_compiles(tmp_path):
    """A 2,000-stage RC ladder's compile (LAPACK on 4,000 unknowns, ~35 CPU s) under --time-limit 5: the alarm
    waited for each factorisation to return (a 3,000-stage ladder ran 234 s at --time-limit 50); the factorisations
    now run where the limit stops the wait, and the command ends with its one line and exit 2 (not the segmentation
    fault an interpreter's exit met with LAPACK still working)."""
    (tmp_path / "ladder.cir").write_text(rc_ladder(2000))
    code, out, err, cpu, maxrss_kb = bounded(["simulate", "ladder.cir", "--time-limit", "5"], tmp_path)
    assert code == 2 and out == "", (code, err)
    (line,) = err.strip().splitlines()
    assert line.startswith("pcsuite: error: the run did not finish within the time limit of 5 s (--time-limit)")
    assert cpu < 20.0, cpu


@pytest.mark.parametrize("command", [["sensitivity"], ["bode", "--input", "D", "--points", "3"]])
def test_a_file_names_control_characters_reach_the_terminal_as_escapes(capsys, tmp_path, monkeypatch, command):
    """An ESC in a netlist's file name reached stdout raw in sensitivity's and bode's headers (their errors were
    escaped already): a file could recolour or clear what the user reads. Every command's output is escaped."""
    buck = Path(__file__).resolve().parents[2] / "netlists" / "circuits" / "buck.cir"
    monkeypatch.chdir(tmp_path)
    (tmp_path / "e\x1b[2Jx.cir").write_text(buck.read_text())
    assert main([command[0], "e\x1b[2Jx.cir", *command[1:]]) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out and out.startswith("e\\x1b[2Jx.cir: ")


def test_a_command_without_a_stdout_runs(tmp_path):
    """With stdout closed (`pcsuite list >&-`) Python's sys.stdout is None and print does nothing; the escaping
    stream wrapped it and ended in a traceback."""
    root = Path(__file__).resolve().parents[2]
    done = subprocess.run(["sh", "-c", f'"{sys.executable}" -m validation.cli list >&-'], capture_output=True,
                          text=True, cwd=root, env={**os.environ, "PYTHONPATH": str(root)}, timeout=120)
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
