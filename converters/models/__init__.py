"""The converter library: one module per converter, looked up by name."""
from __future__ import annotations

from ..errors import ParameterError
from .base import OFF, ON, Converter, check_h
from .boost import Boost
from .buck import Buck
from .buckboost import BuckBoost
from .cuk import Cuk
from .prc import PRC

CONVERTERS: dict[str, Converter] = {c.name: c for c in (Buck(), Boost(), BuckBoost(), Cuk(), PRC())}


def get_converter(name: str) -> Converter:
    try:
        return CONVERTERS[name]
    except KeyError:
        raise ParameterError(f"CONVERTER must be one of {', '.join(CONVERTERS)}; got {name!r}") from None


__all__ = ["CONVERTERS", "get_converter", "Converter", "ON", "OFF", "check_h"]
