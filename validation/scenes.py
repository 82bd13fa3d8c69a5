"""Scenes: TOML files naming a converter, its parameters, the run, the methods and the checks.

Strict: an unknown key anywhere is refused with the list of valid keys; parameters are validated by
the converter (range errors name the parameter); thresholds must be positive numbers.

    name = "buck-dcm"                       # defaults to the file name
    converter = "buck"
    description = "..."
    suites = ["default"]
    control = "smc"                         # optional: boost under sliding-mode control ("smc",
                                            # "smc-implicit"); params are then those of converters.models.sliding
    [params]            # converter parameters, SPICE suffixes allowed
    [run]               # start = "steady" | "rest", periods, window; control scenes: t_end
    [methods.lcp]       # h, theta; or rtol (accuracy on request: pcsuite picks the method and h)
    [methods.spice]     # tmax_fraction, reltol, method, diode_n, diode_is, switch_ron, switch_roff
    [checks]            # vout_mean_rel, mode_agreement, turn_off_error_T, closed_form_rel;
                        # control scenes: vout_ref_rel, frequency_rel, frequency_agreement,
                        # recovery_agreement, lambda_settle
"""
from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from converters.errors import ParameterError
from converters.models import CONTROLS, get_converter, get_model
from converters.validate import parse_value
from netlists import SpiceOptions

from .defaults import THRESHOLDS

SCENE_DIR = Path(__file__).with_name("scenes")
TOP_KEYS = ("name", "converter", "description", "suites", "control", "params", "run", "methods", "checks")
RUN_KEYS = ("start", "periods", "window", "t_end")
METHOD_KEYS = {"lcp": ("h", "theta", "rtol"), "spice": tuple(SpiceOptions.__dataclass_fields__)}
CHECK_KEYS = ("vout_mean_rel", "mode_agreement", "vout_ripple_rel", "turn_off_error_T", "closed_form_rel", "vout_ref_rel",
              "frequency_rel", "frequency_agreement", "recovery_agreement", "lambda_settle")
#: The study each control runs, whose thresholds (data/defaults.toml) are the scene's default checks.
STUDY = {"pwm": "compare", "smc": "smc", "smc-implicit": "smc-implicit"}


@dataclass(frozen=True)
class Scene:
    name: str
    converter: str
    description: str = ""
    suites: tuple = ("default",)
    params: dict = field(default_factory=dict)
    run: dict = field(default_factory=dict)
    lcp: dict = field(default_factory=dict)
    spice: dict = field(default_factory=dict)
    checks: dict = field(default_factory=lambda: dict(THRESHOLDS["compare"]))
    path: str = ""
    control: str = "pwm"


def _strict(table: dict, valid, where: str):
    if not isinstance(table, dict):
        raise ParameterError(f"{where} must be a table; got {type(table).__name__}")
    for key in table:
        if key not in valid:
            raise ParameterError(f"unknown key {key!r} in {where}; valid keys: {', '.join(valid)}")


def load_scene(path) -> Scene:
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text())
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise ParameterError(f"scene {path.name}: not a readable TOML file ({exc})") from None
    where = f"scene {path.name}"
    _strict(data, TOP_KEYS, where)
    if "converter" not in data:
        raise ParameterError(f"{where}: 'converter' is required; valid: buck, boost, buck-boost, cuk, prc")
    converter = get_converter(data["converter"])
    control = data.get("control", "pwm")
    if control not in CONTROLS:
        raise ParameterError(f"{where}: control must be one of {', '.join(CONTROLS)}; got {control!r}")
    try:
        model = get_model(converter.name, control)
    except ParameterError as exc:
        raise ParameterError(f"{where}: {exc}") from None
    params = data.get("params", {})
    _strict(params, tuple(p.name for p in model.parameters), f"{where} [params]")
    try:
        model.resolve(params)  # errors name the parameter
    except ParameterError as exc:
        raise ParameterError(f"{where} [params]: {exc}") from None
    run = data.get("run", {})
    _strict(run, RUN_KEYS, f"{where} [run]")
    if run.get("start", "steady") not in ("steady", "rest"):
        raise ParameterError(f"{where} [run] start must be 'steady' or 'rest'; got {run['start']!r}")
    if "t_end" in run and parse_value(f"{where} [run] t_end", run["t_end"]) <= 0:
        raise ParameterError(f"{where} [run] t_end must be positive; got {run['t_end']!r}")
    for key in ("periods", "window"):
        if key in run and not (isinstance(run[key], int) and run[key] >= 1):
            raise ParameterError(f"{where} [run] {key} must be an integer >= 1; got {run[key]!r}")
    methods = data.get("methods", {})
    _strict(methods, tuple(METHOD_KEYS), f"{where} [methods]")
    for method, table in methods.items():
        _strict(table, METHOD_KEYS[method], f"{where} [methods.{method}]")
    SpiceOptions(**methods.get("spice", {}))  # validates values
    lcp = methods.get("lcp", {})
    if "rtol" in lcp:
        if set(lcp) & {"h", "theta"}:
            raise ParameterError(f"{where} [methods.lcp]: rtol chooses the method and its step; give either rtol or "
                                 f"{' and '.join(sorted(set(lcp) & {'h', 'theta'}))}")
        from converters.analysis.accuracy import RTOL_RANGE
        rtol = parse_value(f"{where} [methods.lcp] rtol", lcp["rtol"])
        if not RTOL_RANGE[0] <= rtol <= RTOL_RANGE[1]:
            raise ParameterError(f"{where} [methods.lcp] rtol must be in [{RTOL_RANGE[0]:g}, {RTOL_RANGE[1]:g}]; "
                                 f"got {lcp['rtol']!r}")
    checks = data.get("checks", {})
    _strict(checks, CHECK_KEYS, f"{where} [checks]")
    for key, value in checks.items():
        if parse_value(f"{where} [checks] {key}", value) <= 0:
            raise ParameterError(f"{where} [checks] {key} must be positive; got {value!r}")
    suites = data.get("suites", ["default"])
    if not (isinstance(suites, list) and all(isinstance(s, str) for s in suites)):
        raise ParameterError(f"{where}: suites must be a list of names; got {suites!r}")
    return Scene(name=data.get("name", path.stem), converter=converter.name, description=data.get("description", ""),
                 suites=tuple(suites), params=dict(params), run=dict(run), lcp=dict(methods.get("lcp", {})),
                 spice=dict(methods.get("spice", {})), path=str(path), control=control,
                 checks={**THRESHOLDS[STUDY[control]], **checks})


def scenes_of(suite: str, directory=SCENE_DIR) -> list[Scene]:
    scenes = [load_scene(p) for p in sorted(Path(directory).glob("*.toml"))]
    return [s for s in scenes if suite in s.suites]


def suite_names(directory=SCENE_DIR) -> list[str]:
    return sorted({name for p in Path(directory).glob("*.toml") for name in load_scene(p).suites})
