"""ngspice as a method: the same circuit's netlist run by ngspice, its result a Trajectory like any method's.

ngspice solves the circuit, not an LCS: its ideal switches and diodes become near-ideal devices
(:class:`netlists.SpiceOptions`) and the netlist is the model's own file (a ``.cir`` circuit) or the one
:mod:`netlists` writes for a built-in model. So :class:`Spice` declares the domain ``circuit`` and runs a model at
its parameters (:meth:`Spice.run_model`, which :func:`converters.run.run_converter` calls for a method of that
domain) instead of solving a problem; its error is its devices' (``error_kind`` ``model``): what a run can say
is whether its 10-period mean has settled. A steady state has no period map to shoot on: ngspice starts on the
LCP stepper's orbit and runs on, from where it ended, until its own 10-period mean moves less than
``SPICE_SETTLE`` (at most ``MAX_SPICE_PERIODS`` periods).

It is registered as an entry point (``pcsuite.methods``, in pyproject.toml): ``get_method("spice")`` and the
command line load it on first use, as any backend; :mod:`converters` never imports it (ngspice lives above the
core's layers).
"""
from __future__ import annotations

import time
from dataclasses import dataclass

from converters.errors import ParameterError
from converters.methods.base import ErrorKind, Method
from converters.trajectory import ReturnCode
from converters.validate import parse_value

#: RELTOL ngspice is allowed (its own default is 1e-3).
RELTOL_RANGE = (1e-9, 0.1)


def spice_settings(period: float, tmax=None, reltol=None, method=None):
    """The SpiceOptions that --spice-tmax (s, below the period), --spice-reltol and --spice-method ask for, or
    None when none is given (the netlist's or the defaults then)."""
    from netlists import SpiceOptions
    given = {}
    if tmax is not None:
        value = parse_value("--spice-tmax", tmax, "s")
        if not 0.0 < value < period:
            raise ParameterError(f"--spice-tmax must be in (0, {period:g}) s (below the switching period); got "
                                 f"{value:g}")
        given["tmax_fraction"] = value / period
    if reltol is not None:
        value = parse_value("--spice-reltol", reltol)
        if not RELTOL_RANGE[0] <= value <= RELTOL_RANGE[1]:
            raise ParameterError(f"--spice-reltol must be in [{RELTOL_RANGE[0]:g}, {RELTOL_RANGE[1]:g}]; got {value:g}")
        given["reltol"] = value
    if method is not None:
        given["method"] = method
    return SpiceOptions(**given) if given else None


@dataclass(frozen=True)
class Spice(Method, key="spice"):
    """The same circuit in ngspice (module docstring).

    Parameters
    ----------
    spice_tmax : float or str, optional
        ngspice's ``.tran`` TMAX in s, below the switching period (default T/200, or the netlist's own).
    spice_reltol : float, optional
        ngspice's RELTOL in [1e-9, 0.1] (default 1e-3, or the netlist's own).
    spice_method : str, optional
        ngspice's METHOD, ``trap`` or ``gear`` (default gear, or the netlist's own).
    """

    spice_tmax: float | str | None = None
    spice_reltol: float | str | None = None
    spice_method: str | None = None
    domains = ("circuit",)
    error_kind = ErrorKind.MODEL
    model_error = "its near-ideal devices' and its own time-step control's"
    counts = "accepted steps"
    description = ("the same circuit in ngspice, its ideal devices near-ideal (--spice-tmax, --spice-reltol, "
                   "--spice-method; --steady runs it on from the LCP's orbit until its 10-period mean settles)")

    #: A sweep point in ngspice (:meth:`sweep_row`): the last period's measures, the mode and held fraction from
    #: ngspice's diode currents, how far the mean moved from the period before (``settle``) and its accepted steps.
    sweep_measures = {"vout_mean": float, "vout_ripple": float, "rms_state0": float, "mode": str,
                      "held_fraction": float, "settle": float, "spice_steps": int}

    def __post_init__(self):
        if self.spice_reltol is not None:
            spice_settings(1.0, reltol=self.spice_reltol)
        if self.spice_method is not None and self.spice_method not in ("trap", "gear"):
            raise ParameterError(f"--spice-method must be one of trap, gear; got {self.spice_method!r}")

    @property
    def order(self) -> float:
        """ngspice's trapezoidal rule and its gear of order 2 (the default MAXORD)."""
        return 2.0

    def solve(self, problem, x0):
        raise ParameterError("ngspice runs a circuit's netlist, not an LCS problem: run the model with this method "
                             "(converters.run.run_converter(model, params, method=Spice(...)))")

    def sweep_check(self, model, p: dict, steady: bool, periods: int) -> None:
        if not (isinstance(periods, int) and periods >= 2):
            raise ParameterError(f"periods must be an integer >= 2 for an ngspice sweep; got {periods!r}")
        options = spice_settings(model.period(p), self.spice_tmax, self.spice_reltol, self.spice_method)
        _deck(model, p, 2 * model.period(p), options)[0](None)          # refuses a model without a netlist

    def sweep_row(self, model, p: dict, steady: bool, periods: int) -> dict:
        """``periods`` periods in ngspice from the LCP stepper's orbit (``steady``) or from rest, measured over the
        last one (a failed run, "timestep too small", raises: the sweep stores it as a failed row)."""
        from converters.analysis.modes import mode_intervals, period_modes
        from converters.run import make_method, steady_state

        from .gdcm import SPICE_MIN_RUN
        from .spice import run_spice
        T = model.period(p)
        x0 = steady_state(model, p, make_method(model, p, "lcp", None)).x0 if steady else None
        options = spice_settings(T, self.spice_tmax, self.spice_reltol, self.spice_method)
        write, labelled = _deck(model, p, periods * T, options)
        netlist = write(x0)
        result = run_spice(netlist)
        end = float(result.time[-1])
        start = end - T
        run = labelled(model, p, netlist, result, start)
        mode, held = period_modes(model, mode_intervals(run.t, run.modes(), start, end, T, SPICE_MIN_RUN))
        previous = run.mean("vout", t0=start - T, t1=start)
        mean = run.mean("vout", t0=start)
        # from rest, a row that has not settled says so, as the LCP's do (a boost at 50 periods: 40.5 V, settle 5e-4,
        # its orbit 54.37 V)
        from converters.sweeps.ensemble import unsettled
        return {"vout_mean": float(mean), "vout_ripple": float(run.ripple("vout", t0=start)),
                "rms_state0": float(run.rms(model.state_names[0], t0=start)), "mode": mode, "held_fraction": held,
                "settle": float(abs(mean - previous) / max(abs(mean), 1e-12)), "spice_steps": int(run.steps),
                **({} if steady else {"message": unsettled(run, T)})}

    def sweep_chunk_done(self) -> None:
        from .spice import close_spice_worker
        close_spice_worker()          # the chunk's ngspice process ends with the chunk (no orphan)

    def run_model(self, model, p: dict, *, t_end=None, periods=None, steady: bool = False, x0=None):
        """The model at ``p`` in ngspice over ``t_end`` s or ``periods`` periods (default 500; with ``steady``, the
        span returned on the settled run, default 20 periods): a Trajectory labelled by the model, its metadata
        the run's options (``ngspice`` its version) and, with ``steady``, ``steady_periods`` with the notes
        ``spice_settle`` (the last 10-period mean's relative move) and ``spice_settled``."""
        from dataclasses import replace

        from converters.run import STEADY_PERIODS, check_steady, duration, make_method, steady_state
        from .compare import MAX_SPICE_PERIODS, SPICE_SETTLE, spice_drift
        from .spice import run_spice
        start = time.perf_counter()
        options = spice_settings(model.period(p), self.spice_tmax, self.spice_reltol, self.spice_method)
        if steady:
            check_steady(model, p)
            if x0 is None:
                x0 = steady_state(model, p, make_method(model, p)).x0
            if t_end is None and periods is None:
                periods = STEADY_PERIODS
        span_s = duration(model, p, t_end, periods)
        T = model.period(p)
        if hasattr(model, "netlist") and not model.periodic(p):
            T = span_s / 10
        write, labelled = _deck(model, p, span_s, options)
        netlist = write(x0)
        result = run_spice(netlist)
        window_start = result.time[-1] - 10 * T
        tr = labelled(model, p, netlist, result, window_start)
        notes, warnings = {}, []
        if steady:
            span = int(round(span_s / T))
            if span < 20:
                raise ParameterError(f"--steady with --method spice needs at least 20 periods (two 10-period "
                                     f"windows); got {span}")
            total, settle = span, spice_drift(tr, T, span, 10)
            while settle > SPICE_SETTLE and total < MAX_SPICE_PERIODS:
                netlist = write(tr.x[-1])
                result = run_spice(netlist)
                tr = labelled(model, p, netlist, result, window_start)
                total, settle = total + span, spice_drift(tr, T, span, 10)
            notes = {"spice_settle": settle, "spice_settled": bool(settle <= SPICE_SETTLE)}
            if not notes["spice_settled"]:
                warnings.append(f"ngspice has not settled after {total} periods (its 10-period mean still moves "
                                f"{settle:.2g})")
            notes["steady_periods"] = total
        metadata = {**tr.metadata, "model": model.name, "control": model.control, "params": p,
                    "method_options": {**result.options, "ngspice": result.ngspice_version}, "notes": notes,
                    "warnings": warnings}
        return replace(tr, algorithm=self, wall_s=time.perf_counter() - start, metadata=metadata,
                       retcode=ReturnCode.SUCCESS if notes.get("spice_settled", True) else ReturnCode.NOT_CONVERGED)


def _deck(model, p: dict, span_s: float, options):
    """(write(x0) -> the Netlist of ``span_s`` s from ``x0``, labelled(model, p, netlist, result, window_start) -> its
    Trajectory): a netlist file's own circuit (its signals and modes its own: a sweep had read a built-in model's
    probes on it, "KeyError: 'vout'"), or a built-in model's deck."""
    if hasattr(model, "netlist"):             # a netlist file: ngspice runs the same circuit
        from netlists.circuit import circuit_netlist, file_spice_options

        from .spice import circuit_trajectory
        options = file_spice_options(model, options)
        return (lambda start: circuit_netlist(model, p, span_s, options, x0=start)), circuit_trajectory
    from netlists import model_netlist

    from .spice import spice_trajectory
    return (lambda start: model_netlist(model, p, span_s, options, x0=start)), spice_trajectory
