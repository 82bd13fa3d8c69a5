"""The tests' oracles: two small diode circuits from the Siconos examples (DiodeBridge and CircuitRLCD) as LCS
matrices derived by hand, which the netlist compiler must reproduce (``netlists/circuits/half-wave.cir`` and
``diode-bridge.cir``: ``tests/circuits/test_builtin_netlists.py``) and on which the methods are checked.

Both are an LC tank (C = 1 uF, L = 10 mH, vC(0) = 10 V, iL(0) = 0) discharging into R = 1 kOhm:
- :func:`half_wave_rectifier` (CircuitRLCD): R in series with one diode across the tank; the diode
  conducts while vC > 0 (parallel RLC), the tank rings freely while vC < 0.
- :func:`diode_bridge` (DiodeBridge): R behind a four-diode bridge; with ideal diodes the bridge
  conducts whenever vC != 0, so the tank always sees R (a parallel RLC) and vR = |vC|.
State x = (vC, iL) in V and A; C vC' = -iL - i_load, L iL' = vC.
"""
from __future__ import annotations

import numpy as np
import numpy.typing as npt

from converters.problems import Configuration, LCSProblem, Schedule
from converters.validate import check_positive, parse_value


def _tank(L: float, C: float) -> npt.NDArray[np.float64]:
    return np.array([[0.0, -1.0 / C], [1.0 / L, 0.0]])


def half_wave_rectifier(L: float | str = 1e-2, C: float | str = 1e-6, R: float | str = 1e3, V0: float | str = 10.0,
                        t_end: float = 5e-3) -> LCSProblem:
    """Tank with R + diode across it. Pair: u = i_D (diode current), y = -v_D = R i_D - vC (k = 1, D = R)."""
    L, C, R = (check_positive(n, v, u) for n, v, u in (("L", L, "H"), ("C", C, "F"), ("R", R, "ohm")))
    V0 = parse_value("V0", V0)
    config = Configuration(A=_tank(L, C), B=[[-1.0 / C], [0.0]], C=[[-1.0, 0.0]], D=[[R]], name="rlcd")
    return LCSProblem((config,), Schedule.constant(), x0=[V0, 0.0], t_span=(0.0, t_end),
                      state_names=("vC", "iL"), pair_names=("diode",),
                      metadata={"circuit": "half-wave rectifier (CircuitRLCD)", "L": L, "C": C, "R": R})


def diode_bridge(L: float | str = 1e-2, C: float | str = 1e-6, R: float | str = 1e3, V0: float | str = 10.0,
                 t_end: float = 5e-3) -> LCSProblem:
    """Tank feeding R through a diode bridge (Siconos DiodeBridge), k = 4.

    Bridge: D1 from the tank's top node to the load's + node, D3 from the tank's bottom node to it;
    D2 from the load's - node to the top node, D4 from it to the bottom node.
    u = (-v_D3, -v_D4, i_D1, i_D2), y = (i_D3, i_D4, -v_D1, -v_D2); load voltage vR = u1 + u2.
    D is the sum of a PSD and a skew matrix, so each step is a monotone LCP.
    """
    L, C, R = (check_positive(n, v, u) for n, v, u in (("L", L, "H"), ("C", C, "F"), ("R", R, "ohm")))
    V0 = parse_value("V0", V0)
    g = 1.0 / R
    config = Configuration(
        A=_tank(L, C),
        B=[[0.0, 0.0, -1.0 / C, 1.0 / C], [0.0, 0.0, 0.0, 0.0]],
        C=[[0.0, 0.0], [0.0, 0.0], [-1.0, 0.0], [1.0, 0.0]],
        D=[[g, g, -1.0, 0.0], [g, g, 0.0, -1.0], [1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]],
        name="bridge")
    return LCSProblem((config,), Schedule.constant(), x0=[V0, 0.0], t_span=(0.0, t_end),
                      state_names=("vC", "iL"), pair_names=("D3", "D4", "D1", "D2"),
                      metadata={"circuit": "diode bridge (DiodeBridge)", "L": L, "C": C, "R": R})
