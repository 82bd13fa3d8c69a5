"""Numerical stability at the extremes: the buck converter pushed one parameter at a time to the edge of
its range, every method run from rest, and each run checked.

Extremes (one at a time around the default DCM buck, Vin 12 V, L 10 uH, C 100 uF, R 10 ohm, 100 kHz,
D 0.4): the LCP step h from 1e-6 T to T/2; D in {0, 1e-4, 0.5, 1 - 1e-4, 1}; R from 1e-3 to 1e9 ohm;
L and C from 1e-9 to 1e-1; Vin = 0. Ill-posed requests (L = 0, C < 0, D > 1, R = NaN, h >= T, netlist
text in a value) must be refused with one clear line before any run.

Checks per run (``PERIODS`` periods from rest; 2 periods for h = 1e-6 T):
    finite        no NaN or inf anywhere in the states
    diverged      stored energy above 10 x (energy supplied + 1 nJ) at some point
    energy        energy created: (E_end - E_0) - (E_in - E_load) above ENERGY_TOL = 1e-3 of the energy
                  scale (the largest of E_in, E_load, stored energy and ENERGY_FLOOR_J = 1 pJ)
                  (ideal switches and diodes are lossless; a scheme may dissipate, never create)
    finished      the run ended (a ``TIMEOUT_S`` limit per run, in a separate process)
    error         the message of a refused or failed run (ngspice failures are counted here)
"""
from __future__ import annotations

import time

import numpy as np
import pandas as pd

from converters.models import get_converter
from converters.parallel import parallel_map

from .defaults import STABILITY_BASE

PERIODS = 10
TIMEOUT_S = 60.0
BASE = STABILITY_BASE["params"]


def extreme_cases() -> list[dict]:
    cases = [{"vary": "h", "value": f, "params": {}, "h_fraction": f, "periods": 2 if f < 1e-5 else PERIODS}
             for f in (1e-6, 1e-4, 1e-2, 0.5)]
    for name, values in (("D", (0.0, 1e-4, 0.5, 1 - 1e-4, 1.0)), ("R", (1e-3, 1.0, 1e3, 1e9)),
                         ("L", (1e-9, 1e-6, 1e-3, 1e-1)), ("C", (1e-9, 1e-6, 1e-3, 1e-1)), ("Vin", (0.0,))):
        cases += [{"vary": name, "value": v, "params": {name: v}, "h_fraction": 1e-3, "periods": PERIODS}
                  for v in values]
    return cases


ILL_POSED = (("L", {"L": 0.0}), ("C", {"C": -1e-6}), ("D", {"D": 1.5}), ("R", {"R": float("nan")}),
             ("Vin", {"Vin": "12; shell rm -rf /"}), ("h", {"h": 2e-5}))


ENERGY_FLOOR_J = 1e-12
ENERGY_TOL = 1e-3


def _energy_checks(p, t, x, on, rule, totals=None, i_in=None):
    """(finite, diverged, energy residual relative) from sampled states of the buck.

    ``on[k]`` says whether the switch conducts over [t_k, t_k+1] (the source current is iL there).
    ``rule`` is each scheme's own discrete power balance: 'end' (backward Euler: power at the step
    end), 'mid' (trapezoidal scheme: power at the mid-step state), 'trap' (dense samples of an accurate
    solution). ``totals`` = (E_in, E_load) computed exactly elsewhere (the event method's quadrature)
    replaces the sums; ``i_in`` (samples of the source current) replaces iL where ``on``."""
    L, C, R, Vin = p["L"], p["C"], p["R"], p["Vin"]
    if not np.all(np.isfinite(x)):
        return False, True, float("nan")
    iL, vC = x[:, 0], x[:, 1]
    stored = 0.5 * L * iL ** 2 + 0.5 * C * vC ** 2
    dt = np.diff(t)
    source = iL if i_in is None else i_in
    if rule == "end":
        p_in, p_load = Vin * source[1:] * on, vC[1:] ** 2 / R
    elif rule == "mid":
        p_in, p_load = Vin * 0.5 * (source[1:] + source[:-1]) * on, (0.5 * (vC[1:] + vC[:-1])) ** 2 / R
    else:
        p_in, p_load = Vin * 0.5 * (source[1:] + source[:-1]) * on, 0.5 * (vC[1:] ** 2 + vC[:-1] ** 2) / R
    e_in, e_load = np.concatenate([[0.0], np.cumsum(dt * p_in)]), np.concatenate([[0.0], np.cumsum(dt * p_load)])
    diverged = bool(np.any(stored > 10.0 * (stored[0] + np.abs(e_in) + 1e-9)))
    total_in, total_load = totals if totals is not None else (e_in[-1], e_load[-1])
    residual = (stored[-1] - stored[0]) - (total_in - total_load)
    scale = max(abs(total_in), abs(total_load), stored.max(), ENERGY_FLOOR_J)
    return True, diverged, float(residual / scale)


def _stepper(theta: float):
    def run(problem, p, T, case):
        from converters.methods import Theta
        from converters.simulate import simulate
        tr = simulate(problem, Theta(case["h_fraction"] * T, theta))
        return tr.t, tr.x, tr.config[1:] == 0, "end" if theta == 1.0 else "mid", None, None
    return run


def _event(problem, p, T, case):
    """Its samples and the exact energy totals from the piecewise solution's quadrature."""
    from converters.methods import EventDriven
    from converters.simulate import simulate
    run = simulate(problem, EventDriven())
    nodes, w = run.exact.quadrature()
    tq, xq, cq = nodes.t, nodes.x, nodes.config
    totals = (float(np.sum(w * p["Vin"] * xq[:, 0] * (cq == 0))), float(np.sum(w * xq[:, 1] ** 2)) / p["R"])
    order = np.argsort(tq)
    t = np.concatenate([[0.0], tq[order], [problem.t_span[1]]])
    x = np.vstack([problem.x0, xq[order], run.x[-1]])
    node_on = cq[order] == 0
    return t, x, np.append(node_on, node_on[-1]), "trap", totals, None    # on: for the divergence check


def _smooth(problem, p, T, case):
    from converters.methods import Smoothing
    from converters.simulate import simulate
    tr = simulate(problem, Smoothing(eps=1e-4, solver_rtol=1e-6, output_step=T / 1000))
    return tr.t, tr.x, tr.config[1:] == 0, "trap", None, None


def _ngspice(problem, p, T, case):
    """The source's own current (the switch's leakage included) replaces iL over every interval."""
    from netlists import SpiceOptions, build_netlist

    from .spice import run_spice
    conv = get_converter(STABILITY_BASE["converter"])
    netlist = build_netlist(conv.name, p, problem.t_span[1], SpiceOptions(tmax_fraction=1e-2, reltol=1e-3,
                                                                          method="trap"))
    result = run_spice(netlist)
    x = np.column_stack([result.signal(netlist.probes[n]) for n in conv.state_names])
    return result.time, x, np.ones(result.time.size - 1, bool), "trap", None, -result.vectors["vin#branch"]


#: Each method of the study at its settings: (problem, p, T, case) -> (t, x, switch on per interval, quadrature
#: rule, exact energy totals or None, the source's measured current or None).
RUNNERS = {"LCP theta=1": _stepper(1.0), "LCP theta=0.5": _stepper(0.5), "event": _event, "smooth": _smooth,
           "ngspice": _ngspice}
METHODS = tuple(RUNNERS)


def _run_one(case: dict, method: str) -> dict:
    """One run in the worker process: returns the checks (never raises)."""
    conv = get_converter(STABILITY_BASE["converter"])
    start = time.perf_counter()
    try:
        p = conv.resolve({**BASE, **case["params"]})
        T = conv.period(p)
        problem = conv.problem(p, case["periods"] * T)
        t, x, on, rule, totals, i_source = RUNNERS[method](problem, p, T, case)
        finite, diverged, residual = _energy_checks(p, t, x, on, rule, totals, i_source)
        return {"status": "ok", "finite": finite, "diverged": diverged, "energy_residual": residual,
                "energy_created": bool(np.isfinite(residual) and residual > ENERGY_TOL), "points": int(t.size),
                "wall_s": time.perf_counter() - start, "error": ""}
    except Exception as exc:  # refused or failed: the message is the result
        return {"status": "error", "finite": None, "diverged": None, "energy_residual": float("nan"),
                "energy_created": None, "points": 0, "wall_s": time.perf_counter() - start,
                "error": f"{type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''}"}


def _in_worker(args):
    case, method = args
    try:
        return _run_one(case, method)
    finally:
        from .spice import close_spice_worker
        close_spice_worker()


def stability_table(methods=METHODS, cases=None, progress: bool = True) -> pd.DataFrame:
    """Every (extreme case, method) run in its own process with a time limit, one at a time (a run's
    time is its own); one row each. A run past ``TIMEOUT_S`` is terminated (status ``timeout``), one whose
    process dies is ``crashed`` (not retried: the crash is the verdict)."""
    cases = extreme_cases() if cases is None else cases
    jobs = [(c, m) for c in cases for m in methods if m.startswith("LCP") or c["vary"] != "h"]
    outs = parallel_map(_in_worker, jobs, workers=1, timeout=TIMEOUT_S, tasks_per_process=1, attempts=1,
                        progress=progress, label="stability", unit="run", on_lost=_lost_run)
    rows = [{"vary": case["vary"], "value": case["value"],
             "h": f"{case['h_fraction']:g} T" if method.startswith("LCP") else "", "method": method, **out}
            for (case, method), out in zip(jobs, outs)]
    table = pd.DataFrame(rows)
    table["verdict"] = [_verdict(r) for r in table.itertuples()]
    return table


def _lost_run(job, message: str) -> dict:
    if message.startswith("timeout"):
        return {"status": "timeout", "error": f"did not finish within {TIMEOUT_S:g} s"}
    return {"status": "crashed", "error": "the worker process died"}


def _verdict(row) -> str:
    if row.status != "ok":
        return row.status
    if not row.finite:
        return "NaN/inf"
    if row.diverged:
        return "diverged"
    if row.energy_created:
        return "energy created"
    return "ok"


def ill_posed_table() -> pd.DataFrame:
    """Each ill-posed request and the one line it is refused with."""
    from converters.errors import PcsuiteError
    from converters.run import run_converter
    rows = []
    for name, given in ILL_POSED:
        params = {k: v for k, v in given.items() if k != "h"}
        try:
            run_converter(STABILITY_BASE["converter"], params, h=given.get("h"), periods=1)
            rows.append({"parameter": name, "given": str(given), "refused": False, "message": "accepted"})
        except PcsuiteError as exc:
            rows.append({"parameter": name, "given": str(given), "refused": True, "message": str(exc)})
    return pd.DataFrame(rows)


def stability_summary(table: pd.DataFrame) -> pd.DataFrame:
    """Per method: runs, ok, NaN/inf, diverged, energy created, errors (ngspice failures), timeouts."""
    out = []
    for method, group in table.groupby("method", sort=False):
        verdicts = group["verdict"]
        out.append({"method": method, "runs": len(group), "ok": int((verdicts == "ok").sum()),
                    "NaN/inf": int((verdicts == "NaN/inf").sum()), "diverged": int((verdicts == "diverged").sum()),
                    "energy created": int((verdicts == "energy created").sum()),
                    "errors": int((verdicts == "error").sum()), "timeouts": int((verdicts == "timeout").sum()),
                    "crashed": int((verdicts == "crashed").sum())})
    return pd.DataFrame(out)
