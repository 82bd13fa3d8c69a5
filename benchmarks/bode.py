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


def case(title: str, model, params: dict, name: str, output: str) -> None:
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


def main() -> None:
    case("CCM buck, vout/D", get_model("buck"), {"L": "100u", "C": "100u", "R": 10, "D": 0.4}, "D", "vout")
    case("voltage-mode buck, vout/vcomparator", get_model("buck", "voltage-mode"), {"Vin": 22}, "control", "vout")
    case("peak current-mode buck, iL/Iref", get_model("buck", "peak-current"), {"Iref": 0.6, "ma": 2e4}, "Iref", "iL")


if __name__ == "__main__":
    main()
