"""Numbers and ``.param`` expressions as SPICE writes them, evaluated without ``eval``.

A netlist comes from a user's directory: its text is parsed here by a small recursive-descent parser over a
fixed grammar (numbers with SPICE suffixes, names of parameters, + - * / ^ **, parentheses and a fixed list of
functions), so nothing in it can reach Python. Numbers take SPICE's magnitude suffixes (T G meg k m u n p f,
``mil``) and, as ngspice does, ignore letters after them (``10uF``, ``48V``, ``1kohm``).
"""
from __future__ import annotations

import functools
import math
import re
from collections.abc import Callable
from decimal import Decimal, InvalidOperation
from typing import Any, NoReturn, cast

from ..errors import ParameterError

#: SPICE magnitude suffixes (case-insensitive; ``m`` is milli, ``meg`` mega, ``mil`` 25.4e-6).
SUFFIXES = {"t": 1e12, "g": 1e9, "meg": 1e6, "k": 1e3, "mil": 25.4e-6, "m": 1e-3, "u": 1e-6, "n": 1e-9, "p": 1e-12,
            "f": 1e-15}
_EXPONENTS = {"t": 12, "g": 9, "meg": 6, "k": 3, "m": -3, "u": -6, "n": -9, "p": -12, "f": -15}
_NUMBER = re.compile(r"(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?", re.ASCII)
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_.]*", re.ASCII)
FUNCTIONS: dict[str, tuple[Callable[..., float], int]]    # name -> (function, arity)
FUNCTIONS = {"sqrt": (math.sqrt, 1), "exp": (math.exp, 1), "ln": (math.log, 1), "log": (math.log, 1),
             "log10": (math.log10, 1), "abs": (abs, 1), "sin": (math.sin, 1), "cos": (math.cos, 1),
             "tan": (math.tan, 1), "atan": (math.atan, 1), "sinh": (math.sinh, 1), "cosh": (math.cosh, 1),
             "tanh": (math.tanh, 1), "floor": (math.floor, 1), "ceil": (math.ceil, 1), "min": (min, 2),
             "max": (max, 2), "pow": (math.pow, 2), "pwr": (math.pow, 2)}
CONSTANTS = {"pi": math.pi}
#: Longest expression read (characters): a value is a formula, not a program.
MAX_LENGTH = 2000
#: Deepest nesting of parentheses, function calls and powers.
MAX_DEPTH = 100


def number(text: str) -> tuple[float, int]:
    """(value, characters read) of the SPICE number at the start of ``text``, or (nan, 0) when there is none.
    The suffix is scaled exactly (``100u`` is 1e-4, not 9.999999999999999e-05); letters after it are skipped."""
    match = _NUMBER.match(text)
    if not match:
        return math.nan, 0
    end = match.end()
    rest = text[end:end + 3].lower()
    exponent = 0
    for suffix in ("meg", "mil", "t", "g", "k", "m", "u", "n", "p", "f"):
        if rest.startswith(suffix):
            end += len(suffix)
            if suffix == "mil":
                return float(match.group()) * SUFFIXES["mil"], _skip_letters(text, end)
            exponent = _EXPONENTS[suffix]
            break
    try:
        value = float(Decimal(match.group()).scaleb(exponent))
    except InvalidOperation:
        value = math.inf
    return value, _skip_letters(text, end)


def _skip_letters(text: str, end: int) -> int:
    while end < len(text) and text[end].isascii() and text[end].isalpha():
        end += 1
    return end


def evaluate(text: str, names: dict[str, float], what: str = "value") -> float:
    """The value of ``text``: a number, or an expression over ``names`` (parameter name -> value, lower case).

    Raises ParameterError naming ``what`` and the problem (an unknown name, a syntax error, a result that is
    not a finite number). A text is parsed once (:func:`_tree`, cached): a sweep re-reads a netlist per point with
    new values and the same expressions."""
    text = text.strip()
    if text.startswith("{") and text.endswith("}") or text.startswith("'") and text.endswith("'"):
        text = text[1:-1]
    if len(text) > MAX_LENGTH:
        raise ParameterError(f"{what}: an expression of {len(text)} characters (at most {MAX_LENGTH})")
    tree = _tree(text)
    if isinstance(tree, _Failure):
        raise tree.error(what, text)
    value = _value(tree, names, what, text)
    if not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ParameterError(f"{what}: {_shown(text)} is not a finite number (it gives {value!r})")
    return float(value)


def _shown(text: str, limit: int = 60) -> str:
    """``text`` quoted for a one-line message, its middle elided past ``limit`` characters."""
    if len(text) > limit:
        text = text[:limit // 2] + "..." + text[-(limit // 2):]
    return repr(text)


class _Failure(Exception):
    """Why a text does not parse, and where (the message is completed with the value's name when raised)."""

    def __init__(self, why: str, pos: int | None = None) -> None:
        super().__init__(why)
        self.why, self.pos = why, pos

    def error(self, what: str, text: str) -> ParameterError:
        if self.pos is None:
            return ParameterError(f"{what}: {self.why}")
        return ParameterError(f"{what}: {self.why} in {_shown(text)} at character {self.pos + 1}")


#: A node of the parse tree (:func:`_tree`): a tuple whose first item is its kind.
_Node = tuple[Any, ...]


@functools.lru_cache(maxsize=4096)
def _tree(text: str) -> _Node | _Failure:
    """The parse tree of ``text`` (tuples: ``(NUMBER, value)``, ``(NAME, name, pos)``, ``(NEG, a)``,
    ``(op, a, b, pos)`` for + - * / ^, ``(CALL, name, args, pos)``; ``pos`` where a failure is reported), or the
    :class:`_Failure` of a text that does not parse."""
    parser = _Parser(text)
    try:
        tree = parser.expression()
        parser.skip()
        if parser.pos != len(text):
            return _Failure(f"cannot read {_shown(text)} past {_shown(text[:parser.pos])}")
    except _Failure as failure:
        return failure
    return tree


NUMBER, NAME, NEG, CALL = "n", "v", "neg", "call"


def _value(node: _Node, names: dict[str, float], what: str, text: str) -> float:
    kind = node[0]
    if kind == NUMBER:
        return cast(float, node[1])
    if kind == NAME:
        name = node[1]
        if name in names:
            return names[name]
        if name in CONSTANTS:
            return CONSTANTS[name]
        raise _Failure(f"{_shown(name)} is not a parameter defined before it (.param)", node[2]).error(what, text)
    if kind == NEG:
        return -_value(node[1], names, what, text)
    if kind == CALL:
        function, _ = FUNCTIONS[node[1]]
        args = [_value(a, names, what, text) for a in node[2]]
        try:
            return float(function(*args))
        except (ValueError, OverflowError):
            raise _Failure(f"{node[1]}{tuple(args)} is not defined", node[3]).error(what, text) from None
    a, b = _value(node[1], names, what, text), _value(node[2], names, what, text)
    if kind == "+":
        return a + b
    if kind == "-":
        return a - b
    if kind == "*":
        return a * b
    if kind == "/":
        if b == 0:
            raise _Failure("division by zero", node[3]).error(what, text)
        return a / b
    try:                                                                   # "^"
        return math.pow(a, b)
    except (OverflowError, ValueError):
        raise _Failure(f"{a!r} to the power {b!r} is not a finite number", node[3]).error(what, text) from None


class _Parser:
    """expression := term (('+' | '-') term)*; term := power (('*' | '/') power)*;
    power := unary (('^' | '**') power)?; unary := ('-' | '+') unary | atom;
    atom := number | name | name '(' args ')' | '(' expression ')'. Builds the tree :func:`_value` evaluates."""

    def __init__(self, text: str) -> None:
        self.text, self.pos, self.depth = text, 0, 0

    def skip(self) -> None:
        while self.pos < len(self.text) and self.text[self.pos] in " \t":
            self.pos += 1

    def peek(self, token: str) -> bool:
        self.skip()
        return self.text.startswith(token, self.pos)

    def take(self, token: str) -> bool:
        if self.peek(token):
            self.pos += len(token)
            return True
        return False

    def fail(self, why: str) -> NoReturn:
        raise _Failure(why, self.pos)

    def nest(self, step: int) -> None:
        """Count the recursion (parentheses, signs, powers, calls): a formula deeper than MAX_DEPTH is refused
        before Python's own recursion limit is reached (a RecursionError would be a traceback)."""
        self.depth += step
        if self.depth > MAX_DEPTH:
            self.fail(f"expressions nested deeper than {MAX_DEPTH} (parentheses, calls or powers)")

    def expression(self) -> _Node:
        self.nest(1)
        node = self.term()
        while True:
            if self.take("+"):
                node = ("+", node, self.term())
            elif self.take("-"):
                node = ("-", node, self.term())
            else:
                self.nest(-1)
                return node

    def term(self) -> _Node:
        node = self.power()
        while True:
            if self.peek("**"):
                return node
            if self.take("*"):
                node = ("*", node, self.power())
            elif self.take("/"):
                divisor = self.power()
                node = ("/", node, divisor, self.pos)
            else:
                return node

    def power(self) -> _Node:
        base = self.unary()
        if self.take("**") or self.take("^"):
            self.nest(1)
            exponent = self.power()
            self.nest(-1)
            return ("^", base, exponent, self.pos)
        return base

    def unary(self) -> _Node:
        sign = 1.0
        while True:                        # a run of signs is a loop, not a recursion
            if self.take("-"):
                sign = -sign
            elif not self.take("+"):
                break
        node = self.atom()
        return (NEG, node) if sign < 0 else node

    def atom(self) -> _Node:
        self.skip()
        if self.take("("):
            node = self.expression()
            if not self.take(")"):
                self.fail("a ')' is missing")
            return node
        value, used = number(self.text[self.pos:])
        if used:
            self.pos += used
            return (NUMBER, value)
        match = _NAME.match(self.text, self.pos)
        if not match:
            self.fail("a number, a name or '(' expected")
        name = match.group().lower()
        self.pos = match.end()
        if self.peek("("):
            if name not in FUNCTIONS:
                self.fail(f"unknown function {_shown(name)} (known: {', '.join(sorted(FUNCTIONS))})")
            self.take("(")
            _, arity = FUNCTIONS[name]
            args = [self.expression()]
            while self.take(","):
                args.append(self.expression())
            if not self.take(")"):
                self.fail("a ')' is missing")
            if len(args) != arity:
                self.fail(f"{name}() takes {arity} argument{'s' if arity > 1 else ''}; got {len(args)}")
            return (CALL, name, tuple(args), self.pos)
        return (NAME, name, self.pos)
