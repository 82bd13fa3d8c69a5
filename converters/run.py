"""Run a converter: parameters in, labelled waveforms and a summary out.

``run_converter`` builds the problem, picks h and the duration, optionally runs to the periodic
steady state (chunk by chunk, keeping only the last chunk in memory), and returns a
:class:`ConverterRun` whose ``waveforms()`` has the CONTRACT columns: time, one per state, vout,
switch, mode.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from .errors import ParameterError, SimulationError
from .models import Converter, check_h, get_converter
from .methods import EventDriven, Smoothing, Theta
from .analysis.periodic import newton_fixed_point, one_period, shoot
from .simulate import simulate
from .trajectory import Trajectory
from .validate import parse_value

STEADY_CHUNK_PERIODS = 20
DEFAULT_PERIODS = 500


@dataclass
class ConverterRun:
    converter: Converter
    params: dict
    method: Theta
    trajectory: Trajectory
    wall_s: float
    periods_simulated: int
    steady_periods: int | None = None
    extra: dict = field(default_factory=dict)

    @property
    def period(self) -> float:
        return self.converter.period(self.params)

    def vout(self) -> np.ndarray:
        tr = self.trajectory
        return self.converter.vout(tr.x, tr.u, tr.config, self.params)

    def modes(self) -> np.ndarray:
        tr = self.trajectory
        return self.converter.modes(tr.active, tr.config, tr.x)

    def waveforms(self) -> pd.DataFrame:
        tr = self.trajectory
        data = {"time": tr.t}
        for i, name in enumerate(tr.state_names):
            data[name] = tr.x[:, i]
        data["vout"] = self.vout()
        data["switch"] = self.converter.switch(tr.config)
        data["mode"] = self.modes()
        return pd.DataFrame(data)

    def window(self, periods: int) -> np.ndarray:
        """Boolean mask of the points in the last ``periods`` switching periods."""
        t = self.trajectory.t
        return t >= t[-1] - periods * self.period * (1.0 + 1e-12)

    @property
    def method_name(self) -> str:
        return {EventDriven: "event", Smoothing: "smooth"}.get(type(self.method), "lcp")

    def method_options(self) -> dict:
        if isinstance(self.method, Theta):
            return {"h": self.method.h, "theta": self.method.theta}
        return dict(self.method.__dict__)

    def vout_mean(self, periods: int = 10) -> float:
        """Mean output voltage over the last ``periods`` periods: exact (Gauss-Legendre on the exact
        solution) for the event-driven method, trapezoidal for smoothing, the stepper's own rule for LCP."""
        solution = self.extra.get("event_solution")
        t = self.trajectory.t
        t0 = max(t[0], t[-1] - periods * self.period)
        if solution is not None:
            tq, w, x, u, config = solution.quadrature(t0, t[-1])
            return float(w @ self.converter.vout(x, u, config, self.params) / (t[-1] - t0))
        if isinstance(self.method, Smoothing):
            mask = self.window(periods)
            return float(np.trapezoid(self.vout()[mask], t[mask]) / (t[mask][-1] - t[mask][0]))
        return self.mean(self.vout(), periods)

    def mean(self, signal: np.ndarray, periods: int = 10) -> float:
        """Time average over the last ``periods`` periods.

        Each step counts with its end-point value (as in backward Euler, and as the mode labels are
        assigned), so switched quantities are weighted by the configuration that held in the step.
        """
        mask = self.window(periods)
        t = self.trajectory.t[mask]
        return float(np.sum(np.diff(t) * signal[mask][1:]) / (t[-1] - t[0]))

    def mode_fractions(self, periods: int = 1) -> dict:
        """Fraction of the last period(s) spent in each mode (each step counted by its end-point label)."""
        mask = self.window(periods)
        t = self.trajectory.t[mask]
        labels = self.modes()[mask][1:]
        dt = np.diff(t)
        total = dt.sum()
        return {str(label): float(dt[labels == label].sum() / total) for label in sorted(set(labels))}

    def summary(self) -> dict:
        out = {"converter": self.converter.name, "method": self.method_name,
               "options": {**self.method_options(), "params": self.params},
               "steps": int(self.trajectory.steps), "wall_s": self.wall_s,
               "vout_mean": self.vout_mean(10), "mode_fractions": self.mode_fractions(1),
               "periods": self.periods_simulated}
        if self.steady_periods is not None:
            out["steady_periods"] = self.steady_periods
        return out


def run_converter(name_or_converter, params: dict | None = None, *, h=None, theta=None, t_end=None,
                  periods=None, steady=False, steady_tol=1e-6, max_periods=200_000, x0=None,
                  method: str = "lcp", eps=None, rtol=None) -> ConverterRun:
    """Simulate a converter with the LCP time-stepper (or the event-driven or smoothing method).

    Parameters
    ----------
    name_or_converter : str or Converter
    params : dict
        Parameter values (numbers or SPICE-style strings); unknown names are refused.
    h : float, optional
        Step in s; default T/1000 (PRC: 50 ns). Must be below the switching period T.
    theta : float, optional
        0.5..1; the converter's default when omitted.
    t_end, periods : optional
        Duration in s or in switching periods (default 500 periods). With ``steady`` it is the
        budget (default 200000 periods): the run stops earlier once the cycle-to-cycle change is below ``steady_tol``.
    steady : bool
        Run until the periodic steady state: 20 warm-up periods, Newton shooting on the one-period
        map (:mod:`converters.analysis.periodic`), then 20 periods simulated on until the estimated distance to the periodic orbit (from
        the geometric decay of the cycle-to-cycle change max |x((m+1)T) - x(mT)|) below
        ``steady_tol`` times (1 + max |x|). The last 20 periods are returned.
    """
    converter = get_converter(name_or_converter) if isinstance(name_or_converter, str) else name_or_converter
    p = converter.resolve(params)
    T = converter.period(p)
    h = check_h(converter.default_h(p) if h is None else parse_value("h", h), T)
    if method not in ("lcp", "event", "smooth"):
        raise ParameterError(f"method must be one of lcp, event, smooth; got {method!r}")
    if method != "smooth" and (eps is not None or rtol is not None):
        raise ParameterError("eps and rtol apply to method='smooth' only")
    if method != "lcp" and theta is not None:
        raise ParameterError("theta applies to method='lcp' only")
    kind = method
    if kind == "event":
        method = EventDriven(output_step=h)
    elif kind == "smooth":
        method = Smoothing(eps=1e-4 if eps is None else eps, rtol=1e-6 if rtol is None else rtol, output_step=h)
    else:
        method = Theta(h, converter.default_theta if theta is None else theta)
    if t_end is not None and periods is not None:
        raise ParameterError("give either t_end or periods, not both")
    if t_end is not None:
        t_end = parse_value("t_end", t_end)
        if t_end <= 0:
            raise ParameterError(f"t_end must be positive (> 0 s); got {t_end!r}")
        n_periods = t_end / T
    elif periods is not None:
        if not (isinstance(periods, (int, np.integer)) and periods >= 1):
            raise ParameterError(f"periods must be an integer >= 1; got {periods!r}")
        n_periods = periods
    else:
        n_periods = max_periods if steady else DEFAULT_PERIODS
    start = time.perf_counter()
    if kind != "lcp":
        return _run_exact_or_smooth(converter, p, method, x0, n_periods, steady, steady_tol, start)
    if steady:
        return _run_to_steady_state(converter, p, method, x0, steady_tol, int(np.ceil(n_periods)), start)
    tr = simulate(converter.problem(p, n_periods * T, x0), method)
    return ConverterRun(converter, p, method, tr, time.perf_counter() - start, int(round(n_periods)))


def _run_exact_or_smooth(converter, p, method, x0, n_periods, steady, tol, start) -> ConverterRun:
    """Event-driven or smoothing run; ``steady``: Newton shooting on the method's own period map (from
    the LCP stepper's periodic orbit), then the last STEADY_CHUNK_PERIODS periods from the fixed point."""
    from .analysis.modes import periodic_orbit
    from .methods.event import _Machine, simulate_event
    from .methods.smoothing import simulate_smooth
    T = converter.period(p)
    extra = {}
    if steady:
        guess = periodic_orbit(converter, p).x[0]
        one = converter.problem(p, T)
        if isinstance(method, EventDriven):
            machine = _Machine(one, method)
            period_map = lambda x: machine.run(x, record=False).x_end  # noqa: E731
        else:
            period_map = lambda x: simulate_smooth(one, method, x0=x).x[-1]  # noqa: E731
        shot = newton_fixed_point(period_map, guess, tol=min(1e-12, 0.1 * tol))
        if not shot.converged:
            raise SimulationError(f"Newton shooting found no periodic orbit (residual {shot.residual:.3g} after "
                                  f"{shot.iterations} iterations); try --periods without --steady")
        x0, n_periods = shot.x, STEADY_CHUNK_PERIODS
        extra = {"shooting_iterations": shot.iterations, "shooting_residual": shot.residual}
    problem = converter.problem(p, n_periods * T, x0)
    if isinstance(method, EventDriven):
        solution = simulate_event(problem, method)
        tr = solution.trajectory(method.output_step)
        extra["event_solution"] = solution
    else:
        tr = simulate_smooth(problem, method)
        extra["solver_stats"] = tr.metadata["stats"]
    periods = int(round(n_periods))
    return ConverterRun(converter, p, method, tr, time.perf_counter() - start, periods,
                        periods if steady else None, extra=extra)


def _run_to_steady_state(converter, p, method, x0, tol, budget, start) -> ConverterRun:
    """Warm up, shoot for the periodic orbit, then confirm by simulating on; brute force as fallback."""
    T = converter.period(p)
    chunk_t = STEADY_CHUNK_PERIODS * T
    warm = simulate(converter.problem(p, chunk_t, x0), method)
    state = warm.x[-1].copy()
    done = STEADY_CHUNK_PERIODS
    shot = shoot(one_period(converter.problem(p, T), T), method, state, tol=0.1 * tol)
    done += shot.periods_simulated
    if shot.converged:
        state = shot.x
    remaining = np.inf
    while done < budget + STEADY_CHUNK_PERIODS:
        tr = simulate(converter.problem(p, chunk_t, state), method)
        done += STEADY_CHUNK_PERIODS
        boundaries = np.searchsorted(tr.t, np.arange(STEADY_CHUNK_PERIODS + 1) * T - 1e-12 * T)
        x_at = tr.x[np.minimum(boundaries, len(tr.t) - 1)]
        change = np.abs(np.diff(x_at, axis=0)).max(axis=1) / (1.0 + np.abs(x_at).max())
        remaining = _distance_to_steady_state(change)
        if remaining < tol:
            tr = replace(tr, t=tr.t + (done - STEADY_CHUNK_PERIODS) * T)
            return ConverterRun(converter, p, method, tr, time.perf_counter() - start, done, done,
                                extra={"cycle_change": float(change[-1]), "distance_estimate": remaining,
                                       "shooting_iterations": shot.iterations, "shooting_converged": shot.converged})
        state = tr.x[-1].copy()
    raise SimulationError(f"no periodic steady state within {budget} periods (estimated distance "
                          f"{remaining:.3g} > tol = {tol:g}); raise --periods or the tolerance")


def _distance_to_steady_state(change: np.ndarray) -> float:
    """Estimated remaining distance to the periodic orbit from the last cycle-to-cycle changes.

    The changes of a converging orbit shrink geometrically, c_m ~ rho^m; the distance left is
    about c_m rho / (1 - rho) + c_m. rho is fitted over the last half of the chunk (robust to
    the oscillation of lightly damped converters); rho >= 1 means not converging yet.
    """
    half = change.size // 2
    first, last = change[-half - 1], change[-1]
    if last == 0.0:
        return 0.0
    if first <= 0.0:
        return float("inf")
    rho = (last / first) ** (1.0 / half)
    if rho >= 0.999:
        return float("inf") if rho >= 1.0 else last * 1000.0
    return float(last * (1.0 + rho / (1.0 - rho)))
