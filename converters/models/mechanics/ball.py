"""A ball dropped on a fixed floor with restitution e: the closed-form check of impacts. Its bounces shrink by
e and accumulate at t_inf = sqrt(2 H / g) (1 + 2 e / (1 - e)), after which it rests on the floor."""
from __future__ import annotations

import numpy as np
import numpy.typing as npt

from ...params import Param, positive
from ...problems.mechanical import HarmonicForce, MechanicalProblem, UnilateralContact
from .base import MechanicalModel


def accumulation_time(H: float, g: float, e: float) -> float:
    return float(np.sqrt(2.0 * H / g) * (1.0 + 2.0 * e / (1.0 - e)))


class BouncingBall(MechanicalModel):
    name = "bouncing-ball"
    title = "bouncing ball on a fixed floor"
    parameters = (
        positive("m", 1.0, "kg", "mass"),
        positive("g", 9.81, "m/s^2", "gravity"),
        positive("H", 1.0, "m", "drop height"),
        Param("e", 0.5, "", "Newton restitution", low=0.0, high=1.0, low_open=False, high_open=True),
    )
    state_names = ("z", "v")
    contact_names = ("floor",)
    output_state = "z"

    def period(self, p: dict) -> float:
        return np.inf

    def time_scale(self, p: dict) -> float:
        return accumulation_time(p["H"], p["g"], p["e"])

    def problem(self, p: dict, t_end: float, x0: npt.NDArray[np.float64] | None = None,
                t_start: float = 0.0) -> MechanicalProblem:
        return MechanicalProblem(mass=[[p["m"]]], damping=[[0.0]], stiffness=[[0.0]],
                                 force=HarmonicForce([0.0], 0.0, constant=[-p["m"] * p["g"]]),
                                 contacts=(UnilateralContact([1.0], p["e"], name="floor"),),
                                 x0=np.array([p["H"], 0.0]) if x0 is None else x0, t_span=(t_start, t_end),
                                 period=np.inf, state_names=self.state_names, metadata={"model": self.name, **p})
