"""State-driven switching laws: which configuration holds is decided by the state, not the clock.

A switching function is affine in the state, with an optional periodic sawtooth ramp:

    s(x, t) = c . x + d - ramp(t),      ramp(t) = low + (high - low) frac((t - delay) / period)

(sliding-mode current control: s = iL - Iref; voltage-mode PWM: s = A (vC - Vref) - ramp(t)).
Two laws use it:

* :class:`StateSwitching` (hysteresis or latch): configuration ``below`` is entered when s falls
  below -band, ``above`` when s rises above +band. With ``latch`` at most one switching happens per
  ramp period; at every period start (the ramp's reset, where s jumps) the configuration is set again by
  s against the band (below -band: ``below``; above +band: ``above``; inside it holds). ``clocked`` latches
  are set by the clock only (peak current mode's SR latch): inside a period the law switches from ``below``
  to ``above``, never back.
* :class:`Comparators`: several such laws at once (interleaved phases, one comparator per phase), each a channel
  with its own function, ramp (its ``delay`` shifts its phase), band and latch; the configuration in force is
  looked up from the channels' states.
* :class:`Relay` (the implicit, chattering-free law): the configuration is a convex blend
  x' = f_low(x) + z (f_high(x) - f_low(x)) with z in [0, 1] and -s in N_[0,1](z) (s < 0 gives z = 1,
  s > 0 gives z = 0, s = 0 lets z take the value that keeps it there: the equivalent control).
  A time-stepper imposes it at the step end (Acary and Brogliato 2008: an LCP of size 2 per step).

Every law exposes ``period`` (its clock period, inf when it has none) and ``configs`` (the
configurations it selects), so methods treat all laws alike where they can.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError
from ..validate import as_vector, check_positive, parse_value


@dataclass(frozen=True)
class Ramp:
    """A periodic sawtooth: ``low`` at t = delay + m period, rising linearly to ``high`` at the period's end."""

    low: float
    high: float
    period: float
    #: Where the first period starts (s), in [0, period): a second phase's ramp delayed by period / 2.
    delay: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "low", parse_value("ramp low", self.low))
        object.__setattr__(self, "high", parse_value("ramp high", self.high))
        object.__setattr__(self, "period", check_positive("ramp period", self.period, "s"))
        delay = parse_value("ramp delay", self.delay)
        if not 0.0 <= delay < self.period:
            raise ParameterError(f"ramp delay must be in [0, period = {self.period:g}) s; got {delay!r}")
        object.__setattr__(self, "delay", delay)

    @property
    def slope(self) -> float:
        """d ramp / dt inside a period (V/s or the unit of s per second)."""
        return (self.high - self.low) / self.period

    def __call__(self, t: npt.ArrayLike) -> np.ndarray:
        return self.low + self.slope * self.phase(t)

    def phase(self, t: npt.ArrayLike) -> np.ndarray:
        """Time since the ramp's last reset (s), in [0, period); within 1e-9 period of a reset it is that reset's 0
        (t = 100 T may be 100 T less one rounding, whose remainder would read a whole period), as the stepper's
        compiled loop rounds it."""
        since = np.asarray(t, dtype=float) - self.delay
        return np.maximum(since - np.floor(since / self.period + 1e-9) * self.period, 0.0)


@dataclass(frozen=True)
class SwitchingFunction:
    """s(x, t) = c . x + d - ramp(t); ``c`` has one entry per state."""

    c: np.ndarray
    d: float = 0.0
    ramp: Ramp | None = None

    def __post_init__(self) -> None:
        c = as_vector("switching function c", self.c, None)
        c.setflags(write=False)
        object.__setattr__(self, "c", c)
        object.__setattr__(self, "d", parse_value("switching function d", self.d))

    @property
    def n(self) -> int:
        return self.c.shape[0]

    def __call__(self, x: npt.ArrayLike, t: npt.ArrayLike) -> np.ndarray:
        """s at states ``x`` (shape (n,) or (N, n)) and times ``t``."""
        value = np.asarray(x, dtype=float) @ self.c + self.d
        return value - self.ramp(t) if self.ramp is not None else value


def _check_config(name: str, value: object) -> int:
    if not (isinstance(value, (int, np.integer)) and value >= 0):
        raise ParameterError(f"{name} must be a configuration index (an integer >= 0); got {value!r}")
    return int(value)


def _check_function(function: object) -> None:
    if not isinstance(function, SwitchingFunction):        # None failed later with an AttributeError
        raise ParameterError(f"function must be a SwitchingFunction; got {function!r}")


@dataclass(frozen=True)
class StateSwitching:
    """Hysteresis (or latched) switching between two configurations on a switching function.

    Parameters
    ----------
    function : SwitchingFunction
    below : int
        Configuration entered when s falls below -band (e.g. switch ON for s = iL - Iref).
    above : int
        Configuration entered when s rises above +band.
    band : float
        Hysteresis half-width, >= 0, in the unit of s.
    latch : bool
        At most one switching per ramp period (needs a ramp); at every period start the configuration
        is set again by s against the band.
    clocked : bool
        With ``latch``: only the clock enters ``below`` (at a period start where s < -band); inside a period
        the one switching is to ``above`` (a current-mode controller's comparator resets its latch, its clock
        sets it: without this a current that falls back below the command mid-period would turn the switch on).
    limit : float or None
        With ``latch``: at this fraction of every ramp period a law still in ``below`` switches to ``above`` and
        latches (a current-mode controller's maximum duty ratio); None: no limit.
    initial : int or None
        Configuration at the start of a run; None: ``below`` if s(x0, t0) < 0, else ``above``.
    """

    function: SwitchingFunction
    below: int
    above: int
    band: float = 0.0
    latch: bool = False
    initial: int | None = None
    clocked: bool = False
    limit: float | None = None

    def __post_init__(self) -> None:
        _check_function(self.function)
        for name in ("latch", "clocked"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):          # a string ("no") is truthy
                raise ParameterError(f"{name} must be True or False; got {getattr(self, name)!r}")
        if self.clocked and not self.latch:
            raise ParameterError("clocked needs latch (the clock sets a latch the law resets); got latch=False")
        if self.limit is not None:
            limit = parse_value("limit", self.limit)
            if not (self.latch and 0.0 < limit < 1.0):
                raise ParameterError(f"limit (the fraction of each ramp period after which the law leaves below) must "
                                     f"be in (0, 1) on a latched law; got {limit!r}" + ("" if self.latch else
                                                                                          " without latch"))
            object.__setattr__(self, "limit", limit)
        object.__setattr__(self, "below", _check_config("below", self.below))
        object.__setattr__(self, "above", _check_config("above", self.above))
        if self.below == self.above:
            raise ParameterError(f"below and above must be different configurations; got {self.below} for both")
        band = parse_value("band", self.band)
        if band < 0.0:
            raise ParameterError(f"band (hysteresis half-width) must be >= 0; got {band!r}")
        object.__setattr__(self, "band", band)
        if self.latch and self.function.ramp is None:
            raise ParameterError("latch needs a ramp (one switching per ramp period); got a switching function "
                                 "without a ramp")
        if self.initial is not None:
            initial = _check_config("initial", self.initial)
            if initial not in (self.below, self.above):
                raise ParameterError(f"initial must be below ({self.below}) or above ({self.above}); got {initial}")
            object.__setattr__(self, "initial", initial)

    @property
    def period(self) -> float:
        return self.function.ramp.period if self.function.ramp is not None else np.inf

    @property
    def configs(self) -> tuple[int, ...]:
        return (self.below, self.above)

    def initial_config(self, x0: npt.ArrayLike, t0: float) -> int:
        """The configuration at a run's start: ``initial`` (a run that continues another: a load step), set again
        by s against the band where the run starts on a ramp reset as any period start is; without ``initial``,
        ``below`` where s(x0, t0) < 0."""
        s = float(self.function(x0, t0))
        if self.initial is None:
            return self.below if s < 0.0 else self.above
        if np.isfinite(self.period):
            phase = float(self.function.ramp.phase(t0))
            if min(phase, self.period - phase) <= 1e-9 * self.period:
                f = self.function                            # the ramp at its foot (t0 mod T may round to T)
                s = float(np.asarray(x0, dtype=float) @ f.c + f.d - f.ramp.low)
                return self.below if s < -self.band else self.above if s > self.band else self.initial
        return self.initial

    def breakpoints(self, t0: float, t1: float) -> np.ndarray:
        """Ramp resets and limit instants in the open interval (t0, t1) (where s jumps and a latch opens again, or
        the limit closes it), sorted."""
        times = np.concatenate([self.resets(t0, t1), self.limits(t0, t1)])
        times.sort()
        return times

    def resets(self, t0: float, t1: float) -> np.ndarray:
        """Ramp resets in the open interval (t0, t1)."""
        if not np.isfinite(self.period):
            return np.empty(0)
        T, delay = self.period, self.function.ramp.delay
        times = np.arange(np.floor((t0 - delay) / T), np.ceil((t1 - delay) / T) + 1) * T + delay
        return times[(times > t0) & (times < t1)]

    def limits(self, t0: float, t1: float) -> np.ndarray:
        """The limit's instants (``limit`` T into each period) in the open interval (t0, t1)."""
        if self.limit is None or not np.isfinite(self.period):
            return np.empty(0)
        T, delay = self.period, self.function.ramp.delay
        times = (np.arange(np.floor((t0 - delay) / T), np.ceil((t1 - delay) / T) + 1) + self.limit) * T + delay
        return times[(times > t0) & (times < t1)]


#: At most this many channels in one :class:`Comparators` (2^m configurations in its table).
MAX_CHANNELS = 8


@dataclass(frozen=True)
class Comparators:
    """Several state-driven switchings at once: interleaved phases, each with its own comparator.

    Parameters
    ----------
    channels : tuple of StateSwitching
        Channel j switches between its states 0 (``below``, entered when its s_j falls below -band_j) and 1
        (``above``): each channel is a :class:`StateSwitching` with ``below=0, above=1`` (and ``initial`` 0, 1 or
        None), its own ramp (a ``delay`` for its phase), band, latch, ``clocked`` and ``limit``.
    table : tuple of int
        The configuration in force for each combination of the channels' states: ``table[sum(state_j << j)]``
        (2^m entries for m channels); -1 where the system has none (two comparators whose switches would short a
        source together): a run that reaches it stops naming it.
    names : tuple of str
        A label per channel for messages (a netlist's switch names); default ``comparator0``, ...
    words : (str, str)
        What a channel's states 0 and 1 are called in messages (a netlist's switch: closed, open).
    reasons : tuple of str
        Why each combination with no configuration has none (one entry per ``table`` entry, '' elsewhere; default
        none): said when a run reaches it.
    """

    channels: tuple
    table: tuple
    names: tuple = ()
    words: tuple = ("below", "above")
    reasons: tuple = ()

    def __post_init__(self) -> None:
        channels = tuple(self.channels)
        if not 2 <= len(channels) <= MAX_CHANNELS:
            raise ParameterError(f"channels must hold 2 to {MAX_CHANNELS} StateSwitching laws (one is a "
                                 f"StateSwitching itself); got {len(channels)}")
        for j, channel in enumerate(channels):
            if not isinstance(channel, StateSwitching) or (channel.below, channel.above) != (0, 1):
                raise ParameterError(f"channels[{j}] must be a StateSwitching with below=0, above=1 (the channel's "
                                     f"own states); got {channel!r}")
        table = tuple(-1 if isinstance(c, (int, np.integer)) and c == -1 else _check_config(f"table[{i}]", c)
                      for i, c in enumerate(self.table))
        if len(table) != 2 ** len(channels):
            raise ParameterError(f"table must have 2^{len(channels)} = {2 ** len(channels)} entries (one per "
                                 f"combination of the channels' states); got {len(table)}")
        if all(c < 0 for c in table):
            raise ParameterError("table must name a configuration for at least one combination; got only -1")
        names = tuple(str(x) for x in self.names) or tuple(f"comparator{j}" for j in range(len(channels)))
        if len(names) != len(channels):
            raise ParameterError(f"names must have one entry per channel ({len(channels)}); got {len(names)}")
        object.__setattr__(self, "channels", channels)
        object.__setattr__(self, "table", table)
        object.__setattr__(self, "names", names)
        periods = [c.period for c in channels if np.isfinite(c.period)]
        object.__setattr__(self, "_period", common_period(periods) if periods else np.inf)

    @property
    def period(self) -> float:
        """The channels' ramps' common period (inf when none has a ramp)."""
        return self._period

    @property
    def configs(self) -> tuple[int, ...]:
        return tuple(sorted(set(self.table) - {-1}))

    def initial_bits(self, x0: npt.ArrayLike, t0: float) -> int:
        """The channels' states at a run's start, bit j channel j's (each channel's own rule)."""
        return sum(channel.initial_config(x0, t0) << j for j, channel in enumerate(self.channels))

    def initial_config(self, x0: npt.ArrayLike, t0: float) -> int:
        return self.config(self.initial_bits(x0, t0), t0)

    def config(self, bits: int, t: float) -> int:
        """The configuration of the channels' states ``bits``; a SimulationError naming them where there is none."""
        config = self.table[bits]
        if config < 0:
            from ..errors import SimulationError
            states = ", ".join(f"{name} {self.words[bits >> j & 1]}" for j, name in enumerate(self.names))
            why = self.reasons[bits] if bits < len(self.reasons) else ""
            raise SimulationError(f"at t = {t:.9g} s the comparators reach a combination of states the system has no "
                                  f"configuration for ({states})" + (f": {why}" if why else ""))
        return config

    def breakpoints(self, t0: float, t1: float) -> np.ndarray:
        return np.unique(np.concatenate([c.breakpoints(t0, t1) for c in self.channels]))


def common_period(periods: Sequence[float], what: str = "the ramps' periods") -> float:
    """The least common multiple of periods (s) whose ratios are rational with denominators up to 1000."""
    from fractions import Fraction
    import math
    base = max(periods)
    fractions = [Fraction(p / base).limit_denominator(1000) for p in periods]
    for p, f in zip(periods, fractions):
        if abs(float(f) * base - p) > 1e-9 * p:
            raise ParameterError(f"{what} {sorted(set(periods))} s have no common period")
    denominator = math.lcm(*[f.denominator for f in fractions])
    return base * math.lcm(*[f.numerator * denominator // f.denominator for f in fractions]) / denominator


def law_channels(law: StateSwitching | Comparators) -> tuple[tuple[StateSwitching, ...], tuple[int, ...]]:
    """(channels, table) of a state-driven law: one channel (its table ``(below, above)``) for a StateSwitching."""
    if isinstance(law, Comparators):
        return law.channels, law.table
    return (law,), (law.below, law.above)


def initial_bits(law: StateSwitching | Comparators, x0: npt.ArrayLike, t0: float) -> int:
    """The channels' states (bit j: channel j above) at a run's start, for a StateSwitching or Comparators."""
    if isinstance(law, Comparators):
        return law.initial_bits(x0, t0)
    return int(law.initial_config(x0, t0) == law.above)


@dataclass(frozen=True)
class Relay:
    """The implicit relay: a convex blend of configurations ``low`` (z = 0) and ``high`` (z = 1).

    x' = f_low(x) + z (f_high(x) - f_low(x)), z in [0, 1], with ``-s in N_[0,1](z)`` on the switching
    function s (z = 1 where s < 0). The complementarity pairs of configuration ``low`` stay in force.
    """

    function: SwitchingFunction
    low: int
    high: int

    def __post_init__(self) -> None:
        _check_function(self.function)
        object.__setattr__(self, "low", _check_config("low", self.low))
        object.__setattr__(self, "high", _check_config("high", self.high))
        if self.low == self.high:
            raise ParameterError(f"low and high must be different configurations; got {self.low} for both")
        if self.function.ramp is not None:
            raise ParameterError("the relay law takes a switching function without a ramp")

    @property
    def period(self) -> float:
        return np.inf

    @property
    def configs(self) -> tuple[int, ...]:
        return (self.low, self.high)

    def initial_config(self, x0: npt.ArrayLike, t0: float) -> int:
        return self.low

    def breakpoints(self, t0: float, t1: float) -> np.ndarray:
        return np.empty(0)
