"""pcsuite against the live peers, side by side in one run: Siconos 4.4 and ngspice on the same buck circuit.

The case (issue 20): buck in DCM, Vin 12 V, f_sw 100 kHz, D 0.4, L 10 uH, C 100 uF, R 10 ohm, 5 ms from rest.

- **Warm**: the same trajectory computed by a process that has everything loaded. pcsuite: `simulate(problem,
  BackwardEuler(h))` end to end (step plan, compiled loop, Trajectory). Siconos: its own script's time loop
  (FirstOrderLinearDS + FirstOrderLinearR with the same LCS matrices, switched at the same instants,
  EulerMoreauOSI(theta = 1) + LCP with Lemke, h = 50 ns), run with the system Python (Debian's
  python3-siconos; `make bench` installs it), which must give the same trajectory (printed: max relative
  difference). ngspice: `ngspice -b` on pcsuite's netlist, at its default accuracy; pcsuite is then timed at the
  largest h whose error is not above ngspice's (error: |mean vout over the last 10 periods - exact| / exact,
  exact from the event-driven method). A warm time is the median of WARM_CALLS back-to-back calls (the first
  call after the other programs ran is slower, 1.3-2 ms against 1.0-1.2: the caches and TLB they evicted;
  printed too).
- **Cold**: each as a fresh process, as a user runs it: `pcsuite simulate buck ... --t-end 5e-3 --json`, `ngspice
  -b FILE.cir`, `/usr/bin/python3 siconos_buck.py` (pcsuite's bytecode compiled first, as any earlier run leaves it).
- The LCP peer collection per call against Siconos' solvers (benchmarks/peer_lcp.py), when present.

Medians of REPEATS interleaved runs (2 shared cores: noisy). Run: .venv/bin/python benchmarks/peers.py
"""
from __future__ import annotations

import json
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from record import Figures

ROOT = Path(__file__).resolve().parents[1]
REPEATS = 5
WARM_CALLS = 5
PARAMS = {"Vin": 12.0, "f_sw": "100k", "D": 0.4, "L": "10u", "C": "100u", "R": 10.0}
T_END = 5e-3
H_SICONOS = 50e-9
SYSTEM_PYTHON = "/usr/bin/python3"

SICONOS_SCRIPT = r'''
import json, sys, time
import numpy as np
import siconos.kernel as sk
import siconos.numerics as sn
spec = json.load(open(sys.argv[1]))
h, t_end, T = spec["h"], spec["t_end"], spec["period"]
configs, starts, order = spec["configs"], spec["starts"], spec["order"]
clock = time.perf_counter()
c0 = configs[order[0]]
x0 = np.array(spec["x0"], dtype=float)
ds = sk.FirstOrderLinearDS(x0, np.array(c0["A"]))
ds.setbPtr(np.array(c0["E"], dtype=float))
rel = sk.FirstOrderLinearR(np.array(c0["C"]), np.array(c0["B"]))
rel.setDPtr(np.array(c0["D"], dtype=float))
rel.setePtr(np.array(c0["F"], dtype=float))
inter = sk.Interaction(sk.ComplementarityConditionNSL(len(c0["F"])), rel)
nsds = sk.NonSmoothDynamicalSystem(0.0, t_end)
nsds.insertDynamicalSystem(ds)
nsds.link(inter, ds)
sim = sk.TimeStepping(nsds, sk.TimeDiscretisation(0.0, h), sk.EulerMoreauOSI(spec["theta"]),
                      sk.LCP(sn.SICONOS_LCP_LEMKE))
steps = int(round(t_end / h))
xs = np.empty((steps + 1, x0.size))
xs[0] = x0
current = order[0]
for j in range(steps):
    phase = ((j + 0.5) * h) % T             # the configuration of the step's midpoint (steps align with the edges)
    which = order[0]
    for s, c in zip(starts, order):
        if phase >= s:
            which = c
    if which != current:
        c = configs[which]
        ds.setbPtr(np.array(c["E"], dtype=float))
        rel.setCPtr(np.array(c["C"], dtype=float))
        rel.setBPtr(np.array(c["B"], dtype=float))
        rel.setDPtr(np.array(c["D"], dtype=float))
        rel.setePtr(np.array(c["F"], dtype=float))
        current = which
    sim.computeOneStep()
    sim.nextStep()
    xs[j + 1] = ds.x()
wall = time.perf_counter() - clock
if len(sys.argv) > 2:
    np.save(sys.argv[2], xs)
print(json.dumps({"wall_s": wall, "steps": steps}))
'''


def siconos_available() -> str:
    """'' when the system Python imports siconos, else the reason."""
    if not Path(SYSTEM_PYTHON).exists():
        return f"{SYSTEM_PYTHON} not found"
    probe = subprocess.run([SYSTEM_PYTHON, "-c", "import siconos.kernel, siconos.numerics"], capture_output=True,
                           text=True)
    return "" if probe.returncode == 0 else "python3-siconos is not installed (make bench installs it: apt-get install " \
                                              "python3-siconos)"


def timed(argv, **kwargs) -> tuple[float, subprocess.CompletedProcess]:
    start = time.perf_counter()
    done = subprocess.run(argv, capture_output=True, text=True, **kwargs)
    return time.perf_counter() - start, done


def main() -> None:
    from converters.methods import BackwardEuler
    from converters.models import get_model
    from converters.run import run_converter
    from converters.simulate import simulate

    model = get_model("buck")
    p = model.resolve(PARAMS)
    T = model.period(p)
    problem = model.problem(p, T_END)
    work = Path(tempfile.mkdtemp(prefix="pcsuite-peers-"))
    spec = {"h": H_SICONOS, "t_end": T_END, "period": problem.switching.period,
            "starts": list(problem.switching.starts), "order": list(problem.switching.configs), "theta": 1.0,
            "x0": list(map(float, problem.x0)),
            "configs": [{key: np.atleast_1d(getattr(c, key)).tolist() for key in "ABCDEF"} for c in problem.configurations]}
    (work / "spec.json").write_text(json.dumps(spec))
    (work / "siconos_buck.py").write_text(SICONOS_SCRIPT)
    netlist = work / "buck.cir"
    argv_p = [arg for name, value in PARAMS.items() for arg in ("-p", f"{name}={value}")]
    subprocess.run([sys.executable, "-m", "validation.cli", "netlist", "buck", *argv_p, "--t-end", str(T_END), "--out",
                    str(netlist)], check=True, capture_output=True, cwd=ROOT)
    sic = siconos_available()
    ngspice = shutil.which("ngspice")

    # accuracy: the exact mean over the last 10 periods, and each simulator's error
    exact = run_converter(model, p, method="event", t_end=T_END).mean("vout", periods=10)

    def error_at(h):
        return abs(run_converter(model, p, method="lcp", h=h, theta=1.0, t_end=T_END).mean("vout", periods=10)
                   / exact - 1.0)

    simulate(problem, BackwardEuler(H_SICONOS))                   # warm: the kernels loaded
    same = ""
    if not sic:
        done = subprocess.run([SYSTEM_PYTHON, str(work / "siconos_buck.py"), str(work / "spec.json"),
                               str(work / "x.npy")], capture_output=True, text=True, check=True)
        ours = simulate(problem, BackwardEuler(H_SICONOS)).x
        theirs = np.load(work / "x.npy")
        same = f"{np.abs(ours - theirs).max() / np.abs(ours).max():.1e}"

    spice_error, spice_cold = np.nan, []
    if ngspice:
        out = subprocess.run([ngspice, "-b", str(netlist)], capture_output=True, text=True).stdout
        mean = float(re.search(r"vout_mean\s*=\s*([-+0-9.eE]+)", out).group(1))
        spice_error = abs(mean / exact - 1.0)
    # pcsuite at equal accuracy: the largest h (T/50 .. T/1000) whose error is not above ngspice's
    candidates = [T / n for n in (50, 100, 200, 500, 1000, 2000)]
    errors = {h: error_at(h) for h in candidates}
    equal_h = max((h for h in candidates if errors[h] <= spice_error), default=candidates[-1])

    # The sources' bytecode, as any run after the first leaves it (a process started with PYTHONDONTWRITEBYTECODE
    # set, as in some CI sandboxes, would otherwise compile ~40 modules anew each time: 0.05-0.06 s)
    subprocess.run([sys.executable, "-m", "compileall", "-q", "converters", "validation", "netlists"], cwd=ROOT,
                   check=True, capture_output=True)
    warm_ours, warm_equal, warm_siconos, cold_ours, cold_spice, cold_siconos = [], [], [], [], [], []
    cold_argv = [sys.executable, "-m", "validation.cli", "simulate", "buck", *argv_p, "--h", str(H_SICONOS), "--t-end",
                 str(T_END), "--json"]
    first_ours = []

    def warm(method):
        """The first call's time and the median of WARM_CALLS back-to-back calls."""
        times = []
        for _ in range(WARM_CALLS):
            start = time.perf_counter()
            simulate(problem, method)
            times.append(time.perf_counter() - start)
        return times[0], statistics.median(times)

    for _ in range(REPEATS):                     # interleaved: every measure sees the same machine load
        first, typical = warm(BackwardEuler(H_SICONOS))
        first_ours.append(first)
        warm_ours.append(typical)
        warm_equal.append(warm(BackwardEuler(equal_h))[1])
        wall, done = timed(cold_argv, cwd=ROOT)
        cold_ours.append(wall)
        if ngspice:
            cold_spice.append(timed([ngspice, "-b", str(netlist)])[0])
        if not sic:
            wall, done = timed([SYSTEM_PYTHON, str(work / "siconos_buck.py"), str(work / "spec.json")])
            cold_siconos.append(wall)
            warm_siconos.append(json.loads(done.stdout)["wall_s"])
    med = statistics.median
    figures = Figures("peers", "pcsuite against Siconos and ngspice on the same buck circuit, side by side")
    case = "buck DCM (Vin 12 V, 100 kHz, D 0.4, L 10 uH, C 100 uF, R 10 ohm), 5 ms from rest"
    runs = f"median of {REPEATS} interleaved repetitions"
    print(f"buck DCM (Vin 12 V, 100 kHz, D 0.4, 10 uH, 100 uF, 10 ohm), {T_END * 1e3:g} ms from rest; medians of "
          f"{REPEATS} interleaved runs")
    print(f"  exact mean vout over the last 10 periods (event method): {exact:.9f} V")
    print(f"  pcsuite warm, h = 50 ns (theta 1, {int(round(T_END / H_SICONOS)):,} steps; median of {WARM_CALLS} calls): "
          f"{med(warm_ours) * 1e3:.2f} ms "
          f"({med(warm_ours) / (T_END / H_SICONOS) * 1e9:.1f} ns/step end to end), error {errors.get(H_SICONOS, error_at(H_SICONOS)):.1e}")
    warm_label = (f"{case}, h = 50 ns (theta 1, {int(round(T_END / H_SICONOS)):,} steps): pcsuite simulate() warm, "
                  f"median of {WARM_CALLS} back-to-back calls")
    figures.add("warm_ms", med(warm_ours) * 1e3, "ms", f"{warm_label}; {runs}")
    figures.add("warm_ns", med(warm_ours) / (T_END / H_SICONOS) * 1e9, "ns/step", f"{warm_label}, per step end to end")
    figures.add("warm_first_ms", med(first_ours) * 1e3, "ms",
                f"{case}, h = 50 ns: pcsuite simulate(), the first call after the other programs ran; {runs}")
    if sic:
        print(f"  Siconos: skipped ({sic})")
    else:
        print(f"  Siconos 4.4 warm (EulerMoreauOSI + Lemke, h = 50 ns; same trajectory to {same}): "
              f"{med(warm_siconos) * 1e3:.1f} ms -> pcsuite {med(warm_siconos) / med(warm_ours):.0f}x faster "
              f"(target >= 300x; the first call after the other programs ran: {med(first_ours) * 1e3:.2f} ms, "
              f"{med(warm_siconos) / med(first_ours):.0f}x)")
        figures.add("siconos_warm_ms", med(warm_siconos) * 1e3, "ms",
                    f"{case}, h = 50 ns: Siconos 4.4's own time loop (EulerMoreauOSI + Lemke, the same LCS matrices), "
                    f"timed in its process from building the model (imports excluded); {runs}")
        figures.add("siconos_ratio", med(warm_siconos) / med(warm_ours), "x",
                    "Siconos' warm time over pcsuite's warm time, h = 50 ns", target=">= 300x")
        figures.add("siconos_ratio_first_call", med(warm_siconos) / med(first_ours), "x",
                    "Siconos' warm time over pcsuite's first call after the other programs ran, h = 50 ns")
    if ngspice:
        print(f"  ngspice -b (TMAX T/200, RELTOL 1e-3, gear): error {spice_error:.1e}, {med(cold_spice) * 1e3:.0f} ms per "
              f"process; pcsuite at equal accuracy (h = T/{round(T / equal_h)}, error {errors[equal_h]:.1e}): "
              f"{med(warm_equal) * 1e3:.3f} ms -> {med(cold_spice) / med(warm_equal):.0f}x (target >= 300x; ngspice's "
              "time is its whole process: it has no warm mode)")
        figures.add("equal_accuracy_steps_per_period", round(T / equal_h), "",
                    "pcsuite's step at ngspice's accuracy: T divided by (the largest h of T/50 .. T/2000 whose error "
                    "in the mean vout over the last 10 periods is not above ngspice's)", digits=1)
        figures.add("equal_accuracy_ms", med(warm_equal) * 1e3, "ms",
                    f"{case}: pcsuite simulate() warm at h = T/{round(T / equal_h)} (ngspice's accuracy), median of "
                    f"{WARM_CALLS} back-to-back calls; {runs}")
        figures.add("ngspice_ms", med(cold_spice) * 1e3, "ms",
                    f"{case}: `ngspice -b` on pcsuite's netlist, its whole process (it has no warm mode); {runs}")
        figures.add("ngspice_ratio", med(cold_spice) / med(warm_equal), "x",
                    "ngspice's time over pcsuite's warm time at ngspice's accuracy", target=">= 300x")
    print(f"  cold, a fresh process each: pcsuite simulate --json {med(cold_ours) * 1e3:.0f} ms"
          + (f", ngspice -b {med(cold_spice) * 1e3:.0f} ms ({med(cold_spice) / med(cold_ours):.2f}x pcsuite's)" if ngspice else "")
          + (f", Siconos script {med(cold_siconos) * 1e3:.0f} ms ({med(cold_siconos) / med(cold_ours):.2f}x)" if not sic else "")
          + " (target: pcsuite below both)")
    figures.add("cold_ms", med(cold_ours) * 1e3, "ms",
                f"{case}, h = 50 ns: `pcsuite simulate buck ... --t-end 5e-3 --json` as a fresh process (bytecode "
                f"compiled); {runs}", target="below ngspice's and Siconos' cold time")
    if ngspice:
        figures.add("ngspice_cold_ratio", med(cold_spice) / med(cold_ours), "x",
                    "`ngspice -b`'s time over pcsuite's cold process")
    if not sic:
        figures.add("siconos_cold_ms", med(cold_siconos) * 1e3, "ms",
                    f"{case}, h = 50 ns: the Siconos script as a fresh process of the system Python; {runs}")
        figures.add("siconos_cold_ratio", med(cold_siconos) / med(cold_ours), "x",
                    "the Siconos script's cold time over pcsuite's cold process")
    figures.save()
    lcp = ROOT / "benchmarks" / "peer_lcp.py"
    if lcp.exists():
        print()
        subprocess.run([sys.executable, str(lcp)], cwd=ROOT)


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    main()
