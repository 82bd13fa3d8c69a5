"""Scenes: TOML files naming a converter, its parameters, the run, the methods and the checks.

Strict, because a scene file may be a user's (``pcsuite report FILE.toml``): an unknown key anywhere is
refused with the list of valid keys, and so is a key that does not apply to the scene's kind (``t_end`` in a
PWM scene, ``theta`` in a control scene); every value is checked for its type (a bool is not a number, a
description must be a string) and its range (parameters by the converter, ``h`` below the switching period,
``theta`` in [0.5, 1], ``window <= periods``, ngspice options in :data:`SPICE_RANGES`, thresholds positive);
the name (and every suite name) must be a safe file name (:func:`validation.io.safe_name`). A bad scene is
refused at load with one line naming the file, the key and the value, before anything runs.

    name = "buck-dcm"                       # defaults to the file name
    converter = "buck"                      # or circuit = "sepic.cir": a netlist (beside the scene, or shipped in
                                            # netlists/circuits), compared by validation.circuit_compare
    description = "..."
    suites = ["default"]
    control = "smc"                         # optional: boost under sliding-mode control ("smc",
                                            # "smc-implicit"); params are then those of converters.models.sliding
    [params]            # converter parameters, SPICE suffixes allowed
    [run]               # start = "steady" | "rest", periods, window; control scenes: t_end
    [methods.lcp]       # h, theta; or rtol (accuracy on request: pcsuite picks the method and h)
    [methods.spice]     # tmax_fraction, reltol, method, diode_n, diode_is, switch_ron, switch_roff, edge_fraction,
                        # abstol, diode_cjo
    [checks]            # vout_mean_rel, mode_agreement, turn_off_error_T, closed_form_rel;
                        # control scenes: vout_ref_rel, frequency_rel, frequency_agreement,
                        # recovery_agreement, lambda_settle
"""
from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from converters.errors import ParameterError
from converters.models import get_converter, get_model
from converters.validate import parse_value, shown
from netlists import SpiceOptions

from .defaults import AT_LEAST, THRESHOLDS
from .io import safe_name

SCENE_DIR = Path(__file__).with_name("scenes")
TOP_KEYS = ("name", "converter", "circuit", "description", "suites", "control", "params", "run", "methods",
            "checks")
#: The keys of a circuit scene (circuit = "FILE.cir"): the netlist's compare (validation.circuit_compare).
CIRCUIT_KEYS = ("name", "circuit", "description", "suites", "params", "run", "methods", "checks")
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
    #: A circuit scene's netlist (its resolved path); its control is "circuit".
    circuit: str = ""


def _strict(table: dict, valid, where: str):
    if not isinstance(table, dict):
        raise ParameterError(f"{where} must be a table; got {type(table).__name__} {table!r}")
    for key in table:
        if key not in valid:
            raise ParameterError(f"unknown key {key!r} in {where}; valid keys: {', '.join(valid)}")


#: A scene file is untrusted input: its size, its strings and every value are bounded.
MAX_SCENE_BYTES = 1 << 20
MAX_DESCRIPTION = 4000
PERIODS_RANGE = (1, 100_000)
T_END_MAX = 10.0
#: Plausible ranges of the ngspice options (netlists.SpiceOptions only requires them positive):
#: (low, high, high_open, meaning).
SPICE_RANGES = {
    "tmax_fraction": (1e-6, 1.0, True, ".tran TMAX as a fraction of the switching period"),
    "reltol": (1e-9, 0.1, False, "ngspice RELTOL"),
    "diode_n": (1e-4, 10.0, False, "the diode's emission coefficient N"),
    "diode_is": (1e-20, 1e-3, False, "the diode's saturation current IS in A"),
    "switch_ron": (1e-9, 1e3, False, "the switch's on resistance in ohm"),
    "switch_roff": (1.0, 1e15, False, "the switch's off resistance in ohm"),
    "edge_fraction": (1e-9, 1e-2, False, "the gate's rise and fall time as a fraction of the switching period"),
    "abstol": (1e-15, 1e-3, False, "ngspice ABSTOL in A"),
    "diode_cjo": (0.0, 1e-6, False, "the diode's junction capacitance CJO in F"),
}
#: Keys of [run] and [methods] that apply to each kind of scene.
RUN_FOR = {"pwm": ("start", "periods", "window"), "smc": ("t_end",), "smc-implicit": ("t_end",)}
LCP_FOR = {"pwm": ("h", "theta", "rtol"), "smc": ("h",), "smc-implicit": ("h",)}
#: The kinds of scene that compare over a fixed number of periods (a PWM converter's), and that run ngspice.
PERIODIC = ("pwm",)
RUNS_SPICE = ("pwm", "smc")


def _string(where: str, key: str, value, limit: int = 200) -> str:
    if not isinstance(value, str):
        raise ParameterError(f"{where}: {key} must be a string; got {value!r}")
    if len(value) > limit:
        raise ParameterError(f"{where}: {key} must be at most {limit} characters; got {len(value)}")
    return value


def _number(where: str, key: str, value) -> float:
    """A number (SPICE suffixes allowed in a string; a bool is not a number)."""
    if isinstance(value, bool):
        raise ParameterError(f"{where} {key} must be a number; got {value!r}")
    return parse_value(f"{where} {key}", value)


def _integer(where: str, key: str, value, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise ParameterError(f"{where} {key} must be an integer in [{low}, {high}]; got {shown(value)}")
    return value


#: An integer longer than Python reads from text (sys.get_int_max_str_digits, 4300): tomllib then raises a bare
#: ValueError that names neither the key nor the line.
_LONG_DIGITS = re.compile(r"[0-9][0-9_]{4300,}")


def _long_integer(text: str, where: str) -> ParameterError:
    """The one-line error for the first integer tomllib could not read: its table, key, line and length."""
    table = ""
    for number, line in enumerate(text.splitlines(), 1):
        header = re.match(r"\s*(\[\[?[^\]]*\]\]?)", line)
        if header and "=" not in line[:header.end()]:
            table = header.group(1).strip()
        found = _LONG_DIGITS.search(line)
        if found:
            key = line[:found.start()].partition("=")[0].strip() or "a value"
            count = sum(ch.isdigit() for ch in found.group())
            place = f"{where} {table} {key}" if table else f"{where} {key}"
            return ParameterError(f"{place}: an integer of {count} digits (line {number}), beyond every range of a "
                                  "scene's values")
    return ParameterError(f"{where}: not a readable TOML file (an integer too long to read)")


def _read(path: Path, where: str) -> dict:
    try:
        size = path.stat().st_size
        if size > MAX_SCENE_BYTES:
            raise ParameterError(f"{where}: a scene file must be at most {MAX_SCENE_BYTES} bytes; got {size}")
        return tomllib.loads(path.read_bytes().decode("utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        detail = str(exc).replace("\n", " ")
        raise ParameterError(f"{where}: not a readable TOML file ({detail})") from None
    except RecursionError:      # tomllib parses nested arrays and tables recursively
        raise ParameterError(f"{where}: not a readable TOML file (arrays or tables nested too deeply; a scene "
                             "needs at most a few levels)") from None
    except ParameterError:
        raise
    except ValueError:          # int() of more digits than Python reads from text
        raise _long_integer(path.read_bytes().decode("utf-8", "replace"), where) from None


def load_scene(path) -> Scene:
    """Read and check a scene file completely: every key known, every value of the right type and in its range
    (a bad scene is refused here, before anything runs, with one line naming the file, the key and the value)."""
    path = Path(path)
    shown = path.name if path.name.isprintable() else repr(path.name)
    where = f"scene {shown}"
    data = _read(path, where)
    _strict(data, TOP_KEYS, where)
    if "name" in data:
        name = safe_name(f"{where}: name", _string(where, "name", data["name"]))
    else:
        name = safe_name(f"{where}: name (by default the file's name; set name = \"...\")", path.stem)
    if "circuit" in data:
        return _circuit_scene(data, path, name, where)
    if "converter" not in data:
        raise ParameterError(f"{where}: 'converter' (a built-in converter: buck, boost, buck-boost, cuk, prc) or "
                             "'circuit' (a netlist FILE.cir) is required")
    converter = get_converter(_string(where, "converter", data["converter"]))
    description = _string(where, "description", data.get("description", ""), MAX_DESCRIPTION)
    control = _string(where, "control", data.get("control", "pwm"))
    if control not in STUDY:
        raise ParameterError(f"{where}: control must be one of {', '.join(STUDY)}; got {control!r}")
    try:
        model = get_model(converter.name, control)
    except ParameterError as exc:
        raise ParameterError(f"{where}: {exc}") from None
    suites = _suites(data, where)
    params = data.get("params", {})
    _strict(params, tuple(p.name for p in model.parameters), f"{where} [params]")
    try:
        p = model.resolve(params)  # errors name the parameter
    except ParameterError as exc:
        raise ParameterError(f"{where} [params]: {exc}") from None
    run = _check_run(data.get("run", {}), control, model, p, f"{where} [run]")
    methods = data.get("methods", {})
    _strict(methods, tuple(METHOD_KEYS), f"{where} [methods]")
    for method, table in methods.items():
        _strict(table, METHOD_KEYS[method], f"{where} [methods.{method}]")
    lcp = _check_lcp(methods.get("lcp", {}), control, model, p, run, f"{where} [methods.lcp]")
    spice = _check_spice(methods.get("spice", {}), control, f"{where} [methods.spice]")
    checks = _check_checks(data.get("checks", {}), control, converter, f"{where} [checks]")
    return Scene(name=name, converter=converter.name, description=description,
                 suites=tuple(suites), params=dict(params), run=run, lcp=lcp, spice=spice, path=str(path),
                 control=control, checks={**THRESHOLDS[STUDY[control]], **checks})


#: Where a circuit scene's netlist is looked for after the scene's own directory: the shipped circuits.
CIRCUIT_DIR = Path(__file__).resolve().parents[1] / "netlists" / "circuits"


def _circuit_file(where: str, value, scene_dir: Path) -> Path:
    """The netlist a circuit scene names: a relative path without '..' ending in .cir, in the scene's directory
    or else among the shipped circuits (netlists/circuits)."""
    text = _string(where, "circuit", value, 300)
    relative = Path(text)
    if relative.is_absolute() or ".." in relative.parts or relative.suffix.lower() != ".cir":
        raise ParameterError(f"{where}: circuit must be a relative path to a .cir file without '..' (looked for "
                             f"beside the scene, then in the shipped circuits); got {text!r}")
    for base in (scene_dir, CIRCUIT_DIR):
        if (base / relative).is_file():
            return base / relative
    raise ParameterError(f"{where}: circuit {text!r} is neither beside the scene ({str(scene_dir)!r}) nor a shipped "
                         f"circuit ({', '.join(sorted(p.name for p in CIRCUIT_DIR.glob('*.cir')))})")


def _circuit_scene(data: dict, path: Path, name: str, where: str) -> Scene:
    """A scene comparing a netlist's LCS with ngspice on the same file (validation.circuit_compare): [params] are
    the file's (.param names and element values), [run] start, periods and window, [methods.lcp] h,
    [methods.spice] ngspice's options (without them the file's own), [checks] those of [thresholds.circuit]."""
    from converters.models import Circuit
    from converters.circuits.netlist import NetlistError
    if "converter" in data or "control" in data:
        raise ParameterError(f"{where}: a circuit scene takes neither converter nor control; valid keys: "
                             f"{', '.join(CIRCUIT_KEYS)}")
    _strict(data, CIRCUIT_KEYS, where)
    file = _circuit_file(where, data["circuit"], path.parent)
    try:
        circuit = Circuit.from_netlist(file)
    except (NetlistError, ParameterError) as exc:
        raise ParameterError(f"{where}: {exc}") from None
    description = _string(where, "description", data.get("description", ""), MAX_DESCRIPTION)
    suites = _suites(data, where)
    params = data.get("params", {})
    names = tuple(p.name for p in circuit.parameters)
    if not isinstance(params, dict):
        raise ParameterError(f"{where} [params] must be a table; got {type(params).__name__} {params!r}")
    for key in params:                            # SPICE names are case-insensitive
        if str(key).lower() not in names:
            raise ParameterError(f"unknown key {key!r} in {where} [params]; valid keys: {', '.join(names)}")
    try:
        p = circuit.resolve(params)
        circuit.compiled(p)                       # what the file cannot be compiled into is refused here
    except (NetlistError, ParameterError) as exc:
        raise ParameterError(f"{where} [params]: {exc}") from None
    run = data.get("run", {})
    _strict(run, ("start", "periods", "window"), f"{where} [run]")
    if "start" in run and run["start"] not in ("steady", "rest"):
        raise ParameterError(f"{where} [run] start must be 'steady' or 'rest'; got {run['start']!r}")
    from .circuit_compare import PERIODS, WINDOW
    periods = _integer(f"{where} [run]", "periods", run["periods"], *PERIODS_RANGE) if "periods" in run else PERIODS
    window = _integer(f"{where} [run]", "window", run["window"], *PERIODS_RANGE) if "window" in run else WINDOW
    if window > periods:
        raise ParameterError(f"{where} [run] window must be in [1, periods = {periods}]; got {window}")
    methods = data.get("methods", {})
    _strict(methods, ("lcp", "spice"), f"{where} [methods]")
    lcp = methods.get("lcp", {})
    _strict(lcp, ("h",), f"{where} [methods.lcp]")
    if "h" in lcp:
        h = _number(f"{where} [methods.lcp]", "h", lcp["h"])
        if not 0.0 < h <= circuit.max_h(p) or (circuit.periodic(p) and not h < circuit.period(p)):
            raise ParameterError(f"{where} [methods.lcp] h must be a positive number below the circuit's period and "
                                 f"at most {circuit.max_h(p):.3g} s; got {lcp['h']!r}")
    spice = _check_spice(methods.get("spice", {}), "pwm", f"{where} [methods.spice]")
    checks = data.get("checks", {})
    _strict(checks, tuple(THRESHOLDS["circuit"]), f"{where} [checks]")
    for key, value in checks.items():
        number = _number(f"{where} [checks]", key, value)
        if number <= 0 or (key in AT_LEAST and number > 1):
            bound = "in (0, 1] (a fraction)" if key in AT_LEAST else "positive"
            raise ParameterError(f"{where} [checks] {key} must be {bound}; got {value!r}")
    return Scene(name=name, converter=file.name, description=description, suites=tuple(suites), params=dict(params),
                 run=dict(run), lcp=dict(lcp), spice=spice, path=str(path), control="circuit", circuit=str(file),
                 checks={**THRESHOLDS["circuit"], **checks})


def _suites(data: dict, where: str) -> list:
    """The scene's suites: a list of safe names (default: the default suite)."""
    suites = data.get("suites", ["default"])
    if not isinstance(suites, list):
        raise ParameterError(f"{where}: suites must be a list of names; got {suites!r}")
    for suite in suites:
        safe_name(f"{where}: suites entry", suite)
    return suites


def _check_run(run, control: str, model, p: dict, where: str) -> dict:
    _strict(run, RUN_KEYS, where)
    for key in run:
        if key not in RUN_FOR[control]:
            kind = "a pwm scene" if control in PERIODIC else "a control scene (smc, smc-implicit)"
            raise ParameterError(f"{where} {key} does not apply to {kind}; valid keys: {', '.join(RUN_FOR[control])}")
    if "start" in run and run["start"] not in ("steady", "rest"):
        raise ParameterError(f"{where} start must be 'steady' or 'rest'; got {run['start']!r}")
    for key in ("periods", "window"):
        if key in run:
            _integer(where, key, run[key], *PERIODS_RANGE)
    if control in PERIODIC:
        defaults = model.compare_defaults
        periods, window = run.get("periods", defaults["periods"]), run.get("window", defaults["window"])
        if window > periods:
            given = "" if "window" in run else " (the default)"
            raise ParameterError(f"{where} window must be in [1, periods = {periods}]; got {window}{given}")
    if "t_end" in run:
        t_end = _number(where, "t_end", run["t_end"])
        if not 0.0 < t_end <= T_END_MAX:
            raise ParameterError(f"{where} t_end must be in (0, {T_END_MAX:g}] s; got {run['t_end']!r}")
        if "t_step" in p and not p["t_step"] < t_end:
            raise ParameterError(f"{where} t_end must be after the load step t_step = {p['t_step']:g} s; "
                                 f"got {run['t_end']!r}")
    return dict(run)


def _check_lcp(lcp: dict, control: str, model, p: dict, run: dict, where: str) -> dict:
    for key in lcp:
        if key not in LCP_FOR[control]:
            raise ParameterError(f"{where} {key} does not apply to a control scene ({control}); valid keys: "
                                 f"{', '.join(LCP_FOR[control])}")
    if "rtol" in lcp:
        if set(lcp) & {"h", "theta"}:
            raise ParameterError(f"{where}: rtol chooses the method and its step; give either rtol or "
                                 f"{' and '.join(sorted(set(lcp) & {'h', 'theta'}))}")
        from converters.analysis.accuracy import RTOL_RANGE
        rtol = _number(where, "rtol", lcp["rtol"])
        if not RTOL_RANGE[0] <= rtol <= RTOL_RANGE[1]:
            raise ParameterError(f"{where} rtol must be in [{RTOL_RANGE[0]:g}, {RTOL_RANGE[1]:g}]; got {lcp['rtol']!r}")
        start = run.get("start", model.compare_defaults["start"])
        if start != "steady":
            raise ParameterError(f"{where} rtol gives the periodic steady state: it needs [run] start = 'steady'; "
                                 f"got start = {start!r}" + ("" if "start" in run else " (the model's default)"))
    if "h" in lcp:
        h = _number(where, "h", lcp["h"])
        if model.periodic(p):
            period = model.period(p)
            if not 0.0 < h < period:
                raise ParameterError(f"{where} h must be a positive number below the switching period "
                                     f"({period:g} s); got {lcp['h']!r}")
        elif not 0.0 < h <= model.max_h(p):
            raise ParameterError(f"{where} h must be in (0, {model.max_h(p):.3g}] s (at most 1/20 of the shorter "
                                 f"switching interval); got {lcp['h']!r}")
    if "theta" in lcp:
        theta = _number(where, "theta", lcp["theta"])
        if not 0.5 <= theta <= 1.0:
            raise ParameterError(f"{where} theta must be in [0.5, 1]; got {lcp['theta']!r}")
    return dict(lcp)


def _check_spice(spice: dict, control: str, where: str) -> dict:
    if spice and control not in RUNS_SPICE:
        raise ParameterError(f"{where}: an {control} scene runs no ngspice; remove [methods.spice]")
    for key, value in spice.items():
        if key == "method":
            if value not in ("trap", "gear"):
                raise ParameterError(f"{where} method must be 'trap' or 'gear'; got {value!r}")
            continue
        number = _number(where, key, value)
        if key not in SPICE_RANGES:                  # an option added to SpiceOptions without a range here
            continue
        low, high, high_open, meaning = SPICE_RANGES[key]
        if not (low <= number < high if high_open else low <= number <= high):
            raise ParameterError(f"{where} {key} ({meaning}) must be in [{low:g}, {high:g}{')' if high_open else ']'}; "
                                 f"got {value!r}")
    options = SpiceOptions(**spice)
    if not options.switch_ron < options.switch_roff:
        raise ParameterError(f"{where} switch_roff must be above switch_ron = {options.switch_ron:g}; "
                             f"got {options.switch_roff:g}")
    return dict(spice)


def _check_checks(checks: dict, control: str, converter, where: str) -> dict:
    _strict(checks, CHECK_KEYS, where)
    valid = list(THRESHOLDS[STUDY[control]])
    if control in PERIODIC and converter.closed_form:
        valid.append("closed_form_rel")
    for key, value in checks.items():
        if key not in valid:
            raise ParameterError(f"{where} {key} does not apply to this scene ({converter.name}, {control}); "
                                 f"valid keys: {', '.join(valid)}")
        number = _number(where, key, value)
        if number <= 0 or (key in AT_LEAST and number > 1):
            bound = "in (0, 1] (a fraction)" if key in AT_LEAST else "positive"
            raise ParameterError(f"{where} {key} must be {bound}; got {value!r}")
    return dict(checks)


def load_scenes(paths) -> list[Scene]:
    """Several scene files: each checked by :func:`load_scene`, and no two with one name (a scene's name names
    its files in the report)."""
    scenes, seen = [], {}
    for path in paths:
        scene = load_scene(path)
        if seen.get(scene.name) is not None:
            raise ParameterError(f"scene {Path(path).name}: name {scene.name!r} is already the name of scene "
                                 f"{Path(seen[scene.name]).name}; scene names must be unique")
        seen[scene.name] = scene.path
        scenes.append(scene)
    return scenes


def scene_files(target) -> list[Path]:
    """The scene files a user names: FILE.toml, or every *.toml in DIR (sorted)."""
    path = Path(target)
    if path.is_dir():
        files = sorted(p for p in path.glob("*.toml") if p.is_file())
        if not files:
            raise ParameterError(f"scene directory {str(path)!r} holds no *.toml scene file")
        return files
    if path.is_file() and path.suffix.lower() == ".toml":
        return [path]
    raise ParameterError(f"a scene file must be an existing FILE.toml or a directory of them; got {str(path)!r}")


def scenes_of(suite: str, directory=SCENE_DIR) -> list[Scene]:
    scenes = load_scenes(sorted(Path(directory).glob("*.toml")))
    return [s for s in scenes if suite in s.suites]


def suite_names(directory=SCENE_DIR) -> list[str]:
    return sorted({name for p in Path(directory).glob("*.toml") for name in load_scene(p).suites})


#: The suites made of report sections (:data:`validation.sections.EXTRA_SECTIONS`, whose module imports pandas,
#: matplotlib and the solvers: ``pcsuite list`` reads the names here; a test checks that the two agree).
EXTRA_SUITES = ("bench", "bifurcation", "default", "gdcm", "lcp", "mechanics", "thermal")


def all_suites() -> list[str]:
    """Every suite ``pcsuite report`` takes: those of the scene files and those of report sections."""
    return sorted(set(suite_names()) | set(EXTRA_SUITES))
