"""Input checks shared by every public entry point.

Each check raises :class:`ParameterError` with one line naming the parameter, the valid range
and the value received, e.g. ``h must be positive and below the switching period (1e-05 s); got 0.002``.
"""
from __future__ import annotations

import math
import re
from decimal import Decimal, InvalidOperation

from typing import Any

import numpy as np
import numpy.typing as npt

from .errors import ParameterError

#: SPICE-style magnitude suffixes (case-insensitive; ``meg`` before ``m``).
SI_EXPONENTS = {"t": 12, "g": 9, "meg": 6, "k": 3, "m": -3, "u": -6, "µ": -6, "n": -9, "p": -12, "f": -15}
_NUMBER = re.compile(r"^([+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?)(meg|[tgkmuµnpf])?([a-zA-ZΩ]+)?$",
                     re.IGNORECASE)
#: How a unit may be typed after the value (case-insensitive), by the parameter's unit.
UNIT_SPELLINGS = {"V": ("v",), "A": ("a",), "H": ("h",), "F": ("f",), "Hz": ("hz",), "ohm": ("ohm", "ohms", "Ω"),
                  "s": ("s",)}
#: Units where SPICE's "M" (milli) is the classic slip for mega: refused with a hint.
_MEGA_SLIPS = ("Hz", "H")
#: The largest integer an integer option takes (numpy's int64: every count ends up in one).
INT64_MAX = 2 ** 63 - 1
_LOG10_2 = math.log10(2.0)


def digits(value: int | np.integer[Any]) -> int:
    """The number of decimal digits of an integer, without its text (str() refuses beyond 4300 digits)."""
    n = abs(int(value))
    count = max(1, int(n.bit_length() * _LOG10_2))
    while n >= 10 ** count:
        count += 1
    while count > 1 and n < 10 ** (count - 1):
        count -= 1
    return count


def shown(value: object, limit: int = 40) -> str:
    """``repr(value)`` for a one-line message, shortened: an integer of more than ``limit`` digits by its number
    of digits (repr raises beyond 4300), a text longer than ``limit`` by its ends and its length."""
    if isinstance(value, (int, np.integer)) and not isinstance(value, bool) and abs(int(value)) >= 10 ** limit:
        return f"an integer of {digits(value)} digits"
    if isinstance(value, str) and len(value) > limit:
        return repr(f"{value[:20]}...{value[-10:]} ({len(value)} characters)")
    return repr(value)


def quoted(path: object) -> str:
    """A path as a one-line message shows it: as typed when every character prints, else quoted as repr does (a
    newline or an ESC in a file name never reaches the terminal raw, nor splits the line)."""
    text = str(path)
    return text if text.isprintable() else repr(text)


def _to_float(name: str, value: float | np.number[Any]) -> float:
    """float(value) for a number given as a Python or numpy number; an int beyond a double is refused by name."""
    try:
        return float(value)
    except OverflowError:
        raise ParameterError(f"{name} must be a finite number, at most 1.8e308 in magnitude; "
                             f"got {shown(value)}") from None


def parse_value(name: str, text: object, unit: str | None = None) -> float:
    """Parse a number as SPICE users type it: a magnitude suffix (``10u``, ``100k``, ``2.2n``, ``1meg``) and,
    when the parameter's ``unit`` is known, that unit after it (``10uH``, ``250kHz``, ``48V``, ``2.2nF``).

    A unit that contradicts the parameter's (``L=10uF``) is refused, and so is ``M`` on a frequency or an
    inductance (``1M``, ``1MHz``: SPICE reads milli; "did you mean 1meg?"). Anything else (trailing text,
    several numbers) is refused: values end up in netlists, so only a plain finite number may pass.
    """
    if isinstance(text, (int, float, np.floating, np.integer)) and not isinstance(text, bool):
        value = _to_float(name, text)
    else:
        text = str(text).strip()
        if not all(ch.isascii() or ch in "µΩ" for ch in text):
            odd = next(ch for ch in text if not (ch.isascii() or ch in "µΩ"))
            raise ParameterError(f"{name} must be a number typed in plain ASCII digits and letters (SPICE reads nothing "
                                 "else); "
                                 f"got {text!r} (the character {odd!r}, U+{ord(odd):04X})")
        parts, compact = text.split(), text
        if len(parts) == 2 and parts[1].isalpha() and not _starts_with_suffix(parts[1]):
            compact = "".join(parts)           # "10 Ω", "48 V": a unit after a space (checked below like "48V")
        elif len(parts) > 1:
            raise ParameterError(f"{name} must be a number with no space inside (SPICE would read {parts[0]!r} "
                                 f"and stop; write {''.join(parts)!r}); got {text!r}")
        match = _NUMBER.match(compact)
        if match is None:
            raise ParameterError(f"{name} must be a number, optionally with a SPICE suffix "
                                 f"(T G meg k m u n p f){' and its unit ' + unit if unit else ''}; got {str(text)!r}")
        number, suffix, typed = match.group(1), match.group(2) or "", match.group(3) or ""
        if typed:
            allowed = UNIT_SPELLINGS.get(unit or "", ())
            if typed.lower() not in allowed and typed not in allowed:
                expected = f"its unit is {unit}" if unit else "it takes no unit"
                raise ParameterError(f"{name}: the unit {typed!r} in {str(text)!r} contradicts the parameter ({expected})")
        if suffix == "M" and unit in _MEGA_SLIPS:
            raise ParameterError(f"{name}: {str(text)!r} means milli in SPICE (M = m); did you mean "
                                 f"{number}meg{typed}?")
        # Decimal scaling keeps "100u" exactly 1e-4 (not 9.999999999999999e-05).
        try:
            exact = Decimal(number).scaleb(SI_EXPONENTS.get(suffix.lower(), 0))
            value, zero = float(exact), exact == 0
        except InvalidOperation:        # an exponent beyond Decimal's own (1e99999999999999999999): far beyond a double
            zero = not any(ch in "123456789" for ch in re.split("[eE]", number)[0])
            value = 0.0 if zero or "e-" in number.lower() else math.inf
        if value == 0.0 and not zero:
            raise ParameterError(f"{name} must be 0 or at least 5e-324 in magnitude (smaller underflows to 0 in double "
                                 f"precision); got {shown(text)}")
        if not math.isfinite(value):
            raise ParameterError(f"{name} must be a finite number, at most 1.8e308 in magnitude; got {shown(text)}")
    if not math.isfinite(value):
        raise ParameterError(f"{name} must be a finite number; got {value!r}")
    return value


def _starts_with_suffix(word: str) -> bool:
    """``u``, ``uH``, ``meg``, ``kHz``: a SPICE magnitude suffix (then perhaps a unit), which must touch its number."""
    lower = word.lower()
    for suffix in sorted(SI_EXPONENTS, key=len, reverse=True):
        if lower.startswith(suffix):
            rest = lower[len(suffix):]
            return rest == "" or any(rest in spellings for spellings in UNIT_SPELLINGS.values())
    return False


def check_positive(name: str, value: object, unit: str = "") -> float:
    value = parse_value(name, value)
    if value <= 0.0:
        raise ParameterError(f"{name} must be positive (> 0{(' ' + unit) if unit else ''}); got {value!r}")
    return value


def check_range(name: str, value: object, low: float, high: float, *, low_open: bool = False,
                high_open: bool = False) -> float:
    value = parse_value(name, value)
    below = value <= low if low_open else value < low
    above = value >= high if high_open else value > high
    if below or above:
        lb = "(" if low_open else "["
        rb = ")" if high_open else "]"
        raise ParameterError(f"{name} must be in {lb}{low:g}, {high:g}{rb}; got {value!r}")
    return value


def check_integer(name: str, value: object, low: int, high: int | None = None) -> int:
    """An integer (int or numpy integer, not bool) in [low, high] (high None: >= low, and at most 2^63 - 1, where
    every count ends up: a larger one would overflow later, far from its name)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low \
            or value > (INT64_MAX if high is None else high):
        within = f"in [{low}, {high:,}]" if high is not None else \
            f">= {low}" + (" (at most 2^63 - 1)" if isinstance(value, (int, np.integer)) and value > INT64_MAX else "")
        raise ParameterError(f"{name} must be an integer {within}; got {shown(value)}")
    return int(value)


def check_indices(name: str, indices: npt.ArrayLike, size: int) -> np.ndarray:
    """Integer indices in [0, size) as int64 (0.7 is refused, not truncated to 0; -1 is refused, not the last)."""
    given = np.asarray(indices)
    if given.ndim != 1 or (given.size and (given.dtype.kind not in "iu" or given.min() < 0 or given.max() >= size)):
        raise ParameterError(f"{name} must be integers in [0, {size - 1}]; got {np.array2string(given, threshold=8)}")
    return given.astype(np.int64)


def check_flag(name: str, value: object) -> bool:
    """A bool (or numpy bool): a string such as "no" is refused, not read as True."""
    if not isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"{name} must be True or False; got {value!r}")
    return bool(value)


def as_matrix(name: str, value: object, shape: tuple[int | None, int | None]) -> np.ndarray:
    """A finite float matrix of the given shape (``None`` leaves a dimension free)."""
    _check_real(name, value, "matrix")
    try:
        arr = np.array(value, dtype=float, order="C")      # C order: what the compiled kernels read
    except (TypeError, ValueError, OverflowError):
        raise ParameterError(f"{name} must be a numeric matrix of doubles; got {shortened(value)}") from None
    if arr.ndim == 1 and shape[1] == 1:
        arr = arr.reshape(-1, 1)
    if arr.ndim != 2 or any(s is not None and s != a for s, a in zip(shape, arr.shape)):
        want = "x".join("any" if s is None else str(s) for s in shape)
        raise ParameterError(f"{name} must have shape {want}; got shape {'x'.join(map(str, arr.shape))}")
    if not np.all(np.isfinite(arr)):
        raise ParameterError(f"{name} must contain only finite numbers; got {_first_bad(arr)}")
    return arr


def as_vector(name: str, value: object, size: int | None) -> np.ndarray:
    """A finite float vector of the given size (``None`` leaves it free)."""
    _check_real(name, value, "vector")
    try:
        arr = np.array(value, dtype=float, order="C")
    except (TypeError, ValueError, OverflowError):
        raise ParameterError(f"{name} must be a numeric vector of doubles; got {shortened(value)}") from None
    if arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim == 2 and 1 in arr.shape:
        arr = arr.ravel()
    if arr.ndim != 1 or (size is not None and arr.shape[0] != size):
        raise ParameterError(f"{name} must be a vector of length {size if size is not None else 'n'}; "
                             f"got shape {'x'.join(map(str, arr.shape))}")
    if not np.all(np.isfinite(arr)):
        raise ParameterError(f"{name} must contain only finite numbers; got {_first_bad(arr)}")
    return arr


def _check_real(name: str, value: object, what: str) -> None:
    """Refuse what float() would quietly mangle: complex numbers (the imaginary part dropped), booleans (read as
    0/1), dates, strings and records. A list or an object array is left to the conversion."""
    if value is None:
        raise ParameterError(f"{name} must be a numeric {what}; got None")
    kind = getattr(getattr(value, "dtype", None), "kind", None)
    if kind is None and isinstance(value, (list, tuple)):
        # a list of Python floats (the models' matrices) is common and cannot hold the dtypes refused here
        # except through its entries: look at one row's first entry, not a whole conversion
        first = value
        while isinstance(first, (list, tuple)) and first:
            first = first[0]
        if isinstance(first, (bool, np.bool_, complex, np.complexfloating, str, bytes)):
            kind = np.asarray(value).dtype.kind
    if kind is not None and kind not in "fiuO":
        names = {"c": "complex", "b": "boolean", "M": "datetime", "m": "timedelta", "U": "text", "S": "bytes",
                 "V": "record"}
        raise ParameterError(f"{name} must be a {what} of real numbers; got {names.get(kind, kind)} values")


def shortened(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def _first_bad(arr: np.ndarray) -> str:
    idx = np.argwhere(~np.isfinite(arr))[0]
    return f"{float(arr[tuple(idx)])!r} at index {tuple(int(i) for i in idx)}"
