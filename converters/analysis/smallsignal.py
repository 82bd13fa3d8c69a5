"""The exact small-signal model of a switched circuit about its periodic orbit: frequency responses and loop gains.

A small sinusoidal perturbation of an input u (a source's value, the duty ratio, the comparator's input) drives
the linearisation of the circuit about its periodic orbit, a linear T-periodic system: inside each segment of the
orbit dx' = A_i dx + b_i du (b_i the derivative of the mode's field with respect to u), and at each event the
saltation dx+ = S dx- + s_u du, where an event's time moves with the state and with u,

    S = J + (f+ - J f-) n^T / (n^T f- + dg/dt),   s_u = (f+ - J f-) g_u / (n^T f- + dg/dt) + J_u

(n the gradient of the event's guard g, g_u its derivative in u, J the jump of a Moreau impulse, f-/f+ the fields
before and after; a time-driven edge whose instant t_e moves with u, as the duty ratio moves the turn-off, has
n = 0, dg/dt = 1, g_u = -dt_e/du). For du = e^{jwt} the steady response is dx = e^{jwt} p(t) with p T-periodic:
p' = (A_i - jw) p + b_i, p+ = S p- + s_u, and the output's component at w is the mean over one period of
r_i p + r_u (its row in each mode), plus, where the output steps at an event (vout through a capacitor's ESR
when a diode starts to carry), that step times the event's move. Per frequency that is one matrix exponential per segment of the augmented
[p; integral; 1] and one linear solve for the periodic p: exact (no averaging), at every frequency up to and beyond
fs/2. Its poles are the Floquet multipliers' (a response is infinite where e^{jwT} is one).

Everything the linearisation needs is read from one event-method run over the orbit (its ``timeline``) and, for
the input's derivatives, from the same modes' flows with the input moved by a finite amount: the circuit is affine
in its sources and an edge's instant in the duty ratio, so that difference is exact to rounding. An input that
changes a mode's matrices (an inductance, a load resistance) drives p' = (A_i - jw) p + dA_i x(t) + dE_i along the
orbit's own x(t) (the augmented [p; integral; x~] per segment), its matrices' derivatives by a five-point
difference; at w = 0 the periodic p is the implicit function theorem's dx*/dp, the steady state's exact
sensitivity (:mod:`converters.analysis.sensitivity`).

The loop gain of a state-driven law s = c x + d - ramp is Middlebrook's injection (R. D. Middlebrook, "Measurement
of loop gain in feedback systems", Int. J. Electronics 38, 1975), read on the exact model: a perturbation added
to the comparator's input, Y the response of the sensed c x to it, T = -Y / (1 + Y).
"""
from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, cast

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError, SimulationError
from ..problems import Comparators, Schedule, StateSwitching
from ..methods.event.timeline import Crossing, Edge, FlowSpan
from ..trajectory import Samples

if TYPE_CHECKING:
    import control

    from ..methods.base import PeriodMap
    from ..methods.event.flow import Flow
    from ..models.base import Model
    from ..models.compensator import Compensator
    from ..params import Param
    from ..problems import LCSProblem
    from .periodic import PeriodicOrbit

    #: The event method's LCS engine of a problem (EventDriven.engine's: a private class of the method, read here
    #: through its flows, guard rows, impulses and runs).
    Machine = Any

#: The comparator's input of a state-driven law (a perturbation added to its switching function s).
CONTROL = "control"
#: Frequencies of a response by default: this many, log-spaced from fs/1000 to fs/2.
POINTS = 200
MAX_POINTS = 100_000
#: The highest frequency a response is asked at, in switching frequencies (a switched circuit's small-signal
#: response far above fs is its sidebands'; at 1e300 Hz the phase factors overflowed to NaN, printed with exit 0).
MAX_FS_MULTIPLE = 1000.0
#: The longest common period (in switching periods) a brute-force check simulates: a frequency below fs/this
#: (1e-6 Hz under a 100 kHz switch asked for a 1e11-period run, 745 GiB) is refused.
MAX_CHECK_PERIODS = 20_000
#: The finite move of an input for its derivatives (relative to its value, at least this absolute amount): the
#: circuit is affine in it, so the difference is exact to rounding.
RELATIVE_MOVE = 1e-3
#: An orbit whose mode sequence changes within this fraction of the period (a mode this short, or a pair's guard
#: reaching 0 this soon after another event) lies at a border: its derivatives are one-sided
#: (:meth:`SmallSignalModel.border`).
BORDER_PERIODS = 1e-6
#: The move of a parameter of the dynamics (relative to its value) in its five-point difference.
DYNAMIC_MOVE = 1e-5
#: Its move in a three-point one-sided difference (at the end of its range: a resistance at 0), whose error is of
#: order move^2 where the five-point's is move^4: at 1e-5 the matrices' rounding over the move had put the buck's
#: d vout / d rl at 0 1.2e-4 off (-0.6736114 for -0.6735335; its ESR's 4e-4); at 1e-3 both agree with differences
#: of exact orbits to 1e-6.
ONE_SIDED_MOVE = 1e-3


@dataclass(frozen=True)
class FrequencyResponse:
    """A frequency response of the exact small-signal model.

    Attributes
    ----------
    frequency_hz : ndarray
        Frequencies (Hz).
    response : ndarray (complex)
        The output's phasor per unit input phasor at each frequency (output unit per input unit).
    input, output : str
        What was perturbed and what was read; ``kind`` is ``transfer`` or ``loop gain``.
    period : float
        The switching period T (s) of the orbit it is taken about.
    multipliers : ndarray
        The orbit's Floquet multipliers (the poles of every response).
    """

    frequency_hz: np.ndarray
    response: np.ndarray
    input: str
    output: str
    kind: str
    period: float
    multipliers: np.ndarray
    input_unit: str = ""
    output_unit: str = ""

    @property
    def magnitude_db(self) -> np.ndarray:
        return 20.0 * np.log10(np.abs(self.response))

    @property
    def phase_deg(self) -> np.ndarray:
        """Phase (degrees), unwrapped along the frequencies, the first in (-180, 180]."""
        return np.degrees(np.unwrap(np.angle(self.response)))

    def frd(self) -> control.FrequencyResponseData:
        """The response as a python-control frequency-response data object (``control.FRD``, rad/s)."""
        import control
        return control.frd(self.response, 2.0 * np.pi * self.frequency_hz)

    def as_dict(self) -> dict:
        out = {"input": self.input, "output": self.output, "kind": self.kind, "period_s": self.period,
               "input_unit": self.input_unit, "output_unit": self.output_unit,
               "frequency_hz": self.frequency_hz.tolist(), "magnitude_db": self.magnitude_db.tolist(),
               "phase_deg": self.phase_deg.tolist(),
               "multipliers": [[float(m.real), float(m.imag)] for m in self.multipliers]}
        return out


@dataclass(frozen=True)
class Margins:
    """Stability margins of a loop gain: the gain crossover (|T| = 1) and phase margin 180 + angle T there, the
    phase crossover (angle T = -180) and gain margin -20 log10 |T| there; NaN where the loop gain has none in the
    frequencies searched."""

    crossover_hz: float
    phase_margin_deg: float
    phase_crossover_hz: float
    gain_margin_db: float

    def as_dict(self) -> dict:
        return {"crossover_hz": self.crossover_hz, "phase_margin_deg": self.phase_margin_deg,
                "phase_crossover_hz": self.phase_crossover_hz, "gain_margin_db": self.gain_margin_db}


class SmallSignalModel:
    """The linearisation of a model about its periodic orbit for one input (module docstring).

    ``response(f)`` evaluates it at any frequencies (Hz) for any output it was built with."""

    def __init__(self, model: Model | str, params: dict | None = None, *, input: str,
                 outputs: Iterable[str] = ("vout",), tol: float = 1e-9, orbit: PeriodicOrbit | None = None):
        from ..methods import EventDriven
        from .periodic import ANALYSIS_REMEDY, require, shoot
        if isinstance(model, str):
            from ..models import get_model
            model = get_model(model)
        self.model = model
        self.params = p = model.resolve(params)
        if not model.periodic(p):
            raise ParameterError(f"{model.key} has no switching period (an autonomous law): the small-signal model "
                                 "is taken about a periodic orbit of a clocked circuit")
        if model.step_times(p):
            raise ParameterError("a load or input step has no periodic orbit to linearise about; leave out t_step, "
                                 "R_step and Vin_step (a step's response is simulate's)")
        self.input = input
        self.method = method = EventDriven()
        self.T = T = model.period(p)
        problem = model.problem(p, T)
        if getattr(problem, "inputs", None) is not None:
            raise ParameterError(f"{model.key} has sinusoidal sources (SIN): the small-signal model is taken about the "
                                 "periodic orbit of a circuit with constant sources and a clock")
        if isinstance(problem.switching, Comparators):
            raise ParameterError(f"{model.key} switches on {len(problem.switching.channels)} comparators: the "
                                 "small-signal model is built for one comparator or a schedule")
        if orbit is None:
            orbit = require(shoot(problem, method, problem.x0, tol=tol), f"the periodic orbit of {model.key}",
                            remedy=ANALYSIS_REMEDY)
        self.orbit = orbit
        problem = model.problem(p, T, orbit.x0)
        self.n = problem.n
        self.machine = method.engine(problem)
        self.timeline = self.machine.timeline(self.orbit.x0)
        self.stencil, self.dynamic = self._stencil(problem, method.engine)
        self.law = problem.switching
        self.outputs = tuple(outputs)
        self.pieces = self._pieces()

    # --- the input's derivatives ---------------------------------------------------------------------------

    def _stencil(self, problem: LCSProblem, engine: Callable[[LCSProblem], Machine]) -> tuple:
        """(stencil, dynamic): the machines of the problem at moved values of the input, as [(machine, params,
        weight)] with the derivative of any quantity X read as sum(weight X(machine, params)), and whether the input
        changes a mode's matrices. A source, a reference, the duty ratio or the comparator's input enters affinely:
        one finite move, exact to rounding. A parameter of the dynamics (an inductance, a load, a capacitance) enters
        smoothly, not affinely: a five-point central difference (error of order move^4, 1e-12 here), or a
        three-point one-sided one at the edge of its range (ONE_SIDED_MOVE: error of order 1e-6)."""
        model, p, name = self.model, self.params, self.input
        law = problem.switching
        if name == CONTROL:
            if not isinstance(law, StateSwitching):
                raise ParameterError(f"input {CONTROL!r} is the comparator's input of a state-driven law; "
                                     f"{model.key} is driven by a schedule: use input 'D' (the duty ratio)")
            ramp = law.function.ramp
            delta = RELATIVE_MOVE * (abs(ramp.high - ramp.low) if ramp is not None and ramp.high != ramp.low
                                     else max(abs(law.function.d), 1.0))
            moved = replace(problem, switching=replace(law, function=replace(law.function, d=law.function.d + delta)))
            return [(engine(moved), p, 1.0 / delta), (self.machine, p, -1.0 / delta)], False
        key = model.parameter_name(name)
        names = [q.name for q in model.parameters]
        if key not in names:
            raise ParameterError(f"input must be {CONTROL!r} (a state-driven law) or one of the parameters "
                                 f"{', '.join(names)}; got {name!r}")
        param = next(q for q in model.parameters if q.name == key)
        value = p.get(key)
        if value is None:
            raise ParameterError(f"input {name!r} has no value here (an optional parameter that is not set); give "
                                 f"it one with -p {name}=VALUE")
        given = {k: v for k, v in p.items() if v is not None}
        refused: list[str] = []

        def at(offset: float) -> tuple[Machine, dict, LCSProblem] | None:
            """(machine, params) with the input moved by ``offset``, None outside its range."""
            try:
                moved_p = model.resolve({**given, key: value + offset})
                # a netlist's .param has no range of its own: the element it sets refuses the value (a resistance
                # at 0 moved to -2e-5, which had left rl, rc and rd "not taken")
                moved = model.problem(moved_p, self.T, self.orbit.x0)
            except ParameterError as why:
                refused.append(str(why))
                return None
            if moved.switching.period != problem.switching.period:
                raise ParameterError(f"input {name!r} changes the switching period: the small-signal model is taken "
                                     "about an orbit of one period; its inputs are sources, references, the duty ratio, "
                                     "element values or a comparator's input")
            return engine(moved), moved_p, moved

        scale = max(abs(value), 1.0)
        edges = len(law.starts) if isinstance(law, Schedule) else None
        for delta in (RELATIVE_MOVE * scale, -RELATIVE_MOVE * scale):
            found = at(delta)
            # a move that adds or removes a schedule's edge (the duty ratio 0.999 moved to 1) is no derivative of the
            # edges there: the other side's is (it had been refused as "a duty ratio of 0 or 1")
            if found is not None and (edges is None or len(getattr(found[2].switching, "starts", ())) == edges):
                break
        else:
            if edges is not None and any(found is not None for found in (at(RELATIVE_MOVE * scale),
                                                                        at(-RELATIVE_MOVE * scale))):
                raise ParameterError(f"input {name!r} = {value!r}: any move of it adds or removes a switching edge "
                                     "(a duty ratio of 0 or 1, where the converter does not switch): the response "
                                     "there is one-sided, no small-signal model; take it inside (0, 1)")
            raise ParameterError(f"input {name!r} = {value!r} cannot be moved inside its range {param.range_text()}")
        machine, moved_p, moved = found
        if not _changes_matrices(problem, moved):
            return [(machine, moved_p, 1.0 / delta), (self.machine, p, -1.0 / delta)], False
        for offsets, weights, denominator in STENCILS:
            h = (DYNAMIC_MOVE if 0 not in offsets else ONE_SIDED_MOVE) * move_scale(param, value)
            points = [(self.machine, p, problem) if k == 0 else at(k * h) for k in offsets]
            if all(point is not None for point in points):
                found_all = cast("list[tuple[Machine, dict, LCSProblem]]", points)      # (all() does not narrow)
                return [(m, q, w / (denominator * h)) for (m, q, _), w in zip(found_all, weights)], True
        scale = move_scale(param, value)
        raise ParameterError(f"input {name!r} = {value!r} cannot be moved by +-{2 * DYNAMIC_MOVE * scale:g}, nor by "
                             f"{2 * ONE_SIDED_MOVE * scale:g} to one side, inside its range {param.range_text()}"
                             + (f" ({refused[-1]})" if refused else ""))

    @property
    def moved(self) -> Machine:
        """The machine with the input moved by :attr:`delta`, for an input that moves sources only (what the
        injection check perturbs)."""
        if self.dynamic:
            raise ParameterError(f"input {self.input!r} changes the circuit's matrices; the injection check perturbs a "
                                 "source, a reference, the duty ratio or a comparator's input")
        return self.stencil[0][0]

    @property
    def delta(self) -> float:
        return 1.0 / self.stencil[0][2]

    def _derivative(self, quantity: Callable[[Machine, dict], npt.ArrayLike]) -> np.ndarray:
        """d quantity / d input: ``quantity(machine, params)`` read on the stencil."""
        return sum(w * np.asarray(quantity(m, q), dtype=float) for m, q, w in self.stencil)

    def _field_derivative(self, flow: Flow) -> np.ndarray:
        """d[A E] / du of a mode (n x (n + 1)): its last column alone for an input that moves only the sources."""
        n = self.n
        return self._derivative(lambda m, q: m.flow(flow.config, flow.held).Z[:n, :])

    def _output_rows(self, flow: Flow, t: float, name: str) -> tuple[np.ndarray, np.ndarray, float]:
        """(r, dr, r0) of an output in a mode: y = r x + r0, dr = d[r r0]/du (its derivative's row on x~)."""
        n = self.n
        if name == "sensed":                       # the comparator's sensed quantity c x (a state-driven law's)
            return np.asarray(cast(StateSwitching, self.law).function.c, dtype=float), np.zeros(n + 1), 0.0
        if name in self.machine.problem.state_names:
            return np.eye(n)[self.machine.problem.state_names.index(name)], np.zeros(n + 1), 0.0
        xt = np.vstack([np.eye(n + 1)[:n] + np.eye(n + 1)[n], np.eye(n + 1)[n]])     # e_i + "1", then "1"

        def row(machine: Machine, params: dict) -> np.ndarray:
            f = machine.flow(flow.config, flow.held)
            samples = Samples(np.full(n + 1, t), xt[:, :n], xt @ f.u_rows.T, xt @ f.y_rows.T,
                              np.full(n + 1, flow.config), held=np.broadcast_to(f.held_flags, (n + 1, f.held_flags.size)))
            values = np.asarray(self.model.labels(params).signal(name, samples), dtype=float)
            return np.append(values[:n] - values[n], values[n])
        base = row(self.machine, self.params)
        return base[:n], self._derivative(row), base[n]

    def _rows(self, flow: Flow, t: float) -> dict:
        key = (flow.config, flow.held)
        rows = self._row_cache.get(key)
        if rows is None:
            rows = self._row_cache[key] = {name: self._output_rows(flow, t, name) for name in self.outputs}
        return rows

    def _step(self, flow_b: Flow, xt_b: npt.NDArray[np.float64], flow_a: Flow, xt_a: npt.NDArray[np.float64],
              t: float) -> dict:
        """Per output, its jump y- - y+ at an event (what moving the event's instant adds to its integral)."""
        before, after = self._rows(flow_b, t), self._rows(flow_a, t)
        return {name: (before[name][0] @ xt_b[:-1] + before[name][2]) - (after[name][0] @ xt_a[:-1] + after[name][2])
                for name in self.outputs}

    def _jump_offset(self, config: int, xt_before: npt.NDArray[np.float64], t: float) -> np.ndarray:
        """d x+ / du of a Moreau impulse entering ``config`` (zero without one)."""
        quiet = lambda *a: None          # noqa: E731
        return self._derivative(lambda m, q: m.enter(config, xt_before, t, quiet)[0][:-1])

    def _edge_shift(self, t: float, config: int | str) -> float:
        """d t_e / du of a schedule's edge at t entering ``config`` (the duty ratio moves the turn-off)."""
        law = self.machine.problem.switching
        if config == "limit":                 # a latched law's limit (a maximum duty ratio): moved by its own input
            return float(self._derivative(lambda m, q: (m.problem.switching.limit or 0.0) * law.period))
        if not isinstance(law, Schedule):
            return 0.0
        if any(not isinstance(m.problem.switching, Schedule) or len(m.problem.switching.starts) != len(law.starts)
               for m, _, _ in self.stencil):
            raise ParameterError(f"input {self.input!r} at this value changes the schedule's edges (a duty ratio of 0 "
                                 "or 1): no small-signal model there")
        phase = (t - self.machine.problem.t_span[0]) % law.period
        candidates = [i for i, c in enumerate(law.configs) if c == config]
        i = min(candidates, key=lambda i: min(abs(phase - law.starts[i]), law.period - abs(phase - law.starts[i])))
        return float(self._derivative(lambda m, q: m.problem.switching.starts[i]))

    def _pieces(self) -> list:
        """The orbit's segments and events: ("flow", h, A, dZ, {output: (r, dr, r0)}, x~ at its start, Z), and
        ("jump", S, s_u, dt_row, dt_u, {output: y- - y+}) with the event's time moving by dt_row dx- + dt_u du."""
        n, pieces = self.n, []
        self._row_cache: dict = {}
        for item in self.timeline:
            if isinstance(item, FlowSpan):
                flow, t0 = item.flow, item.t0
                pieces.append(("flow", item.t1 - t0, flow.Z[:n, :n], self._field_derivative(flow),
                               self._rows(flow, t0), item.xt0, flow.Z))
            elif isinstance(item, Crossing):
                t, dgdt, f_b, f_a, J, pair = item.t, item.dgdt, item.f_before, item.f_after, item.jump, item.pair
                flow_b, latched_b, xt_b, config = item.flow_before, item.latched_before, item.xt_before, item.config
                flow_a, xt_a = item.flow_after, item.xt_after
                grad = item.row[:n]
                denominator = grad @ f_b + dgdt
                if abs(denominator) <= 1e-12 * (np.abs(grad) @ np.abs(f_b) + abs(dgdt)):
                    raise SimulationError(f"the orbit grazes an event surface at t = {t:.9g} s (the crossing's speed "
                                          "is zero): it has no small-signal model there")
                # the guard g = row x~ + slope (t - the ramp's last reset): its row (the parameters of the dynamics
                # move its state part too), a ramp's level and slope all move with the input
                ramp = self.law.function.ramp if isinstance(self.law, StateSwitching) else None
                phase = float(ramp.phase(t)) if ramp is not None else t - math.floor(t / self.T) * self.T

                def guard(m: Machine, q: dict, config: int = flow_b.config, held: int = flow_b.held,
                          latched: int = latched_b, pair: int = pair, xt: npt.NDArray[np.float64] = xt_b,
                          phase: float = phase) -> float:
                    row_m, slope = ((m.flow(config, held).watch_rows[pair], 0.0) if pair >= 0
                                    else m.switch_row(config, latched))
                    return row_m @ xt + slope * phase
                g_u = float(self._derivative(guard))
                jumped = not np.array_equal(J, np.eye(n))
                j_u = self._jump_offset(config, xt_b, t) if jumped and pair < 0 else np.zeros(n)
                dt_row, dt_u = -grad / denominator, -g_u / denominator
                pieces.append(self._jump(J, f_a - J @ f_b, j_u, dt_row, dt_u, self._step(flow_b, xt_b, flow_a, xt_a, t)))
            else:
                t, kind, config, J = item.t, item.kind, item.config, item.jump
                xt_b, flow_b, flow_a, xt_a = item.xt_before, item.flow_before, item.flow_after, item.xt_after
                shift = self._edge_shift(t, kind) if kind != "reset" else 0.0
                kick = flow_a.field(xt_a) - J @ flow_b.field(xt_b)
                j_u = self._jump_offset(config, xt_b, t) if not np.array_equal(J, np.eye(n)) else np.zeros(n)
                pieces.append(self._jump(J, kick, j_u, np.zeros(n), shift, self._step(flow_b, xt_b, flow_a, xt_a, t)))
        return pieces

    def border(self) -> str:
        """Where the orbit lies within BORDER_PERIODS of the period from a border of its mode sequence, what meets
        there, in one line; "" where it does not. At a border (a boost whose diode current reaches 0 as its switch
        closes: CCM on one side, a DCM interval on the other) the orbit's derivatives are one-sided: the boost's
        normalised d vout / d L read +0.00013 on one side, -0.2857 on the other, with no word. Three signs: a mode
        that a state event begins or ends and that lasts less than that (the modes taken around the period: two
        schedule edges close together swap smoothly), a pair's guard (a held diode's current, a free one's voltage)
        that would reach 0 less than that after its mode ends at another event, or a comparator whose switching
        function, kept on one side through a ramp's reset, was that close to its threshold there (a loop held at a
        duty ratio of 0 or 1: vout / Vref 0 on one side, 0.84 on the other)."""
        from scipy.linalg import expm
        T, names = self.T, self.machine.problem.pair_names
        timeline = self.timeline
        spans = [(i, item) for i, item in enumerate(timeline) if isinstance(item, FlowSpan)]
        nearest, what = BORDER_PERIODS * T, ""
        modes = [(item.flow.config, item.flow.held) for _, item in spans]
        # the modes' lengths around the period (a mode that runs on across the period's end is one)
        changes = [j for j in range(len(spans)) if modes[j] != modes[j - 1]] if len(spans) > 1 else []

        def stated(i: int) -> bool:                       # a state event begins the span that starts after i
            return isinstance(timeline[i], Crossing) if 0 <= i < len(timeline) else False
        for a, b in zip(changes, changes[1:] + [changes[0] + len(spans)] if changes else []):
            length = sum(spans[j % len(spans)][1].t1 - spans[j % len(spans)][1].t0 for j in range(a, b))
            begins, ends = spans[a][0] - 1, spans[(b - 1) % len(spans)][0] + 1
            if length < nearest and (stated(begins) or stated(ends)):
                item = spans[a][1]
                nearest, what = length, f"a mode lasts {length / T:.2g} of the period from t = {item.t0:.6g} s"
        for j, (i, item) in enumerate(spans):
            after = timeline[i + 1] if i + 1 < len(timeline) else None
            flow = item.flow
            xt = expm(flow.Z * (item.t1 - item.t0)) @ item.xt0
            if len(spans) > 1 and modes[(j + 1) % len(spans)] != modes[j]:     # an event ends its mode here
                rows = flow.watch_rows
                # the pair whose own event ends the mode, and those in series with it (one current through a
                # winding and two clamps, a bridge's two diodes: their guards are one, and reach 0 together)
                own = np.zeros(rows.shape[0], dtype=bool)
                if isinstance(after, Crossing) and after.pair >= 0:
                    norms = np.linalg.norm(rows, axis=1)
                    ref = rows[after.pair] / max(norms[after.pair], 1e-300)
                    own = np.abs(rows @ ref) >= (1.0 - 1e-9) * norms
                g, speed = rows @ xt, rows @ (flow.Z @ xt)
                for k in range(g.size):
                    if own[k] or not speed[k] < 0.0:
                        continue
                    until = max(g[k], 0.0) / -speed[k]
                    if until < nearest:
                        quantity = "current" if flow.held_flags[k] == self._currents(flow.config)[k] else "voltage"
                        nearest, what = until, (f"{names[k].upper()}'s {quantity} would reach 0 {until / T:.2g} of "
                                                f"the period after the event at t = {item.t1:.6g} s")
            own_event = isinstance(after, Crossing) and after.pair < 0
            if isinstance(self.law, StateSwitching) and not own_event:
                until = self._comparator_margin(flow, xt, item.t1, ahead=True)
                if until < nearest:
                    nearest, what = until, (f"the comparator's switching function would reach its threshold "
                                            f"{until / T:.2g} of the period after t = {item.t1:.6g} s")
            before = timeline[i - 1] if i > 0 else None
            if (isinstance(self.law, StateSwitching) and isinstance(before, Edge) and before.kind == "reset"
                    and before.flow_before.config == flow.config):
                until = self._comparator_margin(flow, item.xt0, item.t0, ahead=False)
                if until < nearest:
                    nearest, what = until, (f"the comparator's switching function, kept on its side through the "
                                            f"ramp's reset at t = {item.t0:.6g} s, was {until / T:.2g} of the period "
                                            "from its threshold")
        return f"the orbit lies {nearest / T:.2g} of the period from a border of its mode sequence ({what})" if what \
            else ""

    def _comparator_margin(self, flow: Flow, xt: npt.NDArray[np.float64], t: float, ahead: bool) -> float:
        """The time (s) in which the one comparator's switching function s = c x + d - ramp, moving at its rate in
        ``flow`` at state ``xt`` and time ``t``, reaches the threshold that ends its side (ahead), or since it
        would have (not ahead); inf where it moves away (ahead) or toward it (not ahead)."""
        law = cast(StateSwitching, self.law)
        f, n = law.function, self.n
        ramp = f.ramp
        phase = float(ramp.phase(t)) if ramp is not None else 0.0
        if ahead and ramp is not None and phase <= 1e-9 * ramp.period:
            phase = ramp.period                 # a mode that ends at the ramp's reset: the top it reached
        value = float(f.c @ xt[:n] + f.d - (ramp.low + ramp.slope * phase if ramp is not None else 0.0))
        rate = float(f.c @ flow.field(xt) - (ramp.slope if ramp is not None else 0.0))
        below = flow.config == law.below
        g, dg = (law.band - value, -rate) if below else (value + law.band, rate)   # > 0 on its side
        if ahead:
            return max(g, 0.0) / -dg if dg < 0.0 else math.inf
        return max(g, 0.0) / dg if dg > 0.0 else math.inf

    def _currents(self, config: int) -> npt.NDArray[np.bool_]:
        """Per pair, whether u is the device's current in configuration ``config`` (else its voltage)."""
        compiled = getattr(self.model, "compiled", None)
        currents = compiled(self.params).pair_currents if compiled is not None else self.model.pair_currents
        return np.asarray(currents[config], dtype=bool)

    @staticmethod
    def _jump(J: npt.NDArray[np.float64], kick: npt.NDArray[np.float64], j_u: npt.NDArray[np.float64],
              dt_row: npt.NDArray[np.float64], dt_u: float | npt.NDArray[np.float64], steps: dict) -> tuple:
        """An event's piece: dx+ = J dx- - kick dt + j_u du with dt = dt_row dx- + dt_u du (the saltation)."""
        return ("jump", J - np.outer(kick, dt_row), -kick * dt_u + j_u, dt_row, dt_u, steps)

    # --- responses -----------------------------------------------------------------------------------------

    def response(self, frequency_hz: npt.ArrayLike, output: str = "vout") -> np.ndarray:
        """The output's phasor per unit input phasor at each frequency (Hz)."""
        from scipy.linalg import expm
        if output not in self.outputs:
            raise ParameterError(f"output must be one of {', '.join(self.outputs)} (this model was built for "
                                 f"them); got {output!r}")
        f = np.atleast_1d(np.asarray(frequency_hz, dtype=float))
        n, m = self.n, self.n + 2
        jw = 2j * np.pi * f
        G = np.broadcast_to(np.eye(m, dtype=complex), (f.size, m, m)).copy()
        for piece in self.pieces:
            if piece[0] == "flow":
                _, h, A, dZ, rows, xt0, Z = piece
                r, dr, _ = rows[output]
                if not (np.any(dZ[:, :n]) or np.any(dr[:n])):        # the input moves sources only: p' = A p + b
                    M = np.zeros((f.size, m, m), dtype=complex)
                    M[:, :n, :n] = A
                    M[:, range(n), range(n)] -= jw[:, None]
                    M[:, :n, n + 1] = dZ[:, n]
                    M[:, n, :n] = r
                    M[:, n, n + 1] = dr[n]
                    G = expm(M * h) @ G
                    continue
                # the input moves A (and the output's row): p' = A p + dZ x~(t), x~' = Z x~ from the orbit's x~0
                M = np.zeros((f.size, 2 * n + 2, 2 * n + 2), dtype=complex)
                M[:, :n, :n] = A
                M[:, range(n), range(n)] -= jw[:, None]
                M[:, :n, n + 1:] = dZ
                M[:, n, :n] = r
                M[:, n, n + 1:] = dr
                M[:, n + 1:, n + 1:] = Z
                E = expm(M * h)
                P = np.broadcast_to(np.eye(m, dtype=complex), (f.size, m, m)).copy()
                P[:, :n + 1, :n + 1] = E[:, :n + 1, :n + 1]
                P[:, :n + 1, n + 1] = E[:, :n + 1, n + 1:] @ xt0
                G = P @ G
            else:
                _, S, s_u, dt_row, dt_u, steps = piece
                P = np.eye(m, dtype=complex)
                P[:n, :n], P[:n, n + 1] = S, s_u
                P[n, :n], P[n, n + 1] = steps[output] * dt_row, steps[output] * dt_u     # the output's step moves
                G = P @ G
        # the periodic p: p0 = G_pp p0 + G_p1; the integral of the output over the period at that p0
        p0 = np.linalg.solve(np.eye(n) - G[:, :n, :n], G[:, :n, n + 1][..., None])[..., 0]
        integral = np.einsum("fi,fi->f", G[:, n, :n], p0) + G[:, n, n + 1]
        return integral / self.T


#: Derivative stencils, tried in order, as (offsets in steps h, weights, denominator in h): the five-point central
#: difference (error of order h^4), then the three-point one-sided ones (order h^2) where a range ends on one side.
STENCILS = (((-2, -1, 1, 2), (1, -8, 8, -1), 12.0), ((0, 1, 2), (-3, 4, -1), 2.0), ((0, -1, -2), (3, -4, 1), 2.0))


def move_scale(param: Param, value: float) -> float:
    """The scale of a finite move of a parameter: its value, or its distance to the nearer end of its range where
    that is smaller (a coupling k = 0.99 moves on the scale of 1 - k, where the circuit's dependence on it lives),
    or 1 at 0."""
    scale = abs(value) if value != 0.0 else 1.0
    for bound in (param.low, param.high):
        if math.isfinite(bound) and bound != value:
            scale = min(scale, abs(value - bound))
    return scale


def _changes_matrices(problem: LCSProblem, moved: LCSProblem) -> bool:
    """Whether a moved problem's modes differ from the problem's in A, B, C or D (not only in the sources' E, F)."""
    for c, m in zip(problem.configurations, moved.configurations):
        for a, b in ((c.A, m.A), (c.B, m.B), (c.C, m.C), (c.D, m.D)):
            a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
            if not np.allclose(a, b, rtol=1e-12, atol=1e-14 * np.abs(a).max(initial=1.0)):
                return True
    return False


def frequencies(model_period: float, fmin: float | None = None, fmax: float | None = None,
                points: int = POINTS) -> np.ndarray:
    """Log-spaced frequencies (Hz), by default from fs/1000 to fs/2, each bound in (0, MAX_FS_MULTIPLE fs]; one
    frequency with ``points`` = 1 and fmin = fmax."""
    fs = 1.0 / model_period
    fmin = fs / 1000.0 if fmin is None else fmin
    fmax = fs / 2.0 if fmax is None else fmax
    top = MAX_FS_MULTIPLE * fs
    for name, value in (("fmin", fmin), ("fmax", fmax)):
        if not (isinstance(value, (int, float, np.floating)) and not isinstance(value, bool) and math.isfinite(value)
                and 0 < value <= top):
            raise ParameterError(f"{name} must be a frequency in (0, {top:g}] Hz ({MAX_FS_MULTIPLE:g} times the "
                                 f"switching frequency); got {value!r}")
    if not (isinstance(points, (int, np.integer)) and not isinstance(points, bool) and 1 <= points <= MAX_POINTS):
        raise ParameterError(f"points must be an integer in [1, {MAX_POINTS}]; got {points!r}")
    if points == 1 or fmin == fmax:
        if not (points == 1 and fmin == fmax):
            raise ParameterError(f"one frequency is --fmin F --fmax F --points 1; got fmin = {fmin:g} Hz, fmax = "
                                 f"{fmax:g} Hz, points = {points}")
        return np.array([float(fmin)])
    if not fmin < fmax:
        raise ParameterError(f"fmin must be below fmax; got fmin = {fmin:g} Hz, fmax = {fmax:g} Hz")
    return np.geomspace(fmin, fmax, int(points))


def quantity_unit(model: Model, params: dict, name: str) -> str:
    """The unit of an input or output of a response: a parameter's, a signal's, V for vout, none for the duty ratio
    and a comparator's input."""
    units = getattr(model, "signal_units", {})
    if name in ("vout", "sensed"):
        return "V" if name == "vout" else ""
    if name == CONTROL:
        return ""
    from ..trajectory import signal_unit
    key = model.parameter_name(name)
    param = next((q for q in model.parameters if q.name == key), None)
    return param.unit if param is not None else signal_unit(units, name)


def frequency_response(model: Model | str, params: dict | None = None, *, input: str, output: str = "vout",
                       frequency_hz: npt.ArrayLike | None = None, fmin: float | None = None, fmax: float | None = None,
                       points: int = POINTS) -> FrequencyResponse:
    """The exact frequency response from ``input`` (a source's value or a parameter such as ``Vin``, the duty
    ratio ``D``, or ``control``: the comparator's input of a state-driven law) to ``output`` (``vout``, a state,
    or any signal of the model), about the model's periodic orbit at ``params``. Frequencies: ``frequency_hz``, or
    ``points`` log-spaced in [fmin, fmax] (default fs/1000 to fs/2)."""
    small = SmallSignalModel(model, params, input=input, outputs=(output,))
    f = (frequencies(small.T, fmin, fmax, points) if frequency_hz is None
         else np.atleast_1d(np.asarray(frequency_hz, dtype=float)))
    units = (quantity_unit(small.model, small.params, input), quantity_unit(small.model, small.params, output))
    return FrequencyResponse(f, small.response(f, output), input, output, "transfer", small.T, small.orbit.multipliers,
                             *units)


#: Where a loop is broken for its gain: at the comparator's input (every state-driven law), or at the reference of
#: a voltage loop (its error amplifier's input: the outer loop of a current-mode controller).
LOOP_POINTS = ("comparator", "reference")


def loop_gain(model: Model | str, params: dict | None = None, *, at: str = "comparator",
              frequency_hz: npt.ArrayLike | None = None, fmin: float | None = None, fmax: float | None = None,
              points: int = POINTS) -> tuple[FrequencyResponse, Margins]:
    """The loop gain T of a closed loop and its margins (:func:`margins`), Middlebrook's injection read on the exact
    model (module docstring). ``at="comparator"``: a perturbation added to the comparator's input, Y the sensed
    quantity's response, T = -Y / (1 + Y). ``at="reference"``: the loop broken at the error amplifier's input, where
    vout is subtracted from Vref: Y the response of vout to Vref, T = Y / (1 - Y); for a single loop the two are the
    same T, for a current-mode controller the second is its outer (voltage) loop."""
    name, output = loop_signals(at)
    small = SmallSignalModel(model, params, input=name, outputs=(output,))

    def gain(freq: npt.ArrayLike) -> npt.NDArray[np.complex128]:
        return loop_from_closed(small.response(freq, output), at)
    f = (frequencies(small.T, fmin, fmax, points) if frequency_hz is None
         else np.atleast_1d(np.asarray(frequency_hz, dtype=float)))
    response = FrequencyResponse(f, gain(f), name, output, "loop gain", small.T, small.orbit.multipliers)
    return response, margins(gain, f)


def loop_signals(at: str) -> tuple[str, str]:
    """(the input perturbed, the output read) of a loop broken ``at`` one of LOOP_POINTS."""
    if at not in LOOP_POINTS:
        raise ParameterError(f"at must be one of {', '.join(LOOP_POINTS)}; got {at!r}")
    return (CONTROL, "sensed") if at == "comparator" else ("Vref", "vout")


def loop_from_closed(Y: npt.NDArray[np.complex128], at: str) -> npt.NDArray[np.complex128]:
    """The loop gain from the closed loop's response Y at the break point: -Y / (1 + Y) at the comparator (the
    perturbation adds to what it senses), Y / (1 - Y) at the reference (vout is subtracted from it)."""
    return -Y / (1.0 + Y) if at == "comparator" else Y / (1.0 - Y)


def margins(gain: Callable[[npt.NDArray[np.float64]], npt.NDArray[np.complex128]], f: np.ndarray) -> Margins:
    """The margins of a loop gain ``gain(f)`` (a function of frequency, Hz): each crossing bracketed on the grid
    ``f`` and located on the function itself (Brent's method), the first of each kind."""
    from scipy.optimize import brentq
    f = np.asarray(f, dtype=float)
    values = np.atleast_1d(gain(f))
    at = lambda x: complex(np.atleast_1d(gain(np.array([x])))[0])      # noqa: E731
    phase = np.unwrap(np.angle(values))

    def first_root(samples: npt.NDArray[np.float64], function: Callable[[float], float]) -> float:
        change = np.flatnonzero(np.sign(samples[:-1]) * np.sign(samples[1:]) < 0)
        if not change.size:
            return math.nan
        i = change[0]
        return math.exp(brentq(lambda lf: function(math.exp(lf)), math.log(f[i]), math.log(f[i + 1]), xtol=1e-13,
                               rtol=4 * np.finfo(float).eps))

    fc = first_root(np.log(np.abs(values)), lambda x: math.log(abs(at(x))))
    # the -180 degree line on the unwrapped branch the grid's phase starts on
    target = -np.pi + 2 * np.pi * np.round((phase[0] + np.pi) / (2 * np.pi))
    fp = first_root(phase - target, lambda x: (np.angle(at(x)) - target + np.pi) % (2 * np.pi) - np.pi)
    pm = (math.degrees(np.angle(at(fc))) + 360.0) % 360.0 - 180.0 if math.isfinite(fc) else math.nan
    gm = -20.0 * math.log10(abs(at(fp))) if math.isfinite(fp) else math.nan
    return Margins(fc, pm, fp, gm)


# --- the brute-force check: a sinusoid injected, the periodic steady state, its fundamental ------------------------

#: The check's frequencies are moved to the nearest fraction b/N of fs with N at most this (or the periods one cycle
#: of the sinusoid takes, when more): the perturbation and the switching then share a period of N switching periods,
#: over which the fundamental is read.
WINDOW = 50


def _common(f: float, T: float) -> tuple[float, float]:
    """(the frequency used, the common period) for a check at ``f``."""
    from fractions import Fraction
    ratio = Fraction(f * T).limit_denominator(max(WINDOW, int(round(1.0 / (f * T)))))
    if ratio == 0:
        ratio = Fraction(1, max(WINDOW, int(round(1.0 / (f * T)))))
    if (2 * ratio).denominator == 1:
        # at a multiple of fs/2 the cosine's other half, e^{-jwt}, lands on w through the switching's sidebands
        # (-w + k ws = w): the check then measures their sum, so it moves off by 1 / (2 WINDOW) of fs
        ratio -= Fraction(1, 2 * WINDOW)
    return float(ratio) / T, ratio.denominator * T


@dataclass
class _AugmentedMap:
    """x -> x after the common period of the circuit with its perturbation's oscillator started at (1, 0): the
    augmented problem's exact event-method map, restricted to the circuit's states (the oscillator's own
    multipliers are on the unit circle and would stall Newton)."""

    inner: PeriodMap
    n: int
    period: float
    evaluations: int = 0
    jacobian_kind: str = "exact"

    def _x(self, x: npt.ArrayLike) -> npt.NDArray[np.float64]:
        return np.concatenate([np.asarray(x, dtype=float), [1.0, 0.0]])

    def __call__(self, x: npt.NDArray[np.float64]) -> tuple[np.ndarray, np.ndarray]:
        self.evaluations += 1
        px, jac = self.inner(self._x(x))
        return px[:self.n], jac[:self.n, :self.n]

    def end(self, x: npt.NDArray[np.float64]) -> np.ndarray:
        self.evaluations += 1
        return self.inner.end(self._x(x))[:self.n]


def _augmented(small: SmallSignalModel, omega: float, amplitude: float) -> LCSProblem:
    """The circuit with the input perturbed by ``amplitude`` cos(omega t): an oscillator's two states w' = [[0, -w],
    [w, 0]] w beside the circuit's, entering where the input does (the sources' columns of E and F, the comparator's
    function, or the duty ratio's comparison with a sawtooth)."""
    from ..problems import Configuration, LCSProblem, Ramp, SwitchingFunction
    problem, moved = small.machine.problem, small.moved.problem
    n, k = problem.n, problem.k
    configs = []
    for c, m in zip(problem.configurations, moved.configurations):
        A, B, C, D = (np.asarray(v, dtype=float) for v in (c.A, c.B, c.C, c.D))
        E = np.zeros(n) if c.E is None else np.asarray(c.E, dtype=float)
        F = np.zeros(k) if c.F is None else np.asarray(c.F, dtype=float)
        E_u = ((np.zeros(n) if m.E is None else np.asarray(m.E)) - E) / small.delta
        F_u = ((np.zeros(k) if m.F is None else np.asarray(m.F)) - F) / small.delta
        Aa = np.zeros((n + 2, n + 2))
        Aa[:n, :n], Aa[:n, n] = A, amplitude * E_u
        Aa[n, n + 1], Aa[n + 1, n] = -omega, omega
        Ca = np.hstack([C, (amplitude * F_u)[:, None], np.zeros((k, 1))])
        configs.append(Configuration(A=Aa, B=np.vstack([B, np.zeros((2, k))]), C=Ca, D=D, E=np.append(E, [0.0, 0.0]),
                                     F=F, name=c.name))
    law = problem.switching
    if small.input == CONTROL:
        f = law.function
        law = replace(law, function=SwitchingFunction(c=np.append(f.c, [amplitude, 0.0]), d=f.d, ramp=f.ramp))
    elif isinstance(law, Schedule) and isinstance(moved.switching, Schedule) and law.starts != moved.switching.starts:
        # a PWM whose turn-off the input moves: ON while a sawtooth 0 -> 1 over T lies below D + amplitude w1
        if len(law.starts) != 2:
            raise ParameterError(f"the injection check moves a two-edge PWM's turn-off; this schedule has "
                                 f"{len(law.starts)} edges")
        T = law.period
        duty = law.starts[1] / T
        slope = (moved.switching.starts[1] - law.starts[1]) / small.delta / T     # d(duty)/du
        function = SwitchingFunction(c=np.append(np.zeros(n), [-amplitude * slope, 0.0]), d=-duty,
                                     ramp=Ramp(low=0.0, high=-1.0, period=T))
        law = StateSwitching(function, below=law.configs[0], above=law.configs[1], latch=True, initial=law.configs[0])
    elif isinstance(law, StateSwitching):
        # a parameter of the law (a reference, a ramp's level) moves s = c x + d - ramp by a constant
        f, g = law.function, moved.switching.function
        level = lambda h: h.ramp.low if h.ramp is not None else 0.0                  # noqa: E731
        slope = lambda h: h.ramp.slope if h.ramp is not None else 0.0                # noqa: E731
        if not np.isclose(slope(f), slope(g), rtol=1e-12, atol=0.0):
            raise ParameterError(f"the injection check moves a law's reference or ramp level; {small.input!r} moves "
                                 "its ramp's slope")
        d_u = ((g.d - level(g)) - (f.d - level(f))) / small.delta
        law = replace(law, function=replace(f, c=np.append(f.c, [amplitude * d_u, 0.0])))
    return LCSProblem(tuple(configs), law, x0=np.append(problem.x0, [1.0, 0.0]), t_span=problem.t_span,
                      state_names=problem.state_names + ("w1", "w2"), pair_names=problem.pair_names)


def injection_response(small: SmallSignalModel, frequency_hz: npt.ArrayLike, output: str = "vout",
                       amplitude: float | None = None, tol: float = 1e-11) -> tuple[np.ndarray, np.ndarray]:
    """The brute-force response, the way an AC sweep measures it: at each frequency (moved to the nearest multiple
    of fs / WINDOW, off the multiples of fs/2) the input perturbed by ``amplitude`` cos(2 pi f t) (default: 1e-5 of
    the input's value, or of the comparator's ramp), the periodic steady state of the circuit with it (Newton shooting over the common
    period, exact event method), and the output's fundamental over that period, per unit amplitude. Returns (the
    frequencies used, each once, and the responses)."""
    from .periodic import newton_orbit, require
    T, n = small.T, small.n
    # each frequency once: neighbours moved to the same multiple (eight asked about one frequency had run it four
    # times each)
    plan = list(dict.fromkeys(_common(float(f), T) for f in np.atleast_1d(np.asarray(frequency_hz, dtype=float))))
    longest = max((span for _, span in plan), default=0.0)
    if longest > MAX_CHECK_PERIODS * T * (1 + 1e-9):
        lowest = min(f for f, _ in plan)
        raise ParameterError(f"the check injects at frequencies down to fs/{MAX_CHECK_PERIODS:,} "
                             f"({1 / (MAX_CHECK_PERIODS * T):.4g} Hz): at {lowest:.4g} Hz its common period spans "
                             f"{longest / T:.3g} switching periods; raise --fmin (the exact response needs no check)")
    amplitude = 0.01 * abs(small.delta) if amplitude is None else amplitude
    out = np.empty(len(plan), dtype=complex)
    for i, (f, span) in enumerate(plan):
        omega = 2.0 * np.pi * f
        problem = _augmented(small, omega, amplitude)
        problem = replace(problem, t_span=(problem.t_span[0], problem.t_span[0] + span))
        machine = small.method.engine(problem)
        period_map = _AugmentedMap(small.method.period_map(problem), n, span)
        orbit = require(newton_orbit(period_map, small.orbit.x0, tol=tol, max_iter=50), "the perturbed periodic orbit")
        solution = machine.run(np.append(orbit.x0, [1.0, 0.0]), record=True)[0]
        samples, weights = solution.quadrature()
        values = _output_on(small.model, small.params, small.machine.problem, samples, output)
        out[i] = 2.0 / span * np.sum(weights * values * np.exp(-1j * omega * samples.t)) / amplitude
    return np.array([f for f, _ in plan]), out


def _output_on(model: Model, params: dict, problem: LCSProblem, samples: Samples, output: str) -> np.ndarray:
    """The output at quadrature samples of a run of ``problem`` (its first n states the circuit's, then perhaps an
    oscillator's)."""
    n = problem.n
    plain = replace(samples, x=np.asarray(samples.x)[:, :n])
    if output == "sensed":
        return plain.x @ cast(StateSwitching, problem.switching).function.c       # (a state-driven law's)
    if output in problem.state_names:
        return plain.x[:, problem.state_names.index(output)]
    return np.asarray(model.labels(params).signal(output, plain), dtype=float)


def _orbit_mean(machine: Machine, x0: npt.NDArray[np.float64], model: Model, params: dict, output: str) -> float:
    """The mean of an output over one period of a machine's run from x0 (the event method's exact pieces)."""
    solution = machine.run(x0, record=True)[0]
    samples, weights = solution.quadrature()
    values = _output_on(model, params, machine.problem, samples, output)
    return float(np.sum(weights * values) / (machine.problem.t_span[1] - machine.problem.t_span[0]))


def _mean_output(small: SmallSignalModel, output: str = "vout") -> float:
    """The mean of an output over the orbit's period."""
    return _orbit_mean(small.machine, small.orbit.x0, small.model, small.params, output)


def steady_mean(model: Model, params: dict | None = None, output: str = "vout", tol: float = 1e-12) -> float:
    """The mean of an output over the exact periodic orbit (Newton shooting on the event method's map to ``tol``):
    what a finite difference of the steady state reads."""
    from ..methods import EventDriven
    from .periodic import ANALYSIS_REMEDY, require, shoot
    p = model.resolve(params)
    T = model.period(p)
    method = EventDriven()
    problem = model.problem(p, T)
    orbit = require(shoot(problem, method, problem.x0, tol=tol), f"the periodic orbit of {model.key}",
                    remedy=ANALYSIS_REMEDY)
    return _orbit_mean(method.engine(model.problem(p, T, orbit.x0)), orbit.x0, model, p, output)


# --- compensator design: the k-factor method on the exact control-to-output response -----------------------------


def operating_duty(model: Model | str, params: dict, vref: float, tol: float = 1e-12) -> tuple[float, SmallSignalModel]:
    """The duty ratio at which the open-loop converter's exact periodic orbit has mean |vout| = vref, by Newton's
    method on D with the exact model's response at zero frequency as the slope (its d mean(vout) / dD); and the
    small-signal model (input D) there."""
    if isinstance(model, str):
        from ..models import get_model
        model = get_model(model)
    from ..models.compensator import ccm_duty
    p = model.resolve({k: v for k, v in dict(params or {}).items() if k != "D"})
    duty = ccm_duty(model, vref, p["Vin"]) or 0.5
    for _ in range(30):
        small = SmallSignalModel(model, {**p, "D": duty}, input="D", outputs=("vout",))
        mean = abs(_mean_output(small))
        slope = float(np.real(small.response([1e-6 / small.T], "vout")[0])) * np.sign(_mean_output(small))
        step = (vref - mean) / slope
        duty = float(np.clip(duty + step, 1e-6, 1 - 1e-6))
        if abs(vref - mean) <= tol * vref:
            return duty, small
    raise SimulationError(f"no duty ratio gives a mean output of {vref:g} V on {model.key} (last D = {duty:.6g}, "
                          f"mean {mean:.6g} V)")


@dataclass(frozen=True)
class Design:
    """A compensator designed by the k-factor method, and what it was designed from."""

    compensator: Compensator
    crossover_hz: float
    phase_margin_deg: float
    duty: float
    plant_db: float             # |Fm Gvd| at the crossover (dB)
    plant_deg: float            # its phase (degrees, unwrapped from low frequency)
    boost_deg: float
    k: float

    def as_dict(self) -> dict:
        return {"compensator": self.compensator.kind, **self.compensator.as_dict(), "crossover_hz": self.crossover_hz,
                "phase_margin_deg": self.phase_margin_deg, "duty": self.duty, "plant_db": self.plant_db,
                "plant_deg": self.plant_deg, "boost_deg": self.boost_deg, "k": self.k}


def design_compensator(model: Model | str, params: dict, *, crossover_hz: float, phase_margin_deg: float, vref: float,
                       carrier: tuple = (0.0, 1.0), kind: str = "type3") -> Design:
    """A type II or III compensator for the open-loop converter ``model`` at ``params`` regulated to ``vref`` with a
    carrier from carrier[0] to carrier[1] (trailing edge: Fm = 1 / (VU - VL)), by the k-factor method (H. D.
    Venable, "The k factor: a new mathematical tool for stability analysis and synthesis", Powercon 10, 1983) on the
    exact control-to-output response at the operating point: the boost theta = PM - 90 - angle(Fm Gvd(fc)); type III
    k = tan^2(theta/4 + 45 deg), a double zero at fc/sqrt(k) and a double pole at fc sqrt(k), wi = wc / (k |Fm Gvd|);
    type II k = tan(theta/2 + 45 deg), one of each, wi = wc / (sqrt(k) |Fm Gvd|)."""
    from ..models.compensator import Compensator
    if kind not in ("type2", "type3"):
        raise ParameterError(f"kind must be type2 or type3; got {kind!r}")
    VL, VU = carrier
    if not VU > VL:
        raise ParameterError(f"the carrier's high level must be above its low level; got {VL:g} V to {VU:g} V")
    if not 0.0 < phase_margin_deg < 90.0:
        raise ParameterError(f"phase_margin_deg must be in (0, 90) degrees; got {phase_margin_deg!r}")
    duty, small = operating_duty(model, params, vref)
    fs = 1.0 / small.T
    if not 0.0 < crossover_hz < fs / 2:
        raise ParameterError(f"crossover_hz must be in (0, fs/2 = {fs / 2:g} Hz); got {crossover_hz!r}")
    sweep = np.geomspace(crossover_hz / 1e3, crossover_hz, 400)
    plant = small.response(sweep, "vout") / (VU - VL)
    phase = float(np.degrees(np.unwrap(np.angle(plant)))[-1])
    magnitude = float(np.abs(plant[-1]))
    boost = phase_margin_deg - 90.0 - phase
    limit = 180.0 if kind == "type3" else 90.0
    if not 0.0 < boost < limit:
        raise ParameterError(f"a {kind} compensator boosts the phase by less than {limit:g} degrees; this crossover "
                             f"and margin need {boost:.1f} (the plant's phase at {crossover_hz:g} Hz is {phase:.1f} "
                             "degrees): choose a lower crossover or margin" + (", or type3" if kind == "type2" else ""))
    wc = 2 * math.pi * crossover_hz
    if kind == "type3":
        k = math.tan(math.radians(boost / 4 + 45.0)) ** 2
        root = math.sqrt(k)
        comp = Compensator(wc / (k * magnitude), (crossover_hz / root,) * 2, (crossover_hz * root,) * 2)
    else:
        k = math.tan(math.radians(boost / 2 + 45.0))
        root = math.sqrt(k)
        comp = Compensator(wc / (root * magnitude), (crossover_hz / root,), (crossover_hz * root,))
    return Design(comp, crossover_hz, phase_margin_deg, duty, 20 * math.log10(magnitude), phase, boost, k)
