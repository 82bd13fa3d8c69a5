"""Periodic orbits along a parameter path: pseudo-arclength continuation, bifurcations, branch switching.

A family is a problem per parameter value p, a method, and the orbit's period k in switching periods. Its
orbits solve F(x, p) = P^k(x; p) - x = 0, P the method's one-period (stroboscopic) map with its Jacobian J
(exact for the event method: state-transition and saltation matrices; :mod:`.periodic`). Continuation
works in scaled variables z = (x / x_scale, p / p_scale) so that state and parameter count alike:

* predictor z + ds t along the unit tangent t, the null vector of [J - I, F_p] (F_p by a central
  difference in p);
* corrector: Newton on [F(x, p); t . (z - z_pred)] = 0 (pseudo-arclength: it passes folds, where p
  turns back);
* step ds grows after quick corrections, shrinks after slow or failed ones, bounded by ``max_step`` in p.

Between consecutive orbits the Floquet multipliers mu (eigenvalues of J) give the test functions

    period doubling   det(J + I)                         a real multiplier crosses -1
    fold              det(J - I)                         a real multiplier crosses +1
    Neimark-Sacker    max |mu| - 1 over complex pairs    a complex pair crosses the unit circle

and each orbit's *signature*, the sequence of its events over the k periods (switchings with the
configuration entered, activations and releases of each complementarity pair), changes at a border
collision: a switching instant reaching the period boundary (the ramp's limit: a switching skipped), a
new crossing, a pair's current grazing zero (the CCM/DCM boundary). A change of sign or of signature is
located by bisection on the chord between the two orbits (the orbit at each midpoint solved on the plane
normal to the chord, so that folds bisect too) to ``locate_tol``. A test function that changes sign at
a change of signature is a multiplier jumping at the border collision (a non-smooth bifurcation), not a
smooth one, and is reported as part of that border collision.

After a period doubling on which the period-k orbit loses stability, the period-2k orbit is born with
the tangent (v, 0), v the eigenvector of the multiplier -1: the 2k-family has a pitchfork there. A
pseudo-arclength step along (v, 0) lands on the new branch, which is then followed in turn
(:func:`switch_branch`, :func:`cascade`).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import ParameterError
from .periodic import multipliers_of, newton_orbit

KINDS = ("period-doubling", "fold", "neimark-sacker", "border-collision", "grazing-sliding", "crossing-sliding",
         "switching-sliding", "adding-sliding")
TEST_NAMES = {"period-doubling": "det(J + I)", "fold": "det(J - I)",
              "neimark-sacker": "max |mu| - 1 over the complex pairs"}


def test_functions(jacobian: np.ndarray, multipliers: np.ndarray) -> dict:
    """The bifurcation test functions of one orbit (None where one does not apply)."""
    n = jacobian.shape[0]
    complex_pairs = multipliers[np.abs(multipliers.imag) > 1e-9 * (1.0 + np.abs(multipliers))]
    return {"period-doubling": float(np.linalg.det(jacobian + np.eye(n))),
            "fold": float(np.linalg.det(jacobian - np.eye(n))),
            "neimark-sacker": float(np.abs(complex_pairs).max() - 1.0) if complex_pairs.size else None}


@dataclass(frozen=True)
class OrbitPoint:
    """One orbit of a branch.

    Attributes
    ----------
    value : float
        The parameter value.
    x0 : ndarray, shape (n,)
        State at the orbit's start t0.
    samples : ndarray, shape (k, n)
        x(t0 + m T), m = 0 .. k-1 (the points of the stroboscopic map on the orbit).
    jacobian : ndarray, shape (n, n)
        d P^k / d x at x0 (the monodromy matrix).
    multipliers : ndarray, shape (n,)
        Floquet multipliers, largest modulus first.
    signature : tuple
        The orbit's events over one of its periods: (kind, pair, config), as a cyclic sequence.
    """

    value: float
    x0: np.ndarray
    samples: np.ndarray
    jacobian: np.ndarray
    multipliers: np.ndarray
    signature: tuple
    #: The same events with their times, as (fraction of the orbit's period from the window's start, kind,
    #: pair, config): what a classifier of border collisions reads (which new segment is short).
    timed_events: tuple = ()

    @property
    def spectral_radius(self) -> float:
        return float(np.abs(self.multipliers).max())

    @property
    def stable(self) -> bool:
        return self.spectral_radius < 1.0

    @property
    def tests(self) -> dict:
        return test_functions(self.jacobian, self.multipliers)


@dataclass(frozen=True)
class Bifurcation:
    """A bifurcation located on a branch of orbits of ``period`` switching periods.

    ``value`` is the parameter at the bifurcation (a smooth one: the secant zero of its test function in
    the final bracket; a border collision: the bracket's midpoint), ``width`` the final bracket's width in
    the parameter, ``multipliers`` the Floquet multipliers of the orbit at the bracket's end nearest to
    the bifurcation (for a border collision: just before it, ``multipliers_after`` just after, in the
    direction of increasing parameter), ``stable_before`` / ``stable_after`` the orbit's stability just
    below and just above ``value``."""

    kind: str
    value: float
    period: int
    multipliers: np.ndarray
    x0: np.ndarray
    located_by: str
    width: float
    stable_before: bool
    stable_after: bool
    multipliers_after: np.ndarray | None = None
    detail: str = ""

    @property
    def loses_stability(self) -> bool:
        return self.stable_before and not self.stable_after

    def to_dict(self) -> dict:
        def pairs(values):
            return [[float(m.real), float(m.imag)] for m in values]
        out = {"type": self.kind, "value": self.value, "period": self.period, "multipliers": pairs(self.multipliers),
               "stable_before": self.stable_before, "stable_after": self.stable_after, "x0": self.x0.tolist(),
               "located_by": self.located_by, "bracket_width": self.width, "detail": self.detail}
        if self.multipliers_after is not None:
            out["multipliers_after"] = pairs(self.multipliers_after)
        return out


@dataclass
class Branch:
    """The orbits of one period followed along the path, with the bifurcations located on them.
    ``message`` says why the branch stopped before the path's end (what it found is kept);
    ``parent``: the period-doubling it was born at (None for the first branch)."""

    period: int
    points: list = field(default_factory=list)
    bifurcations: list = field(default_factory=list)
    message: str = ""
    parent: Bifurcation | None = None

    @property
    def complete(self) -> bool:
        return not self.message

    def values(self) -> np.ndarray:
        return np.array([pt.value for pt in self.points])

    def to_frame(self, state_names=None):
        """One row per orbit and sample m: value, m, the states at t0 + m T, stable, spectral radius."""
        import pandas as pd
        rows = []
        for pt in self.points:
            names = state_names or [f"x{i}" for i in range(pt.x0.size)]
            for m, sample in enumerate(pt.samples):
                rows.append({"period": self.period, "value": pt.value, "m": m, **dict(zip(names, sample)),
                             "stable": pt.stable, "spectral_radius": pt.spectral_radius})
        return pd.DataFrame(rows)


class OrbitFamily:
    """The orbits of period k (in switching periods) of ``problem_of(value)`` under ``method``.

    ``problem_of`` returns the problem at a parameter value (only its start time is used); its switching
    law must have a period T (a schedule, or a state-driven law with a ramp)."""

    def __init__(self, problem_of, method, periods: int = 1, classify=None):
        if not (isinstance(periods, (int, np.integer)) and periods >= 1):
            raise ParameterError(f"periods (of the orbit, in switching periods) must be an integer >= 1; got {periods!r}")
        self.problem_of, self.method, self.periods = problem_of, method, int(periods)
        #: classify(below, above) -> (kind, detail) or None: names a change of signature between the orbits just
        #: below and just above a border collision (e.g. the sliding bifurcations of :mod:`.sliding`); None
        #: keeps it a plain border collision.
        self.classify = classify
        self._maps: dict = {}
        #: The last refusal of a parameter value or state by the model or the method (why a correction failed).
        self.refusal = ""

    def doubled(self) -> "OrbitFamily":
        return OrbitFamily(self.problem_of, self.method, 2 * self.periods, self.classify)

    def problem(self, value: float, periods: int | None = None):
        problem = self.problem_of(value)
        T = problem.period
        if not np.isfinite(T):
            raise ParameterError("continuation needs a periodic switching law (a schedule or a ramp); this problem's "
                                 "law has no period")
        t0 = problem.t_span[0]
        return replace(problem, t_span=(t0, t0 + (periods or self.periods) * T))

    def period_map(self, value: float, periods: int | None = None):
        key = (float(value), periods or self.periods)
        cached = self._maps.get(key)
        if cached is None:
            if len(self._maps) >= 32:
                self._maps.pop(next(iter(self._maps)))
            cached = self._maps[key] = self.method.period_map(self.problem(value, periods))
        return cached

    def residual(self, value: float, x) -> tuple[np.ndarray, np.ndarray]:
        """F = P^k(x) - x and J = d P^k / d x."""
        px, jac = self.period_map(value)(x)
        return px - x, jac

    def parameter_derivative(self, value: float, x, step: float) -> np.ndarray:
        """d F / d p by a central difference of half-width ``step``."""
        return (self.period_map(value + step).end(x) - self.period_map(value - step).end(x)) / (2.0 * step)

    def orbit(self, value: float, x_guess, tol: float = 1e-10, max_iter: int = 30):
        """The orbit at a fixed parameter value (Newton shooting, :func:`.periodic.newton_orbit`)."""
        return newton_orbit(self.period_map(value), x_guess, tol=tol, max_iter=max_iter)

    def _events(self, value: float, x0) -> list:
        events = self.period_map(value).events(x0)
        if events is None:                              # a method whose map does not record events
            from ..simulate import simulate
            table = simulate(self.problem(value), self.method, x0=x0).events
            config = table["config"] if "config" in table else np.full(len(table), -1)
            events = list(zip(table["time"], table["kind"], table["pair"], config))
        return events

    def signature(self, value: float, x0) -> tuple:
        """(kind, pair, config) of every event over one orbit, as a cyclic sequence (its smallest rotation)."""
        return self.timed_signature(value, x0)[0]

    def timed_signature(self, value: float, x0) -> tuple[tuple, tuple]:
        """(signature, timed events). The orbit's events are read over two of its periods, in a window of one
        period that starts in the middle of the largest gap between them: an event at the orbit's start t0
        (a held state that begins right there, say) is then counted once, whichever side of t0 it falls on."""
        first = self._events(value, x0)
        if not first:
            return (), ()
        span = self.periods * self.problem_of(value).period
        x1 = self.period_map(value).end(x0)
        shifted = [(t + span, kind, pair, config) for t, kind, pair, config in self._events(value, x1)]
        times = sorted(float(e[0]) for e in first)
        gaps = np.diff(times + [times[0] + span])
        widest = int(np.argmax(gaps))
        cut = times[widest] + 0.5 * gaps[widest]
        window = sorted((e for e in list(first) + shifted if cut <= e[0] < cut + span), key=lambda e: e[0])
        timed = tuple(((float(t) - cut) / span, str(kind), int(pair), int(config)) for t, kind, pair, config in window)
        sequence = tuple(e[1:] for e in timed)
        return min((sequence[i:] + sequence[:i] for i in range(len(sequence))), default=()), timed

    def point(self, value: float, x0, jacobian) -> OrbitPoint:
        x0 = np.array(x0, dtype=float)
        samples = [x0]
        if self.periods > 1:
            one = self.period_map(value, 1)
            for _ in range(self.periods - 1):
                samples.append(one.end(samples[-1]))
        signature, timed = self.timed_signature(value, x0)
        return OrbitPoint(float(value), x0, np.array(samples), np.array(jacobian), multipliers_of(jacobian),
                          signature, timed)

    def event_names(self, value: float) -> tuple[tuple[str, ...], tuple[str, ...]]:
        problem = self.problem_of(value)
        configs = getattr(problem, "config_names", None) or tuple(c.name or f"config{i}"
                                                                  for i, c in enumerate(problem.configurations))
        return problem.pair_names, tuple(configs)


# --- the corrector ------------------------------------------------------------------------------------

@dataclass
class _Scaling:
    x_scale: float
    p_scale: float
    #: Relative step of the forward difference for F_p: 1e-7 suits exact maps; a map accurate to eps wants
    #: about sqrt(eps).
    fd_step: float = 1e-7

    def z(self, x, p) -> np.ndarray:
        return np.append(np.asarray(x, dtype=float) / self.x_scale, p / self.p_scale)

    def split(self, z) -> tuple[np.ndarray, float]:
        return z[:-1] * self.x_scale, float(z[-1] * self.p_scale)


@dataclass
class _Solved:
    z: np.ndarray
    x: np.ndarray
    value: float
    jacobian: np.ndarray
    tangent: np.ndarray
    iterations: int


def _extended_rows(family, scaling, x, value, fx, jacobian, fp=None):
    """[J - I, F_p p_scale / x_scale]: the Jacobian of F / x_scale in the scaled variables (F_p by a forward
    difference unless given)."""
    n = x.size
    if fp is None:
        step = scaling.fd_step * max(abs(value), scaling.p_scale)
        fp = (family.period_map(value + step).end(x) - x - fx) / step
    rows = np.empty((n, n + 1))
    rows[:, :n] = jacobian - np.eye(n)
    rows[:, n] = fp * scaling.p_scale / scaling.x_scale
    return rows, fp


def _null_vector(rows: np.ndarray) -> np.ndarray:
    """The unit null vector of an n x (n + 1) matrix (its last right singular vector)."""
    return np.linalg.svd(rows)[2][-1]


def _correct(family, scaling: _Scaling, z_start, normal, anchor, tol: float, max_iter: int = 10) -> _Solved | None:
    """Newton on [F(x, p) / x_scale; normal . (z - anchor)] = 0 from z_start (scaled variables). The column
    F_p is taken once at the start (a chord Newton in p: it moves little over one correction) and again at
    the solution for its tangent."""
    z = np.array(z_start, dtype=float)
    n = z.size - 1
    A = np.empty((n + 1, n + 1))
    fp = None
    for iteration in range(1, max_iter + 1):
        x, value = scaling.split(z)
        try:
            fx, jac = family.residual(value, x)
            if not np.all(np.isfinite(fx)):
                return None
            A[:n], fp = _extended_rows(family, scaling, x, value, fx, jac, fp)
        except (ValueError, RuntimeError) as exc:        # a parameter or state the model or method refuses
            family.refusal = str(exc)
            return None
        A[n] = normal
        rhs = -np.append(fx / scaling.x_scale, normal @ (z - anchor))
        try:
            dz = np.linalg.solve(A, rhs)
        except np.linalg.LinAlgError:
            return None
        if not np.all(np.isfinite(dz)):
            return None
        z = z + dz
        if np.abs(dz).max() <= tol:
            x, value = scaling.split(z)
            fx, jac = family.residual(value, x)
            rows, _ = _extended_rows(family, scaling, x, value, fx, jac)
            tangent = _null_vector(rows)
            return _Solved(z, x, value, jac, tangent if tangent @ normal >= 0 else -tangent, iteration)
    return None


# --- following a branch -----------------------------------------------------------------------------

def follow(family: OrbitFamily, start: float, stop: float, x_guess, *, max_step: float | None = None,
           tol: float = 1e-10, locate_tol: float = 1e-8, max_points: int = 2000, warm_up: int = 100,
           fd_step: float = 1e-7, on_point=None) -> Branch:
    """Follow the family's orbit from ``start`` to ``stop`` by pseudo-arclength continuation, locating every
    bifurcation on the way (module docstring).

    Parameters
    ----------
    family : OrbitFamily
    start, stop : float
        The parameter path; the branch is followed while the parameter stays in [min, max] of the two.
    x_guess : array_like, shape (n,)
        Seeds the first orbit: ``warm_up`` periods are simulated from it, then Newton shooting at ``start``.
    max_step : float, optional
        Largest step in the parameter (default |stop - start| / 60).
    tol : float
        Newton tolerance on the scaled variables (relative).
    locate_tol : float
        Bifurcations are bracketed to this chord length in scaled variables (relative to |stop - start|).
    fd_step : float
        Relative step of the difference quotient for d F / d p (1e-7 for exact maps; about the square root
        of the map's accuracy otherwise, with ``tol`` above that accuracy).
    on_point : callable, optional
        Called with each new orbit's parameter value (a progress bar).
    """
    from ..validate import as_vector, check_integer, check_positive, check_range, parse_value
    start, stop = parse_value("start", start), parse_value("stop", stop)
    span = stop - start
    if span == 0.0:
        raise ParameterError(f"the parameter path must have STOP != START; got {start:g}:{stop:g}")
    if max_step is not None:       # -1 or NaN had hung
        check_positive("max_step", max_step)
    check_range("tol", tol, 1e-15, 0.1)
    check_range("locate_tol", locate_tol, 1e-15, 0.1)
    check_range("fd_step", fd_step, 1e-15, 0.1)
    check_integer("max_points", max_points, 2, 10**6)
    check_integer("warm_up", warm_up, 0, 100_000)
    branch = Branch(family.periods)
    x = as_vector("x_guess", x_guess, None)
    try:
        one = family.period_map(start, 1)
        for _ in range(warm_up):
            x = one.end(x)
        # Newton from each of the orbit's k phases in turn: a phase where the map is degenerate (a state held
        # on a constraint for a whole period, say) is no start.
        for _ in range(family.periods):
            first = family.orbit(start, x, tol)
            if first.converged:
                break
            x = one.end(x)
    except (ValueError, RuntimeError) as exc:           # the model or method refused: a message, not a crash
        branch.message = f"no orbit of period {family.periods} at {start:.9g}: {exc}"
        return branch
    if not first.converged:
        branch.message = f"no orbit of period {family.periods} at {start:.9g}: {first.message}"
        return branch
    scaling = _Scaling(1.0 + float(np.abs(first.x0).max()), abs(span), fd_step)
    current = family.point(start, first.x0, first.jacobian)
    branch.points.append(current)
    fx, jac = family.residual(start, first.x0)
    tangent = _null_vector(_extended_rows(family, scaling, first.x0, start, fx, jac)[0])
    if abs(tangent[-1]) < 1e-3:                                  # starting on a fold: leave along the path
        tangent = np.zeros(first.x0.size + 1)
        tangent[-1] = 1.0
    tangent *= np.sign(span) * np.sign(tangent[-1])
    return _trace(family, branch, scaling, current, tangent, (min(start, stop), max(start, stop)), max_step or abs(span) / 60.0,
                  tol, locate_tol, max_points, on_point=on_point)


def _trace(family, branch, scaling, current: OrbitPoint, tangent, bounds, max_step, tol, locate_tol, max_points,
           first_step: float | None = None, on_point=None) -> Branch:
    """Pseudo-arclength steps from ``current`` along ``tangent`` until the parameter leaves ``bounds``."""
    ds_max = max_step / scaling.p_scale
    ds = first_step if first_step is not None else ds_max
    ds_min = 1e-7 * ds_max
    lo, hi = bounds
    while len(branch.points) < max_points:
        z = scaling.z(current.x0, current.value)
        predicted = z + ds * tangent
        family.refusal = ""
        solved = _correct(family, scaling, predicted, tangent, predicted, tol)
        nxt = None
        if solved is not None:
            turned = solved.tangent @ tangent
            drift = np.abs(solved.z - predicted).max()
            if turned < 0.8 or drift > 0.5 * ds + 10 * tol:
                # Turned or drifted: another branch was reached, unless the branch has a corner here (a border
                # collision changes the map's piece, so the orbit's events change) and still goes forward.
                nxt = family.point(solved.value, solved.x, solved.jacobian)
                if nxt.signature == current.signature or turned <= 0.0 or drift > 2.0 * ds:
                    solved = nxt = None
        if solved is None:
            if ds <= ds_min:
                previous = branch.points[-2] if len(branch.points) > 1 else None
                turned_branch = _turn_at_corner(family, scaling, current, previous, tangent, 10.0 * ds_max * 1e-3, tol)
                if turned_branch is not None:
                    solved, new_tangent = turned_branch
                    nxt = family.point(solved.value, solved.x, solved.jacobian)
                    branch.bifurcations += _detect(family, scaling, current, nxt, tol, locate_tol)
                    branch.points.append(nxt)
                    current, tangent, ds = nxt, new_tangent, 10.0 * ds_min
                    continue
                why = (f"the model or method refused the next orbit ({family.refusal})" if family.refusal else
                       "the branch ends, or turns at a border collision")
                branch.message = (f"continuation of the period-{family.periods} orbit stopped at {current.value:.9g}: "
                                  f"Newton's corrector does not converge even with a step of {ds * scaling.p_scale:.3g} "
                                  f"in the parameter; {why}")
                return branch
            ds = max(0.5 * ds, ds_min)
            continue
        if not lo <= solved.value <= hi:                          # past the path's end: land on it
            end = hi if solved.value > hi else lo
            frac = (end - current.value) / (solved.value - current.value)
            guess = z + frac * (solved.z - z)
            normal = np.zeros_like(z)
            normal[-1] = 1.0
            landed = _correct(family, scaling, guess, normal, scaling.z(guess[:-1] * scaling.x_scale, end), tol)
            if landed is None:
                branch.message = f"no orbit of period {family.periods} at the path's end {end:.9g} (Newton's corrector failed)"
                return branch
            nxt = family.point(end, landed.x, landed.jacobian)
            branch.bifurcations += _detect(family, scaling, current, nxt, tol, locate_tol)
            branch.points.append(nxt)
            return branch
        nxt = nxt or family.point(solved.value, solved.x, solved.jacobian)
        branch.bifurcations += _detect(family, scaling, current, nxt, tol, locate_tol)
        branch.points.append(nxt)
        if on_point is not None:
            on_point(nxt.value)
        tangent = solved.tangent if solved.tangent @ tangent > 0 else -solved.tangent
        current = nxt
        ds = min(ds * (1.6 if solved.iterations <= 3 else 0.8 if solved.iterations >= 6 else 1.0), ds_max)
    branch.message = f"stopped after {max_points} orbits at {current.value:.9g} (max_points)"
    return branch


def _turn_at_corner(family, scaling, current: OrbitPoint, previous: OrbitPoint | None, tangent, ds, tol):
    """The branch has a corner at ``current`` (a border collision where it turns back: a non-smooth fold), and
    no step along ``tangent`` finds an orbit. Candidates: the tangent of the map's piece at ``current`` itself
    (the last steps may already have crossed the corner), and that of the piece on the far side, found by
    probing where the event signature changes; each in both orientations. The first that lands on an orbit
    in a direction that does not reverse the arrival ``tangent`` wins. Returns (solved, tangent) or None.
    (``previous``: the orbit before ``current``, kept for the caller's bookkeeping.)"""
    z = scaling.z(current.x0, current.value)
    n = current.x0.size
    fx, jac = family.residual(current.value, current.x0)
    candidates = [_null_vector(_extended_rows(family, scaling, current.x0, current.value, fx, jac)[0])]
    probes = [tangent[:-1] / (np.linalg.norm(tangent[:-1]) or 1.0)] + list(np.eye(n))
    for direction in probes:
        for sign in (1.0, -1.0):
            for size in (1e-6, 1e-4):
                x_other = current.x0 + sign * size * scaling.x_scale * direction
                try:
                    if family.signature(current.value, x_other) == current.signature:
                        continue
                    fx, jac = family.residual(current.value, x_other)
                    candidates.append(_null_vector(_extended_rows(family, scaling, x_other, current.value, fx, jac)[0]))
                except (ValueError, RuntimeError):
                    continue
                break
    for other in candidates:
        for orientation in (other, -other):
            predicted = z + ds * orientation
            solved = _correct(family, scaling, predicted, orientation, predicted, tol)
            if solved is None or np.abs(solved.z - z).max() <= 0.1 * ds:
                continue
            # Not back the way the branch came: the step's direction must not reverse the arrival ``tangent``.
            step = (solved.z - z) / np.linalg.norm(solved.z - z)
            if step @ tangent < -0.9:
                continue
            new_tangent = solved.tangent if solved.tangent @ orientation > 0 else -solved.tangent
            return solved, new_tangent
    return None


# --- detection and location ---------------------------------------------------------------------------

def _detect(family, scaling, a: OrbitPoint, b: OrbitPoint, tol, locate_tol) -> list[Bifurcation]:
    """Every bifurcation between consecutive orbits a and b (module docstring)."""
    found: list[Bifurcation] = []
    collision = None
    if a.signature != b.signature:
        lo, hi, note = _locate(family, scaling, a, b, lambda s: s.signature == a.signature, None, tol, locate_tol)
        collision = _border_collision(family, lo, hi, note)
    tests_a, tests_b = a.tests, b.tests
    for kind in ("period-doubling", "fold", "neimark-sacker"):
        fa, fb = tests_a[kind], tests_b[kind]
        if fa is None or fb is None or fa == 0.0 or np.sign(fa) == np.sign(fb):
            continue
        lo, hi, note = _locate(family, scaling, a, b,
                               lambda s, kind=kind: s.tests[kind] is not None and np.sign(s.tests[kind]) == np.sign(fa),
                               lambda s, kind=kind: s.tests[kind], tol, locate_tol)
        at_collision = collision is not None and abs(0.5 * (lo.value + hi.value) - collision.value) <= (
            2.0 * (collision.width + abs(hi.value - lo.value)) + 1e-12 * (1.0 + abs(collision.value)))
        if at_collision:                                         # the multipliers jump at the border collision
            crossing = {"period-doubling": "-1", "fold": "+1"}.get(kind, "the unit circle")
            collision = replace(collision, detail=collision.detail + f"; {TEST_NAMES[kind]} changes sign there (a "
                                f"multiplier jumps across {crossing})")
            continue
        f_lo, f_hi = lo.tests[kind], hi.tests[kind]
        if f_lo is not None and f_hi is not None and f_lo != f_hi:
            value = lo.value + (hi.value - lo.value) * f_lo / (f_lo - f_hi)
        else:
            value = 0.5 * (lo.value + hi.value)
        near = lo if abs(f_lo or 0.0) <= abs(f_hi or 0.0) else hi
        below, above = (lo, hi) if lo.value <= hi.value else (hi, lo)
        found.append(Bifurcation(kind, float(value), family.periods, near.multipliers, near.x0,
                                 f"false position (Illinois) on {TEST_NAMES[kind]} along the branch, then the secant zero "
                                 "of the final bracket" + (f" ({note})" if note else ""), abs(hi.value - lo.value),
                                 below.stable, above.stable))
    if collision is not None:
        found.append(collision)
    return sorted(found, key=lambda b: b.value)


def _locate(family, scaling, a: OrbitPoint, b: OrbitPoint, same_as_a, test, tol, locate_tol):
    """Bracket the change between orbits a and b of the predicate ``same_as_a`` (true at a, false at b), to a
    chord of ``locate_tol`` in scaled variables. Each new orbit is solved on the plane normal to the chord
    through the trial point, so that a bracket around a fold narrows too. The trial point is the chord's
    midpoint (bisection), or with a signed ``test`` function its false-position zero (Illinois: the
    retained end's value is halved, so both ends converge). Returns (lo, hi, note): the final bracket, lo
    on a's side, and a note when it could not be narrowed."""
    lo, hi = a, b
    f_lo, f_hi = (test(a), test(b)) if test is not None else (None, None)
    retained = 0
    for _ in range(100):
        z_lo, z_hi = scaling.z(lo.x0, lo.value), scaling.z(hi.x0, hi.value)
        chord = z_hi - z_lo
        length = float(np.linalg.norm(chord))
        if length <= locate_tol:
            return lo, hi, ""
        fraction = 0.5
        if test is not None and f_lo != f_hi:
            fraction = min(max(f_lo / (f_lo - f_hi), 0.02), 0.98)   # a step off the ends, so the bracket shrinks
        trial = z_lo + fraction * chord
        solved = _correct(family, scaling, trial, chord / length, trial, tol)
        if solved is None:
            return lo, hi, f"bracket left at chord length {length:.2g}: no orbit found inside it"
        mid = family.point(solved.value, solved.x, solved.jacobian)
        f_mid = test(mid) if test is not None else None
        if same_as_a(mid):
            lo, f_lo = mid, f_mid
            retained = retained + 1 if retained >= 0 else 1       # hi retained again: halve its value
            if test is not None and retained >= 2:
                f_hi *= 0.5
        else:
            hi, f_hi = mid, f_mid
            retained = retained - 1 if retained <= 0 else -1
            if test is not None and retained <= -2:
                f_lo *= 0.5
    return lo, hi, "bracket left after 100 steps"


def _border_collision(family, lo: OrbitPoint, hi: OrbitPoint, note: str) -> Bifurcation:
    pairs, configs = family.event_names(lo.value)
    below, above = (lo, hi) if lo.value <= hi.value else (hi, lo)
    detail = (f"events per orbit {len(below.signature)} -> {len(above.signature)}: "
              + _describe_change(below.signature, above.signature, pairs, configs))
    how = "bisection on the orbit's event signature along the branch" + (f" ({note})" if note else "")
    kind = "border-collision"
    named = family.classify(below, above) if family.classify is not None else None
    if named is not None:
        kind, explanation = named
        detail = f"{explanation}; {detail}"
    return Bifurcation(kind, 0.5 * (lo.value + hi.value), family.periods, below.multipliers,
                       below.x0, how, abs(hi.value - lo.value), below.stable, above.stable,
                       multipliers_after=above.multipliers, detail=detail)


def _event_label(event, pairs, configs) -> str:
    kind, pair, config = event
    if kind == "switch":
        return f"switching to {configs[config] if 0 <= config < len(configs) else config}"
    name = pairs[pair] if 0 <= pair < len(pairs) else f"pair {pair}"
    where = f" in {configs[config]}" if 0 <= config < len(configs) else ""
    # In the LCS's own terms: which of the pair's u and y is held at zero is the model's business.
    state = {"activate": "held (y = 0)", "release": "freed (u = 0)"}.get(kind, kind)
    if kind in ("stick", "slip", "cross", "touch", "impact", "chatter", "detach"):     # mechanical contacts
        where = f" ({configs[config]})" if 0 <= config < len(configs) else ""
    return f"{name} {state}{where}"


def _describe_change(before: tuple, after: tuple, pairs, configs) -> str:
    from collections import Counter
    count_before, count_after = Counter(before), Counter(after)
    gained = [f"{_event_label(e, pairs, configs)} x{count_after[e] - count_before[e]}"
              for e in count_after if count_after[e] > count_before[e]]
    lost = [f"{_event_label(e, pairs, configs)} x{count_before[e] - count_after[e]}"
            for e in count_before if count_before[e] > count_after[e]]
    parts = ([f"appear: {', '.join(gained)}"] if gained else []) + ([f"vanish: {', '.join(lost)}"] if lost else [])
    return "; ".join(parts) or "the order of the events changes"


# --- branch switching -------------------------------------------------------------------------------

def switch_branch(family: OrbitFamily, bifurcation: Bifurcation, start: float, stop: float, *,
                  max_step: float | None = None, tol: float = 1e-10, locate_tol: float = 1e-8,
                  max_points: int = 2000, fd_step: float = 1e-7) -> Branch:
    """The period-2k branch born at a period doubling of the period-k branch, followed while the parameter
    stays in [min, max] of (start, stop) (module docstring). The bifurcation orbit, counted twice, is its
    first point."""
    if bifurcation.kind != "period-doubling":
        raise ParameterError(f"branch switching starts at a period doubling; got a {bifurcation.kind}")
    doubled = family.doubled()
    branch = Branch(doubled.periods, parent=bifurcation)
    span = abs(stop - start)
    _, jac = family.period_map(bifurcation.value)(bifurcation.x0)
    values, vectors = np.linalg.eig(jac)
    v = np.real(vectors[:, np.argmin(np.abs(values + 1.0))])
    scaling = _Scaling(1.0 + float(np.abs(bifurcation.x0).max()), span, fd_step)
    z_star = scaling.z(bifurcation.x0, bifurcation.value)
    direction = np.append(v / scaling.x_scale, 0.0)
    direction /= np.linalg.norm(direction)
    _, jac2 = doubled.period_map(bifurcation.value)(bifurcation.x0)
    branch.points.append(doubled.point(bifurcation.value, bifurcation.x0, jac2))
    max_step = max_step or span / 60.0
    # The smallest step along v that lands on a genuine period-2k orbit: the new branch leaves the pitchfork
    # as p - p* ~ |x - x*|^2, so a long first step can carry it past the next bifurcation.
    for ds in (1e-5, 3e-5, 1e-4, 3e-4, 1e-3, 3e-3, 1e-2):
        predicted = z_star + ds * direction
        solved = _correct(doubled, scaling, predicted, direction, predicted, tol)
        if solved is None or not min(start, stop) <= solved.value <= max(start, stop):
            continue
        half = family.period_map(solved.value).end(solved.x)            # P^k(x) != x on a genuine 2k orbit
        if np.abs(half - solved.x).max() <= 1e-3 * ds * scaling.x_scale:
            continue
        point = doubled.point(solved.value, solved.x, solved.jacobian)
        branch.points.append(point)
        tangent = solved.tangent if solved.tangent @ (solved.z - z_star) > 0 else -solved.tangent
        return _trace(doubled, branch, scaling, point, tangent, (min(start, stop), max(start, stop)), max_step, tol,
                      locate_tol, max_points, first_step=max(ds, 1e-3 * max_step / span))
    branch.message = (f"no period-{doubled.periods} orbit found next to the period doubling at {bifurcation.value:.9g} "
                      "(steps of 3e-4 to 3e-2 along the multiplier -1's eigenvector)")
    return branch


def cascade(family: OrbitFamily, start: float, stop: float, x_guess, *, max_period: int = 8, **options) -> list[Branch]:
    """Follow the period-k orbit over the path and, at every period doubling where an orbit loses stability,
    the period-2k orbit born there, up to orbits of ``max_period`` switching periods. Returns every branch,
    the first one first, each child after its parent."""
    from ..validate import check_integer
    check_integer("max_period", max_period, family.periods, 1024)         # 0, 1.5 or 1e9 are no period count
    branches = [follow(family, start, stop, x_guess, **options)]
    switch_options = {k: v for k, v in options.items() if k in ("max_step", "tol", "locate_tol", "max_points", "fd_step")}
    queue = [(branches[0], family)]
    while queue:
        branch, fam = queue.pop(0)
        if fam.periods * 2 > max_period:
            continue
        for bif in branch.bifurcations:
            if bif.kind != "period-doubling" or bif.stable_before == bif.stable_after:
                continue
            child = switch_branch(fam, bif, start, stop, **switch_options)
            branches.append(child)
            queue.append((child, fam.doubled()))
    return branches


def check_path(name: str, start: float, stop: float, low: float, high: float, low_open: bool = True,
               high_open: bool = True) -> None:
    """A path inside the parameter's valid range, or one clear line."""
    def outside(v):
        return (v <= low if low_open else v < low) or (v >= high if high_open else v > high)
    if outside(start) or outside(stop):
        lb, rb = "(" if low_open else "[", ")" if high_open else "]"
        raise ParameterError(f"the path of {name} must lie in {lb}{low:g}, {high:g}{rb}; got {start:g}:{stop:g}")
    if start == stop:
        raise ParameterError(f"the path of {name} must have START != STOP; got {start:g}:{stop:g}")


__all__ = ["OrbitFamily", "OrbitPoint", "Bifurcation", "Branch", "follow", "switch_branch", "cascade",
           "test_functions", "check_path", "KINDS"]
