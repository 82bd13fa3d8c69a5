"""Checks of the numerical core on the two Siconos circuits: convergence against closed forms.

Results are plain tables (pandas); the report writer turns them into HTML and plots.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from converters.models.circuits import diode_bridge, half_wave_rectifier, parallel_rlc_exact
from converters.methods import Theta
from converters.simulate import simulate


def convergence_table() -> pd.DataFrame:
    """Error against the exact solution versus h, for theta = 1 and 0.5.

    Cases: the LC tank with the diode blocking (no switching, closed form), and the diode bridge
    over 2 ms (closed form: with ideal diodes the tank always sees R).
    """
    rows = []
    lc = half_wave_rectifier(V0=-10.0, t_end=1.5e-4)
    w0 = 1.0 / np.sqrt(1e-2 * 1e-6)
    for theta in (1.0, 0.5):
        for h in 1.5e-4 / 2.0 ** np.arange(7, 12):
            tr = simulate(lc, Theta(h, theta))
            rows.append(dict(case="LC tank, diode blocking (no switching)", theta=theta, h=h, steps=tr.steps,
                             error=abs(tr.x[-1, 0] + 10.0 * np.cos(w0 * tr.t[-1])), wall_s=tr.wall_s))
    bridge = diode_bridge(t_end=2e-3)
    for theta in (1.0, 0.5):
        for h in (8e-6, 4e-6, 2e-6, 1e-6, 5e-7):
            tr = simulate(bridge, Theta(h, theta))
            exact = parallel_rlc_exact(tr.t)
            rows.append(dict(case="diode bridge, k = 4 (switching)", theta=theta, h=h, steps=tr.steps,
                             error=np.abs(tr.x[:, 0] - exact[:, 0]).max(), wall_s=tr.wall_s))
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
    return {"half-wave rectifier (h = 10 us, theta = 0.5)": simulate(half_wave_rectifier(), Theta(1e-5, 0.5)),
            "diode bridge (h = 1 us, theta = 0.5)": simulate(diode_bridge(), Theta(1e-6, 0.5))}
