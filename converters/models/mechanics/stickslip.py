"""Two blocks on a moving belt (a two-block Burridge-Knopoff model; Nussbaum and Ruina 1987, Galvanetto 2001):

    m1 x1'' + k1 x1 + kc (x1 - x2) = lambda1,   s1 = x1' - V,
    m2 x2'' + k2 x2 + kc (x2 - x1) = lambda2,   s2 = x2' - V,

each block tied to a fixed wall by its own spring and to the other by kc, both carried by the belt at
velocity V against Popp friction (the same law as :mod:`.friction`, normal loads m_i g). Autonomous: its
stick-slip orbits are read on the section where block 1 starts to stick. The parameters (stated here,
not from the seed, which gives none): m1 = m2 = 1 kg, k1 = 1 N/m, kc = 1 N/m, g = 10 m/s^2, Popp's
alpha = 0.3, gamma = 1.42, beta = 0.1, eta = 0.01; the belt velocity V and the asymmetry k2 / k1 are the
bifurcation parameters (k2 = k1: the symmetric system).
"""
from __future__ import annotations

import numpy as np
import numpy.typing as npt

from ...params import nonnegative, positive
from ...problems.mechanical import FrictionContact, MechanicalProblem
from .base import MechanicalModel
from .friction import PARAMETERS as FRICTION_PARAMETERS, friction_law

POPP = tuple(p for p in FRICTION_PARAMETERS if p.name in ("alpha", "gamma", "beta", "eta"))
PARAMETERS = (
    positive("m1", 1.0, "kg", "mass of block 1"),
    positive("m2", 1.0, "kg", "mass of block 2"),
    positive("k1", 1.0, "N/m", "spring of block 1 to the wall"),
    positive("k2", 1.5, "N/m", "spring of block 2 to the wall (k2 / k1: the asymmetry)"),
    nonnegative("kc", 1.0, "N/m", "coupling spring"),
    positive("g", 10.0, "m/s^2", "gravity (normal loads m_i g)"),
    positive("V", 0.5, "m/s", "belt velocity"),
) + POPP


class TwoBlock(MechanicalModel):
    name = "stick-slip"
    title = "two blocks on a belt (Burridge-Knopoff), Popp friction"
    parameters = PARAMETERS
    state_names = ("x1", "x2", "v1", "v2")
    friction_names = ("block1", "block2")
    sweep = "V"
    output_state = "x2"
    diagram = "section"

    def period(self, p: dict) -> float:
        return np.inf

    def time_scale(self, p: dict) -> float:
        """The slower block's natural period, 2 pi sqrt(m / (k + kc))."""
        return float(2.0 * np.pi * max(np.sqrt(p["m1"] / (p["k1"] + p["kc"])), np.sqrt(p["m2"] / (p["k2"] + p["kc"]))))

    def problem(self, p: dict, t_end: float, x0: npt.NDArray[np.float64] | None = None,
                t_start: float = 0.0) -> MechanicalProblem:
        """From x0 (default: both blocks at their springs' rest position, block 1 stuck to the belt, block 2
        at rest: an asymmetric start)."""
        K = np.array([[p["k1"] + p["kc"], -p["kc"]], [-p["kc"], p["k2"] + p["kc"]]])
        frictions = tuple(FrictionContact(direction, friction_law(p, mass * p["g"]), belt=p["V"], name=name)
                          for direction, mass, name in (([1.0, 0.0], p["m1"], "block1"), ([0.0, 1.0], p["m2"], "block2")))
        x0 = np.array([0.0, 0.0, p["V"], 0.0]) if x0 is None else x0
        return MechanicalProblem(mass=np.diag([p["m1"], p["m2"]]), damping=np.zeros((2, 2)), stiffness=K, force=None,
                                 frictions=frictions, x0=x0, t_span=(t_start, t_end), period=np.inf,
                                 state_names=self.state_names, metadata={"model": self.name, **p})
