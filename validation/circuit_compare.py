"""``pcsuite compare FILE.cir``: a netlist's LCS (the LCP time-stepper) against ngspice on the same file. At the
default step pcsuite's side is ``simulate --steady``'s answer (:func:`converters.run.default_answer`: the exact
orbit where the step's own check finds a value off by more than the defaults promise, said in the first note).

Both start on the stepper's periodic orbit (a periodic circuit; initial conditions in the netlist) or from the
file's own initial state, run the same span, and are read over its last ``window`` periods (or the last tenth of
a circuit without a period); ngspice steps at most the file's own ``.tran`` TMAX (as a fraction of the period)
unless ``spice_options`` are given. ngspice's near-ideal devices give it a steady state of its own: from the orbit it
runs on, from where it ended, until its window's mean of vout moves less than SPICE_SETTLE (at most
MAX_SPICE_PERIODS periods), as for the built-in converters. Checked per named output (each ``.meas`` vector and
vout): the mean and the per-period peak-to-peak ripple; and the mode sequence of every compared period (the
conducting diodes and the closed switches; on both sides a diode conducts above CURRENT_FRACTION of its peak; a
period agrees where its sequences are equal or its runs' modes part for less than SHORTEST_MODE T at a time:
:func:`_agreement`).
A circuit that switches itself (a comparator without a clock) is read over the last tenth of its run: means,
ripples per cycle, the cycle and the time in each mode (:func:`_self_oscillating`); another circuit without a
period as a transient, its waveforms point by point (:func:`_transient`).
Thresholds: ``[thresholds.circuit]`` in ``validation/data/defaults.toml``.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from converters.analysis.periodic import ROUNDING_RESOLVED
from converters.errors import ParameterError, ResourceError
from converters.problems import Comparators, StateSwitching
from converters.problems.switching import law_channels
from converters.run import default_answer, make_method, require_stable, run_converter, run_summary, steady_state

from .compare import SPICE_SETTLE, START_REST, spice_steady, unsettled_cause
from .defaults import THRESHOLDS, passes

PERIODS, WINDOW = 30, 10
#: A failed comparison runs ngspice again at a quarter of its TMAX, at most this many times, while a check fails
#: (ngspice under-resolved: a Dickson pump and a DCM flyback failed at 1.15e-3 and 2.8e-3 at the file's TMAX and
#: passed at 8e-5 and 8.7e-6 with TMAX 5 ns).
TMAX_REFINEMENTS = 2
#: The tightest RELTOL a refinement asks of ngspice (each takes a tenth of the last).
MIN_RELTOL = 1e-7
#: A ripple below this fraction of the output's mean is no ripple (a square wave rectified into a capacitor): its
#: relative error is measured against this floor, not against the LCP's ripple of 0 (ngspice's was 2.5e-9 of it).
RIPPLE_FLOOR = 1e-6


@dataclass
class CircuitComparison:
    circuit: str
    params: dict
    lcp: object
    spice: object
    window: tuple                    # (t0, t1): the span the comparison measures
    metrics: dict = field(default_factory=dict)
    rows: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    #: The outputs not compared: the circuit leaves them floating over part of the window (the notes say which)
    unset: tuple = ()

    @property
    def converter(self) -> str:           # what the comparison plot titles
        return self.circuit

    @property
    def passed(self) -> bool:
        return all(ok for _, _, _, ok in self.rows)

    def to_dict(self) -> dict:
        return {"converter": self.circuit, "params": self.params, "metrics": self.metrics, "notes": self.notes,
                "ngspice": self.spice.metadata["ngspice"], "spice_options": self.spice.metadata["spice_options"],
                "passed": self.passed}


def _scale(lcp, name: str, t0: float, t1: float) -> float:
    """What a mean's difference is relative to: the LCP's mean, or its RMS where that is larger (an AC output's mean
    is ~0: a half-bridge inverter's refinement had "moved 9e+08 (relative)")."""
    return max(abs(lcp.mean(name, t0=t0, t1=t1)), lcp.rms(name, t0=t0, t1=t1), 1e-12)


def _record(m: dict, label: str, means: tuple, ripples: tuple, scale: float) -> tuple:
    """Write a signal's means and ripples (LCP, ngspice) and their relative errors into ``m``; return the errors (a
    ripple against RIPPLE_FLOOR of the mean where the LCP's is below it)."""
    (mean_l, mean_s), (rip_l, rip_s) = means, ripples
    m[f"{label}_mean_lcp"], m[f"{label}_mean_spice"] = mean_l, mean_s
    m[f"{label}_mean_rel_error"] = abs(mean_s - mean_l) / scale
    m[f"{label}_ripple_lcp"], m[f"{label}_ripple_spice"] = rip_l, rip_s
    m[f"{label}_ripple_rel_error"] = abs(rip_s - rip_l) / max(abs(rip_l), RIPPLE_FLOOR * scale)
    return m[f"{label}_mean_rel_error"], m[f"{label}_ripple_rel_error"]

def compare_circuit(circuit, params: dict | None = None, *, h=None, spice_options=None, start: str | None = None,
                    periods: int = PERIODS, window: int = WINDOW, thresholds: dict | None = None,
                    spice_start: str = "own") -> CircuitComparison:
    """Run a netlist's LCS and ngspice on the same file and measure their agreement (module docstring)."""
    from netlists.circuit import circuit_netlist, file_spice_options

    from .spice import SpiceError, circuit_trajectory, run_spice_retrying
    p = circuit.resolve(params)
    spice_options = file_spice_options(circuit, spice_options)
    periodic = circuit.periodic(p)
    start = start or ("steady" if periodic and not circuit.step_times(p) else "rest")      # a load step runs from rest
    if start == "steady" and not periodic:
        raise ParameterError(f"--start steady needs a periodic circuit; {circuit.name} has no period (its sources "
                             "are DC): use --start rest")
    if periodic and circuit.step_times(p):        # the file's whole run, its window after the last step
        periods = max(periods, int(round(circuit.default_duration(p) / circuit.period(p))))
    T = circuit.period(p) if periodic else circuit.default_duration(p) / periods
    span = periods * T
    x0 = None
    rho = None
    if start == "steady":
        orbit = steady_state(circuit, p, make_method(circuit, p, "lcp", h), tol=1e-9, rounding_bound=ROUNDING_RESOLVED,
                             remedy=START_REST)
        # ngspice started on an orbit neither simulator settles on stays near it for a while and agrees with it
        require_stable(circuit, p, orbit, START_REST)
        x0, rho = orbit.x0, orbit.spectral_radius
    lcp = run_converter(circuit, p, h=h, t_end=span, x0=x0)
    answered = []
    if start == "steady" and h is None:
        # pcsuite's side is its default answer, simulate --steady's: the exact orbit where the step's own check finds a
        # value off by more than the defaults promise (a DCM buck with 1 ohm and 220 pF across its switch: the stepper
        # 1.8 % off, the comparison had failed on pcsuite's side where ngspice was within 1e-4)
        stepped = lcp
        lcp, summary = default_answer(circuit, p, stepped, run_summary(stepped), periods=periods)
        answered = [] if lcp is stepped else [f"pcsuite's side: {summary['warnings'][0]}"]
    t0 = span - window * T
    law = circuit.compiled(p).law
    # a comparator without a clock (each of several: hysteretic phases) switches the circuit by its own cycles
    oscillating = isinstance(law, (StateSwitching, Comparators)) and all(
        channel.function.ramp is None for channel in law_channels(law)[0])
    # a transient's modes are compared over the whole run: a diode conducts above a fraction of its peak over it (the
    # last window's peak can be a blocked diode's leakage, 1e-11 A, read as conduction)
    modes_from = t0 if periodic or oscillating else 0.0
    # a node the circuit leaves floating has no value to compare: ngspice's is its leakages', pcsuite's the LCP's pick
    floating = circuit.floating_shares(lcp, p, ["vout", *circuit.netlist.outputs], modes_from, span)
    if "vout" in floating or circuit.output in floating:
        raise ParameterError(f"compare: {circuit.name}'s output {circuit.floating_text(p, floating)} (the output "
                             "compared is the first .meas vector)")
    unset_note = [f"not compared: {circuit.floating_text(p, floating)}"] if floating else []
    _modes_by_current(lcp, circuit, p, modes_from)
    state = {"options": spice_options, "notes": [], "seconds": 0.0}

    def chunk(x0):
        """``periods`` periods of ngspice from ``x0`` (None: the file's own start) at the last TMAX it took."""
        started = time.perf_counter()
        try:
            netlist, run, notes = run_spice_retrying(lambda o: circuit_netlist(circuit, p, span, o, x0=x0),
                                                     state["options"])
        finally:
            state["seconds"] += time.perf_counter() - started
        state["options"], state["notes"] = netlist.options, state["notes"] + notes
        return circuit_trajectory(circuit, p, netlist, run, modes_from)

    def settled(options, spice_start):
        state["options"], state["notes"] = options, []
        spice, n, drift, notes, independent = spice_steady(chunk, start == "steady", lcp.x[0], T, periods, window,
                                                           spice_start, rho)
        return spice, state["options"], state["notes"] + notes, n, drift, independent

    spice, options, notes, spice_periods, settle, independent = settled(spice_options, spice_start)
    th = {**THRESHOLDS["circuit"], **(thresholds or {})}
    result = CircuitComparison(circuit.name, p, lcp, spice, (t0, span), unset=tuple(floating))
    result.notes += answered + notes + unset_note
    if not periodic:
        done = _self_oscillating(result, circuit, th) if oscillating else _transient(result, circuit, th)
        done.metrics["spice_total_s"] = state["seconds"]
        return done
    _periodic(result, circuit, T, window, th, (settle, spice_periods, start, rho), independent)
    # a difference ngspice's own resolution may make: its answer at a quarter of TMAX and a tenth of RELTOL, from the
    # same start (a capacitor behind a blocked diode keeps what a coarse run put there), at most TMAX_REFINEMENTS
    # times while a check fails (a 60 Hz rectifier's commutations read on ngspice's T/200 steps: its modes and
    # ripple), the finest run compared
    moved, refined = 0.0, []
    losses = model_losses(circuit, p, lcp, options, t0, span)
    for _ in range(TMAX_REFINEMENTS):
        if all(ok for *_, ok in result.rows):
            break
        failed = {name for name, *_, ok in result.rows if not ok}
        _, worst, threshold, _ = next(row for row in result.rows if row[0] == "mean_rel")
        error = result.metrics[f"{circuit.output}_mean_rel_error"]
        if "mean_rel" in failed and failed <= {"mean_rel", "ripple_rel"} and worst == error \
                and losses is not None and losses > max(0.3 * error, threshold):
            # the output's mean fails by what the models' losses make at any resolution (the note below), beyond
            # the threshold: a finer ngspice run cannot pass it (a boost at D = 0.99: its RON's 1 % of the input
            # power; the refinement ran its 600 s time limit)
            break
        finer = replace(options, tmax_fraction=options.tmax_fraction / 4, reltol=max(options.reltol / 10, MIN_RELTOL))
        try:
            spice_f, options_f, notes_f, periods_f, settle_f, independent = settled(finer, spice_start)
        except (SpiceError, ResourceError) as error:
            # the comparison made stands; the note says it could not be refined, and why: ngspice's message, or the
            # limit the finer run would pass (its remedy is the user's options, which the refinement chose instead)
            why = str(error).split(": ", 1)[-1]
            result.notes.append(f"ngspice at TMAX = {finer.tmax_fraction:g} T, RELTOL {finer.reltol:g} did not run "
                                f"({why.split('; ')[0] if isinstance(error, ResourceError) else why}): compared at "
                                f"TMAX = {options.tmax_fraction:g} T, RELTOL {options.reltol:g}")
            break
        before, after = spice.mean("vout", t0=t0, t1=span), spice_f.mean("vout", t0=t0, t1=span)
        moved = abs(after - before) / _scale(lcp, "vout", t0, span)
        refined.append(f"ngspice at TMAX = {finer.tmax_fraction:g} T, RELTOL {finer.reltol:g}: its mean of vout moved "
                       f"{moved:.2g} (relative) from TMAX = {options.tmax_fraction:g} T, RELTOL {options.reltol:g}; "
                       "compared there")
        spice, options, spice_periods = spice_f, options_f, periods_f
        result = CircuitComparison(circuit.name, p, lcp, spice, (t0, span), unset=tuple(floating))
        result.notes += answered + notes_f + unset_note + refined
        _periodic(result, circuit, T, window, th, (settle_f, spice_periods, start, rho), independent)
    error = result.metrics[f"{circuit.output}_mean_rel_error"]
    if moved > 0.1 * error and not _passed(result, "mean_rel"):
        result.notes.append(f"ngspice is under-resolved: its last refinement moved its mean {moved:.2g}, more than a "
                            f"tenth of the difference ({error:.2g}); the difference may be ngspice's (--spice-tmax, "
                            "--spice-reltol)")
    elif moved > error:
        # a pass reached by refining: ngspice's mean is known to about its last move, not to the difference
        result.notes.append(f"ngspice's last refinement moved its mean {moved:.2g}, more than the difference that "
                            f"passes ({error:.2g}): ngspice resolves the mean to about {moved:.2g}, so the agreement "
                            "says no more than that (--spice-tmax, --spice-reltol)")
    ripple_row = next((row for row in result.rows if row[0] == "ripple_rel"), None)
    if ripple_row is not None and not ripple_row[3]:
        # RELTOL bounds ngspice's local error relative to the signal: a ripple far below RELTOL |mean| is its noise;
        # said where every output whose ripple failed is such
        m = result.metrics
        failed = [key[:-len("_ripple_rel_error")] for key, value in m.items()
                  if key.endswith("_ripple_rel_error") and value > ripple_row[2]]
        noise = [label for label in failed if max(abs(m[f"{label}_ripple_spice"]), abs(m[f"{label}_ripple_lcp"]))
                 < 0.1 * options.reltol * abs(m[f"{label}_mean_spice"])]
        if failed and noise == failed:
            reltol = options.reltol
            pairs = ", ".join(f"{label} ({m[label + '_ripple_lcp']:.2g} and {m[label + '_ripple_spice']:.2g}, "
                              f"RELTOL |mean| {reltol * abs(m[label + '_mean_spice']):.2g})" for label in failed)
            result.notes.append(f"both ripples of {pairs} lie below a tenth of what ngspice's RELTOL {reltol:g} "
                                "resolves on the mean: the ripple check compares ngspice's rounding, not the "
                                "circuit's ripple")
    if not _passed(result, "mean_rel"):
        if losses is not None and losses > 0.3 * error:
            result.notes.append(f"ngspice's switch and diode models (RON = {options.switch_ron:g} ohm, N = "
                                f"{options.diode_n:g}) dissipate about {losses:.2g} of the input power on pcsuite's "
                                f"orbit, where its ideal ones dissipate none: a difference of that order "
                                f"({error:.2g}) is the models', not the methods'")
    if start == "steady":
        # (the run's own method: its check is the one the default's answer made, kept on the run)
        _own_estimate(result, circuit, p, result.lcp.algorithm, th,
                      from_orbit=independent is not None or spice_start == "orbit")
    # every ngspice run the comparison made (its settling chunks, retries and refinements): spice_wall_s is the last
    result.metrics["spice_total_s"] = state["seconds"]
    return result


def _own_estimate(result: CircuitComparison, circuit, p: dict, method, th: dict, from_orbit: bool) -> None:
    """The mean check passes only where pcsuite's own estimate is within the threshold too. Where ngspice ran from
    pcsuite's orbit (``from_orbit``: its own start had not settled, or --spice-start orbit) it keeps what that orbit
    holds in a slow mode, so the means agree whatever the orbit is worth (a 1 MHz DCM boost at 10 Mohm: pcsuite's
    1127.95 V at its default step, estimated 0.18 off, 6.1 % above the exact 1063.16; ngspice from it read 1127.95
    and the mean passed). From its own start ngspice may share pcsuite's error: at its default TMAX it damps a
    snubber's ring as the stepper's backward Euler does (a DCM buck with 1 ohm and 220 pF across its switch: both
    21.82 V where the circuit settles at 22.21, pcsuite's own estimate 1.8e-2; the mean passed)."""
    from converters.analysis.accuracy import default_check
    lcp, (t0, span) = result.lcp, result.window
    check = default_check(circuit, p, method, lcp, lcp.mean("vout", t0=t0, t1=span))
    estimate = check.get("vout_mean_error_estimate")
    if estimate is None:
        return
    result.metrics["lcp_mean_error_estimate"] = estimate
    if estimate > th["mean_rel"]:
        result.rows = [(name, value, limit, ok and name != "mean_rel") for name, value, limit, ok in result.rows]
        why = ("ngspice ran from pcsuite's orbit and keeps it: the means' agreement says nothing" if from_orbit else
               "an agreement with ngspice cannot vouch for more than pcsuite's own check does (both may miss the "
               "same thing: a ring both damp)")
        result.notes.append(f"pcsuite's own estimate says its mean may be {estimate:.2g} off (more than "
                            f"{th['mean_rel']:g}), and {why}; the mean check fails (run compare with a smaller --h, "
                            "or simulate --method event)")


#: The thermal voltage ngspice's diode model uses at its default 27 C (V).
THERMAL_VOLTAGE = 0.025865


def model_losses(circuit, p: dict, lcp, options, t0: float, t1: float) -> float | None:
    """What ngspice's near-ideal switch and diode models dissipate on pcsuite's own orbit over [t0, t1], relative
    to the power the DC sources deliver: RON times each switch's mean square current, and each diode's mean current
    times its drop N Vt ln(I_peak / IS) at its peak (an upper bound); None where the currents or the sources'
    power are not among the signals."""
    names = set(lcp.signal_names)
    try:
        loss = sum(options.switch_ron * lcp.rms(f"i({name})", t0=t0, t1=t1) ** 2
                   for name in circuit.compiled(p).switch_names
                   if f"i({name})" in names)
        for e in circuit.netlist.elements:
            if e.kind == "D" and f"i({e.name})" in names:
                current = np.abs(np.asarray(lcp.signal(f"i({e.name})", lcp.rows_between(t0, t1)), dtype=float))
                if current.max() > options.diode_is:
                    drop = options.diode_n * THERMAL_VOLTAGE * np.log(current.max() / options.diode_is)
                    loss += drop * lcp.mean(f"i({e.name})", t0=t0, t1=t1)
        power = sum(abs(float(e.waveform) * lcp.mean(f"i({e.name})", t0=t0, t1=t1)) for e in circuit.netlist.elements
                    if e.kind == "V" and isinstance(e.waveform, (int, float)) and f"i({e.name})" in names)
    except (KeyError, ValueError):
        return None
    return abs(loss) / power if power > 0.0 else None


def _compared(result: CircuitComparison, circuit) -> list[str]:
    """The outputs compared: vout and each .meas vector, but those the circuit leaves floating."""
    return [name for name in dict.fromkeys(["vout", *circuit.netlist.outputs]) if name not in result.unset]


def _passed(result: CircuitComparison, check: str) -> bool:
    return next(ok for name, _, _, ok in result.rows if name == check)


def _periodic(result: CircuitComparison, circuit, T: float, window: int, th: dict, settling: tuple,
              independent: bool | None = None) -> None:
    """The periodic comparison's metrics and rows over the window (module docstring); ``settling``: ngspice's last
    drift, its periods, the start and the LCP orbit's spectral radius; ``independent``: whether ngspice's own start
    approaches its run from the orbit (:func:`~validation.compare.spice_steady`; None: it settled on its own)."""
    settle, spice_periods, start, rho = settling
    lcp, spice, m = result.lcp, result.spice, result.metrics
    t0, span = result.window
    outputs = [name for name in dict.fromkeys(["vout", *[v for v in circuit.netlist.outputs if v != circuit.output]])
               if name not in result.unset]
    worst_mean, worst_ripple = 0.0, 0.0
    for name in outputs:
        mean_l, mean_s = lcp.mean(name, t0=t0, t1=span), spice.mean(name, t0=t0, t1=span)
        scale = _scale(lcp, name, t0, span)
        rip_l = _period_ripple(lcp, name, t0, T, window)
        rip_s = _period_ripple(spice, name, t0, T, window)
        label = circuit.output if name == "vout" else name
        mean_error, ripple_error = _record(m, label, (mean_l, mean_s), (rip_l, rip_s), scale)
        worst_mean, worst_ripple = max(worst_mean, mean_error), max(worst_ripple, ripple_error)
    agreement, sequences_l, sequences_s = _agreement(lcp, spice, t0, T, window)
    m["mode_sequence_lcp"], m["mode_sequence_spice"] = " > ".join(sequences_l[-1]), " > ".join(sequences_s[-1])
    m["mode_agreement"] = agreement
    m["spice_settle"], m["spice_periods"], m["spice_settled"] = settle, spice_periods, bool(settle <= SPICE_SETTLE)
    m["lcp_wall_s"], m["spice_wall_s"] = lcp.wall_s, spice.wall_s
    m["current_signal"] = next((s for s in lcp.state_names if s.startswith("i(")), lcp.state_names[0])
    result.rows = [("mean_rel", worst_mean, th["mean_rel"], passes("mean_rel", worst_mean, th["mean_rel"])),
                   ("mode_agreement", agreement, th["mode_agreement"],
                    passes("mode_agreement", agreement, th["mode_agreement"]))]
    if independent is not None:
        result.rows.append(("spice_own_start", float(independent), 1.0, bool(independent)))
    if settle <= SPICE_SETTLE or start != "steady":
        result.rows.insert(1, ("ripple_rel", worst_ripple, th["ripple_rel"],
                               passes("ripple_rel", worst_ripple, th["ripple_rel"])))
    else:
        result.notes.append(f"the ripple agreement ({worst_ripple:.2g}) is not checked: ngspice has not settled after "
                            f"{spice_periods} periods (its window's mean moves {settle:.2g}; "
                            f"{unsettled_cause(rho, spice_periods)})")


def _modes_by_current(lcp, circuit, p: dict, t0: float) -> None:
    """The LCP's modes read by ngspice's rule (a diode conducts above CURRENT_FRACTION of its peak after t0), so
    that both runs are read alike. The LCS's own rule (its current above its reverse voltage) counts a diode
    whose current decays through a series resistance as conducting down to any fraction of its peak (1e-6 and
    below on the Cockcroft-Walton ladder, until the source reverses), where ngspice's reads it off."""
    from .spice import conducting_by_current, mode_labels
    compiled = circuit.compiled(p)
    diodes = [d for d in compiled.pair_names if d != "none"]
    currents = (np.column_stack([np.asarray(lcp.signal(f"i({d})"), dtype=float) for d in diodes]) if diodes
                else np.zeros((lcp.t.size, 0)))
    closed = np.asarray(compiled.closed, dtype=bool)[lcp.config]
    lcp.measured["mode"] = mode_labels(compiled.switch_names, closed, diodes,
                                       conducting_by_current(currents, lcp.t >= t0, lcp.t, circuit.period(p)))


def _transient(result: CircuitComparison, circuit, th: dict) -> CircuitComparison:
    """A circuit without a period (a transient from its initial state): each named output's waveform over the
    whole run on a common grid (RMS of the difference over the RMS of the LCP's), and the fraction of the run
    in the same mode."""
    lcp, spice, m = result.lcp, result.spice, result.metrics
    result.window = (float(lcp.t[0]), float(lcp.t[-1]))            # what is compared: the whole run
    grid = np.linspace(lcp.t[0], lcp.t[-1], 20001)
    worst = 0.0
    for name in _compared(result, circuit):
        a = np.interp(grid, lcp.t, np.asarray(lcp.signal(name), dtype=float))
        b = np.interp(grid, spice.t, np.asarray(spice.signal(name), dtype=float))
        label = circuit.output if name == "vout" else name
        m[f"{label}_waveform_rel_error"] = float(np.sqrt(np.mean((b - a) ** 2)) / max(np.sqrt(np.mean(a ** 2)), 1e-300))
        worst = max(worst, m[f"{label}_waveform_rel_error"])
    labels_l = np.asarray(lcp.modes()).astype(str)[np.clip(np.searchsorted(lcp.t, grid), 0, lcp.t.size - 1)]
    labels_s = np.asarray(spice.modes()).astype(str)[np.clip(np.searchsorted(spice.t, grid), 0, spice.t.size - 1)]
    agreement = float(np.mean(labels_l == labels_s))
    m["mode_time_agreement"] = agreement
    m["lcp_wall_s"], m["spice_wall_s"] = lcp.wall_s, spice.wall_s
    m["current_signal"] = next((s for s in lcp.state_names if s.startswith("i(")), lcp.state_names[0])
    result.rows = [("waveform_rel", worst, th["waveform_rel"], passes("waveform_rel", worst, th["waveform_rel"])),
                   ("mode_time_agreement", agreement, th["mode_time_agreement"],
                    passes("mode_time_agreement", agreement, th["mode_time_agreement"]))]
    return result


def _cycles(tr, t0: float, closed=None) -> np.ndarray:
    """The instants after t0 where a switch closes: the first (``switch``), or the one whose state per point is
    ``closed``."""
    rows = tr.rows_between(t0, tr.t[-1])
    state = np.asarray(tr.signal("switch", rows) if closed is None else closed[rows]).astype(int)
    return tr.t[rows][1:][np.diff(state) > 0]


def _closed(tr, compiled) -> np.ndarray:
    """Per point and switch, closed: ngspice's from its control voltages (``measured``), the LCP's from its
    configurations."""
    if "closed" in tr.measured:
        return np.asarray(tr.measured["closed"], dtype=bool)
    return np.asarray(compiled.closed, dtype=bool)[np.asarray(tr.config, dtype=np.int64)]


def _self_oscillating(result: CircuitComparison, circuit, th: dict) -> CircuitComparison:
    """A circuit that switches itself (a comparator without a clock: a hysteretic controller): two oscillators
    whose cycles differ by a fraction drift apart in phase over a run, so their waveforms are not compared point
    by point. Over the last tenth of the run: each named output's mean, and its peak-to-peak averaged over the
    cycles (from one closing of the switch to the next), the mean cycle, and the fraction of time in each mode.
    With several comparators (hysteretic phases, each its own oscillator) each one's cycle, and the fraction of
    time each switch is closed: the phases' relative phase drifts, so their combined modes are not compared."""
    lcp, spice, m = result.lcp, result.spice, result.metrics
    t1 = float(lcp.t[-1])
    t0 = t1 - circuit.WINDOW_FRACTION * (t1 - float(lcp.t[0]))
    result.window = (t0, t1)
    compiled = circuit.compiled(result.params)
    leaders = compiled.law.names if isinstance(compiled.law, Comparators) else ()
    closed_l, closed_s = (_closed(lcp, compiled), _closed(spice, compiled)) if leaders else (None, None)
    columns = [compiled.switch_names.index(name) for name in leaders]
    first = None if not columns else columns[0]
    cycles_l = _cycles(lcp, t0, None if first is None else closed_l[:, first])
    cycles_s = _cycles(spice, t0, None if first is None else closed_s[:, first])
    if min(cycles_l.size, cycles_s.size) < 3:
        result.notes.append(f"fewer than 2 cycles in the last tenth of the run ({cycles_l.size - 1} in the LCP's, "
                            f"{cycles_s.size - 1} in ngspice's): compared as a transient")
        return _transient(result, circuit, th)
    cycle_l, cycle_s = np.diff(cycles_l).mean(), np.diff(cycles_s).mean()
    m["cycle_lcp_s"], m["cycle_spice_s"] = float(cycle_l), float(cycle_s)
    cycle_rel = float(abs(cycle_s / cycle_l - 1))
    for name, column in zip(leaders[1:], columns[1:]):
        own_l, own_s = _cycles(lcp, t0, closed_l[:, column]), _cycles(spice, t0, closed_s[:, column])
        if min(own_l.size, own_s.size) < 3:
            result.notes.append(f"{name.upper()} closes fewer than 3 times in the last tenth of the run: its cycle is "
                                "not compared")
            continue
        a, b = np.diff(own_l).mean(), np.diff(own_s).mean()
        m[f"cycle_{name}_lcp_s"], m[f"cycle_{name}_spice_s"] = float(a), float(b)
        cycle_rel = max(cycle_rel, float(abs(b / a - 1)))
    m["cycle_rel_error"] = cycle_rel
    worst_mean, worst_ripple = 0.0, 0.0
    for name in _compared(result, circuit):
        label = circuit.output if name == "vout" else name
        mean_l, mean_s = lcp.mean(name, t0=t0, t1=t1), spice.mean(name, t0=t0, t1=t1)
        scale = max(abs(mean_l), 1e-12)
        rip_l, rip_s = _cycle_ripple(lcp, name, cycles_l), _cycle_ripple(spice, name, cycles_s)
        mean_error, ripple_error = _record(m, label, (mean_l, mean_s), (rip_l, rip_s), scale)
        worst_mean, worst_ripple = max(worst_mean, mean_error), max(worst_ripple, ripple_error)
    if leaders:                 # each switch's closed fraction (time-weighted over the window)
        fractions_l = {n: _closed_fraction(lcp, closed_l[:, c], t0, t1) for c, n in enumerate(compiled.switch_names)}
        fractions_s = {n: _closed_fraction(spice, closed_s[:, c], t0, t1) for c, n in enumerate(compiled.switch_names)}
    else:
        fractions_l = lcp.mode_fractions(None, t0=t0, t1=t1)
        fractions_s = spice.mode_fractions(None, t0=t0, t1=t1)
    apart = max(abs(fractions_l.get(k, 0.0) - fractions_s.get(k, 0.0)) for k in set(fractions_l) | set(fractions_s))
    m["mode_fractions_lcp"], m["mode_fractions_spice"] = fractions_l, fractions_s
    m["mode_fraction_apart"] = apart
    m["lcp_wall_s"], m["spice_wall_s"] = lcp.wall_s, spice.wall_s
    m["current_signal"] = next((s for s in lcp.state_names if s.startswith("i(")), lcp.state_names[0])
    result.rows = [(check, value, th[check], passes(check, value, th[check])) for check, value in
                   (("mean_rel", worst_mean), ("ripple_rel", worst_ripple), ("cycle_rel", cycle_rel),
                    ("mode_fraction_apart", apart))]
    return result


def _closed_fraction(tr, closed: np.ndarray, t0: float, t1: float) -> float:
    """The fraction of [t0, t1] a switch is closed, each sample holding until the next."""
    rows = tr.rows_between(t0, t1)
    t = tr.t[rows]
    return float(np.sum(np.diff(t) * closed[rows][:-1]) / (t[-1] - t[0]))


def _cycle_ripple(tr, name: str, closings: np.ndarray) -> float:
    """The mean over the cycles between ``closings`` of each cycle's peak-to-peak value of a signal."""
    return float(np.mean([np.ptp(np.asarray(tr.signal(name, tr.rows_between(a, b)), dtype=float))
                          for a, b in zip(closings[:-1], closings[1:])]))


def _period_ripple(tr, name: str, t0: float, T: float, window: int) -> float:
    """The mean over the window's periods of each period's peak-to-peak value of a signal."""
    values = []
    for k in range(window):
        rows = tr.rows_between(t0 + k * T, t0 + (k + 1) * T)
        values.append(float(np.ptp(np.asarray(tr.signal(name, rows), dtype=float))))
    return float(np.mean(values))


#: A mode shorter than this fraction of the period is left out of its sequence (an edge's transient); two runs whose
#: modes differ for less than this at a time agree (:func:`_agreement`).
SHORTEST_MODE = 2e-3


def _agreement(lcp, spice, t0: float, T: float, window: int) -> tuple[float, list, list]:
    """The fraction of the window's periods whose modes agree, and the two runs' sequences. A period agrees where
    its sequences are equal (the modes shorter than SHORTEST_MODE T left out: an edge's transient; the instants may
    differ, as a diode's turn-off read on ngspice's tapering current does by ~3e-3 T), or where no stretch of it in
    which the runs' modes differ lasts SHORTEST_MODE T: a pulse near that bound is kept in one sequence and not the
    other (a sine-triangle bridge's ~200 modes a period, a pulse of 2.0e-3 T in one run and 1.9e-3 in the other:
    agreement 0.3 where the runs part for at most 2e-4 T at a time). Either way a difference shorter than
    SHORTEST_MODE T is not one."""
    sequences_l = _mode_sequences(lcp, t0, T, window)
    sequences_s = _mode_sequences(spice, t0, T, window)
    agree = [a == b or _parted_at_most(lcp, spice, t0 + k * T, T, SHORTEST_MODE)
             for k, (a, b) in enumerate(zip(sequences_l, sequences_s))]
    return float(np.mean(agree)), sequences_l, sequences_s


def _parted_at_most(lcp, spice, a: float, T: float, fraction: float) -> bool:
    """No stretch of [a, a + T] where the two runs' modes differ lasts ``fraction`` T or longer (both read at the
    union of their samples)."""
    b = a + T
    grid = np.union1d(lcp.t[lcp.rows_between(a, b)], spice.t[spice.rows_between(a, b)])
    grid = grid[(grid >= a) & (grid <= b)]
    differ = _labels_at(lcp, grid) != _labels_at(spice, grid)
    # each interval (grid[i - 1], grid[i]] in the label of its end; a stretch of differing ones from grid[start] to
    # grid[stop]
    edges = np.flatnonzero(np.diff(np.concatenate([[0], differ[1:].astype(int), [0]])))
    longest = max((grid[stop] - grid[start] for start, stop in zip(edges[::2], edges[1::2])), default=0.0)
    return bool(longest < fraction * T)


def _labels_at(tr, times: np.ndarray) -> np.ndarray:
    """Each run's mode over the step that ends at or after each of ``times`` (a step's label is its end's)."""
    rows = np.clip(np.searchsorted(tr.t, times, side="left"), 0, tr.t.size - 1)
    return np.asarray(tr.modes(rows)).astype(str)


def _mode_sequences(tr, t0: float, T: float, window: int, shortest: float = SHORTEST_MODE) -> list:
    """Per period of the window, its sequence of modes (consecutive duplicates merged; a mode shorter than
    ``shortest`` T, an edge's transient, left out)."""
    out = []
    for k in range(window):
        rows = tr.rows_between(t0 + k * T, t0 + (k + 1) * T)
        t, labels = tr.t[rows], np.asarray(tr.modes(rows)).astype(str)
        sequence, start = [], t[0]
        for i in range(1, len(labels) + 1):
            if i == len(labels) or labels[i] != labels[i - 1]:
                end = t[min(i, len(t) - 1)]
                if end - start >= shortest * T and (not sequence or sequence[-1] != labels[i - 1]):
                    sequence.append(labels[i - 1])
                start = end
        out.append(tuple(sequence))
    return out
