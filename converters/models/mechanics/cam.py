"""The cam-follower with impacts (Siconos' CamFollower example, di Bernardo, Osorio and
Santini): a follower of mass m on a spring k to a fixed point rides a rotating cam; contact is unilateral
with Newton restitution e.

    m x'' + k x = Lambda,   g = x - c(t) >= 0,   Lambda >= 0,   g Lambda = 0,   g'(+) = -e g'(-) at an impact,

c(t) = h_c(beta) - 0.3 the cam's position, beta = (omega t + pi/2) mod 2 pi, omega = 2 pi rpm / 60, the profile
mirrored for beta > pi (beta -> 2 pi - beta). The follower stays on the cam while k c + m c'' >= 0: it detaches
where the cam decelerates faster than the spring can pull it, flies, and comes back in impacts that may
accumulate (complete chattering) or be interrupted by the next lift (incomplete chattering).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ...params import Param, positive
from ...problems.mechanical import MechanicalProblem, UnilateralContact
from .base import MechanicalModel

RB, K1, RHO1 = 0.40, 0.45, 0.85
K2, RHO3, RHO2 = 0.40393320723821, 0.15, 0.55393320723821
BETA2, BETA3 = 1.050328174371336, 1.22173047639603
SHIFT = 0.3
#: The profile's joints: the cam angles beta where one arc meets the next and h_c'' jumps (the base circle to the
#: flank at pi/2, flank to nose at pi/2 + BETA2, nose to the top circle at pi/2 + BETA3, and their mirrors), with
#: the names the corner-impact study gives them.
JOINTS = {"base | flank (rise)": np.pi / 2, "flank | nose (rise)": np.pi / 2 + BETA2,
          "nose | top (rise)": np.pi / 2 + BETA3, "top | nose (fall)": 1.5 * np.pi - BETA3,
          "nose | flank (fall)": 1.5 * np.pi - BETA2, "flank | base (fall)": 1.5 * np.pi}


def _circle_arc(A: np.ndarray, A1: np.ndarray, A2: np.ndarray, u: np.ndarray, u1: np.ndarray, u2: np.ndarray,
                rho: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """h, h', h'' of A(beta) + rho sqrt(1 - u(beta)^2) from A, u and their first two derivatives."""
    S = np.sqrt(1.0 - u * u)
    S1 = -u * u1 / S
    S2 = -(u1 * u1 + u * u2) / S - (u * u1) ** 2 / S ** 3
    return A + rho * S, A1 + rho * S1, A2 + rho * S2


def profile(beta: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The lift h_c and its first two derivatives in beta, for beta in [0, pi] (arrays)."""
    beta = np.asarray(beta, dtype=float)
    h, h1, h2 = np.full(beta.shape, RB), np.zeros(beta.shape), np.zeros(beta.shape)
    first = (beta > np.pi / 2) & (beta <= np.pi / 2 + BETA2)
    second = (beta > np.pi / 2 + BETA2) & (beta <= np.pi / 2 + BETA3)
    last = beta > np.pi / 2 + BETA3
    b = beta[first]
    c1 = K1 / RHO1
    values = _circle_arc(-K1 * np.sin(b), -K1 * np.cos(b), K1 * np.sin(b),
                         c1 * np.cos(b), -c1 * np.sin(b), -c1 * np.cos(b), RHO1)
    h[first], h1[first], h2[first] = values
    phi = beta[second] + np.pi / 9.0
    c2 = K2 / RHO3
    values = _circle_arc(-K2 * np.cos(phi), K2 * np.sin(phi), K2 * np.cos(phi),
                         c2 * np.sin(phi), c2 * np.cos(phi), -c2 * np.sin(phi), RHO3)
    h[second], h1[second], h2[second] = values
    h[last] = RHO2
    return h, h1, h2


@dataclass(frozen=True)
class CamOffset:
    """c_j(t) of the contact gap g = x + c_j(t): minus the cam's position, with its time derivatives."""

    omega: float

    def position(self, t: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """c(t), c'(t), c''(t) of the cam (m, m/s, m/s^2)."""
        t = np.asarray(t, dtype=float)
        beta = np.mod(self.omega * t + np.pi / 2.0, 2.0 * np.pi)
        mirrored = beta > np.pi
        h, h1, h2 = profile(np.where(mirrored, 2.0 * np.pi - beta, beta))
        sign = np.where(mirrored, -1.0, 1.0)
        return h - SHIFT, sign * h1 * self.omega, h2 * self.omega ** 2

    def __call__(self, t: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        c, c1, c2 = self.position(t)
        return -c, -c1, -c2


class CamFollower(MechanicalModel):
    name = "cam-follower"
    title = "cam-follower with impacts (Siconos CamFollower)"
    parameters = (
        positive("m", 1.221, "kg", "follower mass"),
        positive("k", 1430.8, "N/m", "follower spring"),
        Param("e", 0.8, "", "Newton restitution", low=0.0, high=1.0, low_open=False, high_open=False),
        positive("rpm", 358.0, "1/min", "cam speed"),
    )
    state_names = ("x", "v")
    contact_names = ("cam",)
    sweep = "rpm"
    output_state = "x"
    diagram = "impacts"

    def period(self, p: dict) -> float:
        return 60.0 / p["rpm"]

    def offset(self, p: dict) -> CamOffset:
        return CamOffset(2.0 * np.pi * p["rpm"] / 60.0)

    def problem(self, p: dict, t_end: float, x0: npt.NDArray[np.float64] | None = None,
                t_start: float = 0.0) -> MechanicalProblem:
        """From x0 (default: on the cam at rest, in its dwell)."""
        offset = self.offset(p)
        if x0 is None:
            c, c1, _ = offset.position(t_start)
            x0 = np.array([float(c), float(c1)])
        return MechanicalProblem(mass=[[p["m"]]], damping=[[0.0]], stiffness=[[p["k"]]], force=None,
                                 contacts=(UnilateralContact([1.0], p["e"], offset, name="cam"),), x0=x0,
                                 t_span=(t_start, t_end), period=self.period(p), state_names=self.state_names,
                                 metadata={"model": self.name, **p})

    def cam_angle(self, p: dict, t: npt.ArrayLike) -> np.ndarray:
        """beta = (omega t + pi/2) mod 2 pi (rad): where on its profile the cam meets the follower at time t."""
        return np.mod(2.0 * np.pi * p["rpm"] / 60.0 * np.asarray(t, dtype=float) + np.pi / 2.0, 2.0 * np.pi)

    def detachment_margin(self, p: dict, t: npt.ArrayLike) -> np.ndarray:
        """k c + m c'' (N): the contact force the cam must supply to keep the follower on it; below zero the
        spring cannot follow the cam's deceleration and the follower detaches."""
        c, _, c2 = self.offset(p).position(t)
        return p["k"] * c + p["m"] * c2
