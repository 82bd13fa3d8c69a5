"""The harmonically forced dry-friction oscillator on a moving belt (Popp and Stelter 1990; the seed's sliding
bifurcations, after Kowalczyk and Piiroinen 2008).

    m x'' + k x = A cos(omega t) + lambda,   s = x' - Vdr,
    lambda = -m g mu(s) sign(s) slipping,  |lambda| <= m g mu(0) sticking (s = 0: the block rides the belt),
    mu(s) = alpha / (1 + gamma |s|) + beta + eta s^2   (Popp).

A Filippov system on x' = Vdr: Filippov's convex combination of the two slip vector fields is the stick
force that keeps s = 0; the sliding (stick) region is |(-k x + A cos(omega t)) / (m g mu(0))| < 1.
"""
from __future__ import annotations

import numpy as np
import numpy.typing as npt

from ...params import Param, nonnegative, positive
from ...problems.mechanical import FrictionContact, HarmonicForce, MechanicalProblem, PoppFriction
from .base import MechanicalModel

PARAMETERS = (
    positive("m", 1.0, "kg", "block mass"),
    positive("k", 1.0, "N/m", "spring stiffness"),
    positive("g", 10.0, "m/s^2", "gravity (the normal load is m g)"),
    Param("Vdr", 1.0, "m/s", "belt velocity", low=-np.inf, high=np.inf),
    nonnegative("A", 0.5, "N", "forcing amplitude"),
    positive("omega", 2.9, "rad/s", "forcing frequency"),
    nonnegative("alpha", 0.3, "", "Popp law: velocity-weakening part"),
    nonnegative("gamma", 1.42, "s/m", "Popp law: its decay"),
    nonnegative("beta", 0.1, "", "Popp law: constant part"),
    nonnegative("eta", 0.01, "s^2/m^2", "Popp law: quadratic part"),
)


def friction_law(p: dict, normal: float) -> PoppFriction:
    return PoppFriction(normal=normal, alpha=p["alpha"], gamma=p["gamma"], beta=p["beta"], eta=p["eta"])


class FrictionOscillator(MechanicalModel):
    name = "friction"
    title = "dry-friction oscillator on a belt (Popp friction law)"
    parameters = PARAMETERS
    state_names = ("x", "v")
    friction_names = ("belt",)
    sweep = "omega"
    output_state = "x"
    diagram = "stroboscopic"
    sliding = True

    def period(self, p: dict) -> float:
        return 2.0 * np.pi / p["omega"]

    def problem(self, p: dict, t_end: float, x0: npt.NDArray[np.float64] | None = None,
                t_start: float = 0.0) -> MechanicalProblem:
        """From x0 (default: at rest, x = 0, v = 0: slipping backwards on the belt)."""
        return MechanicalProblem(mass=[[p["m"]]], damping=[[0.0]], stiffness=[[p["k"]]],
                                 force=HarmonicForce([p["A"]], p["omega"]),
                                 frictions=(FrictionContact([1.0], friction_law(p, p["m"] * p["g"]), belt=p["Vdr"],
                                                            name="belt"),),
                                 x0=np.zeros(2) if x0 is None else x0, t_span=(t_start, t_end), period=self.period(p),
                                 state_names=self.state_names, metadata={"model": self.name, **p})
