"""Smoothing: the ideal diode replaced by a smooth law and integrated by a stiff ODE solver.

Each complementarity pair 0 <= u _|_ y >= 0 (with D = 0, so y = C x + F is a function of the state)
becomes the softplus penalty

    u = eps log(1 + exp(-y / eps^2))    (SI units: V or A, whatever the pair carries)

a penalty max(0, -y) / eps with its corner rounded over |y| ~ eps^2. The LCS turns into the smooth
ODE x' = A x + E + B u(C x + F). A held pair (u > 0) sits at y ~ -eps u, a free one carries
u ~ eps exp(-y / eps^2), and u(0) = eps log 2: every error is O(eps). The price is stiffness: the
Jacobian A - B diag(sigma(-y / eps^2) / eps) C has an eigenvalue near -(C B) / eps while the pair is held, so
the stiffness ratio grows like 1/eps; scipy's implicit solvers (Radau, BDF, LSODA) with a tolerance
integrate it, restarted at every schedule instant. ``metadata['stats']`` of the returned Trajectory
reports output points, function and Jacobian evaluations, LU factorisations (``Trajectory.steps``)
and max |lambda| T along the run, the measure of stiffness.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, NotRequired, TypedDict, cast

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError, SimulationError
from ..validate import check_positive, check_range, parse_value
from ..problems import LCSProblem, Schedule
from ..trajectory import Trajectory
from .base import ErrorKind, Method

#: Accepted eps (V or A): the error is O(eps), so above 0.1 the answer is the smoothing's, not the circuit's; below
#: 1e-8 the stiffness (~1/eps) and the corner's width eps^2 leave double precision and the solver nothing to resolve.
EPS_RANGE = (1e-8, 0.1)

Vector = npt.NDArray[np.float64]
Matrix = npt.NDArray[np.float64]


@dataclass(frozen=True)
class Smoothing(Method, key="smooth"):
    """The ideal diode replaced by a smooth law (module docstring), integrated by a stiff solver.

    The complementarity pair 0 <= u _|_ y >= 0 becomes u = eps log(1 + exp(-y / eps^2)) (SI units,
    V or A): the penalty max(0, -y) / eps with its corner rounded over |y| ~ eps^2, exponential like
    a real diode's law. A held pair sits at y ~ -eps u, a free one carries u ~ eps exp(-y / eps^2).

    Parameters
    ----------
    eps : float
        Smoothing width in the units of y, in [1e-8, 0.1] (``EPS_RANGE``; smaller is closer to the ideal diode and
        stiffer).
    solver_rtol, atol : float
        Tolerances of scipy's solve_ivp (atol default 1e-3 solver_rtol). Not an accuracy target: the result's
        error is the smoothing's, O(eps), whatever the solver's tolerance (``--rtol`` is the accuracy target
        of the other methods' steady states, :mod:`converters.analysis.accuracy`).
    solver : str
        A stiff solve_ivp method: 'Radau', 'BDF' or 'LSODA'.
    output_step : float or None
        Spacing of the output samples (s); None: the solver's own steps.
    """

    counts = "LU factorisations"
    error_kind = ErrorKind.MODEL
    model_error = "the smoothing's, O(eps)"

    eps: float = 1e-4
    solver_rtol: float = 1e-6
    atol: float | None = None
    solver: str = "Radau"
    output_step: float | None = None
    step_option = "output_step"
    bytes_per_value = 200.0
    description = "pairs smoothed by u = eps log(1 + exp(-y / eps^2)) (--eps), scipy Radau (--solver-rtol)"

    def __post_init__(self) -> None:
        object.__setattr__(self, "eps", check_range("eps", self.eps, *EPS_RANGE))
        rtol = parse_value("solver_rtol", self.solver_rtol)
        if not 1e-13 <= rtol <= 0.1:
            raise ParameterError(f"solver_rtol must be in [1e-13, 0.1]; got {rtol!r}")
        object.__setattr__(self, "solver_rtol", rtol)
        if self.atol is not None:
            object.__setattr__(self, "atol", check_positive("atol", self.atol))
        if self.solver not in ("Radau", "BDF", "LSODA"):
            raise ParameterError(f"solver must be one of Radau, BDF, LSODA; got {self.solver!r}")
        if self.output_step is not None:
            object.__setattr__(self, "output_step", check_positive("output_step", self.output_step, "s"))

    @property
    def order(self) -> float:
        """The model error is O(eps): order 1 in eps (the solver's own error is set by solver_rtol)."""
        return 1.0

    @property
    def label(self) -> str:
        return f"smooth({self.eps:g})"

    def supports(self, problem: LCSProblem) -> None:
        if problem.inputs is not None:
            raise ParameterError("the smoothing method takes constant inputs per configuration; sinusoidal inputs "
                                 "(SIN sources): use --method lcp")
        if not isinstance(problem.switching, Schedule):
            raise ParameterError(f"the smoothing method integrates time schedules only; this problem is switched by "
                                 f"{type(problem.switching).__name__}: use --method lcp or event")
        for c in problem.configurations:
            if np.any(c.D):
                raise ParameterError(f"the smoothing method needs D = 0 in every configuration (y a function of the "
                                     f"state); configuration {c.name!r} has D = {c.D.tolist()}: use the LCP "
                                     "time-stepper")

    def solve(self, problem: LCSProblem, x0: np.ndarray) -> Trajectory:
        """Integrate the smoothed LCS over ``problem.t_span``; solver statistics in ``metadata['stats']``."""
        return _integrate(problem, self, np.array(x0, dtype=float))


def _pair_law(y: npt.NDArray[np.float64], eps: float) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """u(y) and du/dy of the softplus law u = eps log(1 + exp(-y / eps^2))."""
    z = -y / (eps * eps)
    from scipy.special import expit
    return eps * np.logaddexp(0.0, z), -expit(z) / eps


class _SolverStats(TypedDict):
    """``metadata['stats']`` of a smoothing run (module docstring)."""

    points: int
    nfev: int
    njev: int
    nlu: int
    max_rho_T: float
    wall_s: NotRequired[float]


def _integrate(problem: LCSProblem, method: Smoothing, x: np.ndarray) -> Trajectory:
    from scipy.integrate import solve_ivp
    start_clock = time.perf_counter()
    t0, t1 = problem.t_span
    assert isinstance(problem.switching, Schedule)          # supports() admits schedules only
    edges = np.concatenate([[t0], problem.switching.breakpoints(t0, t1), [t1]])
    eps, atol = method.eps, method.atol if method.atol is not None else 1e-3 * method.solver_rtol
    ts, xs, cs = [np.array([t0])], [x[None, :]], []
    stats: _SolverStats = {"points": 0, "nfev": 0, "njev": 0, "nlu": 0, "max_rho_T": 0.0}
    scale_T = problem.switching.period if np.isfinite(problem.switching.period) else (t1 - t0)
    first_config = int(problem.switching.config_at(np.array([0.5 * (edges[0] + edges[1])]))[0])
    cs.append(np.array([first_config]))
    for a, b in zip(edges[:-1], edges[1:]):
        config_index = int(problem.switching.config_at(np.array([0.5 * (a + b)]))[0])
        c = problem.configurations[config_index]
        assert c.E is not None and c.F is not None          # a Configuration fills them in (zero by default)
        A, B, C, E, F = c.A, c.B, c.C, c.E, c.F

        def rhs(t: float, state: Vector, A: Matrix = A, B: Matrix = B, C: Matrix = C, E: Vector = E,
                F: Vector = F) -> Vector:
            u, _ = _pair_law(C @ state + F, eps)
            return A @ state + E + B @ u

        def jac(t: float, state: Vector, A: Matrix = A, B: Matrix = B, C: Matrix = C, F: Vector = F) -> Matrix:
            _, du = _pair_law(C @ state + F, eps)
            return A + (B * du) @ C

        t_eval = None
        if method.output_step is not None:
            inner = a + method.output_step * np.arange(1, int(np.ceil((b - a) / method.output_step)) + 1)
            t_eval = np.concatenate([[a], inner[inner < b - 1e-9 * method.output_step], [b]])   # sol.t[0] = a
        # with a small eps, scipy's Radau step-size predictor (predict_factor) can divide by zero; the infinite
        # ratio is then capped by its min(1, .), as scipy intends: not a warning for the user
        with np.errstate(divide="ignore"):
            sol = solve_ivp(rhs, (a, b), x, method=method.solver, rtol=method.solver_rtol, atol=atol, jac=jac,
                            t_eval=t_eval)
        if sol.status != 0 or not np.all(np.isfinite(sol.y)):
            raise SimulationError(f"the smoothed system could not be integrated over [{a:.6g}, {b:.6g}] s "
                                  f"({method.solver}, eps = {eps:g}, solver_rtol = {method.solver_rtol:g}): {sol.message}")
        stats["points"] += sol.t.size - 1
        stats["nfev"] += int(sol.nfev)
        stats["njev"] += int(sol.njev)
        stats["nlu"] += int(sol.nlu)
        pts = sol.y.T
        for state in pts[:: max(1, pts.shape[0] // 16)]:
            rho = np.abs(np.linalg.eigvals(jac(0.0, state))).max()
            stats["max_rho_T"] = max(stats["max_rho_T"], float(rho * scale_T))
        ts.append(sol.t[1:])
        xs.append(pts[1:])
        cs.append(np.full(sol.t.size - 1, config_index))
        x = pts[-1].copy()
    t, xx, config = np.concatenate(ts), np.vstack(xs), np.concatenate(cs)
    Cs = np.stack([c.C for c in problem.configurations])[config]
    Fs = np.stack([cast(np.ndarray, c.F) for c in problem.configurations])[config]       # F filled in (zero by default)
    y = np.einsum("nkj,nj->nk", Cs, xx) + Fs
    u, _ = _pair_law(y, eps)
    stats["wall_s"] = time.perf_counter() - start_clock
    return Trajectory(t=t, x=xx, u=u, y=y, config=config, state_names=problem.state_names,
                      pair_names=problem.pair_names,
                      config_names=tuple(c.name or f"config{i}" for i, c in enumerate(problem.configurations)),
                      event_columns=_events(t, u, y, config), method=method.key, steps=stats["nlu"],
                      wall_s=stats["wall_s"], rule="linear", period=problem.switching.period,
                      metadata=dict(problem.metadata, eps=eps, solver_rtol=method.solver_rtol, solver=method.solver, stats=stats,
                                    label=method.label))


def _events(t: npt.NDArray[np.float64], u: npt.NDArray[np.float64], y: npt.NDArray[np.float64],
            config: npt.NDArray[np.int64]) -> dict[str, npt.NDArray[Any]]:
    """Pair switches where sign(u - y) changes inside a configuration, placed by linear interpolation."""
    d = u - y
    steps, pairs = np.nonzero(np.sign(d[1:]) != np.sign(d[:-1]))
    keep = config[steps] == config[steps + 1]
    steps, pairs = steps[keep], pairs[keep]
    a, b = d[steps, pairs], d[steps + 1, pairs]
    frac = np.where(a != b, a / (a - b), 0.5)
    return {"time": t[steps] + frac * (t[steps + 1] - t[steps]), "step": steps, "pair": pairs,
            "kind": np.where(b > 0, "activate", "release")}
