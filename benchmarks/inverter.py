"""The three-phase two-level inverter against ngspice: time per fundamental period at equal accuracy.

Run: .venv/bin/python benchmarks/inverter.py. Prints ratios measured side by side in one run (2 shared cores: noisy,
each the best of REPEATS). netlists/circuits/three-phase-inverter.cir (six switches, six antiparallel diodes, a
split DC link, LC filter, RL load; sine-triangle PWM at 10 kHz, 50 Hz out: T = 20 ms holds 200 carrier periods).

Both sides run PERIODS fundamental periods from the same state on the circuit's periodic orbit (the event method's,
exact) and are judged on the same quantity, the load current's RMS over the last period (the file's output,
i(Lla)), against the event method's exact value on the orbit. Each side's step (the stepper's h at theta 0.5 and
at theta 1, ngspice's TMAX) is halved (from STEPPER_FRACTIONS, SPICE_FRACTIONS) until that error is TARGET (compare's threshold), and its
wall time per fundamental period printed; the event method's (exact, no step) beside them. Goal (issue: everyday
circuits): the stepper 100x ngspice.
"""
from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from netlist import TARGET, best, refined  # noqa: E402

from converters.methods import EventDriven, Theta  # noqa: E402
from converters.models import Circuit  # noqa: E402
from converters.run import run_converter  # noqa: E402
from converters.simulate import simulate  # noqa: E402

PERIODS = 2
#: The longer run that separates a run's fixed cost from its cost per period.
LONG = 12
#: The stepper's h from T/250 (its steps end on every switching instant, which it computes: a step may span most of
#: a carrier period), ngspice's TMAX from T/5000 (at T/5000 it is 1.1e-2 off), each halved.
STEPPER_FRACTIONS = tuple(1 / (250 * 2 ** k) for k in range(10))
SPICE_FRACTIONS = tuple(1 / (5000 * 2 ** k) for k in range(7))


def main() -> int:
    circuit = Circuit.from_netlist(ROOT / "netlists" / "circuits" / "three-phase-inverter.cir")
    p = circuit.resolve({})
    T = circuit.period(p)
    orbit = run_converter(circuit, {}, method="event", steady=True, periods=1)
    x0, reference = orbit.x[0], orbit.rms("vout", t0=0.0, t1=T)
    problem = circuit.problem(p, PERIODS * T, x0=x0)

    def last_rms(tr) -> float:
        return replace(tr, labels=circuit.labels(p)).rms("vout", t0=(PERIODS - 1) * T, t1=PERIODS * T)

    wall_event, tr_event = best(lambda: simulate(problem, EventDriven()))
    event_error = abs(last_rms(tr_event) / reference - 1)

    def stepper(theta):
        def run(fraction):
            method = Theta(h=fraction * T, theta=theta)
            simulate(problem, method)                                   # its compiled loop loaded
            wall, tr = best(lambda: simulate(problem, method))
            return wall / PERIODS, last_rms(tr)
        return run

    def spice(fraction):
        from netlists.circuit import circuit_netlist, file_spice_options
        from validation.spice import circuit_trajectory, run_spice
        options = replace(file_spice_options(circuit), tmax_fraction=fraction)
        netlist = circuit_netlist(circuit, p, PERIODS * T, options, x0=x0, diode_currents=False)
        wall, result = best(lambda: run_spice(netlist))
        tr = circuit_trajectory(circuit, p, netlist, result, (PERIODS - 1) * T)
        return wall / PERIODS, tr.rms("vout", t0=(PERIODS - 1) * T, t1=PERIODS * T)

    print(f"three-phase inverter, {PERIODS} fundamental periods ({T * 1e3:g} ms each) from its orbit; the load "
          f"current's RMS over the last, exact: {reference:.9g} A. Steps halved until the error is "
          f"{TARGET:g}.")
    print(f"  event method (exact): {wall_event / PERIODS:.3e} s/period, error {event_error:.1e}")
    rows = {"stepper, theta 0.5": refined(stepper(0.5), STEPPER_FRACTIONS, reference),
            "stepper, theta 1": refined(stepper(1.0), STEPPER_FRACTIONS, reference),
            "ngspice": refined(spice, SPICE_FRACTIONS, reference)}
    for name, runs in rows.items():
        for fraction, wall, error in runs:
            print(f"  {name:20s} step T/{1 / fraction:<7.0f} {wall:.3e} s/period  error {error:.1e}")
    # At the steps chosen, the cost of LONG periods against PERIODS: a run's fixed part (the stepper's matrices
    # for the ~1,450 distinct steps a period's switching instants make, built once and repeated; ngspice's set-up)
    # and its cost per further period.
    def marginal(name, fraction):
        def wall(periods):
            longer = circuit.problem(p, periods * T, x0=x0)
            if name == "ngspice":
                from netlists.circuit import circuit_netlist, file_spice_options
                from validation.spice import run_spice
                options = replace(file_spice_options(circuit), tmax_fraction=fraction)
                netlist = circuit_netlist(circuit, p, periods * T, options, x0=x0, diode_currents=False)
                return best(lambda: run_spice(netlist))[0]
            method = EventDriven() if name == "event" else Theta(h=fraction * T, theta=0.5 if "0.5" in name else 1.0)
            simulate(longer, method)
            return best(lambda: simulate(longer, method))[0]
        short, long_ = wall(PERIODS), wall(LONG)
        per_period = (long_ - short) / (LONG - PERIODS)
        return short - PERIODS * per_period, per_period
    (spice_fraction, _, spice_error) = rows["ngspice"][-1]
    costs = {"ngspice": marginal("ngspice", spice_fraction), "event": marginal("event", None)}
    for name in ("stepper, theta 0.5", "stepper, theta 1"):
        fraction, _, error = rows[name][-1]
        if error <= TARGET:
            costs[name] = marginal(name, fraction)
    print(f"  at the steps above, {PERIODS} and {LONG} periods: fixed part and cost per further period")
    for name, (fixed, per_period) in costs.items():
        print(f"  {name:20s} fixed {fixed:.3e} s, {per_period:.3e} s/period")
    spice_fixed, spice_per = costs["ngspice"]
    for name, (fixed, per_period) in costs.items():
        if name != "ngspice" and spice_error <= TARGET:
            whole = (spice_fixed + LONG * spice_per) / (fixed + LONG * per_period)
            print(f"  ngspice / {name}: {spice_per / per_period:.1f}x per period, {whole:.1f}x over {LONG} periods"
                  + (" (goal 100x)" if name.startswith("stepper") else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
