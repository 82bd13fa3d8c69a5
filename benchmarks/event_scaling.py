"""The event method's cost per event against the number of diodes k, on the N-stage Cockcroft-Walton ladder (k = 2N).

Run: .venv/bin/python benchmarks/event_scaling.py [--quick]. Prints, measured side by side in one run (2 shared
cores: noisy, each the best of REPEATS), for k = 4 .. 48:

- the event method's wall time per event over PERIODS periods started on its own periodic orbit (the mode at each
  event from the mode-selection LCP: converters/methods/event/machine.py ``_Machine.select``), its growth from the
  k before it, and the states n (the ladder has n = k capacitors: a flow's products cost (n+1)^2 or (n+1)^3);
- up to k = 12, the same run with the held set sought by enumerating the 2^k sets nearest the reference first (the
  selection before the LCP), and the ratio: both runs must give the same final state.

Beyond k = 12 the enumeration is not run: 2^k sets.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from netlist import REPEATS, best  # noqa: E402
from record import Figures  # noqa: E402

from converters.methods import EventDriven  # noqa: E402
from converters.methods.event import machine  # noqa: E402
from converters.models import Circuit  # noqa: E402
from converters.run import run_converter  # noqa: E402
from converters.simulate import simulate  # noqa: E402

PERIODS = 20
STAGES = (2, 4, 6, 8, 12, 16, 24)
QUICK_STAGES = (2, 4, 8, 24)
LOAD = "100k"


def ladder(stages: int) -> Circuit:
    from netlists.generators import cockcroft_walton
    import tempfile
    path = Path(tempfile.gettempdir()) / f"pcsuite-event-cw-{stages}.cir"
    path.write_text(cockcroft_walton(stages))
    return Circuit.from_netlist(path)


def _enumerating_select(self, config, xt, t, reference, rate_field=None):
    """The selection before the LCP: every held set, nearest ``reference`` first."""
    order = self.orders.get(reference)
    if order is None:
        order = self.orders[reference] = machine._held_sets_by_distance(self.problem.k, reference)
    slack, size = 4.0 * self.options.event_tol * self.scale, np.abs(xt).max()
    for held in order:
        flow = self.flow(config, held)
        ok, projected = self._on_set(flow, xt, size, rate_field, slack)
        if ok and flow.lexicographic_ok(projected):
            return flow, projected
    raise RuntimeError(f"no held set at t = {t}")


def per_event(problem) -> tuple[float, int, np.ndarray]:
    """(wall s per event, events per period, final state) of PERIODS periods on a fresh engine (its flows built
    in the run, as a user's run builds them)."""
    wall, tr = best(lambda: simulate(problem, EventDriven()))
    events = len(tr.exact.event_list())
    return wall / max(events, 1), events / PERIODS, tr.x[-1]


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help=f"stages {QUICK_STAGES} only")
    args = parser.parse_args(argv)
    figures = Figures("event_scaling", "the event method's cost per event against the number of diodes k, on the "
                      "Cockcroft-Walton ladder" + (" (--quick)" if args.quick else ""))
    print(f"Cockcroft-Walton ladders, R = {LOAD}, {PERIODS} periods from the event method's orbit, best of {REPEATS}")
    print(f"{'k':>4} {'n':>4} {'events/T':>9} {'LCP us/event':>13} {'growth':>7} {'2^k enum us/event':>18} "
          f"{'enum/LCP':>9} {'same end':>9}")
    previous = None
    for stages in QUICK_STAGES if args.quick else STAGES:
        circuit = ladder(stages)
        p = circuit.resolve({"R": LOAD})
        T = circuit.period(p)
        orbit = run_converter(circuit, {"R": LOAD}, method="event", steady=True, periods=1)
        problem = circuit.problem(p, PERIODS * T, orbit.x[0])
        cost, events, end = per_event(problem)
        growth = f"{cost / previous:7.2f}" if previous else f"{'':>7}"
        growth_value = cost / previous if previous else None
        previous = cost
        enum, ratio, same = "", "", ""
        if problem.k <= machine.ENUMERATE_PAIRS:
            lcp_select = machine._Machine.select
            machine._Machine.select = _enumerating_select
            try:
                enum_cost, _, enum_end = per_event(problem)
            finally:
                machine._Machine.select = lcp_select
            enum, ratio = f"{enum_cost * 1e6:18.1f}", f"{enum_cost / cost:9.2f}"
            end_difference = np.abs(enum_end - end).max() / np.abs(end).max()
            same = f"{end_difference:9.1e}"
        print(f"{problem.k:>4} {problem.n:>4} {events:9.1f} {cost * 1e6:13.1f} {growth} {enum:>18} {ratio:>9} {same:>9}",
              flush=True)
        k, ladder_text = problem.k, (f"{stages}-stage Cockcroft-Walton ladder (k = {problem.k} diodes, n = {problem.n} "
                                     f"states, R = {LOAD}), {PERIODS} periods from its orbit, best of {REPEATS}")
        figures.add(f"k{k}_us_per_event", cost * 1e6, "us", f"event method (mode-selection LCP), wall time per event: "
                    f"{ladder_text}")
        figures.add(f"k{k}_run_s", cost * events * PERIODS, "s", f"event method (mode-selection LCP), the whole run: "
                    f"{ladder_text}")
        figures.add(f"k{k}_events_per_period", events, "", f"events per period: {ladder_text}")
        if growth_value is not None:
            figures.add(f"k{k}_growth", growth_value, "x", f"cost per event at k = {k} over the k before it")
        if enum:
            figures.add(f"k{k}_enum_us_per_event", enum_cost * 1e6, "us", "the held set sought by enumerating the 2^k "
                        f"sets nearest the reference first, wall time per event: {ladder_text}")
            figures.add(f"k{k}_enum_over_lcp", enum_cost / cost, "x", f"enumeration's cost per event over the LCP's, "
                        f"k = {k}")
            figures.add(f"k{k}_enum_end_difference", end_difference, "", f"largest difference of the final states, "
                        f"enumeration against the LCP, relative to the largest state, k = {k}", digits=2)
    figures.save()


if __name__ == "__main__":
    main()
