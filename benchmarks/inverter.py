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

from netlist import REPEATS, TARGET, best, refined  # noqa: E402
from record import Figures  # noqa: E402

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


#: A figure's key for each side.
KEYS = {"stepper, theta 0.5": "stepper05", "stepper, theta 1": "stepper1", "ngspice": "ngspice", "event": "event"}


def main() -> int:
    figures = Figures("inverter", "the three-phase inverter against ngspice: time per fundamental period at equal "
                      "accuracy")
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
    run = (f"three-phase inverter (three-phase-inverter.cir, 200 carrier periods per {T * 1e3:g} ms period), "
           f"{PERIODS} periods from its orbit, best of {REPEATS}")
    figures.add("event_ms_per_period", wall_event / PERIODS * 1e3, "ms", f"event method (exact), per period: {run}")
    figures.add("event_error", event_error, "", "event method: the load current's RMS over the last period against "
                "the exact value on the orbit, relative", digits=2)
    rows = {"stepper, theta 0.5": refined(stepper(0.5), STEPPER_FRACTIONS, reference),
            "stepper, theta 1": refined(stepper(1.0), STEPPER_FRACTIONS, reference),
            "ngspice": refined(spice, SPICE_FRACTIONS, reference)}
    for name, runs in rows.items():
        for fraction, wall, error in runs:
            print(f"  {name:20s} step T/{1 / fraction:<7.0f} {wall:.3e} s/period  error {error:.1e}")
        if not runs:
            continue
        fraction, wall, error = runs[-1]
        side = f"{name} at {'TMAX' if name == 'ngspice' else 'h'} = T/{1 / fraction:.0f}"
        unit, scale = ("s", 1.0) if name == "ngspice" else ("ms", 1e3)
        first = (SPICE_FRACTIONS if name == "ngspice" else STEPPER_FRACTIONS)[0]
        figures.add(f"{KEYS[name]}_steps_per_period", 1 / fraction, "", f"{name}: N of the step T/N its halving "
                    f"from T/{1 / first:.0f} ended at (the first with error <= {TARGET:g}, or the last run)", digits=1)
        figures.add(f"{KEYS[name]}_per_period", wall * scale, unit, f"{side}, per period: {run}")
        figures.add(f"{KEYS[name]}_error", error, "", f"{side}: the load current's RMS over the last period against "
                    "the exact value, relative", digits=2)
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
        unit, scale = ("s", 1.0) if name == "ngspice" else ("ms", 1e3)
        at = "exact, no step" if name == "event" else "at the step above"
        long_run = f"{name} ({at}), {PERIODS} and {LONG} periods from the orbit, best of {REPEATS} each"
        figures.add(f"{KEYS[name]}_fixed", fixed * scale, unit, f"{long_run}: the run's fixed part")
        figures.add(f"{KEYS[name]}_per_further_period", per_period * scale, unit,
                    f"{long_run}: the cost of each further period")
    spice_fixed, spice_per = costs["ngspice"]
    for name, (fixed, per_period) in costs.items():
        if name != "ngspice" and spice_error <= TARGET:
            whole = (spice_fixed + LONG * spice_per) / (fixed + LONG * per_period)
            print(f"  ngspice / {name}: {spice_per / per_period:.1f}x per period, {whole:.1f}x over {LONG} periods"
                  + (" (goal 100x)" if name.startswith("stepper") else ""))
            key = KEYS[name]
            goal = "100x" if name.startswith("stepper") else None
            figures.add(f"ngspice_over_{key}_per_period", spice_per / per_period, "x",
                        f"ngspice's cost per further period over the {name}'s, at equal accuracy", target=goal)
            figures.add(f"ngspice_over_{key}_{LONG}_periods", whole, "x",
                        f"ngspice's time for {LONG} periods over the {name}'s, at equal accuracy", target=goal)
            figures.add(f"ngspice_over_{key}_{PERIODS}_periods",
                        (spice_fixed + PERIODS * spice_per) / (fixed + PERIODS * per_period), "x",
                        f"ngspice's time for {PERIODS} periods over the {name}'s, at equal accuracy (from the fixed "
                        "parts and costs per period)", target=goal)
            if goal and spice_per > 100 * per_period:
                goal_from = max(0.0, (100 * fixed - spice_fixed) / (spice_per - 100 * per_period))
                figures.add(f"{key}_goal_from_periods", goal_from, "", f"periods from which ngspice takes 100 times "
                            f"the {name}'s time (from the fixed parts and costs per period)", digits=2)
    figures.save()
    return 0


if __name__ == "__main__":
    sys.exit(main())
