"""Periodic orbits of any problem and method: Newton shooting on the method's period map.

A method's period map P: x(t0) -> x(t0 + span) over the problem's t_span (one period, or m periods for
a period-m orbit) comes with its Jacobian: exact for the LCP stepper (the product of the one-step
derivatives) and the event-driven method (state-transition and saltation matrices), by finite
differences otherwise (the result says which). For autonomous state-switched systems the map is the
return map to the switching surface (a Poincare map; the period is then an unknown it returns).

Newton's method on P(x) - x = 0, with the step halved while the residual does not fall (the map is
piecewise affine: a change of the mode sequence can make a full step overshoot); where no fraction of
the step helps (far from the orbit, in a start-up transient), one period of the map itself is taken. The orbit's
Floquet multipliers are the eigenvalues of the Jacobian at the fixed point; their spectral radius rho
gives the distance to the orbit from a residual r, |x - x*| <= |r| / (1 - rho) for rho < 1, and the
Newton step itself estimates it for any rho. The run stops when that distance is below the
tolerance; a run that cannot get there is reported as not converged, never replaced by a guess.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Protocol

import numpy as np
import numpy.typing as npt

from ..compiled import (NEWTON_CONVERGED, NEWTON_EVALUATE, NEWTON_EXHAUSTED, NEWTON_NO_SOLUTION, NEWTON_NONFINITE,
                        NEWTON_RADIUS, NEWTON_ROUNDING, NEWTON_SINGULAR, kernel)
from ..compiled import ROUNDING as _ROUNDING
from ..errors import ParameterError, SimulationError
from ..validate import as_vector, check_flag, check_integer
from ..problems import LCSProblem
from .floquet import multipliers_of, spectral_radius

if TYPE_CHECKING:
    from ..methods.base import Method, PeriodMap
    from ..models.base import Model

#: Where a circuit goes from an unstable orbit when its leading multiplier is not known (a batched sweep keeps the
#: spectral radius only).
ELSEWHERE = "a period-doubled or quasi-periodic orbit, chaos, or a latch"


def instability(multipliers, period: float) -> str:
    """Why an orbit with these Floquet multipliers (its period ``period`` s) is no steady state, '' when it is
    stable: its spectral radius, the leading multiplier and what leaving the unit circle there means. A real
    multiplier below -1 doubles the period (or leads to chaos); a complex pair (a Neimark-Sacker bifurcation) adds
    an oscillation at |arg mu| / (2 pi T), modulo the switching frequency (an input filter's resonance under a
    regulating loop); one above +1 leaves for another orbit, a latch or a runaway."""
    mu = np.asarray(multipliers, dtype=complex)
    if mu.size == 0 or np.abs(mu).max() < 1.0:
        return ""
    lead = mu[np.argmax(np.abs(mu))]
    if abs(lead.imag) > 1e-9 * abs(lead):
        hz = abs(np.angle(lead)) / (2 * np.pi * period)
        where = (f"a complex pair: an oscillation about it at about {hz:.3g} Hz, modulo the switching frequency: "
                 "a quasi-periodic orbit")
        at = f"{lead.real:.6g}{lead.imag:+.3g}j"
    else:
        where = "a period-doubled orbit, or chaos" if lead.real < 0 else "another orbit, a latch, or a runaway"
        at = f"{lead.real:.6g}"
    return (f"unstable (Floquet spectral radius {abs(lead):.6g}, a multiplier at {at}): the circuit does not settle "
            f"on it ({where})")


def stability_undecided(at_h: npt.ArrayLike, at_2h: npt.ArrayLike) -> str:
    """'' where a stepper's leading Floquet multiplier at h (of the multipliers ``at_h``) is as sure to lie on its
    side of the unit circle as its distance from its counterpart at 2h (the nearest of ``at_2h``: the estimate of its
    error, first order at most) says; else why not. A voltage-mode buck at T/200 reads 0.8829 where the exact
    orbit's radius is 0.8241, and just past its period doubling (exact -1.0139) -0.97 to -0.99: stored as stable.
    (A mode's counterpart, not the radius at 2h: another mode may lead there.)"""
    h = np.asarray(at_h, dtype=complex).ravel()
    twice = np.asarray(at_2h, dtype=complex).ravel()
    if not h.size or not twice.size or not np.all(np.isfinite(h)) or not np.all(np.isfinite(twice)):
        return ""
    lead = h[np.argmax(np.abs(h))]
    if abs(lead.imag) <= 1e-9 * abs(lead) and lead.real > 0.0:
        # a real positive leading multiplier is a slow mode's decay (an output's RC: 0.99005 at h, 0.9776 at 2h on a
        # path the diodes block both ways); the instabilities a step moves are at -1 (a period doubling) and on a
        # complex pair (a quasi-periodic orbit)
        return ""
    error = float(np.abs(twice - lead).min())
    if abs(1.0 - abs(lead)) > 2.0 * error:
        return ""
    counterpart = twice[np.argmin(np.abs(twice - lead))]

    def said(m: complex) -> str:
        return f"{m.real:.6g}" if abs(m.imag) <= 1e-12 * abs(m) else f"{m.real:.6g}{m.imag:+.3g}j"
    return (f"its stability is undecided at this step (its leading Floquet multiplier {said(lead)} at h, "
            f"{said(counterpart)} at 2h: within twice their difference of the unit circle)")


def passive(model: Model, p: dict) -> bool:
    """The circuit can only lose energy: switched on a time schedule, with no controlled source (a netlist's E, F,
    G, H) and no loop of its own: its orbit cannot be unstable, whatever a step's multipliers say (a lossless LC
    ring's pair at 0.81 at h, 0.66 at 2h). A state-driven law or a controlled source can destabilise it."""
    from ..problems import Schedule
    if not isinstance(model.problem(p, model.period(p)).switching, Schedule):
        return False
    netlist = getattr(model, "netlist", None)
    return netlist is None or not any(e.kind in "EFGH" for e in netlist.elements)


def exact_refusal(model: Model, p: dict, span: float | None = None) -> str:
    """'' where the exact (event) method takes the circuit at ``p`` (over ``span``, default its period), else why
    not (a SIN source): the one test of the places that leave a question to the exact method."""
    from ..methods import EventDriven
    try:
        EventDriven().supports(model.problem(p, model.period(p) if span is None else span))
    except ParameterError as refused:
        return str(refused)
    return ""


def undecided_remedy(model: Model, p: dict) -> str:
    """What settles a stability the step leaves open: the exact method where it takes the circuit, else a step."""
    return "use a smaller --h" if exact_refusal(model, p) else "use --method event (or a smaller --h)"


def require_stable(model: Model, p: dict, orbit: PeriodicOrbit, instead: str) -> None:
    """Refuse an unstable orbit in one line: a fixed point of the period map the circuit does not settle on is no
    steady state (``instead``: what the command can run in its place)."""
    why = instability(orbit.multipliers, model.period(p))
    if why:
        raise SimulationError(f"the periodic orbit of {model.key} is {why}; {instead}, or follow its orbits with "
                              "pcsuite bifurcation")


class NewtonMap(Protocol):
    """What Newton shooting calls and reads of a period map: a :class:`~converters.methods.base.PeriodMap`, or a
    map that wraps one without being one (:mod:`.smallsignal`'s map restricted to the circuit's states)."""

    evaluations: int
    jacobian_kind: str

    def __call__(self, x0: npt.NDArray[np.float64], /) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]: ...


@dataclass(frozen=True)
class PeriodicOrbit:
    """A fixed point of a period map and what is known about it.

    Attributes
    ----------
    x0 : ndarray, shape (n,)
        State at the start of the orbit.
    period : float
        The span of the map (s): the problem's t_span length, or the return time of a return map.
    jacobian : ndarray, shape (n, n)
        d P / d x at x0 (the monodromy matrix of the discrete or exact map).
    multipliers : ndarray, shape (n,)
        Floquet multipliers (eigenvalues of ``jacobian``), largest modulus first.
    residual : float
        max |P(x0) - x0| / (s + max |x0|), s the circuit's size where below 1 (:func:`newton_orbit`), else 1.
    distance : float
        Estimated max |x0 - x*| / (s + max |x0|): the larger of the Newton step and residual / (1 - rho).
    iterations, evaluations : int
        Newton iterations; spans simulated (period-map calls, finite-difference columns included).
    converged : bool
        ``distance`` <= the tolerance asked for.
    jacobian_kind : str
        ``exact`` or ``finite differences``.
    message : str
        Why it did not converge (with a remedy), or empty.
    transient : int
        Plain periods simulated before the Newton iteration that converged (:func:`shoot`'s settling rounds).
    warning : str
        What a converged orbit's caller should pass on: an orbit far from where Newton started that the transient
        was not seen to reach (:func:`shoot`), or empty.
    settled : ndarray or None
        Where Newton failed after settling rounds: the state the transient reached (the last round's end), which
        says what the circuit does instead (a loop latched at duty 1); ``x0`` is then Newton's last iterate.
    """

    x0: np.ndarray
    period: float
    jacobian: np.ndarray
    multipliers: np.ndarray
    residual: float
    distance: float
    iterations: int
    evaluations: int
    converged: bool
    jacobian_kind: str
    message: str = ""
    transient: int = 0
    warning: str = ""
    settled: np.ndarray | None = None

    @property
    def spectral_radius(self) -> float:
        return float(np.abs(self.multipliers).max()) if self.multipliers.size else 0.0

    @property
    def stable(self) -> bool:
        return self.spectral_radius < 1.0

    def summary(self) -> dict:
        return {"period_s": self.period, "residual": self.residual, "distance": self.distance,
                "iterations": self.iterations, "evaluations": self.evaluations, "transient": self.transient,
                "converged": self.converged, **({"warning": self.warning} if self.warning else {}),
                "spectral_radius": self.spectral_radius, "stable": self.stable, "jacobian": self.jacobian_kind,
                "multipliers": [[float(m.real), float(m.imag)] for m in self.multipliers]}   # [re, im] pairs


#: A residual below ROUNDING machine epsilons (relative) is rounding noise: iterating further cannot help.
ROUNDING = _ROUNDING


#: Newton shooting's tolerance on the distance to the orbit (state units), its iterations, and the periods a
#: warm-up may simulate (Newton needs a few; more only adds time: a bound against a hang, not a model limit).
TOL_RANGE = (1e-15, 0.1)
MAX_NEWTON_ITER = 10_000
MAX_WARM_UP = 100_000


#: How a message of an orbit resolved only to the rounding level of its map begins (a lightly damped circuit).
ROUNDING_LIMITED = "the residual is at the rounding level of the map"

def check_newton(tol: float, max_iter: int) -> None:
    """Refuse a tolerance or an iteration count Newton shooting cannot honour (tol = 1e308 had "converged" at
    any state)."""
    if not (isinstance(tol, (int, float, np.integer, np.floating)) and not isinstance(tol, bool)
            and TOL_RANGE[0] <= tol <= TOL_RANGE[1]):
        raise ParameterError(f"tol must be in [{TOL_RANGE[0]:g}, {TOL_RANGE[1]:g}] (the distance to the orbit, in "
                             f"state units); got {tol!r}")
    check_integer("max_iter", max_iter, 1, MAX_NEWTON_ITER)


def newton_orbit(period_map: NewtonMap, x_guess: npt.ArrayLike, *, tol: float = 1e-10, max_iter: int = 50,
                 period: float = np.nan, polish: bool = False, size: float | None = None) -> PeriodicOrbit:
    """Newton's method on P(x) - x = 0 for a :class:`~converters.methods.base.PeriodMap` ``period_map``: the
    compiled driver (:func:`converters.analysis.newton_kernel.newton_advance`, the batched steady states' too),
    answered here with the map's values and numpy's spectral radius. ``polish``: return x + the last Newton step
    (within about its square of the orbit) instead of x. ``size``: the circuit's size in state units
    (:func:`problem_size`), where the distance is to be relative to it below 1."""
    check_newton(tol, max_iter)
    check_flag("polish", polish)
    x = np.array(as_vector("x_guess", x_guess, None), dtype=float)
    n = x.size
    px, jac = (np.array(v, dtype=float) for v in period_map(x))       # copies: P's output may be a view
    # The driver measures distances relative to 1 + max |x| (state units): a circuit whose states are far below 1
    # (a buck from 1.2e-8 V) was resolved to 1e-10 V absolute, 1.5 % of its 7 nV output, and its --steady run read
    # "has not settled: use --steady". Given the circuit's ``size``, Newton works on x / s, s the largest of that
    # size, the start and its image where below 1, so its tolerance is relative to s + max |x|; at s = 1 nothing
    # changes. (The states alone are no size: a path the diodes block both ways holds them at 1e-19 in a 12 V
    # circuit, whose orbit is then resolved to its rounding.)
    s = 1.0
    if size is not None:
        largest = max(size, float(np.abs(x).max(initial=0.0)), float(np.abs(px).max(initial=0.0)))
        s = min(1.0, largest) if np.isfinite(largest) and largest > 0.0 else 1.0
    x, px = x / s, px / s
    dx, work, trial, p_trial, jac_trial = np.empty(n), np.empty((n, n + 1)), np.empty(n), np.empty(n), np.empty((n, n))
    istate, rstate = np.zeros(4, dtype=np.int64), np.array([np.inf, np.inf, np.inf, 0.0])
    advance = kernel("newton_advance")
    ok = True
    while True:
        verdict = advance(x, px, jac, dx, work, trial, p_trial, jac_trial, ok, istate, rstate, float(tol), max_iter)
        if verdict == NEWTON_RADIUS:
            rstate[3] = spectral_radius(jac)
        elif verdict == NEWTON_EVALUATE:
            # A trial outside the map's domain (a cam's follower below its surface: a negative gap) is a step too
            # long, halved like one that does not lower the residual (a plain period the map refuses ends Newton:
            # NEWTON_NO_SOLUTION); any other failure of the map raises with its own reason.
            try:
                image, jac_trial[:, :] = period_map(trial * s)
                p_trial[:] = np.asarray(image, dtype=float) / s
                ok = True
            except ParameterError:           # (a substep or memory refusal of a mode only the trial enters too)
                ok = False
        else:
            break
    iteration, relaxations = int(istate[1]), int(istate[3])
    residual, distance, rho = (float(v) for v in rstate[1:])
    span = getattr(period_map, "period", period)
    x, dx = x * s, dx * s
    if verdict == NEWTON_CONVERGED:
        return PeriodicOrbit(x + dx if polish else x, span, jac, multipliers_of(jac), residual, distance, iteration,
                             period_map.evaluations, True, period_map.jacobian_kind)
    message = {
        NEWTON_SINGULAR: "the period map's Jacobian has a multiplier at 1 (the orbit is not isolated: an undamped or "
                         "marginal circuit)",
        NEWTON_ROUNDING: f"{ROUNDING_LIMITED} and 1 - rho = {1.0 - rho:.3g} amplifies "
                         f"it: the orbit is resolved to ~{distance:.3g} in double precision, not to the tolerance "
                         "asked for",
        NEWTON_EXHAUSTED: f"no convergence in {max_iter} Newton iterations ({relaxations} of them plain periods where "
                          "no Newton step reduced the residual)",
        NEWTON_NONFINITE: "the period map left the finite numbers",
        NEWTON_NO_SOLUTION: "a plain period the map could not take (its state outside the map's domain)"}[verdict]
    return PeriodicOrbit(x, span, jac, multipliers_of(jac), residual, distance, iteration, period_map.evaluations,
                         False, period_map.jacobian_kind,
                         f"{message}; residual {residual:.3g}, estimated distance {distance:.3g} > tol {tol:.3g}")


def shoot(problem: LCSProblem, method: Method, x_guess: npt.ArrayLike | None = None, *, periods: int = 1,
          warm_up: int = 0, tol: float = 1e-10, max_iter: int = 50, polish: bool = False,
          period_map: PeriodMap | None = None) -> PeriodicOrbit:
    """The method's periodic orbit of a periodically switched problem (period T of its switching law).

    ``periods``: the orbit's period in switching periods (a period-m orbit); ``warm_up``: periods simulated
    from ``x_guess`` (default problem.x0) before Newton starts, so that it begins on the right sequence of
    modes. The problem's own t_span is ignored (only its start). ``period_map``: the method's map over
    [t0, t0 + periods T] when the caller has built it already (to reuse its plan after the orbit is found)."""
    check_integer("periods", periods, 1, MAX_WARM_UP)
    check_integer("warm_up", warm_up, 0, MAX_WARM_UP)
    check_newton(tol, max_iter)
    T = problem.period
    if not np.isfinite(T):
        raise SimulationError("shoot() needs a periodic switching law (a schedule or a ramp); for an autonomous "
                              "state-switched problem use autonomous_orbit()")
    if period_map is None:
        t0 = problem.t_span[0]
        period_map = method.period_map(replace(problem, t_span=(t0, t0 + periods * T)))
    x = as_vector("x_guess", problem.x0 if x_guess is None else x_guess, problem.n)
    for _ in range(warm_up):
        x = period_map.end(x)
    size = problem_size(problem)
    orbit = newton_orbit(period_map, x, tol=tol, max_iter=max_iter, period=periods * T, polish=polish, size=size)
    # Far from the orbit the map may not be the orbit's: a loop's integrator saturates the duty ratio (0 or 1), the
    # loop is open there and its integrator a multiplier at 1, and Newton's steps leave for worse states. The
    # transient itself settles (a type II voltage loop's in ~500 periods): plain periods in rounds of doubling
    # length, Newton again from where each ends, as far as the transient goes within SETTLE_PERIODS.
    # Such a step can also land on a fixed point of the saturated map (a boost's loop latched at duty 1, its
    # integrator wound up to 2.5 MV: vout 0 V, multiplier 1 - 5e-9), one the circuit would take billions of periods
    # to reach from where Newton started, while its transient settles elsewhere (24 V, in ~30 periods): such a
    # remote orbit stands only where Newton from the settled transient returns to it (a loop in dropout winding up).
    start = x
    remote = orbit if orbit.converged and periods_to_reach(orbit, start, tol) > REMOTE_PERIODS else None
    done, rounds = 0, SETTLE_FIRST
    while (remote is not None or orbit.message.startswith(SETTLE_AFTER)) and not (
            orbit.converged and orbit is not remote) and done < SETTLE_PERIODS:
        diverged = False
        for _ in range(min(rounds, SETTLE_PERIODS - done)):
            x = period_map.end(x)
            if diverged := not np.all(np.isfinite(x)):
                break
        if diverged:
            break
        done, rounds = done + rounds, 2 * rounds
        retry = newton_orbit(period_map, x, tol=tol, max_iter=min(max_iter, SETTLE_NEWTON), period=periods * T,
                             polish=polish, size=size)
        # (a retry that stops at the map's rounding near the remote orbit confirms it as well: a DCM buck's series
        # capacitors, their slow mode 1 - 3.7e-6 a period, had its orbit refused for R = 20.000000000000004 and
        # taken for R = 20, where the first Newton itself had stopped at rounding)
        returned = retry.converged or retry.message.startswith(ROUNDING_LIMITED)
        if remote is not None and returned and _same(remote, retry, tol):
            orbit = replace(remote, evaluations=period_map.evaluations)       # confirmed: Newton's own answer
        elif remote is None or retry.converged:
            orbit = replace(retry, transient=done, evaluations=period_map.evaluations)
    if done and not orbit.converged:
        orbit = replace(orbit, settled=x)
    if remote is not None and orbit is remote:
        return replace(remote, evaluations=period_map.evaluations, warning=(
            f"the orbit lies ~{periods_to_reach(remote, start, tol):.1g} periods of its slowest mode (multiplier "
            f"{remote.spectral_radius:.10g}) from where Newton started, and Newton from {done} periods of the "
            "transient did not return to it: the circuit may settle elsewhere (run --periods N without --steady "
            "to see)"))
    return orbit


def problem_size(problem: LCSProblem) -> float | None:
    """The circuit's size in state units: the largest of its start, each configuration's constant pair terms F (a
    source's voltage across a blocking diode) and its constant drift E over a period (a source's change of a state
    in T), with the sinusoidal inputs' amplitudes. None for another problem (a mechanism's: Newton's distance stays
    relative to 1 + max |x|)."""
    if not isinstance(problem, LCSProblem):
        return None
    T = problem.period if np.isfinite(problem.period) else problem.t_span[1] - problem.t_span[0]
    parts = [np.abs(problem.x0)]
    for c in problem.configurations:
        parts += [np.abs(c.E) * T, np.abs(c.F)]
    if problem.inputs is not None:
        parts += [np.abs(problem.inputs.E) * T, np.abs(problem.inputs.F)]
    return max(float(np.max(part, initial=0.0)) for part in parts)


#: An orbit Newton converged to that the circuit's slowest mode would take more periods than this to bring the start
#: to (:func:`periods_to_reach`) is checked against the transient (:func:`shoot`). A 1 F output's DCM buck (multiplier
#: 1 - 1.5e-7) is one; a type III loop's orbit 1,000 periods from its start (multiplier 0.98) is not.
REMOTE_PERIODS = 1e5


def _same(a: PeriodicOrbit, b: PeriodicOrbit, tol: float) -> bool:
    """Two converged orbits one fixed point: their starts apart by no more than their stated distances to it."""
    gap = float(np.abs(a.x0 - b.x0).max()) / (1.0 + float(np.abs(a.x0).max()))
    return gap <= max(a.distance + b.distance, 2.0 * tol)


def periods_to_reach(orbit: PeriodicOrbit, x_start: npt.NDArray[np.float64], tol: float) -> float:
    """The periods the orbit's slowest mode (its spectral radius rho) takes to bring the distance from ``x_start``
    to the orbit down to the tolerance: ln(distance / tolerance) / -ln(rho) (0 for rho = 0, inf for rho >= 1)."""
    return periods_apart(orbit.x0, orbit.spectral_radius, x_start, tol)


def periods_apart(x_orbit: npt.NDArray[np.float64], rho: float, x_start: npt.NDArray[np.float64],
                  tol: float) -> float:
    """:func:`periods_to_reach` of a fixed point ``x_orbit`` with spectral radius ``rho``."""
    if rho >= 1.0:
        return np.inf
    gap = float(np.abs(x_orbit - x_start).max()) / (tol * (1.0 + float(np.abs(x_orbit).max())))
    return 0.0 if rho == 0.0 or gap <= 1.0 else math.log(gap) / -math.log(rho)


def autonomous_orbit(problem: LCSProblem, method: Method, x_guess: npt.ArrayLike, *, config: int, crossings: int = 1,
                     warm_up: int = 0, tol: float = 1e-10, max_iter: int = 50) -> PeriodicOrbit:
    """The periodic orbit of an autonomous state-switched problem through its return map to the switching
    into ``config`` (``crossings`` switchings per orbit); the period is the return time. The problem's
    t_span must hold the return (a few periods). Methods with a return map: the event method (the
    stepper's switchings fall between its grid points, so its map to a surface is not a fixed-step map)."""
    if not hasattr(method, "return_map"):
        raise ParameterError(f"autonomous orbits need a method with a return map to the switching surface (the "
                             f"event method, EventDriven); got {type(method).__name__}")
    check_integer("crossings", crossings, 1, MAX_WARM_UP)
    check_integer("warm_up", warm_up, 0, MAX_WARM_UP)
    check_newton(tol, max_iter)
    k = len(problem.configurations)
    check_integer("config", config, 0, k - 1)
    period_map = method.return_map(problem, config, crossings)
    x = as_vector("x_guess", x_guess, problem.n)
    for _ in range(warm_up + 1):             # the first return puts x on the section
        x = period_map.end(x)
    return newton_orbit(period_map, x, tol=tol, max_iter=max_iter)


#: :func:`shoot`'s settling rounds: the first round's plain periods (each round doubles), and their total.
SETTLE_FIRST, SETTLE_PERIODS = 32, 2048
#: Newton's iterations after a settling round: from a settled state it converges in a few (2 on a type II loop).
SETTLE_NEWTON = 10
#: The failures a longer transient can help (not the map leaving the finite numbers, nor an orbit resolved to the
#: rounding of its map).
SETTLE_AFTER = ("no convergence", "the period map's Jacobian has a multiplier at 1")


#: An orbit Newton resolves to this (relative) as far as double precision goes, short of a tighter tolerance asked
#: for, serves a check of a 1e-3 estimate or a comparison: a multiplier at 1 - 1.5e-7 (a DCM buck into 1 F)
#: resolves it to ~1.4e-8, where 1e-9 was asked.
ROUNDING_RESOLVED = 1e-6


def resolved(orbit: PeriodicOrbit, bound: float = ROUNDING_RESOLVED) -> bool:
    """Converged, or resolved to ``bound`` where rounding stopped Newton (its distance stated in the orbit)."""
    return orbit.converged or (orbit.message.startswith(ROUNDING_LIMITED) and orbit.distance <= bound)


#: What a period that stays in one mode means where a switching orbit was asked for (:func:`converters.run.one_mode`,
#: :func:`converters.analysis.accuracy.window_check`).
ONE_MODE = ("no switch changes state, so there is no switching orbit there: a loop latched at duty 1 or 0, its "
            "control beyond its ramp")
#: What simulate offers where Newton does not find the orbit.
SIMULATE_REMEDY = "try a looser --steady-tol, or --periods N without --steady to see the transient"
#: What an analysis about the orbit (bode, sensitivity, gdcm), which has no tolerance to loosen, offers.
ANALYSIS_REMEDY = "see where the circuit goes with pcsuite simulate --periods N"


def require(orbit: PeriodicOrbit, what: str = "the periodic orbit", rounding_bound: float = 0.0,
            explain: str = "", remedy: str = SIMULATE_REMEDY) -> PeriodicOrbit:
    """The orbit when converged (or, with ``rounding_bound``, resolved to it as far as rounding goes); otherwise a
    SimulationError with the reason (``explain`` after it) and ``remedy``: what the command asking can run
    instead (compare has no --steady-tol)."""
    if not resolved(orbit, rounding_bound):
        taken = (f" (an orbit rounding resolves to {rounding_bound:.3g} is taken)" if rounding_bound > 0.0 else "")
        raise SimulationError(f"Newton shooting did not find {what}: {orbit.message}{explain or taken}; {remedy}")
    return orbit
