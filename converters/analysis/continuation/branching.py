"""Branch switching at a period doubling (the period-2k branch along the eigenvector of the multiplier -1) and
the cascade of doublings."""
from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from ...errors import ParameterError

from .corrector import _correct, _Scaling
from .family import Bifurcation, Branch, OrbitFamily
from .tracing import _trace, follow


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


def cascade(family: OrbitFamily, start: float, stop: float, x_guess: npt.ArrayLike, *, max_period: int = 8,
            **options: Any) -> list[Branch]:
    """Follow the period-k orbit over the path and, at every period doubling where an orbit loses stability,
    the period-2k orbit born there, up to orbits of ``max_period`` switching periods. Returns every branch,
    the first one first, each child after its parent."""
    from ...validate import check_integer
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
