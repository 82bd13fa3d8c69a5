"""Sliding-mode (indirect current) control of the boost converter (REFERENCE section 5).

Surface sigma = iL - Iref with Iref = Vref^2 / (R Vin) (plus an optional PI correction from the
output error: Iref = Iref0 + Kp (Vref - v) + Ki * integral (Vref - v), clipped at 0; Iref0 uses the
nominal R). Sliding exists only for Vref > Vin (equivalent control s_eq = 1 - Vin / v in (0, 1)).

Two schemes on the same boost LCS (ideal switch, ideal diode as a complementarity pair):

* ``hysteresis`` (explicit): switch ON while sigma < -band ... until sigma > +band, then OFF until
  sigma < -band. The switch is decided from the state; when a backward-Euler step carries sigma
  through a threshold, the crossing instant is placed by the step's own linear interpolation of sigma
  and the step is redone as two sub-steps (before the crossing in the old configuration, after it in
  the new one). Switching frequency f = Vin (v - Vin) / (2 band L v).
* ``implicit`` (chattering-free): the averaged model L i' = Vin - lambda v, C v' = lambda i - v/R with
  lambda = 1 - s in [0, 1] and the relay lambda in -N_[0,1] of sigma(k+1) solved as an LCP of size 2
  per step (M' = [[M, 1], [-1, 0]], q' = [q, 1]; M = h v_k / L, q = -(i_k + h Vin / L - Iref)), so
  lambda settles at Vin / v without switching.

A load step (R -> R_step at t_step) is available in both. Both steppers are compiled (numba).
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import pandas as pd
from numba import njit

from ..errors import ParameterError, SimulationError
from ..lcp.kernels import _masks_by_size, solve_small_lcp
from . import get_converter
from ..params import Param, nonnegative, positive, resolve

PARAMETERS = (
    positive("Vin", 10.0, "V", "input voltage"),
    positive("L", 1e-3, "H", "inductance"),
    positive("C", 100e-6, "F", "output capacitance"),
    positive("R", 40.0, "ohm", "load resistance"),
    positive("Vref", 20.0, "V", "output voltage reference (must exceed Vin)"),
    positive("band", 0.05, "A", "hysteresis half-band on the current error"),
    nonnegative("Kp", 0.0, "A/V", "outer PI loop: proportional gain"),
    nonnegative("Ki", 0.0, "A/(V s)", "outer PI loop: integral gain"),
    positive("t_step", None, "s", "load-step instant (optional, with R_step)"),
    positive("R_step", None, "ohm", "load resistance after t_step (optional)"),
)
SCHEMES = ("hysteresis", "implicit")


def resolve_smc(given: dict | None = None) -> dict:
    """Validated sliding-mode parameters; a request where sliding cannot exist is refused."""
    p = resolve(PARAMETERS, dict(given or {}), "boost --control smc")
    if p["Vref"] <= p["Vin"]:
        raise ParameterError(f"Vref must be above Vin = {p['Vin']:g} V for a boost under sliding-mode control "
                             f"(sliding on i = Iref needs the equivalent control 1 - Vin/v in (0, 1)); "
                             f"got Vref = {p['Vref']:g} V")
    if ("t_step" in p) != ("R_step" in p):
        raise ParameterError("t_step and R_step go together (the load steps from R to R_step at t_step); "
                             f"got only {'t_step' if 't_step' in p else 'R_step'}")
    return p


def iref0(p: dict) -> float:
    return p["Vref"] ** 2 / (p["R"] * p["Vin"])


def predicted_frequency(p: dict, v: float | None = None) -> float:
    """f = Vin (v - Vin) / (2 band L v) (REFERENCE section 5), at v = Vref unless given."""
    v = p["Vref"] if v is None else v
    return p["Vin"] * (v - p["Vin"]) / (2.0 * p["band"] * p["L"] * v)


def default_h(p: dict, scheme: str) -> float:
    """Hysteresis: 1/500 of the shorter of t_on = 2 band L / Vin, t_off = 2 band L / (Vref - Vin).
    Implicit: 1 us bounded by 1/200 of sqrt(L C) (no switching to resolve)."""
    if scheme == "implicit":
        return min(1e-6, np.sqrt(p["L"] * p["C"]) / 200.0)
    t_on = 2.0 * p["band"] * p["L"] / p["Vin"]
    t_off = 2.0 * p["band"] * p["L"] / (p["Vref"] - p["Vin"])
    return min(t_on, t_off) / 500.0


@dataclass
class SMCRun:
    """A sliding-mode run: uniform grid t, states x = (iL, vC), the switch position (0/1 for the
    hysteresis scheme, 1 - lambda in [0, 1] for the implicit one), Iref, and the switching instants."""

    params: dict
    scheme: str
    h: float
    t: np.ndarray
    x: np.ndarray
    switch: np.ndarray
    iref: np.ndarray
    active: np.ndarray
    on_times: np.ndarray      # instants the switch closed (hysteresis)
    off_times: np.ndarray
    wall_s: float

    @property
    def vout(self) -> np.ndarray:
        return self.x[:, 1]

    def window(self, t0: float, t1: float | None = None) -> np.ndarray:
        t1 = self.t[-1] if t1 is None else t1
        return (self.t >= t0) & (self.t <= t1)

    def mean_vout(self, t0: float, t1: float | None = None) -> float:
        w = self.window(t0, t1)
        return float(np.trapezoid(self.vout[w], self.t[w]) / (self.t[w][-1] - self.t[w][0]))

    def switching_frequency(self, t0: float, t1: float | None = None) -> float:
        """Switch closings per second between the first and the last closing in [t0, t1]."""
        t1 = self.t[-1] if t1 is None else t1
        on = self.on_times[(self.on_times >= t0) & (self.on_times <= t1)]
        return float((on.size - 1) / (on[-1] - on[0])) if on.size >= 2 else 0.0

    def recovery_time(self, t_event: float, tol: float = 0.01) -> float:
        """Time after ``t_event`` from which |v - Vref| <= tol Vref holds to the end of the run."""
        return recovery_time(self.t, self.vout, self.params["Vref"], t_event, tol)

    def modes(self) -> np.ndarray:
        config = np.where(self.switch >= 0.5, 0, 1)
        return get_converter("boost").modes(self.active, config, self.x)

    def waveforms(self) -> pd.DataFrame:
        return pd.DataFrame({"time": self.t, "iL": self.x[:, 0], "vC": self.x[:, 1], "vout": self.vout,
                             "switch": self.switch, "mode": self.modes(), "iref": self.iref})

    def summary(self, window_s: float | None = None) -> dict:
        p = self.params
        t_end = self.t[-1]
        t0 = t_end - (window_s or min(0.25 * t_end, 2e-3))
        if "t_step" in p and p["t_step"] < t_end:
            t0 = max(t0, p["t_step"])
        out = {"converter": "boost", "control": "smc", "scheme": self.scheme, "method": "lcp",
               "options": {"h": self.h, "params": p}, "steps": int(self.t.size - 1), "wall_s": self.wall_s,
               "vout_mean": self.mean_vout(t0), "vref": p["Vref"], "window_s": [t0, t_end]}
        if self.scheme == "hysteresis":
            out["switching_frequency_Hz"] = self.switching_frequency(t0)
            out["predicted_frequency_Hz"] = predicted_frequency(p, out["vout_mean"])
        else:
            lam = 1.0 - self.switch[self.window(t0)]
            out["lambda_mean"] = float(lam.mean())
            out["lambda_spread"] = float(lam.max() - lam.min())
            out["vin_over_v"] = p["Vin"] / out["vout_mean"]
        if "t_step" in p:
            out["recovery_time_s"] = self.recovery_time(p["t_step"])
        return out


def recovery_time(t, v, vref, t_event, tol=0.01) -> float:
    """Time after t_event from which |v - vref| <= tol vref to the end (inf if never; 0 if never left)."""
    after = t >= t_event
    outside = np.flatnonzero(after & (np.abs(v - vref) > tol * vref))
    if outside.size == 0:
        return 0.0
    last = outside[-1]
    return float(t[last + 1] - t_event) if last + 1 < t.size else float("inf")


def _load_configurations(p: dict, R: float):
    boost = get_converter("boost")
    q = boost.resolve({"Vin": p["Vin"], "L": p["L"], "C": p["C"], "R": R})
    return boost.configurations(q)


def _stacks(p: dict):
    """(A, B, C, D, E, F) stacked over [ON, OFF] x [before, after the load step]."""
    configs = list(_load_configurations(p, p["R"])) + list(_load_configurations(p, p.get("R_step", p["R"])))
    return tuple(np.ascontiguousarray(np.stack([getattr(c, k) for c in configs])) for k in "ABCDEF")


def simulate_smc(params: dict | None = None, *, scheme: str = "hysteresis", h=None, t_end=20e-3,
                 x0=None) -> SMCRun:
    """Run the boost under sliding-mode control from x0 (default: iL = 0, vC = Vin, the state a boost
    reaches at power-up through its diode)."""
    if scheme not in SCHEMES:
        raise ParameterError(f"scheme must be one of {', '.join(SCHEMES)}; got {scheme!r}")
    p = resolve_smc(params)
    from ..validate import parse_value
    t_end = parse_value("t_end", t_end)
    if t_end <= 0:
        raise ParameterError(f"t_end must be positive (> 0 s); got {t_end!r}")
    h_max = default_h(p, scheme) * (25.0 if scheme == "hysteresis" else 200.0)
    h = default_h(p, scheme) if h is None else parse_value("h", h)
    if not 0.0 < h <= h_max:
        raise ParameterError(f"h must be in (0, {h_max:.3g}] s for this scheme (at most 1/20 of the shorter "
                             f"switching interval); got {h:g}")
    n_steps = int(np.ceil(t_end / h - 1e-9))
    if n_steps > 50_000_000:
        raise ParameterError(f"h gives {n_steps} steps; h must be >= {t_end / 5e7:.3g} s; got {h:g}")
    x_init = np.array([0.0, p["Vin"]]) if x0 is None else np.asarray(x0, dtype=float)
    if x_init.shape != (2,) or not np.all(np.isfinite(x_init)):
        raise ParameterError(f"x0 must be two finite numbers (iL, vC); got {x0!r}")
    step_at = int(round(p["t_step"] / h)) if "t_step" in p else -1
    N = n_steps + 1
    t = h * np.arange(N)
    x = np.empty((N, 2))
    x[0] = x_init
    sw = np.empty(N)
    iref = np.empty(N)
    active = np.zeros((N, 1), dtype=np.bool_)
    gains = np.array([p["Vref"], iref0(p), p["Kp"], p["Ki"], p["band"]])
    start = time.perf_counter()
    if scheme == "hysteresis":
        A, B, C, D, E, F = _stacks(p)
        from ..methods.discretize import step_matrices
        configs = list(_load_configurations(p, p["R"])) + list(_load_configurations(p, p.get("R_step", p["R"])))
        mats = step_matrices(configs, np.full(4, h), 1.0)
        max_events = 2 * int(t_end * predicted_frequency(p) * 4 + 100)
        events = np.empty(max_events)
        kinds = np.empty(max_events, dtype=np.int8)
        status, count = _run_hysteresis(A, B, C, D, E, F, mats.Phi, mats.Gamma, mats.H, mats.M, x, sw, iref,
                                        active, events, kinds, h, step_at, gains)
        if status == 1:
            raise SimulationError(f"more than {max_events} switchings in {t_end:g} s: the run left sliding "
                                  "(check band, L and h)")
        if status == 2:
            raise SimulationError("a step LCP had no solution (M <= 0 with q < 0)")
        on_times, off_times = events[:count][kinds[:count] == 1], events[:count][kinds[:count] == 0]
    else:
        R_after = p.get("R_step", p["R"])
        loads = np.array([p["R"], R_after])
        status = _run_implicit(x, sw, iref, h, step_at, gains, p["Vin"], p["L"], p["C"], loads)
        if status != 0:
            raise SimulationError("the implicit relay LCP could not be solved (the inductor current left CCM: "
                                  "the averaged model needs iL > 0)")
        active[:] = False
        on_times = off_times = np.empty(0)
    wall = time.perf_counter() - start
    return SMCRun(p, scheme, h, t, x, sw, iref, active, on_times, off_times, wall)


@njit(cache=True)
def _be_step(A, B, C, D, E, F, c, x, dt, out):
    """One backward-Euler step of configuration c (k = 1) from x over dt; writes out, returns (u, y, ok)."""
    n = x.shape[0]
    work = np.empty((n, n + 2))
    for i in range(n):
        for j in range(n):
            work[i, j] = -dt * A[c, i, j]
        work[i, i] += 1.0
        work[i, n] = x[i] + dt * E[c, i]
        work[i, n + 1] = dt * B[c, i, 0]
    for col in range(n):
        piv = col
        for r in range(col + 1, n):
            if abs(work[r, col]) > abs(work[piv, col]):
                piv = r
        if piv != col:
            for j in range(n + 2):
                tmp = work[col, j]
                work[col, j] = work[piv, j]
                work[piv, j] = tmp
        for r in range(col + 1, n):
            f = work[r, col] / work[col, col]
            for j in range(col, n + 2):
                work[r, j] -= f * work[col, j]
    xf = np.empty(n)
    hb = np.empty(n)
    for r in range(n - 1, -1, -1):
        s1 = work[r, n]
        s2 = work[r, n + 1]
        for j in range(r + 1, n):
            s1 -= work[r, j] * xf[j]
            s2 -= work[r, j] * hb[j]
        xf[r] = s1 / work[r, r]
        hb[r] = s2 / work[r, r]
    q = F[c, 0]
    m = D[c, 0, 0]
    for i in range(n):
        q += C[c, 0, i] * xf[i]
        m += C[c, 0, i] * hb[i]
    z = 0.0
    if q < 0.0:
        if m <= 0.0:
            return 0.0, q, False
        z = -q / m
    for i in range(n):
        out[i] = xf[i] + hb[i] * z
    return z, q + m * z, True


@njit(cache=True)
def _uniform_step(Phi, Gamma, H, C, F, Mh, c, x, out):
    """A full backward-Euler step from the precomputed one-step matrices (k = 1)."""
    n = x.shape[0]
    q = F[c, 0]
    for i in range(n):
        acc = Gamma[c, i]
        for j in range(n):
            acc += Phi[c, i, j] * x[j]
        out[i] = acc
        q += C[c, 0, i] * acc
    m = Mh[c, 0, 0]
    z = 0.0
    if q < 0.0:
        if m <= 0.0:
            return 0.0, q, False
        z = -q / m
    for i in range(n):
        out[i] += H[c, i, 0] * z
    return z, q + m * z, True


@njit(cache=True)
def _run_hysteresis(A, B, C, D, E, F, Phi, Gamma, H, Mh, x, sw, iref, active, events, kinds, h, step_at, gains):
    vref, i0, kp, ki, band = gains[0], gains[1], gains[2], gains[3], gains[4]
    N = x.shape[0]
    on = True
    integ = 0.0
    ir = i0
    count = 0
    xn = np.empty(2)
    xm = np.empty(2)
    sw[0] = 1.0
    iref[0] = ir
    for k in range(N - 1):
        load = 2 if (step_at >= 0 and k >= step_at) else 0
        c = (0 if on else 1) + load
        z, yv, ok = _uniform_step(Phi, Gamma, H, C, F, Mh, c, x[k], xn)
        if not ok:
            return 2, count
        sig0 = x[k, 0] - ir
        sig1 = xn[0] - ir
        crossed = (on and sig1 > band) or ((not on) and sig1 < -band)
        if crossed:
            level = band if on else -band
            frac = (level - sig0) / (sig1 - sig0)
            if frac < 0.0:
                frac = 0.0
            if frac > 1.0:
                frac = 1.0
            _be_step(A, B, C, D, E, F, c, x[k], frac * h, xm)
            on = not on
            if count >= events.shape[0]:
                return 1, count
            events[count] = (k + frac) * h
            kinds[count] = 1 if on else 0
            count += 1
            c = (0 if on else 1) + load
            if frac < 1.0:
                z, yv, ok = _be_step(A, B, C, D, E, F, c, xm, (1.0 - frac) * h, xn)
                if not ok:
                    return 2, count
            else:
                xn[0] = xm[0]
                xn[1] = xm[1]
        x[k + 1, 0] = xn[0]
        x[k + 1, 1] = xn[1]
        active[k + 1, 0] = z > yv
        sw[k + 1] = 1.0 if on else 0.0
        e = vref - xn[1]
        integ += h * e
        ir = i0 + kp * e + ki * integ
        if ir < 0.0:
            ir = 0.0
        iref[k + 1] = ir
    return 0, count


@njit(cache=True)
def _run_implicit(x, sw, iref, h, step_at, gains, vin, L, C, loads):
    vref, i0, kp, ki = gains[0], gains[1], gains[2], gains[3]
    N = x.shape[0]
    M2 = np.empty((2, 2))
    q2 = np.empty(2)
    z2 = np.empty(2)
    work = np.empty((2, 3))
    order = _masks_by_size(2)
    mask = 0
    integ = 0.0
    ir = i0
    iref[0] = ir
    sw[0] = 1.0
    for k in range(N - 1):
        R = loads[1] if (step_at >= 0 and k >= step_at) else loads[0]
        i_k, v_k = x[k, 0], x[k, 1]
        if v_k <= 0.0:
            return 1
        m = h * v_k / L
        q = -(i_k + h * vin / L - ir)
        # Relay lambda in [0, 1] as an LCP of size 2 (lb = 0, ub = 1).
        M2[0, 0] = m
        M2[0, 1] = 1.0
        M2[1, 0] = -1.0
        M2[1, 1] = 0.0
        q2[0] = q
        q2[1] = 1.0
        mask = solve_small_lcp(M2, q2, 2, z2, mask, order, work)
        if mask < 0:
            return 1
        lam = z2[0]
        i_n = i_k + h * (vin - lam * v_k) / L
        v_n = (v_k + h * lam * i_n / C) / (1.0 + h / (R * C))
        x[k + 1, 0] = i_n
        x[k + 1, 1] = v_n
        sw[k + 1] = 1.0 - lam
        e = vref - v_n
        integ += h * e
        ir = i0 + kp * e + ki * integ
        if ir < 0.0:
            ir = 0.0
        iref[k + 1] = ir
    return 0
