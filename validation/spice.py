"""Run ngspice (through PySpice and the system libngspice) in a worker process.

PySpice keeps memory between runs and an ngspice crash would take its process down, so every run
goes to a worker process (forked, replaced every ``RUNS_PER_WORKER`` runs). Failures come back as
:class:`SpiceError` with ngspice's own message; the calling process keeps working.
"""
from __future__ import annotations

import atexit
import concurrent.futures as futures
import os
import re
import tempfile
import time
from dataclasses import dataclass, field

import numpy as np

from converters.errors import SimulationError
from converters.limits import check_memory, time_limit
from converters.parallel import ProcessSlot
from netlists import Netlist

RUNS_PER_WORKER = 10
TIMEOUT_S = 600.0
_FATAL = re.compile(r"(timestep too small|singular matrix|no convergence|too many iterations|"
                    r"simulation\(s\) aborted|error)", re.IGNORECASE)


_PERCENT = re.compile(r"tran:?\s*([0-9.]+)\s*%", re.IGNORECASE)
#: After this long, a run whose pace (what it reported done, plus the 0.1 % it may have done since) needs
#: CRAWL_FACTOR times its time limit or more is stopped: it would not finish, and the limit's minutes are saved.
CRAWL_AFTER_S = 30.0
CRAWL_FACTOR = 3.0
WATCH_EVERY_S = 5.0     # how often the parent reads the run's progress


class SpiceError(SimulationError):
    """An ngspice run failed (the message carries ngspice's reason)."""


def _crawl_message(netlist: Netlist, reached: float, elapsed: float, limit: float) -> str:
    need = elapsed / (reached + 1e-3)
    return (f"ngspice would not finish {netlist.converter} within the time limit of {limit:g} s: "
            f"{100 * reached:.1f} % of its {netlist.t_end:.3g} s transient in {elapsed:.0f} s, a pace that needs "
            f"{need / 3600:.2g} h or more; raise it with --time-limit S (or PCSUITE_TIME_LIMIT), or run fewer periods "
            "or a larger --spice-tmax")


@dataclass(frozen=True)
class SpiceResult:
    time: np.ndarray
    vectors: dict            # ngspice vector name -> array
    ngspice_version: str
    wall_s: float
    accepted_steps: int
    options: dict = field(default_factory=dict)
    log: str = ""

    def signal(self, probe) -> np.ndarray:
        """A probe of :class:`netlists.Netlist`: (vector, sign) or ((node_a, node_b), sign)."""
        source, sign = probe
        if isinstance(source, tuple):
            return sign * (self.vectors[source[0]] - self.vectors[source[1]])
        return sign * self.vectors[source]

    def switch(self, netlist: Netlist) -> np.ndarray:
        """The commanded switch state (0/1) per point, from the netlist's switch probe."""
        combination, threshold = netlist.probes["switch"]
        value = sum(coefficient * self.vectors[name] for name, coefficient in combination.items())
        return (value >= threshold).astype(np.int8)


def _worker(text: str, progress: str | None = None) -> dict:
    """Runs inside the worker: load, run, collect. Returns plain data (picklable). ``progress``: a file that
    gets ngspice's percentage of its transient each time it reports one (every 0.1 %)."""
    import logging
    logging.getLogger("PySpice").setLevel(logging.CRITICAL)
    from PySpice.Spice.NgSpice.Shared import NgSpiceShared
    ng = NgSpiceShared.new_instance()
    ng.remove_circuit() if ng.plot_names and ng.last_plot not in ("const",) else None
    ng.destroy()
    ng._stdout.clear()
    ng._stderr.clear()
    if progress is not None:
        def stat(message: str, ngspice_id: int) -> int:
            found = _PERCENT.search(message)
            if found:
                with open(progress, "w") as out:
                    out.write(found.group(1))
            return 0
        ng.send_stat = stat
    start = time.perf_counter()
    try:
        ng.load_circuit(text)
        ng.run()
    except Exception as exc:  # PySpice raises on any stderr line it does not like
        return {"error": f"{type(exc).__name__}: {exc}", "log": "\n".join(ng._stdout + ng._stderr)}
    wall = time.perf_counter() - start
    log = "\n".join(ng._stdout + ng._stderr)
    plot_name = ng.last_plot
    if not plot_name.startswith("tran"):
        return {"error": "no transient result", "log": log}
    plot = ng.plot(None, plot_name)
    vectors = {name.lower(): np.array(vec._data, dtype=float) for name, vec in plot.items()}
    stats = ng.exec_command("rusage accept")
    accepted = re.search(r"(\d+)", stats or "")
    version = re.search(r"ngspice-(\S+)", "\n".join(ng.exec_command("version -s", join_lines=False) or []))
    ng.remove_circuit()
    ng.destroy()
    return {"vectors": vectors, "wall": wall, "log": log,
            "accepted": int(accepted.group(1)) if accepted else -1,
            "version": ("ngspice-" + version.group(1)) if version else "ngspice"}


class SpiceRunner:
    """ngspice runs in one recycled worker process (:class:`converters.parallel.ProcessSlot`: a fresh
    process every ``RUNS_PER_WORKER`` runs, terminated past ``TIMEOUT_S``, ending with its parent)."""

    def __init__(self):
        # fork: the worker needs nothing re-imported; only the worker ever loads libngspice.
        self._slot = ProcessSlot(tasks_per_process=RUNS_PER_WORKER)

    def run(self, netlist: Netlist) -> SpiceResult:
        if not isinstance(netlist, Netlist):
            raise TypeError("run() takes a netlists.Netlist (built from validated parameters)")
        check_spice_memory(netlist)
        limit = time_limit(TIMEOUT_S)
        handle, progress = tempfile.mkstemp(prefix="pcsuite-ngspice-", suffix=".progress")
        os.close(handle)

        def reached() -> float | None:
            """The fraction of its transient ngspice has reported (every 0.1 %); None before its first report."""
            try:
                with open(progress) as read:
                    return float(read.read()) / 100.0
            except (OSError, ValueError):
                return None

        def watch(elapsed: float) -> None:
            # at most (reached + 0.1 %) done in `elapsed`: a pace that needs CRAWL_FACTOR times the limit or more
            # will not finish within it (a 16-stage Dickson pump's 10 ps clock edges through sharp diodes: 0.1 %
            # of 30 periods in 300 s). Judged only once ngspice has reported its progress at all.
            done = reached()
            if done is not None and elapsed >= CRAWL_AFTER_S and elapsed / (done + 1e-3) > CRAWL_FACTOR * limit:
                raise SpiceError(_crawl_message(netlist, done, elapsed, limit))
        try:
            out = self._slot.call(_worker, netlist.text, progress, timeout=limit, watch=watch,
                                  every=WATCH_EVERY_S)
        except futures.process.BrokenProcessPool:
            raise SpiceError(f"ngspice worker crashed while simulating {netlist.converter}; the run is lost, "
                             "the caller is unaffected (try a larger TMAX or METHOD=gear)") from None
        except futures.TimeoutError:
            raise SpiceError(f"ngspice did not finish {netlist.converter} within the time limit of {limit:g} s "
                             f"(it had reached {100 * (reached() or 0.0):.1f} % of its {netlist.t_end:.3g} s); raise "
                             "it with --time-limit S (or PCSUITE_TIME_LIMIT), or run fewer periods or a larger "
                             "--spice-tmax") from None
        finally:
            os.unlink(progress)
        if "error" in out:
            reason = _reason(out["log"]) or out["error"]
            raise SpiceError(f"ngspice failed on {netlist.converter}: {reason}")
        vectors = out["vectors"]
        if "time" not in vectors or vectors["time"].size < 2 or vectors["time"][-1] < 0.999 * netlist.t_end:
            reason = _reason(out["log"]) or "the transient stopped early"
            raise SpiceError(f"ngspice failed on {netlist.converter}: {reason}")
        return SpiceResult(time=vectors["time"], vectors=vectors, ngspice_version=out["version"], wall_s=out["wall"],
                           accepted_steps=out["accepted"], log=out["log"],
                           options={**netlist.options.__dict__, "t_end": netlist.t_end})

    def close(self):
        self._slot.close()


#: Measured bytes per ngspice point and vector, the vectors' copies in ngspice, PySpice, the pickle from the
#: worker and the labelled Trajectory included (benchmarks/spice_memory.py).
BYTES_PER_POINT_VECTOR = 32.0
_TRAN = re.compile(r"^\.tran\s+(\S+)\s+(\S+)\s+\S+\s+(\S+)", re.IGNORECASE | re.MULTILINE)


def spice_points(netlist: Netlist) -> float:
    """Points ngspice will store: at least t_end / TMAX (its step never exceeds TMAX), and 1.5 times that for
    the steps it adds at every edge (measured: 1.22 on the buck at T/200; 2.44 M points peaked at 750 MB)."""
    match = _TRAN.search(netlist.text)
    if not match:
        return 0.0
    t_end, tmax = float(match.group(2)), float(match.group(3))
    return 1.3 * t_end / tmax + 1000.0


def check_spice_memory(netlist: Netlist, remedy: str = "fewer periods, a shorter --t-end or a larger --spice-tmax") -> None:
    """Refuse, before ngspice starts, a run whose points exceed the memory limit (:mod:`converters.limits`)."""
    points = spice_points(netlist)
    vectors = sum(1 for line in netlist.text.splitlines() if line[:1].isalpha()) + 4
    check_memory(f"ngspice on {netlist.converter}: {netlist.t_end:.3g} s at TMAX {1.3 * netlist.t_end / (points - 1000):.3g} s "
                 f"(about {points:.3g} points x {vectors} vectors)" if points > 1000 else f"ngspice on {netlist.converter}",
                 points * vectors * BYTES_PER_POINT_VECTOR, remedy=remedy)


def _reason(log: str) -> str:
    for line in log.splitlines():
        if _FATAL.search(line) and "warning" not in line.lower():
            return line.strip()
    return ""


_default = None


def close_spice_worker():
    """Shut the shared ngspice worker down (a pool worker must do this before it exits, or the
    multiprocessing exit handler would wait for the idle ngspice worker forever)."""
    if _default is not None:
        _default.close()


def run_spice(netlist: Netlist) -> SpiceResult:
    """Run one netlist in the shared worker (created on first use)."""
    global _default
    if _default is None:
        _default = SpiceRunner()
        atexit.register(_default.close)  # shut the worker down before the interpreter tears down
    return _default.run(netlist)


#: A device conducts when its current exceeds this fraction of the peak device current in the window
#: (0.1 %: far above the diode's 1e-14 A saturation current, far below any real conduction current).
CURRENT_FRACTION = 1e-3


def spice_trajectory(model, params: dict, netlist: Netlist, result: SpiceResult, window_start: float = 0.0):
    """An ngspice run as a Trajectory labelled by the model: states, ``vout`` and ``switch`` from the
    netlist's probes, and each pair's device conducting where its current exceeds CURRENT_FRACTION of the
    peak device current after ``window_start``; the modes then follow from the model's own rule."""
    from converters.trajectory import Trajectory
    t = result.time
    # the circuit's states, then the controller's the netlist probes (a compensator's capacitors)
    names = tuple(model.state_names) + tuple(name for name in model.problem(params, 1.0).state_names[
        len(model.state_names):] if name in netlist.probes)
    x = np.column_stack([result.signal(netlist.probes[name]) for name in names])
    currents = np.column_stack([result.signal(netlist.probes[name]) for name in netlist.pairs])
    in_window = t >= window_start
    conducting = currents > CURRENT_FRACTION * np.abs(currents[in_window]).max()
    measured = {"vout": result.signal(netlist.probes["vout"]), "switch": result.switch(netlist),
                **{name: currents[:, i] for i, name in enumerate(netlist.pairs)}, "conducting": conducting}
    return Trajectory(t=t, x=x, state_names=names, method="spice", steps=result.accepted_steps,
                      wall_s=result.wall_s, rule="linear", labels=model.labels(params), measured=measured,
                      period=model.period(params),
                      metadata={"spice_options": result.options, "ngspice": result.ngspice_version,
                                "model": model.name, "params": params})


#: The fraction of a switch's hysteresis band inside its edges where ngspice's change of state is read.
HYSTERESIS_SLACK = 0.01
#: The fraction of closings a narrow reading may miss before the wider one is taken (:func:`hysteretic`).
MISSED_CLOSINGS = 0.02


def hysteretic(control: np.ndarray, threshold: float, band: float) -> np.ndarray:
    """A switch's state along its control signal: closed once the control exceeds threshold + band, open once it
    falls below threshold - band, the last of these held in between (the state at the start from the threshold
    alone). ngspice changes a switch at its own time points, the control up to 0.3 % of the band short of the
    edge (a hysteretic buck): the edges are read HYSTERESIS_SLACK of the band inside. Its samples may also
    straddle an edge by the control's change over one of its steps (an inductor current falling 2.5 mA in a 5 ns
    step, 0.6 % of a 0.4 A band), and a change of state is then missed: where reading the edges 1.5 such changes
    inside (their 99th percentile: a ramp's reset is no step; at most a quarter of the band) finds more than
    MISSED_CLOSINGS more closings (a second hysteretic phase's switch: 1,614 read narrowly, 2,918 widely), that
    reading is the switch's; a few missed (the one-phase buck's 13 of 2,906) keep the narrow reading, whose edges
    are not read early."""
    narrow = _hysteresis(control, threshold, band, HYSTERESIS_SLACK * band)
    steps = np.abs(np.diff(control))
    slack = min(1.5 * float(np.percentile(steps, 99)) if steps.size else 0.0, 0.25 * band)
    if slack > HYSTERESIS_SLACK * band:
        wide = _hysteresis(control, threshold, band, slack)
        closings = [np.count_nonzero(np.diff(state.astype(np.int8)) > 0) for state in (narrow, wide)]
        if closings[1] > (1.0 + MISSED_CLOSINGS) * closings[0]:
            return wide
    return narrow


def _hysteresis(control: np.ndarray, threshold: float, band: float, slack: float) -> np.ndarray:
    marks = np.where(control > threshold + band - slack, 1, np.where(control < threshold - band + slack, 0, -1))
    if marks.size and marks[0] < 0:
        marks[0] = int(control[0] > threshold)
    last = np.maximum.accumulate(np.where(marks >= 0, np.arange(marks.size), 0))
    return marks[last].astype(bool)


#: A device's peak current, the scale of CURRENT_FRACTION, is its largest mean over this fraction of the window (or
#: of the period): a spike of ngspice's at a switch's edge (-88 A and +20 A within 2e-13 s in a two-switch forward's
#: clamp diode, whose current is 1.27 A) carries no charge to speak of and must not set the scale (it read the diode
#: off at 7 mA).
PEAK_AVERAGE_FRACTION = 1e-3


def conducting_by_current(currents: np.ndarray, in_window: np.ndarray, t: np.ndarray | None = None,
                          period: float | None = None) -> np.ndarray:
    """Each device (column) conducting where its current exceeds CURRENT_FRACTION of its own peak in the window:
    with the times ``t``, the peak of its mean over PEAK_AVERAGE_FRACTION of the ``period`` (or of the window)."""
    if not in_window.any() or currents.shape[1] == 0:
        return currents > 0.0
    if t is None:
        peaks = np.abs(currents[in_window]).max(axis=0)
    else:
        times, magnitude = t[in_window], np.abs(currents[in_window])
        span = period if period is not None and np.isfinite(period) else float(times[-1] - times[0])
        width = PEAK_AVERAGE_FRACTION * span
        if width <= 0.0:
            peaks = magnitude.max(axis=0)
        else:
            charge = np.vstack([np.zeros(magnitude.shape[1]),
                                np.cumsum(0.5 * (magnitude[1:] + magnitude[:-1]) * np.diff(times)[:, None], axis=0)])
            starts = times[times <= times[-1] - width]
            if not starts.size:
                peaks = magnitude.max(axis=0)
            else:
                ahead = np.column_stack([np.interp(starts + width, times, charge[:, j])
                                         - np.interp(starts, times, charge[:, j]) for j in range(magnitude.shape[1])])
                peaks = ahead.max(axis=0) / width if ahead.size else magnitude.max(axis=0)
    return currents > CURRENT_FRACTION * peaks


def mode_labels(switch_names, closed: np.ndarray, diode_names, conducting: np.ndarray) -> np.ndarray:
    """A circuit's mode per point: its closed switches and conducting diodes (``S1+D2``; ``off`` when none)."""
    names = [n.upper() for n in switch_names] + [n.upper() for n in diode_names]
    flags = np.concatenate([closed, conducting], axis=1).astype(bool)
    keys, inverse = np.unique(flags, axis=0, return_inverse=True)
    text = np.array(["+".join(n for n, on in zip(names, key) if on) or "off" for key in keys], dtype=object)
    return text[np.asarray(inverse).reshape(-1)] if len(flags) else np.empty(0, dtype=object)


def circuit_trajectory(circuit, params: dict, netlist: Netlist, result: SpiceResult, window_start: float = 0.0):
    """An ngspice run of a netlist (:func:`netlists.circuit.circuit_netlist`) as a Trajectory labelled by its
    Circuit: the states, every node voltage and every current ngspice measures (sources, inductors, diodes and
    switches through their sense sources; resistors from their nodes), ``vout`` and ``switch``, and the mode of
    each point from the diodes conducting (current above CURRENT_FRACTION of the largest after
    ``window_start``) and the switches closed (:func:`hysteretic` on the control voltage, or a W switch's current,
    against the model's threshold and hysteresis)."""
    from converters.trajectory import Trajectory
    t = result.time
    compiled = circuit.compiled(params)
    x = np.column_stack([result.signal(netlist.probes[name]) for name in compiled.state_names])
    measured = {}
    for name in compiled.signal_names:
        if name in netlist.probes:
            measured[name] = result.signal(netlist.probes[name])
    nodes = lambda n: np.zeros_like(t) if n == "0" else measured.get(f"v({n})", np.full_like(t, np.nan))   # noqa: E731
    for e in circuit.netlist.elements:
        if e.kind == "R" and e.value:           # a 0 ohm resistor is a 0 V source: its current is a probe
            measured[f"i({e.name})"] = (nodes(e.nodes[0]) - nodes(e.nodes[1])) / e.value
    for name in compiled.signal_names:
        measured.setdefault(name, np.full_like(t, np.nan))
    for vector in circuit.signal_names:      # the output and each .meas vector that is a difference v(a,b)
        if vector not in measured and vector.startswith("v(") and "," in vector:
            a, b = vector[2:-1].split(",")
            measured[vector] = nodes(a.strip()) - nodes(b.strip())
    measured["vout"] = measured[circuit.output]
    in_window = t >= window_start
    diodes = [d for d in compiled.pair_names if d != "none"]
    conducting = conducting_by_current(np.column_stack([measured[f"i({d})"] for d in diodes]) if diodes
                                       else np.zeros((t.size, 0)), in_window, t, circuit.period(params))
    closed = []
    for s in (e for e in circuit.netlist.elements if e.kind in "SW"):
        model = circuit.netlist.models[s.model].params
        if s.kind == "S":
            control, threshold, band = nodes(s.nodes[2]) - nodes(s.nodes[3]), model.get("VT", 0.0), model.get("VH", 0.0)
        else:
            control, threshold, band = measured[f"i({s.control[0]})"], model.get("IT", 0.0), model.get("IH", 0.0)
        closed.append(hysteretic(control, threshold, abs(band)))
    # a diode across a closed switch (a body diode) shares its current in ngspice (its near-ideal drop against the
    # switch's RON); the LCS gives the switch all of it: the diode is not counted as conducting there either
    switches = [e for e in circuit.netlist.elements if e.kind in "SW"]
    by_name = {e.name: e for e in circuit.netlist.elements}
    for i, d in enumerate(diodes):
        terminals = set(by_name[d].nodes)
        for s, on in zip(switches, closed):
            if set(s.nodes[:2]) == terminals:
                conducting[:, i] &= ~on
    measured["switch"] = closed[0].astype(np.int8) if closed else np.zeros(t.size, np.int8)
    closed = np.column_stack(closed) if closed else np.zeros((t.size, 0), dtype=bool)
    labels = mode_labels(compiled.switch_names, closed, diodes, conducting)
    measured["mode"] = labels
    measured["conducting"] = conducting
    measured["closed"] = closed
    return Trajectory(t=t, x=x, state_names=tuple(compiled.state_names), method="spice", steps=result.accepted_steps,
                      wall_s=result.wall_s, rule="linear", labels=circuit.labels(params), measured=measured,
                      period=circuit.period(params),
                      metadata={"spice_options": result.options, "ngspice": result.ngspice_version,
                                "model": circuit.name, "params": params})


#: Times a netlist's ngspice run is retried with TMAX a quarter of the last after "timestep too small".
TMAX_RETRIES = 3
#: The tolerances ngspice's users in power electronics reach for when a near-ideal diode stops it: ABSTOL 1 uA
#: (the default 1 pA asks every branch current, a 0 V sense source's in series with a diode whose N = 0.001 makes
#: its current exponential in 26 uV, to converge to 1 pA) and a 1 pF junction capacitance (a bridge's output
#: floats while its diodes block; the charge is far below any run's). Measured: the capacitor-input bridges and
#: the Cockcroft-Walton ladder, which stopped at their first commutation, run with both, not with either alone.
#: METHOD stays gear: trap rings on the bridge's commutations (all four diodes read conducting in turn).
CONVERGENCE_FALLBACK = {"abstol": 1e-6, "diode_cjo": 1e-12}


def run_spice_retrying(build, options=None):
    """(netlist, result, notes) of ``build(options)`` run in ngspice; a run that stops with "timestep too small"
    (ngspice's Newton failing at its minimum step, typically on a near-ideal diode that an ideal switch's edge
    turns off or a commutation between diodes) is run again, first with the CONVERGENCE_FALLBACK tolerances (where
    the options are looser already, skipped), then with TMAX a quarter of the last, up to TMAX_RETRIES times:
    smaller steps before the edge give its Newton a closer start. The notes say what it took."""
    from dataclasses import replace

    from netlists import SpiceOptions
    options = options or SpiceOptions()
    notes = []
    fallback = options.abstol >= CONVERGENCE_FALLBACK["abstol"] and options.diode_cjo > 0
    attempt = 0
    while True:
        netlist = build(options)
        try:
            return netlist, run_spice(netlist), notes
        except SpiceError as error:
            if "timestep too small" not in str(error).lower():
                raise
            reason = str(error).split(': ', 1)[-1]
            if attempt == TMAX_RETRIES:
                raise SpiceError(f"{error}, after {len(notes)} runs more (ABSTOL {options.abstol:g} A, diode CJO "
                                 f"{options.diode_cjo:g} F, TMAX down to {options.tmax_fraction:g} T): ngspice's "
                                 "near-ideal devices do not converge on this circuit at RELTOL "
                                 f"{options.reltol:g}; compare and simulate take a looser --spice-reltol (1e-2 ran an "
                                 "LLC's output bridge behind an ideal transformer) and --spice-method gear or trap"
                                 ) from None
            if not fallback:
                fallback = True
                notes.append(f"ngspice stopped ({reason}); run again with ABSTOL {CONVERGENCE_FALLBACK['abstol']:g} A, "
                             f"diode CJO {CONVERGENCE_FALLBACK['diode_cjo']:g} F")
                options = replace(options, **CONVERGENCE_FALLBACK)
                continue
            attempt += 1
            notes.append(f"ngspice stopped with TMAX = {options.tmax_fraction:g} T ({reason}); "
                         f"run again with TMAX = {options.tmax_fraction / 4:g} T")
            options = replace(options, tmax_fraction=options.tmax_fraction / 4)
