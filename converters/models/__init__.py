"""The model library: power converters (one module each, closed forms beside them), their control
laws, and the Siconos circuits; looked up by name and control."""
from __future__ import annotations

from ..errors import ParameterError
from .base import OFF, ON, Converter, Model, check_h
from .boost import Boost
from .buck import Buck
from .buckboost import BuckBoost
from .cuk import Cuk
from .prc import PRC
from .sliding import BoostSMC
from .netlist import Circuit, is_netlist, load
from .voltage_mode import BuckVoltageMode

CONVERTERS: dict[str, Converter] = {c.name: c for c in (Buck(), Boost(), BuckBoost(), Cuk(), PRC())}
#: The control of a converter when none is named: open-loop PWM.
DEFAULT_CONTROL = Model.control
#: Every model by (converter name, control): ``pwm`` is the open-loop PWM converter.
MODELS: dict[tuple[str, str], Model] = {**{(name, DEFAULT_CONTROL): c for name, c in CONVERTERS.items()},
                                        ("boost", "smc"): BoostSMC(implicit=False),
                                        ("boost", "smc-implicit"): BoostSMC(implicit=True),
                                        ("buck", "voltage-mode"): BuckVoltageMode()}
CONTROLS = tuple(dict.fromkeys(control for _, control in MODELS))


def get_converter(name: str) -> Converter:
    try:
        return CONVERTERS[name]
    except (KeyError, TypeError):          # TypeError: an unhashable name (a list)
        raise ParameterError(f"CONVERTER must be one of {', '.join(CONVERTERS)} or a netlist FILE.cir; got {name!r}") from None


def get_model(name: str, control: str = DEFAULT_CONTROL) -> Model:
    """The model of converter ``name`` under ``control``, or of the netlist file ``name`` names (``FILE.cir``:
    :class:`converters.circuits.Circuit`); errors name the valid choices."""
    if is_netlist(name):
        if control != DEFAULT_CONTROL:
            raise ParameterError(f"--control {control} applies to the built-in converters; a netlist states its own "
                                 f"drives (got {str(name)!r})")
        return load(name)
    get_converter(name)
    if not isinstance(control, str):
        raise ParameterError(f"control must be one of {', '.join(CONTROLS)}; got {control!r}")
    if control not in CONTROLS:
        raise ParameterError(f"control must be one of {', '.join(CONTROLS)}; got {control!r}")
    try:
        return MODELS[(name, control)]
    except KeyError:
        available = sorted(n for n, c in MODELS if c == control)
        takes = ", ".join(c for c in CONTROLS if (name, c) in MODELS)
        raise ParameterError(f"--control {control} is available for {', '.join(available)} only ({name} takes "
                             f"--control {takes}); got {name!r}") from None


__all__ = ["Circuit", "is_netlist", "CONVERTERS", "MODELS", "CONTROLS", "get_converter", "get_model", "Converter", "Model", "ON", "OFF",
           "check_h"]
