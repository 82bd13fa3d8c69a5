"""Following a branch: predictor-corrector steps with step control, turning at corners of the piecewise-smooth
map, and detection of bifurcations between consecutive orbits."""
from __future__ import annotations

from collections.abc import Callable

import numpy as np
import numpy.typing as npt

from ...errors import ParameterError

from .corrector import _correct, _extended_rows, _null_vector, _Scaling, _Solved
from .detection import _detect
from .family import KINDS, Branch, OrbitFamily, OrbitPoint


def follow(family: OrbitFamily, start: float, stop: float, x_guess: npt.ArrayLike, *, max_step: float | None = None,
           tol: float = 1e-10, locate_tol: float = 1e-8, max_points: int = 2000, warm_up: int = 100,
           fd_step: float = 1e-7, on_point: Callable[[float], object] | None = None,
           stop_at: str | tuple[str, ...] = ()) -> Branch:
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
    stop_at : str or tuple of str
        Bifurcation kinds (:data:`.family.KINDS`) that end the branch once located: a grazing, say, where the
        map's Jacobian has a square-root singularity and beyond which the orbit is another one.
    """
    from ...validate import as_vector, check_integer, check_positive, check_range, parse_value
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
    stop_at = (stop_at,) if isinstance(stop_at, str) else tuple(stop_at)
    unknown = [kind for kind in stop_at if kind not in KINDS]
    if unknown:
        raise ParameterError(f"stop_at must name bifurcation kinds ({', '.join(KINDS)}); got {unknown[0]!r}")
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
                  tol, locate_tol, max_points, on_point=on_point, stop_at=stop_at)


def _trace(family: OrbitFamily, branch: Branch, scaling: _Scaling, current: OrbitPoint,
           tangent: npt.NDArray[np.float64], bounds: tuple[float, float], max_step: float, tol: float,
           locate_tol: float, max_points: int, first_step: float | None = None,
           on_point: Callable[[float], object] | None = None, stop_at: tuple[str, ...] = ()) -> Branch:
    """Pseudo-arclength steps from ``current`` along ``tangent`` until the parameter leaves ``bounds`` (or a
    bifurcation of a kind in ``stop_at`` is located)."""
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
        found = _detect(family, scaling, current, nxt, tol, locate_tol)
        branch.bifurcations += found
        branch.points.append(nxt)
        if on_point is not None:
            on_point(nxt.value)
        ends = [b for b in found if b.kind in stop_at]
        if ends:
            branch.message = f"stopped at the {ends[0].kind} at {ends[0].value:.9g} (stop_at)"
            return branch
        tangent = solved.tangent if solved.tangent @ tangent > 0 else -solved.tangent
        current = nxt
        ds = min(ds * (1.6 if solved.iterations <= 3 else 0.8 if solved.iterations >= 6 else 1.0), ds_max)
    branch.message = f"stopped after {max_points} orbits at {current.value:.9g} (max_points)"
    return branch


def _turn_at_corner(family: OrbitFamily, scaling: _Scaling, current: OrbitPoint, previous: OrbitPoint | None,
                    tangent: npt.NDArray[np.float64], ds: float, tol: float) -> tuple[_Solved, np.ndarray] | None:
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
