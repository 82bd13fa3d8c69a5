"""The model library: power converters (one module each, closed forms beside them), the controls that close
loops around them (:mod:`.control`: a control composes with a converter), and the Siconos circuits; looked up by
name and control."""
from __future__ import annotations

from ..errors import ParameterError
from .base import OFF, ON, Converter, Model, check_h
from .boost import Boost
from .buck import Buck
from .buckboost import BuckBoost
from .control import REGISTERED, Control, Controlled, OpenLoop
from .compensator import VoltageLoop
from .cuk import Cuk
from .current_mode import PeakCurrent, PeakCurrentLoop, ValleyCurrent
from .prc import PRC
from .sliding import SlidingMode
from .netlist import Circuit, is_netlist, load
from .plant import NetlistPlant
from .voltage_mode import VoltageMode

CONVERTERS: dict[str, Converter] = {c.name: c for c in (Buck(), Boost(), BuckBoost(), Cuk(), PRC())}
#: Every control by its --control name; ``pwm`` is open-loop PWM (the converter as it is).
CONTROLS: dict[str, Control] = {c.key: c for c in (OpenLoop(), SlidingMode(implicit=False),
                                                   SlidingMode(implicit=True), VoltageMode(),
                                                   PeakCurrent(), ValleyCurrent(),
                                                   PeakCurrentLoop(), VoltageLoop())}
#: The control of a converter when none is named: open-loop PWM.
DEFAULT_CONTROL = OpenLoop.key
#: Every model by (converter name, control): each control on each converter it applies to (built once, so a
#: model is one object).
MODELS: dict[tuple[str, str], Model] = {(name, key): control.on(converter) for key, control in CONTROLS.items()
                                        for name, converter in CONVERTERS.items() if control.applies_to(converter)}
REGISTERED.update({key: model for key, model in MODELS.items() if isinstance(model, Controlled)})


def get_converter(name: str) -> Converter:
    try:
        return CONVERTERS[name]
    except (KeyError, TypeError):          # TypeError: an unhashable name (a list)
        raise ParameterError(f"CONVERTER must be one of {', '.join(CONVERTERS)} or a netlist FILE.cir; got {name!r}") from None


def get_model(name: str, control: str = DEFAULT_CONTROL) -> Model:
    """The model of converter ``name`` under ``control``, or of the netlist file ``name`` names (``FILE.cir``:
    :class:`converters.circuits.Circuit`); errors name the valid choices."""
    if is_netlist(name):
        if control == DEFAULT_CONTROL:
            return load(name)
        if not isinstance(control, str) or control not in CONTROLS:
            raise ParameterError(f"control must be one of {', '.join(CONTROLS)}; got {control!r}")
        loop = CONTROLS[control]
        if not loop.output_only:
            takes = ", ".join(key for key, c in CONTROLS.items() if c.output_only)
            raise ParameterError(f"--control {control} closes its loop around the built-in converters it names; a "
                                 f"netlist takes --control {takes} (a loop that senses its output and drives its "
                                 f"first switch), or states its own loop (got {str(name)!r})")
        return loop.on(NetlistPlant(load(name)))
    get_converter(name)
    if not isinstance(control, str) or control not in CONTROLS:
        raise ParameterError(f"control must be one of {', '.join(CONTROLS)}; got {control!r}")
    try:
        return MODELS[(name, control)]
    except KeyError:
        available = sorted(n for n, c in MODELS if c == control)
        takes = ", ".join(c for c in CONTROLS if (name, c) in MODELS)
        raise ParameterError(f"--control {control} is available for {', '.join(available)} only ({name} takes "
                             f"--control {takes}); got {name!r}") from None


__all__ = ["Circuit", "is_netlist", "CONVERTERS", "MODELS", "CONTROLS", "get_converter", "get_model", "Converter", "Model",
           "Control", "Controlled", "ON", "OFF", "check_h"]
