"""Checks of the numerical core on the two Siconos circuits: convergence against closed forms.

Results are plain tables (pandas); the report writer turns them into HTML and plots.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from converters.methods import Theta
from converters.models.netlist import builtin
from converters.problems import LCSProblem
from converters.simulate import simulate


def siconos_circuit(name: str, t_end: float = 5e-3, **values: float) -> LCSProblem:
    """One of Siconos' two diode circuits from its netlist (``half-wave.cir``: CircuitRLCD; ``diode-bridge.cir``:
    DiodeBridge; an LC tank, C = 1 uF, L = 10 mH, charged to V0 = 10 V, discharging into R = 1 kOhm), its
    ``.param`` values replaced by ``values``."""
    circuit = builtin(name)
    return circuit.problem(circuit.resolve(values), t_end)


def parallel_rlc_exact(t: np.typing.ArrayLike, L: float = 1e-2, C: float = 1e-6, R: float = 1e3, V0: float = 10.0,
                       iL0: float = 0.0) -> np.ndarray:
    """Exact (vC, iL) of the parallel RLC tank, shape (len(t), 2): the diode bridge's closed form (with ideal diodes
    the tank always sees R)."""
    A = np.array([[-1.0 / (R * C), -1.0 / C], [1.0 / L, 0.0]])
    t = np.asarray(t, dtype=float)
    # Eigen-decomposition is exact for this 2x2 underdamped A and vectorises over t.
    w, V = np.linalg.eig(A)
    coef = np.linalg.solve(V, np.array([V0, iL0], dtype=complex))
    return (V[None, :, :] * (coef[None, None, :] * np.exp(t[:, None, None] * w[None, None, :]))).sum(axis=2).real


def convergence_table() -> pd.DataFrame:
    """Error against the exact solution versus h, for theta = 1 and 0.5.

    Cases: the LC tank with the diode blocking (no switching, closed form), and the diode bridge
    over 2 ms (closed form: with ideal diodes the tank always sees R).
    """
    rows = []
    lc = siconos_circuit("half-wave.cir", 1.5e-4, V0=-10.0)
    vc = lc.state_names.index("v(c1)")
    w0 = 1.0 / np.sqrt(1e-2 * 1e-6)
    for theta in (1.0, 0.5):
        for h in 1.5e-4 / 2.0 ** np.arange(7, 12):
            tr = simulate(lc, Theta(h, theta))
            rows.append(dict(case="LC tank, diode blocking (no switching)", theta=theta, h=h, steps=tr.steps,
                             error=abs(tr.x[-1, vc] + 10.0 * np.cos(w0 * tr.t[-1])), wall_s=tr.wall_s))
    bridge = siconos_circuit("diode-bridge.cir", 2e-3)
    vc = bridge.state_names.index("v(c1)")
    for theta in (1.0, 0.5):
        for h in (8e-6, 4e-6, 2e-6, 1e-6, 5e-7):
            tr = simulate(bridge, Theta(h, theta))
            exact = parallel_rlc_exact(tr.t)
            rows.append(dict(case="diode bridge, k = 4 (switching)", theta=theta, h=h, steps=tr.steps,
                             error=np.abs(tr.x[:, vc] - exact[:, 0]).max(), wall_s=tr.wall_s))
    return pd.DataFrame(rows)


def observed_orders(table: pd.DataFrame) -> pd.DataFrame:
    """Slope of log(error) against log(h) per case and theta."""
    out = []
    for (case, theta), group in table.groupby(["case", "theta"], sort=False):
        slope = np.polyfit(np.log(group["h"]), np.log(group["error"]), 1)[0]
        out.append(dict(case=case, theta=theta, observed_order=slope))
    return pd.DataFrame(out)


def core_waveforms():
    """Half-wave rectifier and diode bridge at the Siconos step sizes (for the report's plots)."""
    return {"half-wave rectifier (h = 10 us, theta = 0.5)": simulate(siconos_circuit("half-wave.cir"), Theta(1e-5, 0.5)),
            "diode bridge (h = 1 us, theta = 0.5)": simulate(siconos_circuit("diode-bridge.cir"), Theta(1e-6, 0.5))}
