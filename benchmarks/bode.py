"""A Bode plot from the exact small-signal model against the brute-force injection, side by side in one process.

Run: .venv/bin/python benchmarks/bode.py. Prints measured numbers only (2 shared cores: noisy, each the best of
REPEATS): for the CCM buck's control-to-output (D -> vout) and the voltage-mode buck's loop gain, the time of the
periodic orbit and its linearisation, of 200 frequencies of the exact response (target: the whole under 0.2 s),
and of the brute force (a sinusoid injected, each frequency simulated to its periodic steady state by the event
method, its fundamental read: what an AC sweep does) at CHECKS frequencies, with its time per frequency and the
largest difference between the two.
"""
from __future__ import annotations

import time

import numpy as np

from record import Figures  # benchmarks/record.py (this script's folder is sys.path[0])

from converters.analysis.smallsignal import SmallSignalModel, frequencies, injection_response
from converters.models import get_model

REPEATS = 3
POINTS = 200
CHECKS = 20


def best(function):
    out, fastest = None, np.inf
    for _ in range(REPEATS):
        start = time.perf_counter()
        out = function()
        fastest = min(fastest, time.perf_counter() - start)
    return fastest, out


def case(figures: Figures, key: str, title: str, model, params: dict, name: str, output: str) -> float:
    model_s, small = best(lambda: SmallSignalModel(model, params, input=name, outputs=(output,)))
    f = frequencies(small.T, None, None, POINTS)
    response_s, _ = best(lambda: small.response(f, output))
    checks = np.geomspace(f[0], 0.49 / small.T, CHECKS)
    start = time.perf_counter()
    used, injected = injection_response(small, checks, output)
    brute_s = time.perf_counter() - start
    exact = small.response(used, output)
    difference = np.abs(20 * np.log10(np.abs(injected / exact))).max()
    print(f"{title}: orbit and linearisation {model_s * 1e3:.1f} ms, {POINTS} frequencies {response_s * 1e3:.1f} ms "
          f"(exact Bode plot {(model_s + response_s) * 1e3:.1f} ms); brute force {CHECKS} frequencies {brute_s:.2f} s "
          f"({brute_s / CHECKS * 1e3:.0f} ms per frequency: {POINTS} would take ~{brute_s / CHECKS * POINTS:.0f} s, "
          f"{brute_s / CHECKS * POINTS / (model_s + response_s):.0f}x the exact plot); largest difference "
          f"{difference:.1e} dB")
    exact_s = model_s + response_s
    what = f"{title} (" + ", ".join(f"{k} = {v:g}" if isinstance(v, float) else f"{k} = {v}"
                                    for k, v in params.items()) + ")"
    figures.add(f"{key}_orbit_ms", model_s * 1e3, "ms", f"{what}: the periodic orbit and its linearisation "
                f"(best of {REPEATS})")
    figures.add(f"{key}_response_ms", response_s * 1e3, "ms", f"{what}: {POINTS} frequencies of the exact response "
                f"(best of {REPEATS})")
    figures.add(f"{key}_exact_ms", exact_s * 1e3, "ms", f"{what}: the exact {POINTS}-point Bode plot (orbit, "
                "linearisation and response)", target="< 0.2 s")
    figures.add(f"{key}_brute_s", brute_s, "s", f"{what}: brute force (a sinusoid injected, each frequency to its "
                f"periodic steady state by the event method) at {CHECKS} frequencies")
    figures.add(f"{key}_brute_per_frequency_ms", brute_s / CHECKS * 1e3, "ms",
                f"{what}: brute force per frequency (mean over {CHECKS})")
    figures.add(f"{key}_brute_{POINTS}_s", brute_s / CHECKS * POINTS, "s",
                f"{what}: brute force's time per frequency times {POINTS} (what a {POINTS}-point plot would take)")
    figures.add(f"{key}_brute_over_exact", brute_s / CHECKS * POINTS / exact_s, "x",
                f"{what}: that {POINTS}-point brute force over the exact plot's time")
    figures.add(f"{key}_difference_db", difference, "dB", f"{what}: largest difference between the brute force "
                f"and the exact response at the {CHECKS} frequencies", digits=2)
    return exact_s


def main() -> None:
    figures = Figures("bode", "the exact small-signal Bode plot against the brute-force injection")
    exact = [case(figures, "ccm_buck", "CCM buck, vout/D", get_model("buck"),
                  {"L": "100u", "C": "100u", "R": 10, "D": 0.4}, "D", "vout"),
             case(figures, "voltage_mode_buck", "voltage-mode buck, vout/vcomparator",
                  get_model("buck", "voltage-mode"), {"Vin": 22}, "control", "vout"),
             case(figures, "peak_current_buck", "peak current-mode buck, iL/Iref", get_model("buck", "peak-current"),
                  {"Iref": 0.6, "ma": 2e4}, "Iref", "iL")]
    figures.add("exact_ms_min", min(exact) * 1e3, "ms", f"the fastest of the three exact {POINTS}-point Bode plots")
    figures.add("exact_ms_max", max(exact) * 1e3, "ms", f"the slowest of the three exact {POINTS}-point Bode plots",
                target="< 0.2 s")
    figures.save()


if __name__ == "__main__":
    main()
