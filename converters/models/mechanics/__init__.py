"""The mechanical models: the dry-friction oscillator, two blocks on a belt, the cam-follower, and the bouncing
ball; looked up by name."""
from __future__ import annotations

from ...errors import ParameterError
from .ball import BouncingBall, accumulation_time
from .base import MechanicalLabels, MechanicalModel
from .cam import CamFollower
from .friction import FrictionOscillator
from .stickslip import TwoBlock

MECHANICAL_MODELS: dict[str, MechanicalModel] = {m.name: m for m in (FrictionOscillator(), TwoBlock(), CamFollower(),
                                                                     BouncingBall())}


def get_mechanical(name: str) -> MechanicalModel:
    try:
        return MECHANICAL_MODELS[name]
    except KeyError:
        raise ParameterError(f"MODEL must be one of {', '.join(MECHANICAL_MODELS)}; got {name!r}") from None


__all__ = ["MECHANICAL_MODELS", "get_mechanical", "MechanicalModel", "MechanicalLabels", "FrictionOscillator",
           "TwoBlock", "CamFollower", "BouncingBall", "accumulation_time"]
