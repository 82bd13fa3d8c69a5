"""Reading a SPICE netlist: the subset switching circuits use, flattened, every value a number.

Why a reader of its own: PySpice 1.5's parser (already a dependency, for ngspice) stops at an ``S`` switch line
and at ``IC=`` on an inductor and does not evaluate ``.param`` expressions; spicelib edits netlists as text
with a regular expression per element and looks for included libraries in the user's directories. pcsuite
reads files other people wrote, so its reader evaluates values without ``eval`` (:mod:`.expressions`), follows
no ``.include`` or ``.lib``, and refuses a ``.control`` block (ngspice would run its ``shell`` commands).

Supported (case-insensitive, SPICE's own conventions: the first line is the title, ``*`` a comment line, ``;``
an inline comment, ``+`` a continuation):

- ``R L C`` (value, ``IC=`` on L and C), ``K`` (coupled inductors), ``V I`` (``DC``, ``PULSE``, ``SIN``,
  ``PWL`` with ``r=0`` to repeat it), ``E G`` (voltage-controlled, gain), ``F H`` (current-controlled through a V source, gain), ``D``
  (with its ``.model D``), ``S`` and ``W`` (voltage- and current-controlled switches with ``.model SW`` /
  ``CSW``), ``X`` (a ``.subckt``, with ``params:``);
- ``.param`` (expressions of numbers and earlier parameters), ``.model``, ``.subckt``/``.ends``, ``.ic``,
  ``.tran``, ``.meas`` (the vector it measures names an output), ``.options`` (RELTOL, ABSTOL and METHOD are
  kept for ngspice's run of the file, the rest is ngspice's), ``.end``; ``.save``,
  ``.print``, ``.plot``, ``.probe``, ``.op`` are read and left to ngspice.

Every problem is one :class:`NetlistError` naming the file, the line and the element.
"""
from __future__ import annotations

import functools
import math
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, AnyStr, cast

from ..errors import ParameterError
from ..validate import quoted
from .expressions import evaluate, number

if TYPE_CHECKING:
    from ..params import Param

#: Largest netlist read (bytes): a circuit, not a data file.
MAX_BYTES = 1 << 20
#: Most elements after flattening, and the deepest subcircuit nesting.
MAX_ELEMENTS = 20_000
MAX_DEPTH = 20

#: What each element letter is, for the messages.
KINDS = {"R": "resistor", "L": "inductor", "C": "capacitor", "K": "coupling", "V": "voltage source",
         "I": "current source", "E": "voltage-controlled voltage source", "G": "voltage-controlled current source",
         "F": "current-controlled current source", "H": "current-controlled voltage source", "D": "diode",
         "S": "voltage-controlled switch", "W": "current-controlled switch", "X": "subcircuit instance"}
#: Elements an LCS cannot hold, with what to write instead.
REFUSED = {"M": "a MOSFET", "Q": "a bipolar transistor", "J": "a JFET", "Z": "a MESFET", "B": "a behavioural source",
           "A": "an XSPICE code model", "T": "a transmission line", "O": "a lossy transmission line",
           "U": "an RC line", "Y": "a transmission line", "N": "a device model", "P": "a coupled line"}
MODEL_TYPES = {"D": "D", "S": "SW", "W": "CSW"}
#: .model types pcsuite refuses, with what they are.
MODEL_KINDS = {"NPN": "a bipolar transistor", "PNP": "a bipolar transistor", "NMOS": "a MOSFET", "PMOS": "a MOSFET",
               "VDMOS": "a MOSFET", "NJF": "a JFET", "PJF": "a JFET", "NMF": "a MESFET", "PMF": "a MESFET",
               "R": "a semiconductor resistor", "C": "a semiconductor capacitor", "L": "an inductor model",
               "URC": "an RC line", "LTRA": "a lossy transmission line", "TXL": "a transmission line",
               "CPL": "a coupled line"}


class NetlistError(ParameterError):
    """A netlist pcsuite cannot read or compile; the message names the file, the line and the element."""


@dataclass(frozen=True)
class Pulse:
    """PULSE(v1 v2 td tr tf pw per): v1 until td, a ramp to v2 over tr, v2 for pw, back over tf; per repeats."""
    v1: float
    v2: float
    td: float = 0.0
    tr: float = 0.0
    tf: float = 0.0
    pw: float = math.inf
    per: float = math.inf


@dataclass(frozen=True)
class Sin:
    """SIN(vo va freq td theta phase)."""
    vo: float
    va: float
    freq: float
    td: float = 0.0
    theta: float = 0.0
    phase: float = 0.0


@dataclass(frozen=True)
class Pwl:
    """PWL(t1 v1 t2 v2 ...) [r=0], times non-decreasing; ``repeat`` 0 (r=0) repeats the whole list, with the
    last time its period (None: it holds its last value)."""
    points: tuple[tuple[float, float], ...]
    repeat: float | None = None

    @property
    def period(self) -> float:
        return self.points[-1][0] - self.repeat if self.repeat is not None else math.inf


#: What a V or I source holds: a DC value or a waveform.
Waveform = float | Pulse | Sin | Pwl


@dataclass(frozen=True)
class Element:
    name: str                  # lower case; inside a subcircuit instance: "x1.l1"
    kind: str                  # the element letter, upper case
    nodes: tuple[str, ...]     # node names, lower case ("0" is ground; inside an instance "x1.n")
    value: float | None = None
    waveform: Waveform | None = None    # V and I sources: a float (DC), Pulse, Sin or Pwl
    model: str | None = None
    control: tuple[str, ...] = ()    # F, H, W: the controlling V source; K: the inductors
    ic: float | None = None
    line: int = 0

    @property
    def title(self) -> str:
        return f"{KINDS.get(self.kind, 'element')} {self.name.upper()}"


@dataclass(frozen=True)
class Model:
    name: str
    kind: str          # D, SW, CSW
    params: dict[str, float]
    line: int = 0


@dataclass(frozen=True)
class Tran:
    tstep: float
    tstop: float
    tstart: float = 0.0
    tmax: float | None = None
    uic: bool = False


@dataclass(frozen=True)
class Netlist:
    """A netlist read and flattened: elements with numbers, models, parameters, directives."""

    path: str
    title: str
    elements: tuple[Element, ...]
    models: dict[str, Model]
    params: dict[str, float]                        # .param name -> value (lower case names)
    ic: dict[str, float] = field(default_factory=dict)    # node -> initial voltage (.ic v(node)=value)
    tran: Tran | None = None
    outputs: tuple[str, ...] = ()                   # vectors named by .meas (v(out), i(l1), ...)
    text: str = ""
    #: Element name -> the parameter expression its value came from (an element given by a .param follows it).
    expressions: dict[str, str] = field(default_factory=dict)
    #: The .param names defined by expressions of others (they follow them; not parameters of their own).
    derived: frozenset[str] = frozenset()
    #: .param name -> (its line, the text of its value) (the first definition at the top level).
    param_lines: dict[str, tuple[int, str]] = field(default_factory=dict)
    #: The .options ngspice's run takes from the file (reltol, abstol in A, method); the others are pcsuite's.
    spice_options: dict[str, float | str] = field(default_factory=dict)

    def where(self, name: str | None = None) -> str:
        """``FILE:LINE`` of the .param or element ``name`` (case-insensitive), ``FILE`` when it names neither:
        the start of a message about it."""
        key = (name or "").lower()
        if key in self.param_lines:
            return f"{self.path}:{self.param_lines[key][0]}"
        line = next((e.line for e in self.elements if e.name == key), None)
        return f"{self.path}:{line}" if line else self.path

    def element(self, name: str) -> Element:
        for e in self.elements:
            if e.name == name.lower():
                return e
        raise NetlistError(f"{quoted(self.path)}: no element {name!r}")

    @property
    def nodes(self) -> tuple[str, ...]:
        seen: list[str] = []
        for e in self.elements:
            for n in e.nodes:
                if n not in seen:
                    seen.append(n)
        return tuple(seen)


@dataclass
class _Line:
    number: int
    text: str


#: A .subckt as read: its header line and its body's lines.
_Subckt = tuple[_Line, list[_Line]]


def read_netlist(source: str | Path, overrides: dict[str, float] | None = None, name: str | None = None) -> Netlist:
    """Read a netlist file (a path) or text (with ``name`` for the messages), with ``overrides`` of its
    ``.param`` values and element values ({name: number}, names case-insensitive)."""
    if isinstance(source, Path) or (isinstance(source, str) and "\n" not in source and name is None):
        path = Path(source)
        label = quoted(path)
        if not path.is_file():
            raise NetlistError(f"{label}: not a regular file" if path.exists() else f"{label}: no such file")
        size = path.stat().st_size
        if size > MAX_BYTES:
            raise NetlistError(f"{label}: {size:,} bytes, more than a netlist's {MAX_BYTES:,}")
        raw = path.read_bytes()
        nul = raw.find(b"\x00")
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError as e:
            if not 0 <= nul < e.start:
                line, column = _position(raw, e.start)
                raise NetlistError(f"{label}:{line}: not UTF-8 text: byte 0x{raw[e.start]:02x} at column {column} "
                                   "(a binary file, or text in another encoding: save it as UTF-8)") from None
            text = raw[:nul].decode("utf-8") + "\x00"
    else:
        text, label = str(source), quoted(name or "<netlist>")
        if len(text.encode("utf-8", "surrogatepass")) > MAX_BYTES:
            raise NetlistError(f"{label}: {len(text.encode('utf-8', 'surrogatepass')):,} bytes, more than a "
                               f"netlist's {MAX_BYTES:,}")
    nul = text.find("\x00")
    if nul >= 0:
        line, column = _position(text, nul)
        raise NetlistError(f"{label}:{line}: a NUL byte at column {column}: a binary file, not a netlist")
    return _Reader(text, label, overrides or {}).read()


def _position(text: AnyStr, offset: int) -> tuple[int, int]:
    """(line, column) of ``offset`` in ``text`` (str or bytes), lines counted as the reader counts them (CR LF,
    CR and LF each end one)."""
    head = text[:offset]
    cr, lf = ("\r", "\n") if isinstance(head, str) else (b"\r", b"\n")
    head = head.replace(cr + lf, lf).replace(cr, lf)
    return head.count(lf) + 1, len(head) - (head.rfind(lf) + 1) + 1


class _Reader:
    def __init__(self, text: str, label: str, overrides: dict[str, float]) -> None:
        self.text, self.label = text, label
        self.overrides: dict[str, float] = {}
        for key, value in overrides.items():
            try:
                self.overrides[str(key).lower()] = float(value)
            except (TypeError, ValueError):
                raise NetlistError(f"{label}: -p {key} must be a number; got {value!r}") from None
        self.used: set[str] = set()
        self.derived: set[str] = set()

    def error(self, line: _Line | int, what: str) -> NetlistError:
        number_ = line.number if isinstance(line, _Line) else line
        return NetlistError(f"{self.label}:{number_}: {what}")

    # --- lines -----------------------------------------------------------------------------------------------

    def lines(self) -> tuple[str, list[_Line]]:
        raw = self.text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
        title = raw[0].strip() if raw else ""
        out: list[_Line] = []
        for i, line in enumerate(raw[1:], start=2):
            stripped = line.strip()
            if not stripped or stripped.startswith("*"):
                continue
            for mark in (";", "$ ", "//"):           # inline comments (ngspice's)
                at = stripped.find(mark)
                if at >= 0:
                    stripped = stripped[:at].rstrip()
            if not stripped:
                continue
            if stripped.startswith("+"):
                if not out:
                    raise self.error(i, "a continuation '+' with no line before it")
                out[-1].text += " " + stripped[1:].strip()
                continue
            out.append(_Line(i, stripped))
        return title, out

    # --- the whole file --------------------------------------------------------------------------------------

    def read(self) -> Netlist:
        title, lines = self.lines()
        params: dict[str, float] = {}
        models: dict[str, Model] = {}
        subckts: dict[str, _Subckt] = {}
        top: list[_Line] = []
        ic: dict[str, float] = {}
        tran = None
        spice: dict[str, float | str] = {}
        outputs: list[str] = []
        # (line, vector, nodes, elements) of .ic and .meas: checked once the circuit is read
        named: list[tuple[_Line, str, Sequence[str], Sequence[str]]] = []
        expressions: dict[str, str] = {}
        param_lines: dict[str, tuple[int, str]] = {}
        self.refuse_commands(lines)
        i = 0
        while i < len(lines):
            line = lines[i]
            word = line.text.split()[0].lower()
            if word == ".subckt":
                end = i + 1
                depth = 1
                while end < len(lines):
                    head = lines[end].text.split()[0].lower()
                    depth += head == ".subckt"
                    depth -= head == ".ends"
                    if depth == 0:
                        break
                    end += 1
                if end >= len(lines):
                    raise self.error(line, ".subckt without its .ends")
                words = line.text.split()
                if len(words) < 2:
                    raise self.error(line, ".subckt needs a name")
                sub_name = words[1].lower()
                if sub_name in subckts:
                    raise self.error(line, f"subcircuit {sub_name!r} defined twice")
                subckts[sub_name] = (line, lines[i + 1:end])
                i = end + 1
                continue
            if word == ".ends":
                raise self.error(line, ".ends without its .subckt")
            if word == ".param":
                self.param_line(line, params, scope=True)
                for key, value in self.assignments(line, line.text.split(None, 1)[1]):
                    param_lines.setdefault(key, (line.number, value))
            elif word == ".model":
                model = self.model_line(line, params)
                if model.name in models:
                    raise self.error(line, f"model {model.name!r} defined twice")
                models[model.name] = model
            elif word == ".ic":
                for key, value in self.assignments(line, line.text.split(None, 1)[1] if len(line.text.split()) > 1
                                                   else ""):
                    match = re.fullmatch(r"v\(([^(),\s]+)\)", key)
                    if not match:
                        raise self.error(line, f".ic takes v(NODE)=VALUE; got {key!r}")
                    ic[match.group(1)] = self.value(line, value, params, f".ic {key}")
                    named.append((line, key, (match.group(1),), ()))
            elif word == ".tran":
                tran = self.tran_line(line, params)
            elif word in (".options", ".option", ".opt"):
                spice.update(self.options_line(line, params))
            elif word in (".meas", ".measure"):
                found = re.findall(r"\b([vi]\([^()]+\))", line.text.lower())
                outputs.extend(v.replace(" ", "") for v in found if v not in outputs)
                for vector in found:
                    inside = [part.strip() for part in vector[2:-1].split(",")]
                    named.append((line, vector, inside if vector[0] == "v" else (), inside if vector[0] == "i" else ()))
            elif word == ".end":
                break
            elif word.startswith("."):
                if word not in (".save", ".print", ".plot", ".probe", ".op",
                                ".temp", ".global", ".width", ".nodeset"):
                    raise self.error(line, f"{word} is not a directive pcsuite reads (it reads .param, .model, "
                                           ".subckt, .ic, .tran, .meas, .options, .end)")
            else:
                top.append(line)
            i += 1
        for key in self.overrides:
            if key in params:
                self.used.add(key)
        elements: list[Element] = []
        self.expand(top, params, models, subckts, "", {}, elements, 0, expressions)
        unknown = [k for k in self.overrides if k not in self.used]
        if unknown:
            names = sorted(set(params) | {e.name for e in elements if e.value is not None})
            raise NetlistError(f"{self.label}: -p {unknown[0]}: no .param or element of that name (valid: "
                               f"{', '.join(names)})")
        seen: dict[str, Element] = {}
        for e in elements:
            if e.name in seen:
                raise self.error(e.line, f"{e.title}: the name is used twice (first on line {seen[e.name].line}): "
                                         "SPICE names an element by its name; rename one")
            seen[e.name] = e
        nodes = {n for e in elements for n in e.nodes} | {"0"}
        for line, vector, wanted_nodes, wanted_elements in named:     # a name that is nowhere: accepted silently before
            missing = [n for n in wanted_nodes if n not in nodes] + [x for x in wanted_elements if x not in seen]
            if missing:
                what = "node" if missing[0] in wanted_nodes else "element"
                raise self.error(line, f"{vector} names {what} {missing[0]!r}, which no element of the circuit "
                                       f"{'connects' if what == 'node' else 'is'}")
        return Netlist(self.label, title, tuple(elements), models, params, ic, tran, tuple(outputs), self.text,
                       expressions, frozenset(self.derived), param_lines, spice)

    # --- directives --------------------------------------------------------------------------------------------

    def refuse_commands(self, lines: list[_Line]) -> None:
        """A .control block or a .include/.lib anywhere (inside a .subckt, after .end) is refused before any
        other line is read: nothing the file says is evaluated first."""
        for line in lines:
            word = line.text.split()[0].lower()
            if word in (".control", ".endc"):
                raise self.error(line, f"{word}: a .control block holds ngspice commands (shell, ...); pcsuite "
                                       "never runs its commands: remove the block")
            if word in (".include", ".inc", ".lib", ".libinclude", ".incl"):
                raise self.error(line, f"{word} reads another file: pcsuite reads this file alone; paste the "
                                       "models and subcircuits in")

    def assignments(self, line: _Line, text: str) -> list[tuple[str, str]]:
        """NAME=VALUE pairs; a value may be {expr}, 'expr' or a bare expression without spaces."""
        out: list[tuple[str, str]] = []
        text = re.sub(r"\s*=\s*", "=", text.strip())
        pos = 0
        while pos < len(text):
            while pos < len(text) and text[pos] in " \t,":
                pos += 1
            if pos >= len(text):
                break
            match = re.match(r"([A-Za-z_][\w.]*|[vV]\([^()]+\))=", text[pos:])
            if not match:
                raise self.error(line, f"NAME=VALUE expected at {text[pos:pos + 30]!r}")
            key = match.group(1).lower().replace(" ", "")
            pos += match.end()
            if pos < len(text) and text[pos] in "{'":
                close = "}" if text[pos] == "{" else "'"
                end = text.find(close, pos + 1)
                if end < 0:
                    raise self.error(line, f"{key}: an unclosed {text[pos]!r}")
                value = text[pos:end + 1]
                pos = end + 1
            else:
                end = pos
                depth = 0
                while end < len(text) and (depth > 0 or text[end] not in " \t,"):
                    depth += (text[end] == "(") - (text[end] == ")")
                    end += 1
                value = text[pos:end]
                pos = end
            out.append((key, value))
        return out

    def param_line(self, line: _Line, params: dict[str, float], scope: bool) -> None:
        body = line.text.split(None, 1)
        if len(body) < 2:
            raise self.error(line, ".param needs NAME=VALUE")
        for key, value in self.assignments(line, body[1]):
            if key in FUNCTION_NAMES:
                raise self.error(line, f".param {key}: the name of a function")
            if scope:
                try:
                    evaluate(value, {}, key)
                except ParameterError:        # an expression of other parameters: it follows them
                    self.derived.add(key)
            if scope and key in self.overrides and key not in self.derived:
                params[key] = self.overrides[key]
            elif scope and key in self.overrides:
                raise self.error(line, f"-p {key}: .param {key} is an expression of other parameters ({value}); "
                                       "set those")
            else:
                params[key] = self.value(line, value, params, f".param {key}")

    def value(self, line: _Line, text: str, params: dict[str, float], what: str) -> float:
        try:
            return evaluate(text, params, what)
        except ParameterError as e:
            raise self.error(line, str(e)) from None

    def model_line(self, line: _Line, params: dict[str, float]) -> Model:
        match = re.match(r"\.model\s+(\S+)\s+([A-Za-z]+)\s*(?:\((.*)\)|(.*))$", line.text, re.IGNORECASE | re.DOTALL)
        if not match:
            raise self.error(line, ".model NAME TYPE(PARAMS) expected")
        name, kind = match.group(1).lower(), match.group(2).upper()
        if kind not in ("D", "SW", "CSW"):
            what = MODEL_KINDS.get(kind, f"a {kind} model")
            raise self.error(line, f".model {match.group(1)} {kind} is {what}: pcsuite compiles ideal diodes (D) and "
                                   "switches (SW, CSW); it has no complementarity form")
        body = match.group(3) if match.group(3) is not None else match.group(4) or ""
        values = {key.upper(): self.value(line, value, params, f".model {name} {key}")
                  for key, value in self.assignments(line, body)}
        return Model(name, kind, values, line.number)

    #: The .options a run of the file keeps: its transient's tolerances and integration method.
    OPTIONS = ("reltol", "abstol", "method")

    def options_line(self, line: _Line, params: dict[str, float]) -> dict[str, float | str]:
        """RELTOL, ABSTOL and METHOD of a .options line (flags and other options are ngspice's own business)."""
        out: dict[str, float | str] = {}
        for key, value in re.findall(r"(\w+)\s*=\s*(\{[^}]*\}|\S+)", line.text.split(None, 1)[1] if " " in line.text
                                     else ""):
            key = key.lower()
            if key == "method":
                if value.lower() not in ("gear", "trap", "trapezoidal"):
                    raise self.error(line, f".options METHOD={value}: pcsuite runs gear or trap")
                out[key] = "trap" if value.lower().startswith("trap") else "gear"
            elif key in self.OPTIONS:
                number = self.value(line, value, params, f".options {key.upper()}")
                if not number > 0:
                    raise self.error(line, f".options {key.upper()}={value}: must be positive")
                out[key] = number
        return out

    def tran_line(self, line: _Line, params: dict[str, float]) -> Tran:
        words = self.words(line.text)[1:]
        uic = any(w.lower() == "uic" for w in words)
        numbers = [self.value(line, w, params, ".tran") for w in words if w.lower() != "uic"]
        if len(numbers) < 2:
            raise self.error(line, ".tran needs TSTEP and TSTOP")
        tstep, tstop = numbers[0], numbers[1]
        tstart = numbers[2] if len(numbers) > 2 else 0.0
        tmax = numbers[3] if len(numbers) > 3 else None
        problems = [(tstep > 0, f"TSTEP = {tstep:g} s must be positive"),
                    (tstop > 0, f"TSTOP = {tstop:g} s must be positive"),
                    (tstart >= 0, f"TSTART = {tstart:g} s must not be negative"),
                    (tstart < tstop, f"TSTOP = {tstop:g} s must be after TSTART = {tstart:g} s"),
                    (tmax is None or tmax > 0, f"TMAX = {tmax} s must be positive")]
        for ok, why in problems:
            if not ok:
                raise self.error(line, f".tran {' '.join(words)}: {why} (.tran TSTEP TSTOP [TSTART [TMAX]] [UIC])")
        return Tran(tstep, tstop, tstart, tmax, uic)

    # --- elements ----------------------------------------------------------------------------------------------

    def expand(self, lines: list[_Line], params: dict[str, float], models: dict[str, Model],
               subckts: dict[str, _Subckt], prefix: str, nodemap: dict[str, str], out: list[Element], depth: int,
               expressions: dict[str, str], chain: tuple[str, ...] = ()) -> None:
        if depth > MAX_DEPTH:
            raise self.error(lines[0] if lines else 0, f"subcircuits nested deeper than {MAX_DEPTH}")
        for line in lines:
            words = line.text.split()
            letter = words[0][0].upper()
            if letter == "." and prefix:
                raise self.error(line, f"{words[0]} inside a .subckt (instance {prefix[:-1].upper()}): a subcircuit "
                                       "holds elements, .param and .model; write the directive at the top level")
            if letter in REFUSED:
                raise self.error(line, f"element {words[0]} is {REFUSED[letter]}: an LCS holds ideal switches and "
                                       "diodes (write a switch as S with a .model SW, a rectifier as D)")
            if letter not in KINDS:
                raise self.error(line, f"{words[0]} is not an element: an element's name starts with its letter "
                                       f"({', '.join(KINDS)}); {letter!r} is none")
            if letter == "X":
                self.instance(line, params, models, subckts, prefix, nodemap, out, depth, expressions, chain)
            else:
                out.append(self.element(line, params, prefix, nodemap, expressions))
            if len(out) > MAX_ELEMENTS:
                raise self.error(line, f"more than {MAX_ELEMENTS:,} elements")

    def node(self, name: str, prefix: str, nodemap: dict[str, str]) -> str:
        name = name.lower()
        if name in ("0", "gnd"):
            return "0"
        if name in nodemap:
            return nodemap[name]
        return prefix + name

    def element(self, line: _Line, params: dict[str, float], prefix: str, nodemap: dict[str, str],
                expressions: dict[str, str]) -> Element:
        words = line.text.split()
        raw_name = words[0]
        name = prefix + raw_name.lower()
        letter = raw_name[0].upper()
        need = {"R": 3, "L": 3, "C": 3, "K": 3, "V": 2, "I": 2, "E": 5, "G": 5, "F": 4, "H": 4, "D": 3, "S": 5, "W": 4}
        rest = line.text[len(raw_name):].strip()
        title = f"{KINDS[letter]} {raw_name}" + (f" (in {prefix[:-1].upper()})" if prefix else "")
        if letter in "RLCDVIEGFHSW":
            count = {"R": 2, "L": 2, "C": 2, "D": 2, "V": 2, "I": 2, "E": 4, "G": 4, "F": 2, "H": 2, "S": 4, "W": 2}[letter]
            tokens = rest.split()
            if len(tokens) < count or len(words) - 1 < need[letter]:
                raise self.error(line, f"{title}: {count} nodes and its value or model expected")
            nodes = tuple(self.node(n, prefix, nodemap) for n in tokens[:count])
            after = rest.split(None, count)[count] if len(tokens) > count else ""
        else:                                         # K: two inductors and a coefficient
            nodes, after = (), rest
        own = raw_name.lower()
        if letter in "RLC":
            tokens = self.words(after)             # a value may be {a * b} or 'a * b', spaces and all
            value_text, options = (tokens[0] if tokens else ""), " ".join(tokens[1:])
            assigns = dict(self.assignments(line, options)) if options.strip() else {}
            unknown = [k for k in assigns if k not in ("ic", "m", "tc1", "tc2")]
            if unknown:
                raise self.error(line, f"{title}: {unknown[0].upper()}= is not read (value and IC= only)")
            if "m" in assigns and self.value(line, assigns["m"], params, f"{title} M") != 1:
                raise self.error(line, f"{title}: M={assigns['m']} (a multiplicity: that many in parallel) is not "
                                       "read; write the value of the combination")
            if value_text.lower().startswith(("r=", "l=", "c=")):
                value_text = value_text[2:]
            value = self.element_value(line, own, prefix, value_text, params, f"{title} value", expressions)
            if not (value > 0 or (letter == "R" and value == 0)):     # a 0 ohm resistor is a short
                raise self.error(line, f"{title}: its value must be "
                                       f"{'non-negative' if letter == 'R' else 'positive'}; got {value:g}")
            ic = self.value(line, assigns["ic"], params, f"{title} IC") if "ic" in assigns and letter != "R" else None
            return Element(name, letter, nodes, value=value, ic=ic, line=line.number)
        if letter == "K":
            tokens = self.words(after)
            if len(tokens) != 3:
                raise self.error(line, f"{title}: K L1 L2 COUPLING expected")
            value = self.element_value(line, own, prefix, tokens[2], params, f"{title} coupling", expressions)
            if not 0 < abs(value) <= 1:
                raise self.error(line, f"{title}: the coupling must be in (0, 1]; got {value:g}")
            return Element(name, letter, (), value=value, control=tuple(prefix + t.lower() for t in tokens[:2]),
                           line=line.number)
        if letter in "VI":
            waveform = self.waveform(line, own, prefix, after, params, title, expressions)
            return Element(name, letter, nodes, waveform=waveform, line=line.number)
        if letter in "EG":
            value = self.element_value(line, own, prefix, (self.words(after) or [""])[0], params,
                                       f"{title} gain", expressions)
            return Element(name, letter, nodes, value=value, line=line.number)
        if letter in "FH":
            tokens = self.words(after)
            if len(tokens) != 2:
                raise self.error(line, f"{title}: {letter} N+ N- VSOURCE GAIN expected")
            value = self.element_value(line, own, prefix, tokens[1], params, f"{title} gain", expressions)
            return Element(name, letter, nodes, value=value, control=(prefix + tokens[0].lower(),), line=line.number)
        if letter == "D":
            tokens = after.split()
            if len(tokens) != 1:
                raise self.error(line, f"{title}: D ANODE CATHODE MODEL expected (no area or options)")
            return Element(name, letter, nodes, model=tokens[0].lower(), line=line.number)
        if letter == "S":
            tokens = after.split()
            if len(tokens) not in (1, 2) or (len(tokens) == 2 and tokens[1].lower() not in ("on", "off")):
                raise self.error(line, f"{title}: S N+ N- NC+ NC- MODEL [ON|OFF] expected")
            return Element(name, letter, nodes, model=tokens[0].lower(), line=line.number)
        tokens = after.split()                       # W N+ N- VSENSE MODEL
        if len(tokens) not in (2, 3):
            raise self.error(line, f"{title}: W N+ N- VSENSE MODEL [ON|OFF] expected")
        return Element(name, letter, nodes, model=tokens[1].lower(), control=(prefix + tokens[0].lower(),),
                       line=line.number)

    def element_value(self, line: _Line, own: str, prefix: str, text: str, params: dict[str, float], what: str,
                      expressions: dict[str, str]) -> float:
        key = prefix + own
        if key in self.overrides:
            self.used.add(key)
            return self.overrides[key]
        if not text:
            raise self.error(line, f"{what} missing")
        stripped = text.strip().strip("{}'").strip().lower()
        try:
            evaluate(text, {}, what)
        except ParameterError:         # {L} or {1/n}: the value follows the .param it names (-p sets those)
            expressions[key] = stripped
        return self.value(line, text, params, what)

    def waveform(self, line: _Line, own: str, prefix: str, text: str, params: dict[str, float], title: str,
                 expressions: dict[str, str]) -> Waveform:
        key = prefix + own
        text = text.strip()
        if re.match(r"(?i)dc\b", text):
            text = text[2:].strip()
            if re.match(r"(?i)(pulse|sin|pwl)\s*\(", text):
                pass
            elif re.search(r"(?i)\b(pulse|sin|pwl|ac)\b", text):
                raise self.error(line, f"{title}: give either DC VALUE or one waveform")
        bare = re.match(r"(?i)(pulse|sin|pwl)\s+([^()=]+?)\s*((?:r|td)\s*=.*)?$", text)
        if bare:                      # SPICE's form without parentheses: PULSE 1 0 4u 1n 1n 6u 10u
            text = f"{bare.group(1)}({bare.group(2)}) {bare.group(3) or ''}".strip()
        match = re.match(r"(?i)(pulse|sin|pwl)\s*\((.*)\)\s*((?:r|td)\s*=.*)?$", text)
        if not match:
            if re.match(r"(?i)(pulse|sin|pwl|exp|sffm|am|trrandom|trnoise)\b", text):
                raise self.error(line, f"{title}: {text.split('(')[0].upper()} is not read (DC, PULSE, SIN, PWL)")
            if key in self.overrides:
                self.used.add(key)
                return self.overrides[key]
            if not text:
                raise self.error(line, f"{title}: its value is missing")
            return self.element_value(line, own, prefix, self.words(text)[0], params, f"{title} value", expressions)
        kind, body = match.group(1).upper(), match.group(2)
        if key in self.overrides:
            raise self.error(line, f"-p {own}: {title} is a {kind} source; change its parameters with .param")
        values = [self.value(line, w, params, f"{title} {kind}") for w in self.words(body)]
        value: float | str                      # a PULSE's time below, an r= assignment's text after
        if kind == "PULSE":
            if not 2 <= len(values) <= 7:
                raise self.error(line, f"{title}: PULSE(V1 V2 TD TR TF PW PER) takes 2 to 7 numbers; got {len(values)}")
            pulse = Pulse(*values)
            for field_, value in (("TD", pulse.td), ("TR", pulse.tr), ("TF", pulse.tf)):
                if value < 0:
                    raise self.error(line, f"{title}: PULSE {field_} = {value:g} s is negative (times are >= 0)")
            for field_, value in (("PW", pulse.pw), ("PER", pulse.per)):
                if value <= 0:
                    raise self.error(line, f"{title}: PULSE {field_} = {value:g} s must be positive")
            if math.isfinite(pulse.per) and pulse.tr + pulse.pw + pulse.tf > pulse.per * (1 + 1e-12):
                raise self.error(line, f"{title}: PULSE TR + PW + TF = {pulse.tr + pulse.pw + pulse.tf:g} s exceeds "
                                       f"its period {pulse.per:g} s")
            return pulse
        if kind == "SIN":
            if not 3 <= len(values) <= 6:
                raise self.error(line, f"{title}: SIN(VO VA FREQ TD THETA PHASE) takes 3 to 6 numbers")
            return Sin(*values)
        if match.group(3) and kind != "PWL":
            raise self.error(line, f"{title}: {match.group(3).strip()!r} after {kind}(...): only a PWL takes r=")
        repeat = None
        for key, value in self.assignments(line, match.group(3) or ""):
            number = self.value(line, value, params, f"{title} PWL {key}")
            if key != "r" or number != 0:
                raise self.error(line, f"{title}: PWL {key}={value}: pcsuite reads r=0 (the whole list repeated, "
                                       "its last time the period) and no TD")
            repeat = 0.0
        if len(values) < 2 or len(values) % 2:
            raise self.error(line, f"{title}: PWL takes pairs of time and value; got {len(values)} numbers")
        points = tuple(zip(values[::2], values[1::2]))
        if points[0][0] < 0:
            raise self.error(line, f"{title}: PWL starts at a negative time {points[0][0]:g} s (times are >= 0)")
        for n, (a, b) in enumerate(zip(points, points[1:]), start=2):
            if b[0] < a[0]:
                raise self.error(line, f"{title}: PWL time {b[0]:g} s (point {n}) comes before {a[0]:g} s: times "
                                       "must not decrease")
        if repeat is not None and (points[0][0] != 0 or points[-1][0] <= 0 or points[-1][1] != points[0][1]
                                   or any(b[0] <= a[0] for a, b in zip(points, points[1:]))):
            raise self.error(line, f"{title}: a repeated PWL (r=0) starts at time 0, its times increase (an edge "
                                   "takes a rise time) and it ends at its first value (its last time the period)")
        return Pwl(points, repeat)

    @staticmethod
    def words(body: str) -> list[str]:
        """``body`` split at blanks and commas outside {...}, (...) and '...'."""
        out, depth, quoted_, current = [], 0, False, ""
        for ch in body:
            if ch == "'":
                quoted_ = not quoted_
            elif ch in "{(" and not quoted_:
                depth += 1
            elif ch in "})" and not quoted_:
                depth = max(depth - 1, 0)
            if ch in " \t," and depth == 0 and not quoted_:
                if current:
                    out.append(current)
                current = ""
            else:
                current += ch
        if current:
            out.append(current)
        return out

    def instance(self, line: _Line, params: dict[str, float], models: dict[str, Model], subckts: dict[str, _Subckt],
                 prefix: str, nodemap: dict[str, str], out: list[Element], depth: int, expressions: dict[str, str],
                 chain: tuple[str, ...]) -> None:
        text = line.text
        parts = re.split(r"(?i)\s+params:\s*", text, maxsplit=1)
        words = parts[0].split()
        assigns = self.assignments(line, parts[1]) if len(parts) > 1 else []
        # X n1 n2 ... SUBNAME [k=v ...] (ngspice also takes assignments without params:)
        while words and "=" in words[-1]:
            key, _, value = words.pop().partition("=")
            assigns.insert(0, (key.lower(), value))
        if len(words) < 2:
            raise self.error(line, f"subcircuit instance {words[0] if words else '?'}: X NODES... SUBCKT expected")
        sub = words[-1].lower()
        if sub not in subckts:
            raise self.error(line, f"subcircuit instance {words[0]}: no .subckt {sub!r}")
        if sub in chain:
            raise self.error(line, f"subcircuit instance {words[0]}: .subckt {sub} instantiates itself "
                                   f"({' -> '.join(chain + (sub,))}): a recursion without end")
        definition_line, body = subckts[sub]
        header = re.split(r"(?i)\s+params:\s*", definition_line.text, maxsplit=1)
        ports = header[0].split()[2:]
        defaults = dict(self.assignments(definition_line, header[1])) if len(header) > 1 else {}
        while ports and "=" in ports[-1]:
            key, _, value = ports.pop().partition("=")
            defaults[key.lower()] = value
        given = words[1:-1]
        if len(given) != len(ports):
            raise self.error(line, f"subcircuit instance {words[0]}: {len(given)} nodes for .subckt {sub}'s "
                                   f"{len(ports)}")
        inner_prefix = prefix + words[0].lower() + "."
        mapping = {p.lower(): self.node(g, prefix, nodemap) for p, g in zip(ports, given)}
        scope = dict(params)
        for key, value in defaults.items():
            scope[key] = self.value(definition_line, value, params, f".subckt {sub} {key}")
        for key, value in assigns:
            if key not in defaults:
                raise self.error(line, f"subcircuit instance {words[0]}: {key} is not a parameter of .subckt {sub} "
                                       f"({', '.join(defaults) or 'it has none'})")
            scope[key] = self.value(line, value, params, f"{words[0]} {key}")
        inner = [ln for ln in body if not ln.text.lower().startswith((".param", ".model"))]
        for ln in body:
            if ln.text.lower().startswith(".param"):
                self.param_line(ln, scope, scope=False)
            elif ln.text.lower().startswith(".model"):
                raise self.error(ln, ".model inside a .subckt: define it at the top level")
            elif ln.text.lower().startswith(".subckt"):
                raise self.error(ln, ".subckt inside a .subckt: define it at the top level")
        self.expand(inner, scope, models, subckts, inner_prefix, mapping, out, depth + 1, expressions,
                    chain + (sub,))


def check_overrides(netlist: Netlist, given: dict[str, float], parameters: Iterable[Param] = ()) -> None:
    """Refuse a ``-p NAME=VALUE`` on ``netlist`` with one line naming the file, the line of the .param or element
    and the problem: a derived .param (an expression of others: set those), a name that is neither a parameter
    nor an element (the valid names listed), a value outside the parameter's range. ``parameters``: the model's
    :class:`~converters.params.Param` list (what ``-p`` may set, each with its ``check``); names are
    case-insensitive."""
    known = {p.name.lower(): p for p in parameters}
    for key, value in given.items():
        name = str(key).lower()
        if name in netlist.derived:
            text = netlist.param_lines.get(name, (None, "?"))[1]
            inputs = ", ".join(_inputs(netlist, name))
            raise NetlistError(f"{netlist.where(name)}: -p {key}: .param {name} = {text} is an expression of other "
                               "parameters, not a parameter of its own; set those"
                               + (f" ({inputs})" if inputs else ""))
        if known and name not in known:
            raise NetlistError(f"{netlist.where()}: -p {key}: unknown parameter {name!r}; valid names: "
                               f"{', '.join(known)}")
        if name in known:
            try:
                known[name].check(value)
            except ParameterError as e:
                raise NetlistError(f"{netlist.where(name)}: -p {key}={value}: {e}") from None


def with_values(netlist: Netlist, changed: dict[str, float]) -> Netlist | None:
    """``netlist`` as the reader gives it with ``changed`` ({name: number}) over the overrides it was read with,
    without reading it again, where the change reaches element values alone: each name an element's own value or
    a .param that only top-level element values name (not another .param, a model, a waveform, an IC, .tran nor
    a subcircuit: its mentions in the file are its definition and those values). None otherwise, or where a
    value is out of the reader's range (read the file: it gives the netlist or the error). A tolerance study's
    points differ in R, L and C alone: this is its read per point (the reader's whole pass costs ten times more)."""
    mentions = _mentions(netlist.text)
    top = {key: text for key, text in netlist.expressions.items() if "." not in key}
    elements = {e.name: e for e in netlist.elements}
    direct: dict[str, float]
    moved: set[str]
    params, direct, moved = dict(netlist.params), {}, set()
    for key, value in changed.items():
        name, value = str(key).lower(), float(value)
        if name in netlist.params:
            if name in netlist.derived:
                return None
            named = [element for element, text in top.items() if _mentioned(text, name)]
            if mentions.get(name, 0) != 1 + sum(len(_WORD(name).findall(top[element])) for element in named):
                return None
            params[name] = value
            moved.update(named)
        elif name in elements and name not in netlist.expressions:
            direct[name] = value
        else:
            return None
    out = []
    for e in netlist.elements:
        if e.name in direct or e.name in moved:
            value = direct[e.name] if e.name in direct else evaluate(top[e.name], params, e.title)
            if e.kind in "VI":
                e = replace(e, waveform=value)
            else:
                if not (0 < abs(value) <= 1 if e.kind == "K" else value > 0 or (e.kind == "R" and value == 0)
                        if e.kind in "RLC" else True):
                    return None
                e = replace(e, value=value)
        out.append(e)
    return replace(netlist, elements=tuple(out), params=params)


_WORD = functools.lru_cache(maxsize=256)(lambda name: re.compile(rf"(?i)(?<![\w.]){re.escape(name)}(?![\w.(])"))


def _mentioned(text: str, name: str) -> bool:
    """Whether an expression names the parameter ``name`` (as a word: not inside another name or a number)."""
    return _WORD(name).search(text) is not None


@functools.lru_cache(maxsize=64)
def _mentions(text: str) -> dict[str, int]:
    """How many times each word is written in a netlist's lines (comments left out, continuations joined)."""
    _, lines = _Reader(text, "", {}).lines()
    counts: dict[str, int] = {}
    for line in lines:
        for word in re.findall(r"(?<![\w.])[A-Za-z_][\w]*(?![\w.(])", line.text):
            counts[word.lower()] = counts.get(word.lower(), 0) + 1
    return counts


def _inputs(netlist: Netlist, name: str) -> list[str]:
    """The .param names (not derived) the derived .param ``name`` follows, through the derived ones it names."""
    out, todo, seen = [], [name], set()
    while todo:
        current = todo.pop()
        if current in seen:
            continue
        seen.add(current)
        text = netlist.param_lines.get(current, (None, ""))[1]
        for other in netlist.params:
            if other not in seen and _mentioned(text, other):
                if other in netlist.derived:
                    todo.append(other)
                elif other not in out:
                    out.append(other)
    return sorted(out)


FUNCTION_NAMES = {"sqrt", "exp", "ln", "log", "log10", "abs", "sin", "cos", "tan", "atan", "min", "max", "pow"}


def with_models(netlist: Netlist) -> Netlist:
    """Check every element's model exists and has the element's type."""
    for e in netlist.elements:
        if e.kind in MODEL_TYPES:
            model = netlist.models.get(cast(str, e.model))      # D, S and W elements name their model
            if model is None:
                raise NetlistError(f"{netlist.path}:{e.line}: {e.title} names model {e.model!r}, which no .model "
                                   "defines")
            if model.kind != MODEL_TYPES[e.kind]:
                raise NetlistError(f"{netlist.path}:{e.line}: {e.title} needs a .model of type "
                                   f"{MODEL_TYPES[e.kind]}; {e.model!r} is {model.kind}")
    return netlist


__all__ = ["read_netlist", "check_overrides", "with_values", "Netlist",
           "Element", "Model", "Pulse", "Sin", "Pwl", "Tran", "NetlistError",
           "with_models", "number", "replace"]
