"""The LCP time-stepper against ngspice on the same circuit, started on the same periodic orbit.

Data flow: the LCP side finds its periodic steady state x* (Newton shooting) and simulates ``periods``
periods from it; the netlist gets x* as initial conditions and ngspice simulates the same span; both
runs become Trajectories labelled by the same model. Metrics are taken over the last ``window``
periods, each simulator on its own time points where possible (means, ripple, mode runs, turn-off
instants) and on a common fine grid only for the pointwise errors, with a guard band of 1 % of T around
every switching edge and diode event so that edge timing is measured by the timing metric, not smeared
into the amplitude errors. The defaults (start, periods, window) are the model's; the thresholds come
from ``data/defaults.toml``.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from converters.errors import ParameterError
from converters.models import get_model
from converters.analysis.periodic import ROUNDING_RESOLVED
from converters.run import make_method, require_stable, run_converter, steady_state
from netlists import SpiceOptions
from netlists.build import model_netlist

from .defaults import THRESHOLDS, passes
from .modes import period_sequences
from .spice import run_spice, spice_trajectory

EDGE_GUARD_T = 1e-2
#: What compare runs in place of a comparison on an orbit it cannot take (unstable, or not found).
START_REST = "compare both from rest with --start rest"
THERMAL_VOLTAGE = 0.025852


@dataclass
class Comparison:
    converter: str
    params: dict
    lcp: object                 # Trajectory
    spice: object               # Trajectory (ngspice)
    netlist: object
    window_start: float
    metrics: dict = field(default_factory=dict)
    checks: dict = field(default_factory=dict)
    rows: list = field(default_factory=list)          # (check, value, threshold, pass)
    notes: list = field(default_factory=list)         # what a reader must know about the numbers
    turn_offs: tuple = (0, 0, 0)      # periods with a diode turn-off: in the LCP run, in ngspice's; periods compared
    thresholds: dict = field(default_factory=lambda: dict(THRESHOLDS["compare"]))

    @property
    def passed(self) -> bool:
        return all(self.checks.values())

    def to_dict(self) -> dict:
        return {"converter": self.converter, "params": self.params, "metrics": self.metrics, "notes": self.notes,
                "thresholds": self.thresholds, "checks": self.checks, "passed": self.passed,
                "ngspice": self.spice.metadata["ngspice"], "spice_options": self.spice.metadata["spice_options"]}


def compare(converter: str, params: dict | None = None, *, periods: int | None = None, window: int | None = None,
            h=None, theta=None, spice_options: SpiceOptions | None = None, start: str | None = None,
            thresholds: dict | None = None, rtol=None, control: str = "pwm", spice_start: str = "own") -> Comparison:
    """Run both simulators on the same circuit and measure their agreement.

    ``start``: 'steady' (the LCP on its periodic orbit, ngspice to its own steady state from rest, or with
    ``spice_start`` = 'orbit' from the LCP's orbit) or 'rest'; the default, ``periods`` and
    ``window`` come from the model (PWM converters: steady, 30 periods, metrics over the last 10; the
    PRC, whose ideal tank keeps a ~1e-4 V cycle-to-cycle jitter: the Siconos scene, 2 ms from rest, the
    last 1 ms)."""
    model = get_model(converter, control)          # a converter, or a converter under a clocked loop
    if not model.periodic(model.resolve(params)):
        raise ParameterError(f"compare starts both simulators on a periodic orbit; {model.key} has no clock (its "
                             "comparison is --control smc's)")
    p = model.resolve(params)
    if p.get("D") in (0.0, 1.0):                # (a loop sets its duty ratio: no D among its parameters)
        # no switching: the output's ripple is 0 and the relative checks divide by it (ngspice's RON and ROFF then
        # read as a difference of 1e8 of nothing)
        raise ParameterError(f"compare checks a switching converter; at D = {p['D']:g} the switch never "
                             f"{'opens' if p['D'] == 1.0 else 'closes'}: give D in (0, 1) (simulate runs the DC "
                             "circuit)")
    T = model.period(p)
    defaults = model.compare_defaults
    start = start or defaults["start"]
    if start not in ("steady", "rest"):
        raise ParameterError(f"start must be 'steady' or 'rest'; got {start!r}")
    periods, window = periods or defaults["periods"], window or defaults["window"]
    if not 1 <= window <= periods:
        raise ParameterError(f"window must be in [1, periods = {periods}]; got {window}")
    x_star, rho = None, None
    if rtol is not None:                        # accuracy on request: the LCP side on its accurate orbit
        if start != "steady":
            raise ParameterError("rtol gives the periodic steady state; it needs start = 'steady'")
        lcp = run_converter(model, p, periods=periods, rtol=rtol, h=h, theta=theta)
        x_star, rho = lcp.x[0], lcp.metadata["orbit"]["spectral_radius"]
    else:
        if start == "steady":
            orbit = steady_state(model, p, make_method(model, p, "lcp", h, theta=theta), tol=1e-7,
                                 rounding_bound=ROUNDING_RESOLVED, remedy=START_REST)
            # ngspice started on an orbit neither simulator settles on stays near it for a while and agrees with it
            require_stable(model, p, orbit, START_REST)
            x_star, rho = orbit.x0, orbit.spectral_radius
        lcp = run_converter(model, p, h=h, theta=theta, periods=periods, x0=x_star)
    window_start = (periods - window) * T
    built = {"seconds": 0.0}

    def chunk(x0):
        started = time.perf_counter()
        try:
            built["netlist"] = model_netlist(model, p, periods * T, spice_options, x0=x0)
            return spice_trajectory(model, p, built["netlist"], run_spice(built["netlist"]), window_start)
        finally:
            built["seconds"] += time.perf_counter() - started
    spice, spice_periods, settle, notes, independent = spice_steady(chunk, start == "steady", x_star, T, periods,
                                                                    window, spice_start, rho)
    netlist = built["netlist"]
    result = Comparison(model.key, p, lcp, spice, netlist, window_start,
                        thresholds={**THRESHOLDS["compare"], **(thresholds or {})})
    _metrics(result, model, T, periods, window)
    result.notes += notes
    if independent is not None:
        result.rows.append(("spice_own_start", float(independent), 1.0, bool(independent)))
        result.checks = {name: ok for name, _, _, ok in result.rows}
    result.metrics["spice_settle"] = settle
    result.metrics["spice_periods"] = spice_periods
    # every ngspice run the comparison made (its settling chunks): spice_wall_s is the last
    result.metrics["spice_total_s"] = built["seconds"]
    result.metrics["spice_settled"] = bool(settle <= SPICE_SETTLE)
    if settle <= SPICE_SETTLE:                  # the ripple agreement is checked on a settled ngspice run only
        th, value = result.thresholds["vout_ripple_rel"], result.metrics["vout_ripple_rel_error"]
        result.rows.insert(2, ("vout_ripple_rel", value, th, passes("vout_ripple_rel", value, th)))
        result.checks = {name: ok for name, _, _, ok in result.rows}
    else:
        result.notes.append(f"the ripple agreement ({result.metrics['vout_ripple_rel_error']:.2g}) is not checked: "
                            "ngspice has not settled")
    if start == "steady" and settle > SPICE_SETTLE:
        result.notes.append(f"ngspice has not settled: after {spice_periods} periods its window's mean of vout still "
                            f"moves {settle:.2g} from the window before ({unsettled_cause(rho, spice_periods)}); the "
                            "comparison includes that drift")
    return result


def spice_steady(chunk, steady: bool, orbit, T: float, periods: int, window: int, spice_start: str = "own",
                 rho: float | None = None):
    """ngspice's steady state for a comparison: (its run, the periods it took, its last drift, notes, and whether its
    own start agrees: None where it needs no saying).

    ``chunk(x0)`` runs ngspice ``periods`` periods from ``x0`` (None: the circuit's own start) and returns its
    trajectory; a run from rest (not ``steady``) is one chunk from ``orbit`` (the run's start); a periodic
    comparison runs on from where each ended until its window's mean moves less than SPICE_SETTLE (at most
    MAX_SPICE_PERIODS), or, once the slowest mode has decayed, until that move stops falling ten times above
    SPICE_SETTLE (STALL_CHUNKS chunks without halving, its mean going back and forth by at most STALL_MOST:
    ngspice's own solution moving between periods, which the verdict then names). With ``spice_start`` 'own' ngspice
    goes from its own start, and has settled only once the LCP orbit's slowest mode (spectral radius ``rho``) has
    decayed to 1e-3 over its run too (the interleaved buck's phase currents balance at 0.99 a period while its mean
    of vout holds still), so that a wrong orbit of pcsuite's is not handed to it (a capacitor behind a blocked diode
    kept 1.36 MV in both); where it has not settled by then (a lightly damped circuit from rest), it runs again from
    the LCP's ``orbit`` and its own run must be approaching that one's mean (its last window closer than the window
    before), else the comparison fails: ngspice's own steady state is elsewhere. 'orbit': from the LCP's orbit only."""
    if spice_start not in ("own", "orbit"):
        raise ParameterError(f"spice_start must be 'own' or 'orbit'; got {spice_start!r}")

    end = periods * T

    def stalled(drifts):
        # the circuit's slowest mode has decayed and the drift no longer falls (its last three chunks' least not
        # half the least before them) and stays ten times above SPICE_SETTLE: ngspice's own solution moving between
        # periods, which more periods do not settle (a full bridge's load current: 2e-4..1.5e-3 of its RMS, chunk
        # after chunk to 600 periods); nearer the threshold a chunk may still fall below it (the voltage-mode buck's
        # 1.8e-5..5.5e-5, then 8.6e-6 at its eighth)
        last = min(drifts[-STALL_CHUNKS:])
        return (len(drifts) >= STALL_CHUNKS + 1 and last > 0.5 * min(drifts[:-STALL_CHUNKS])
                and last > 10.0 * SPICE_SETTLE and max(drifts[-STALL_CHUNKS:]) <= STALL_MOST)

    def trending(means):
        # the window's mean moving one way chunk after chunk is a transient ngspice has not finished, whatever the
        # orbit's slowest mode says (a type II loop's integrator winding down from saturation: vout 5.32 V where it
        # settles at 3.3, 0.07 a chunk, after its small-signal mode, 0.954 a period, had decayed); ngspice's own
        # motion between periods goes back and forth
        steps = np.diff(means[-STALL_CHUNKS - 1:])
        return steps.size == STALL_CHUNKS and bool(np.all(steps > 0) or np.all(steps < 0))

    def decayed(n):
        return rho is None or rho ** n <= 1e-3

    def settle_from(x0, most=MAX_SPICE_PERIODS):
        # a bar on a terminal (ngspice's 600 periods can take minutes); none where stderr is a file or a pipe
        import sys

        from tqdm import tqdm
        desc = "ngspice" + (" from its own start" if x0 is None else " from pcsuite's orbit")
        with tqdm(total=most if steady else periods, unit="period", file=sys.stderr, disable=None,
                  leave=False, desc=desc) as bar:
            said = time.perf_counter()
            run = chunk(x0)
            bar.update(periods)
            n, drifts, means = periods, [spice_drift(run, T, periods, window)], []
            while True:
                if bar.disable and steady and time.perf_counter() - said >= PROGRESS_EVERY_S:
                    # no bar where stderr is a file or a pipe: a line now and then, so a long settling is not
                    # silence (two current-mode loops' compares had printed nothing in 300 s)
                    print(f"{desc}: {n} of at most {most} periods, its window mean moving {drifts[-1]:.2g} a chunk "
                          f"(settled below {SPICE_SETTLE:g})", file=sys.stderr, flush=True)
                    said = time.perf_counter()
                means.append(run.mean("vout", t0=end - window * T, t1=end))
                if not steady or (drifts[-1] <= SPICE_SETTLE and (x0 is not None or decayed(n))) \
                        or n >= most:
                    return run, n, drifts[-1], means, False
                if decayed(n) and stalled(drifts) and not trending(means):
                    return run, n, drifts[-1], means, True
                run = chunk(run.x[-1])
                n = n + periods
                bar.update(periods)
                drifts.append(spice_drift(run, T, periods, window))
    if not steady or spice_start == "orbit":
        return (*settle_from(orbit)[:3], [], None)
    own, n, drift, means, at_noise = settle_from(None)
    if ((drift <= SPICE_SETTLE or at_noise) and decayed(n)) or orbit is None:
        return own, n, drift, [], None
    # where the orbit's slowest mode has decayed over ngspice's own run, what still moves is ngspice's own (its
    # switchings moving between its time points), and the run from the orbit would move alike to its 600 periods:
    # one chunk of it gives where it settles (a full bridge's compare had taken 7.7 minutes, two runs of 600)
    handed, n_orbit, drift_orbit, _, _ = settle_from(orbit, periods if decayed(n) else MAX_SPICE_PERIODS)
    target = handed.mean("vout", t0=end - window * T, t1=end)
    # the envelope of its distance over the run shrinks (a ring-down passes by and away from it window by window);
    # relative to the output's size, as :func:`spice_drift` reads it (an AC output's mean is ~0: a half-bridge's
    # load current had read 7.1e+03)
    size = max(abs(target), handed.rms("vout", t0=end - window * T, t1=end), 1e-12)
    distance = np.abs(np.array(means) - target) / size
    third = max(1, distance.size // 3)
    # (or already there: within a settling's move of it, where the two runs' means differ by rounding alone)
    approaching = bool(distance[-third:].max() < distance[:third].max() or distance[-third:].max() <= SPICE_SETTLE)
    note = (f"ngspice from its own start has not settled after {n} periods: its mean of vout is {means[-1]:.6g}, "
            f"{distance[-1]:.2g} (relative to its size) from where it settles from pcsuite's orbit ({target:.6g}); "
            "the largest "
            f"distance over its last third {distance[-third:].max():.2g}, over its first {distance[:third].max():.2g}: "
            + ("approaching it; compared from the orbit" if approaching else "NOT approaching it: ngspice's own "
               "steady state is elsewhere"))
    return handed, n_orbit, drift_orbit, [note], approaching


def unsettled_cause(rho: float, periods: int) -> str:
    """Why ngspice's window mean may still move after ``periods`` periods, from the LCP orbit's Floquet spectral
    radius ``rho`` (ngspice's circuit is the same but for its switch and diode models): a transient, if its slowest
    mode has not decayed (rho^periods above 1e-3); otherwise not a transient, but ngspice's own solution moving
    between periods (switching instants decided at its time points inside a finite transition)."""
    remaining = rho ** periods
    if remaining > 1e-3:
        return (f"lightly damped: its slowest mode decays by {rho:.6g} per period, to {remaining:.2g} of a start "
                f"error after {periods} periods")
    return (f"not a transient: the circuit's slowest mode decays by {rho:.4g} per period, to {remaining:.1e} after "
            f"{periods} periods; ngspice's switches change state at its time points, and where those fall inside a "
            "gate edge or a comparator's transition moves its switching instants from period to period (a shorter "
            "edge_fraction, or TMAX for a comparator, narrows it)")


#: ngspice counts as settled when its window's mean of vout moves less than this (relative) from the window
#: before; it runs on (from where it ended, at most MAX_SPICE_PERIODS in all) until then.
SPICE_SETTLE = 1e-5
#: Where no progress bar is drawn (stderr not a terminal), a settling ngspice says where it is this often (s).
PROGRESS_EVERY_S = 30.0
MAX_SPICE_PERIODS = 600
#: Chunks of ngspice periods without its drift halving, once the circuit's slowest mode has decayed, after which its
#: run counts as settled as far as ngspice settles it (:func:`spice_steady`).
STALL_CHUNKS = 3
#: The largest drift a chunk (relative) that can be ngspice's own motion between periods: its stalls measured 1.8e-5
#: to 1.5e-3 (a full bridge's); a type II loop's vout swinging 0.07 to 0.29 a chunk as its integrator winds down
#: from saturation is a transient, not a stall.
STALL_MOST = 1e-2


def _period_ripple(tr, t0: float, T: float, window: int) -> float:
    """The mean over the window's periods of each period's peak-to-peak vout, the window's linear trend
    removed first (a run still drifting towards its steady state, ngspice's on a lightly damped circuit, adds
    its drift per period to every period's peak-to-peak)."""
    rows = tr.rows_between(t0, t0 + window * T)
    t, v = tr.t[rows], np.asarray(tr.signal("vout", rows), dtype=float)
    v = v - np.polyval(np.polyfit(t - t0, v, 1), t - t0)
    return float(np.mean([np.ptp(v[(t >= t0 + k * T) & (t <= t0 + (k + 1) * T)]) for k in range(window)]))


def spice_drift(spice, T: float, periods: int, window: int) -> float:
    """|mean vout over the last window - over the window before| / its RMS over the last window (the run's drift;
    the RMS is the mean's size for a DC output, and the size of an AC one, whose mean is ~0 and never "settles"
    relative to itself: an inverter's load current ran ngspice its 600 periods)."""
    end = periods * T
    last = spice.mean("vout", t0=end - window * T, t1=end)
    before = spice.mean("vout", t0=end - 2 * window * T, t1=end - window * T)
    return abs(last - before) / max(abs(last), spice.rms("vout", t0=end - window * T, t1=end), 1e-12)


def _metrics(c: Comparison, model, T, periods, window):
    lcp, spice = c.lcp, c.spice
    t_l, t_s = lcp.t, spice.t
    m = c.metrics
    mean_l, mean_s = lcp.mean("vout", t0=c.window_start), spice.mean("vout", t0=c.window_start)
    m["vout_mean_lcp_V"], m["vout_mean_spice_V"] = mean_l, mean_s
    m["vout_mean_abs_error_V"] = abs(mean_s - mean_l)
    m["vout_mean_rel_error"] = abs(mean_s - mean_l) / max(abs(mean_l), 1e-12)
    m["vout_ripple_lcp_V"] = lcp.ripple("vout", t0=c.window_start)
    m["vout_ripple_spice_V"] = spice.ripple("vout", t0=c.window_start)
    m["vout_ripple_error_V"] = abs(m["vout_ripple_spice_V"] - m["vout_ripple_lcp_V"])
    # the ripple checked: each period's peak-to-peak, averaged over the window (a drift of the mean across the
    # window is not ripple)
    per_l, per_s = _period_ripple(lcp, c.window_start, T, window), _period_ripple(spice, c.window_start, T, window)
    m["vout_period_ripple_lcp_V"], m["vout_period_ripple_spice_V"] = per_l, per_s
    m["vout_ripple_rel_error"] = abs(per_s - per_l) / max(abs(per_l), 1e-12)

    labels_l, labels_s = lcp.modes(), spice.modes()
    first = periods - window
    seq_l = period_sequences(t_l, labels_l, T, first, window)
    seq_s = period_sequences(t_s, labels_s, T, first, window)
    agree = [a == b for a, b in zip(seq_l, seq_s)]
    m["mode_sequence_lcp"] = " > ".join(seq_l[-1])
    m["mode_sequence_spice"] = " > ".join(seq_s[-1])
    m["mode_agreement"] = float(np.mean(agree))

    edges = model.problem(c.params, periods * T).switching.breakpoints(c.window_start - 1e-9 * T, periods * T + 1e-9 * T)
    off_l = _turn_offs(lcp, labels_l, T, first, window, model.turn_off_label)
    off_s = _spice_turn_offs(spice, labels_s, T, first, window, model.turn_off_label, c.netlist.pairs[0])
    pairs = [(a, b) for a, b in zip(off_l, off_s) if a is not None and b is not None]
    m["turn_off_error_T"] = max((abs(a - b) / T for a, b in pairs), default=float("nan"))
    # periods where one side turns the diode off and the other does not: a disagreement, not a pass
    c.turn_offs = (sum(a is not None for a in off_l), sum(b is not None for b in off_s), window)
    events = [x for x in off_l + off_s if x is not None]

    grid = np.linspace(c.window_start, periods * T, window * 2000 + 1)
    guard = np.zeros(grid.shape, dtype=bool)
    for e in np.concatenate([edges, np.array(events, dtype=float)]):
        guard |= np.abs(grid - e) < EDGE_GUARD_T * T
    primary = model.state_names[0]
    cur_l = np.interp(grid, t_l, lcp.state(primary))
    cur_s = np.interp(grid, t_s, spice.state(primary))
    ripple_i = float(np.ptp(cur_l))
    m["current_signal"] = primary
    m["current_rms_error_over_ripple"] = float(np.sqrt(np.mean((cur_l - cur_s)[~guard] ** 2)) / max(ripple_i, 1e-12))
    m["current_max_error_outside_edges_A"] = float(np.abs(cur_l - cur_s)[~guard].max())
    m["vout_max_error_outside_edges_V"] = float(np.abs(np.interp(grid, t_l, lcp.signal("vout")) -
                                                       np.interp(grid, t_s, spice.signal("vout")))[~guard].max())
    m["lcp_wall_s"], m["spice_wall_s"] = lcp.wall_s, spice.wall_s
    m["runtime_ratio_spice_over_lcp"] = spice.wall_s / max(lcp.wall_s, 1e-9)
    m["lcp_steps"], m["spice_accepted_steps"] = lcp.steps, spice.steps
    m["diode_drop_floor_V"] = _diode_drop(spice, c.netlist, c.window_start)
    th = c.thresholds
    c.rows = [("vout_mean_rel", m["vout_mean_rel_error"], th["vout_mean_rel"],
               passes("vout_mean_rel", m["vout_mean_rel_error"], th["vout_mean_rel"])),
              ("mode_agreement", m["mode_agreement"], th["mode_agreement"],
               passes("mode_agreement", m["mode_agreement"], th["mode_agreement"])),
              ]
    lcp_offs, spice_offs, window = c.turn_offs
    if lcp_offs == spice_offs == 0:    # nothing to compare (a model without a diode turn-off): no row
        c.notes.append(f"turn_off_error_T not checked: no diode turn-off in the {window} periods compared, in "
                       "either simulator")
    else:
        # compared where both simulators turn the diode off (an edge at the window's end may fall on one side
        # only); a diode that turns off in one simulator and never in the other fails
        c.rows.append(("turn_off_error_T", m["turn_off_error_T"], th["turn_off_error_T"],
                       bool(lcp_offs and spice_offs)
                       and passes("turn_off_error_T", m["turn_off_error_T"], th["turn_off_error_T"])))
        if not (lcp_offs and spice_offs):
            c.notes.append(f"turn_off_error_T fails: the diode turns off in {lcp_offs} of the {window} periods "
                           f"compared in the LCP run and in {spice_offs} in ngspice's")
    c.checks = {name: ok for name, _, _, ok in c.rows}


def _turn_offs(lcp, labels, T, first, count, label):
    """Per period: the end of the diode's conduction (the last point labelled ``label``; sub-step estimate
    from the LCP's events), or None."""
    if label is None:
        return [None] * count
    t = lcp.t
    events = lcp.events
    activate = events[events["kind"] == "activate"]
    out = []
    for m in range(first, first + count):
        idx = np.flatnonzero((t > m * T) & (t <= (m + 1) * T + 1e-12 * T) & (labels == label))
        if idx.size == 0:
            out.append(None)
            continue
        last = idx[-1]
        hit = activate[activate["step"] == last]
        out.append(float(hit["time"].iloc[0]) if len(hit) else float(t[last]))
    return out


def _spice_turn_offs(spice, labels, T, first, count, label, current):
    """Per period: where the diode current of the last ``label`` run falls through its conduction threshold
    (linear interpolation between ngspice's raw points)."""
    if label is None:
        return [None] * count
    t = spice.t
    diode = spice.signal(current)
    out = []
    for m in range(first, first + count):
        idx = np.flatnonzero((t > m * T) & (t <= (m + 1) * T + 0.01 * T) & (labels == label))
        if idx.size == 0 or idx[-1] + 1 >= t.size:
            out.append(None)
            continue
        j = idx[-1]
        threshold = 1e-3 * np.abs(diode[t >= m * T]).max()
        a, b = diode[j] - threshold, diode[j + 1] - threshold
        frac = a / (a - b) if a > 0 >= b else 0.0
        out.append(float(t[j] + frac * (t[j + 1] - t[j])))
    return out


def _diode_drop(spice, netlist, start):
    """Forward drop of the SPICE diode model at its mean conduction current: the accuracy floor (one diode)."""
    if len(netlist.pairs) != 1:
        return float("nan")
    current = spice.signal(netlist.pairs[0])[spice.t >= start]
    conducting = current[current > 1e-3 * max(current.max(), 1e-30)]
    if conducting.size == 0:
        return 0.0
    o = netlist.options
    return float(o.diode_n * THERMAL_VOLTAGE * np.log1p(conducting.mean() / o.diode_is))
