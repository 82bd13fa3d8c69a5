"""What a run from rest keeps: one object for the output spacing, the thinning and the chunks (as diffrax's
``SaveAt`` is one argument of ``diffeqsolve``).

A run keeps every step, or, like SPICE's output step, one sample per ``spacing`` before ``resolved_from`` (where
what the summary and the plot read begins: the model's ``summary_from``) and every step after it. A run kept at a
spacing is simulated in chunks of about :data:`CHUNK_STEPS` steps, each thinned as it ends, so its memory is what
it keeps, not its steps.
"""
from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from .errors import ParameterError
from .methods.base import Method
from .models import Model
from .trajectory import Trajectory
from .validate import parse_value

#: The most steps a run kept in chunks may take (memory no longer bounds it: ~20-60 s of compiled stepping).
MAX_RUN_STEPS = 2e9
#: Steps one chunk of a run kept at an output spacing simulates at once (its memory before thinning: ~300 MB for
#: a two-state converter's stepper).
CHUNK_STEPS = 500_000


@dataclass(frozen=True)
class SaveAt:
    """What a run over [0, span] keeps: every step (``spacing`` None), or one sample per ``spacing`` s before
    ``resolved_from`` and every step from there on."""

    spacing: float | None = None
    resolved_from: float = 0.0

    @classmethod
    def plan(cls, model: Model, p: dict, method: Method, span: float, x0: npt.NDArray[np.float64] | None,
             output_step: float | str | None = None) -> SaveAt:
        """The plan of a run from rest. Default spacing: none while the whole run fits in the memory limit, else
        the finest multiple of the step whose samples fit in half of it. Refuses, before the first step, a run
        whose kept samples would not fit, or one longer than :data:`MAX_RUN_STEPS`."""
        from .limits import check_memory, max_memory
        resolved = model.summary_from(p, 0.0, span)
        step = getattr(method, method.step_option, None) if method.step_option else None
        if step is None:
            if output_step is not None:
                raise ParameterError(f"output_step needs a method with a fixed step or output spacing; --method "
                                     f"{method.key} keeps its own points")
            return cls(None, resolved)
        whole = model.problem(p, span, x0)
        estimate = method.memory_estimate(whole)
        per_sample = estimate / method.samples(whole)
        if output_step is None:
            if estimate <= max_memory():
                return cls(None, resolved)
            tail = (span - resolved) / step * per_sample
            check_memory(f"--method {method.key}: the last {span - resolved:.3g} s, what the summary and the plot "
                         f"read at every {method.step_option} = {step:.3g} s,", 2.0 * tail,
                         remedy="a larger --h, or a shorter --t-end")
            head = (0.5 * max_memory() - tail) / per_sample              # samples left for the rest
            spacing = step * max(1.0, float(np.ceil(resolved / max(head, 1.0) / step)))
        else:
            spacing = parse_value("output_step", output_step, "s")
            if not step <= spacing <= span:
                raise ParameterError(f"output_step must be in [{step:.3g}, {span:.3g}] s (the method's "
                                     f"{method.step_option} and the run's length); got {spacing:g}")
        check_memory(f"--method {method.key}: {span:.3g} s kept at output_step = {spacing:.3g} s before "
                     f"{resolved:.3g} s and at every step after it",
                     (resolved / spacing + (span - resolved) / step) * per_sample,
                     remedy="a larger --output-step, a larger --h, or a shorter --t-end")
        if not span / step <= MAX_RUN_STEPS:           # kept in chunks, memory no longer bounds its length
            raise ParameterError(f"t_end: {span:.3g} s at {method.step_option} = {step:.3g} s is {span / step:.3g} "
                                 f"steps, more than a run takes ({MAX_RUN_STEPS:.0e}); use a shorter --t-end or "
                                 f"fewer --periods, or a larger --{method.step_option.replace('_', '-')}")
        return cls(spacing, resolved)

    def chunks(self, a: float, b: float, method: Method, period: float) -> Iterator[tuple[float, float]]:
        """[a, b] whole, or, kept at a spacing, in pieces of about CHUNK_STEPS of the method's steps: whole periods
        where the run has a period and a starts on one (each chunk then starts on the grid of the run whole, bit
        for bit), else a multiple of the step."""
        if self.spacing is None:
            yield a, b
            return
        step = getattr(method, method.step_option)
        if np.isfinite(period) and a == round(a / period) * period:
            per = max(1, int(CHUNK_STEPS * step / period))
            first = int(round(a / period))
            edge = lambda k: (first + k * per) * period          # noqa: E731
        else:
            edge = lambda k: a + k * CHUNK_STEPS * step          # noqa: E731
        k, start = 1, a
        while True:                                       # lazily: a long run has many chunks
            end = edge(k)
            if end >= b - 1e-9 * (b - a):
                yield start, b
                return
            yield start, end
            start, k = end, k + 1

    def kept(self, part: Trajectory, start: float) -> Trajectory:
        """What is kept of a chunk starting at ``start``: thinned to the spacing when that is before
        ``resolved_from``."""
        if self.spacing is not None and start < self.resolved_from:
            return part.thinned(self.spacing, self.resolved_from)
        return part

    def metadata(self, tr: Trajectory) -> dict:
        """What a run's metadata says of it: the spacing and where every step is kept from (none kept whole)."""
        return {} if self.spacing is None else {"output_step": self.spacing, "resolved_from_s": tr.resolved_from}
