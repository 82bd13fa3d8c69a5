"""Time-driven switching: a periodic, piecewise-constant schedule of configurations (PWM)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError
from ..validate import check_integer, check_positive, parse_value


@dataclass(frozen=True)
class Schedule:
    """Which configuration holds when: periodic and piecewise constant.

    Over every period [m T, (m + 1) T) configuration ``configs[i]`` holds from ``m T + starts[i]``
    to the next start. ``starts[0]`` must be 0. A constant schedule has period = inf.
    """

    period: float
    starts: tuple[float, ...]
    configs: tuple[int, ...]

    def __post_init__(self) -> None:
        try:
            starts = tuple(parse_value("schedule start", s) for s in self.starts)
        except TypeError:
            raise ParameterError(f"schedule starts must be a sequence of times (s); got {self.starts!r}") from None
        try:     # an index: 0.7 or 1.9 would truncate to 0 and 1, None crash
            configs = tuple(check_integer("schedule config", c, 0) for c in self.configs)
        except TypeError:
            raise ParameterError(f"schedule configs must be a sequence of indices; got {self.configs!r}") from None
        period = self.period
        if not (isinstance(period, (int, float, np.integer, np.floating)) and not isinstance(period, bool)
                and (np.isfinite(period) or period == np.inf)):
            raise ParameterError(f"schedule period must be a positive number of seconds, or inf (constant); got "
                                 f"{period!r}")          # NaN and -inf would read as a constant schedule
        if len(starts) != len(configs) or not starts:
            raise ParameterError(f"schedule starts and configs must have the same non-zero length; "
                                 f"got {len(starts)} and {len(configs)}")
        if starts[0] != 0.0 or any(b <= a for a, b in zip(starts, starts[1:])):
            raise ParameterError(f"schedule starts must begin at 0 and increase strictly; got {starts}")
        if np.isfinite(self.period):
            check_positive("schedule period", self.period, "s")
            if starts[-1] >= self.period:
                raise ParameterError(f"schedule starts must lie in [0, period = {self.period:g}); got {starts}")
        elif len(starts) != 1:
            raise ParameterError("a schedule with period = inf holds one configuration")
        object.__setattr__(self, "starts", starts)
        object.__setattr__(self, "configs", configs)

    @classmethod
    def constant(cls, config: int = 0) -> "Schedule":
        return cls(period=np.inf, starts=(0.0,), configs=(config,))

    @classmethod
    def pwm(cls, period: float, duty: float, on: int = 0, off: int = 1) -> "Schedule":
        """``on`` for duty * period, then ``off``; duty 0 and 1 give a single configuration."""
        duty = parse_value("D", duty)
        if not 0.0 <= duty <= 1.0:
            raise ParameterError(f"D (duty ratio) must be in [0, 1]; got {duty!r}")
        if duty == 0.0:
            return cls(period=period, starts=(0.0,), configs=(off,))
        if duty == 1.0:
            return cls(period=period, starts=(0.0,), configs=(on,))
        return cls(period=period, starts=(0.0, duty * period), configs=(on, off))

    def breakpoints(self, t0: float, t1: float) -> np.ndarray:
        """Times in the open interval (t0, t1) at which the configuration may change."""
        if not np.isfinite(self.period):
            return np.empty(0)
        first, last = int(np.floor(t0 / self.period)), int(np.ceil(t1 / self.period))
        periods = np.arange(first, last + 1) * self.period
        times = (periods[:, None] + np.array(self.starts)[None, :]).ravel()
        return times[(times > t0) & (times < t1)]

    def initial_config(self, x0: npt.ArrayLike, t0: float) -> int:
        return int(self.config_at(np.array([t0]))[0])

    def config_at(self, t: np.ndarray) -> np.ndarray:
        """Configuration index holding at each time in t (right-continuous)."""
        t = np.asarray(t, dtype=float)
        phase = t if not np.isfinite(self.period) else np.mod(t, self.period)
        slot = np.searchsorted(np.array(self.starts), phase, side="right") - 1
        return np.array(self.configs, dtype=np.int64)[np.clip(slot, 0, None)]
