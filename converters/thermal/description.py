"""A device's loss and thermal description, read from PLECS's XML thermal description or from a plain table file.

What is read of a PLECS description (``<SemiconductorLibrary>`` of ``<Package>``, or one ``<Package>``):

* ``<Package class=... vendor=... partnumber=...>``: the class Diode, MOSFET or IGBT ("... with Diode" and the
  other classes are refused: give the switch and its diode as two descriptions);
* one ``<SemiconductorData>`` with ``<TurnOnLoss>`` and ``<TurnOffLoss>`` (``<CurrentAxis>``, ``<VoltageAxis>``,
  ``<TemperatureAxis>``, ``<Energy scale=...>`` of ``<Temperature>`` blocks of ``<Voltage>`` rows over the
  current) and ``<ConductionLoss>`` (``<CurrentAxis>``, ``<TemperatureAxis>``, ``<VoltageDrop scale=...>`` of
  ``<Temperature>`` rows), each ``<ComputationMethod>Table only</ComputationMethod>`` (a formula is evaluated by
  PLECS at run time: refused, not dropped);
* ``<ThermalModel>`` with one ``<Branch type="Foster">`` of ``<RTauElement R= Tau=>`` or ``<Branch type="Cauer">``
  of ``<RCElement R= C=>``;
* ``<Variables>`` only when empty, ``<Comment>`` (ignored). Any other element is refused by name.

A diode's switching losses are stated at negative blocked voltages (PLECS's convention): read at |V|; its turn-off
energy is its reverse-recovery energy. The plain table form (TOML) holds the same: see :func:`read_table`.
Files are read whole up to 16 MB; a document type declaration is refused (a description has none, and its
entities are how an XML file expands without bound).
"""
from __future__ import annotations

import tomllib
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..validate import quoted
from .chains import ThermalChain
from .tables import Table, energy_table, on_state_table

CLASSES = ("Diode", "MOSFET", "IGBT")
MAX_BYTES = 16 * 2 ** 20
_NS = "{http://www.plexim.com/xml/semiconductors/}"


@dataclass(frozen=True)
class DeviceDescription:
    """What a device dissipates and how its heat leaves it: switching energies (J) at turn-on and turn-off over
    (V, A, degC), the on-state voltage (V) over (A, degC), the junction-to-case chain; any may be absent."""

    name: str
    kind: str
    turn_on: Table | None = None
    turn_off: Table | None = None
    conduction: Table | None = None
    thermal: ThermalChain | None = None
    source: str = ""


def read_description(path: str | Path) -> DeviceDescription:
    """A description from ``path``: PLECS's XML (``.xml``) or the table form (``.toml``)."""
    path = Path(path)
    if path.suffix.lower() not in (".xml", ".toml"):
        raise ParameterError(f"a thermal description must be a PLECS .xml or a .toml table file; got {quoted(path)}")
    try:
        size = path.stat().st_size
        if size > MAX_BYTES:
            raise ParameterError(f"{quoted(path)}: {size} bytes, more than a thermal description holds "
                                 f"({MAX_BYTES} at most)")
        data = path.read_bytes()
    except OSError as error:
        raise ParameterError(f"cannot read the thermal description {quoted(path)}: {error.strerror}") from None
    return (parse_plecs if path.suffix.lower() == ".xml" else parse_table)(data, quoted(path))


# --- PLECS's XML ---------------------------------------------------------------------------------------------

def parse_plecs(data: bytes, where: str = "the description") -> DeviceDescription:
    """A PLECS thermal description (the XML text); ``where`` names it in messages."""
    if b"<!DOCTYPE" in data or b"<!ENTITY" in data:
        raise ParameterError(f"{where}: a document type declaration (<!DOCTYPE or <!ENTITY) is not read in a "
                             "thermal description")
    try:
        root = ET.fromstring(data)
    except ET.ParseError as error:
        raise ParameterError(f"{where}: not well-formed XML ({error})") from None
    if _tag(root) == "SemiconductorLibrary":
        packages = list(root)
        if len(packages) != 1 or _tag(packages[0]) != "Package":
            raise ParameterError(f"{where}: <SemiconductorLibrary> must hold one <Package>; got "
                                 f"{[_tag(p) for p in packages]}")
        root = packages[0]
    if _tag(root) != "Package":
        raise ParameterError(f"{where}: the root element must be <SemiconductorLibrary> or <Package>; got "
                             f"<{_tag(root)}>")
    kind = (root.get("class") or "").strip()
    if kind not in CLASSES:
        raise ParameterError(f"{where}: the Package class must be one of {', '.join(CLASSES)} (a switch and its "
                             f"diode as two descriptions); got {kind!r}")
    name = (root.get("partnumber") or "").strip() or "device"
    found: dict[str, Any] = {}
    for child in root:
        tag = _tag(child)
        if tag == "SemiconductorData":
            if "data" in found:
                raise ParameterError(f"{where}: more than one <SemiconductorData> (a package of several chips is "
                                     "not read)")
            found["data"] = _semiconductor_data(child, f"{where} <SemiconductorData>", kind)
        elif tag == "ThermalModel":
            if "thermal" in found:
                raise ParameterError(f"{where}: more than one <ThermalModel>")
            found["thermal"] = _thermal_model(child, f"{where} <ThermalModel>")
        elif tag == "Variables":
            if len(child) or (child.text or "").strip():
                raise ParameterError(f"{where}: <Variables> (custom variables and limits) is not read; remove it "
                                     "or give the tables in the .toml form")
        elif tag != "Comment":
            raise ParameterError(f"{where}: unknown element <{tag}> in <Package> (read: SemiconductorData, "
                                 "ThermalModel, an empty Variables, Comment)")
    tables = found.get("data", {})
    return DeviceDescription(name, kind, tables.get("TurnOnLoss"), tables.get("TurnOffLoss"),
                             tables.get("ConductionLoss"), found.get("thermal"), where)


def _tag(element: ET.Element) -> str:
    return element.tag[len(_NS):] if element.tag.startswith(_NS) else element.tag


def _semiconductor_data(element: ET.Element, where: str, kind: str) -> dict[str, Table]:
    tables: dict[str, Table] = {}
    for child in element:
        tag = _tag(child)
        if tag not in ("TurnOnLoss", "TurnOffLoss", "ConductionLoss"):
            raise ParameterError(f"{where}: unknown element <{tag}> (read: TurnOnLoss, TurnOffLoss, ConductionLoss)")
        if tag in tables:
            raise ParameterError(f"{where}: more than one <{tag}>")
        what = f"{where} <{tag}>"
        _table_only(child, what)
        if tag == "ConductionLoss":
            current, temperature = _axis(child, "CurrentAxis", what), _axis(child, "TemperatureAxis", what)
            rows = _rows(_one(child, "VoltageDrop", what), "Temperature", what, temperature.size)
            tables[tag] = on_state_table(what, current, temperature, rows)
        else:
            current, voltage = _axis(child, "CurrentAxis", what), _axis(child, "VoltageAxis", what)
            temperature = _axis(child, "TemperatureAxis", what)
            energy = _one(child, "Energy", what)
            blocks = _children(energy, "Temperature", what, temperature.size)
            values = np.array([_rows(block, "Voltage", what, voltage.size) for block in blocks]) * _scale(energy, what)
            if kind == "Diode":                      # stated at negative blocked voltages: read at |V|
                if np.any(voltage > 0):
                    raise ParameterError(f"{what}: a diode's switching losses are stated at blocked voltages <= 0 "
                                         f"(PLECS's convention); got {voltage.tolist()} V")
                voltage, values = -voltage[::-1], values[:, ::-1, :]
            tables[tag] = energy_table(what, voltage, current, temperature, values)
    return tables


def _table_only(element: ET.Element, what: str) -> None:
    method = element.find(f"{_NS}ComputationMethod")
    if method is None:
        method = element.find("ComputationMethod")
    text = (method.text or "").strip() if method is not None else "Table only"
    if text.lower() not in ("table only", "lookup table"):
        raise ParameterError(f"{what}: the computation method must be 'Table only' (a formula PLECS evaluates at "
                             f"run time is not dropped silently); got {text!r}")


def _one(element: ET.Element, tag: str, what: str) -> ET.Element:
    found = [c for c in element if _tag(c) == tag]
    if len(found) != 1:
        raise ParameterError(f"{what}: exactly one <{tag}> expected; got {len(found)}")
    return found[0]


def _numbers(text: str | None, what: str) -> np.ndarray:
    try:
        values = np.array([float(v) for v in (text or "").replace(",", " ").split()])
    except ValueError:
        raise ParameterError(f"{what}: numbers separated by spaces expected; got {(text or '').strip()[:40]!r}") \
            from None
    if not np.all(np.isfinite(values)):
        raise ParameterError(f"{what}: the numbers must be finite; got {(text or '').strip()[:40]!r}")
    return values


def _axis(element: ET.Element, tag: str, what: str) -> np.ndarray:
    return _numbers(_one(element, tag, what).text, f"{what} <{tag}>")


def _scale(element: ET.Element, what: str) -> float:
    text = element.get("scale", "1")
    try:
        scale = float(text)
    except ValueError:
        scale = float("nan")
    if not (np.isfinite(scale) and scale > 0):
        raise ParameterError(f"{what}: scale must be a number > 0; got {text!r}")
    return scale


def _children(element: ET.Element, tag: str, what: str, count: int) -> list[ET.Element]:
    children = list(element)
    if any(_tag(c) != tag for c in children) or len(children) != count:
        raise ParameterError(f"{what}: <{_tag(element)}> must hold {count} <{tag}> (one per point of its axis); got "
                             f"{[_tag(c) for c in children]}")
    return children


def _rows(element: ET.Element, tag: str, what: str, count: int) -> np.ndarray:
    rows = [_numbers(c.text, f"{what} <{tag}>") for c in _children(element, tag, what, count)]
    if len({r.size for r in rows}) > 1:
        raise ParameterError(f"{what}: the <{tag}> rows differ in length ({[r.size for r in rows]})")
    return np.array(rows) * (_scale(element, what) if _tag(element) == "VoltageDrop" else 1.0)


def _thermal_model(element: ET.Element, what: str) -> ThermalChain:
    branches = list(element)
    if len(branches) != 1 or _tag(branches[0]) != "Branch":
        raise ParameterError(f"{what}: one <Branch> (a Foster or Cauer chain) expected; got "
                             f"{[_tag(b) for b in branches]}")
    branch = branches[0]
    kind = (branch.get("type") or "").strip().lower()
    element_tag, second = {"foster": ("RTauElement", "Tau"), "cauer": ("RCElement", "C")}.get(kind, ("", ""))
    if not element_tag:
        raise ParameterError(f"{what}: the Branch type must be Foster or Cauer; got {branch.get('type')!r}")
    R, S = [], []
    for stage in branch:
        if _tag(stage) != element_tag:
            raise ParameterError(f"{what}: a {kind} branch holds <{element_tag}> stages; got <{_tag(stage)}>")
        R.append(_attribute(stage, "R", what))
        S.append(_attribute(stage, second, what))
    return ThermalChain(kind, tuple(R), tuple(S), what)


def _attribute(stage: ET.Element, name: str, what: str) -> float:
    text = stage.get(name)
    if text is None:
        raise ParameterError(f"{what}: each <{_tag(stage)}> needs its {name} attribute; got "
                             f"{sorted(stage.attrib)}")
    try:
        return float(text)
    except ValueError:
        raise ParameterError(f"{what}: {name} must be a number (no unit); got {text!r}") from None


# --- the table form ------------------------------------------------------------------------------------------

TABLE_KEYS = {"device": {"name", "kind"}, "conduction": {"current", "temperature", "v_on"},
              "turn_on": {"voltage", "current", "temperature", "energy"},
              "turn_off": {"voltage", "current", "temperature", "energy"},
              "thermal": {"kind", "R", "tau", "C"}}


def parse_table(data: bytes, where: str = "the description") -> DeviceDescription:
    """The table form (TOML), in SI units and degC::

        [device]      name = "Q1", kind = "MOSFET"             (Diode, MOSFET, IGBT)
        [conduction]  current = [A], temperature = [degC], v_on = [[V per current] per temperature]
        [turn_on]     voltage = [V], current = [A], temperature = [degC],
                      energy = [[[J per current] per voltage] per temperature]
        [turn_off]    the same (a diode's: its reverse recovery, at |V|)
        [thermal]     kind = "foster", R = [K/W], tau = [s]     or kind = "cauer", R = [K/W], C = [J/K]
    """
    try:
        doc = tomllib.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as error:
        raise ParameterError(f"{where}: not a TOML table file ({error})") from None
    for section, values in doc.items():
        if section not in TABLE_KEYS or not isinstance(values, dict):
            raise ParameterError(f"{where}: unknown section [{section}] (read: {', '.join(TABLE_KEYS)})")
        unknown = set(values) - TABLE_KEYS[section]
        if unknown:
            raise ParameterError(f"{where}: unknown key {sorted(unknown)[0]!r} in [{section}] (read: "
                                 f"{', '.join(sorted(TABLE_KEYS[section]))})")
    device = doc.get("device", {})
    kind = device.get("kind")
    if kind not in CLASSES:
        raise ParameterError(f"{where}: [device] kind must be one of {', '.join(CLASSES)}; got {kind!r}")

    def need(section: str, key: str) -> Any:
        if key not in doc[section]:
            raise ParameterError(f"{where}: [{section}] needs {key}")
        return _array(doc[section][key], f"{where} [{section}] {key}")
    tables: dict[str, Table] = {}
    if "conduction" in doc:
        tables["conduction"] = on_state_table(f"{where} [conduction]", need("conduction", "current"),
                                              need("conduction", "temperature"), need("conduction", "v_on"))
    for section in ("turn_on", "turn_off"):
        if section in doc:
            tables[section] = energy_table(f"{where} [{section}]", need(section, "voltage"), need(section, "current"),
                                           need(section, "temperature"), need(section, "energy"))
    chain = None
    if "thermal" in doc:
        thermal = doc["thermal"]
        second = "tau" if thermal.get("kind") == "foster" else "C"
        chain = ThermalChain(str(thermal.get("kind")), tuple(need("thermal", "R")), tuple(need("thermal", second)),
                             f"{where} [thermal]")
    return DeviceDescription(str(device.get("name", "device")), kind, tables.get("turn_on"), tables.get("turn_off"),
                             tables.get("conduction"), chain, where)


def _array(value: Any, what: str) -> np.ndarray:
    try:
        array = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{what}: numbers (nested lists of one shape) expected; got {str(value)[:40]}") from None
    if not np.all(np.isfinite(array)):
        raise ParameterError(f"{what}: the numbers must be finite")
    return array
