"""Helpers shared by the subcommands: parameter options, the method options, waveform files."""
from __future__ import annotations

from pathlib import Path

from converters.errors import ParameterError
from converters.parallel.local import MAX_WORKERS

#: Exit codes: bad input (one line on stderr), and Ctrl-C (128 + SIGINT, as the shell reports it).
EXIT_BAD_INPUT = 2
EXIT_INTERRUPTED = 130


def check_workers(workers, flag: str = "--workers") -> None:
    """Refuse a number of processes outside [1, MAX_WORKERS] (None: the command's default)."""
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or not 1 <= workers <= MAX_WORKERS):
        raise ParameterError(f"{flag} must be an integer in [1, {MAX_WORKERS}]; got {workers!r}")


def integer(low: int, high=None):
    """An argparse ``type`` for an integer option whose text may not parse: the error then names the range too
    (argparse's own says only "invalid int value"). ``high``: an int, None (no upper bound), or a function
    returning it (a constant of a module the parser should not import). The range itself is checked where the
    value is used."""
    def described():
        top = high() if callable(high) else high
        return f"an integer >= {low}" if top is None else f"an integer in [{low}, {top:,}]"
    return _typed(int, described)


def number(described):
    """An argparse ``type`` for a real option, as :func:`integer`; ``described``: its range ("(0, 1)"), or a
    function returning it."""
    return _typed(float, lambda: f"a number in {described() if callable(described) else described}")


def given_path(text: str) -> Path:
    """An argparse ``type`` for a file or directory option: an empty text (an unset shell variable, ``--out
    "$OUT"``) is refused rather than read as the current directory."""
    if not text.strip():
        import argparse
        raise argparse.ArgumentTypeError(f"must be a path; got {text!r}")
    return Path(text)


def _typed(parse, described):
    import argparse

    def typed(text):
        try:
            return parse(text)
        except ValueError:
            from converters.validate import shown      # a 5,000-digit number is named by its length, not printed
            raise argparse.ArgumentTypeError(f"must be {described()}; got {shown(text)}") from None
    return typed


def unit_of(model, parameter: str) -> str:
    """" UNIT" of a model's parameter for printing after its value ("" when it has none)."""
    unit = {q.name: q.unit for q in getattr(model, "parameters", ())}.get(parameter, "")
    return f" {unit}" if unit not in ("", "1") else ""


def method_options(key: str, given: dict) -> dict:
    """The given method options (command-line names with underscores, None where not given) that method ``key``
    takes; one an option it does not take is refused naming its flag and the method's own options."""
    from converters.methods.base import get_method
    names = get_method(key).option_names()
    wrong = [name for name, value in given.items() if value is not None and name not in names]
    if wrong:
        flags = ", ".join("--" + name.replace("_", "-") for name in wrong)
        own = [f"--{name.replace('_', '-')}" for name in given if name in names]
        raise ParameterError(f"{flags} do{'es' if len(wrong) == 1 else ''} not apply to --method {key} (its options: "
                             f"{', '.join(own) or 'none'}, and --h)")
    return {name: value for name, value in given.items() if name in names}


def add_params(parser) -> None:
    parser.add_argument("-p", dest="params", action="append", default=[], metavar="NAME=VALUE",
                        help="parameter value, SPICE suffixes allowed (repeatable)")


def add_unstable_option(parser) -> None:
    parser.add_argument("--unstable", action="store_true",
                        help="analyse the periodic orbit even where it is unstable (a Floquet multiplier outside the "
                             "unit circle: the circuit does not settle on it); the output says so")


def orbit_stability(what: str, key: str, multipliers, period: float, allowed: bool, warning: str = "",
                    border: str = "") -> dict:
    """``spectral_radius`` and ``stable`` of the orbit an analysis is about (its period ``period`` s); an unstable
    orbit is refused in one line unless ``allowed`` (--unstable), and then said in a warning. The orbit's own
    ``warning`` (Newton's orbit far from where the settled transient went:
    :func:`converters.analysis.periodic.shoot`) is said on stderr and kept in the JSON as ``orbit_warning``; so is
    a ``border`` of its modes it lies at (:meth:`converters.analysis.smallsignal.SmallSignalModel.border`), as
    ``border``."""
    import sys

    import numpy as np

    from converters.analysis.periodic import instability
    from converters.errors import SimulationError
    rho = float(np.abs(np.asarray(multipliers)).max(initial=0.0))
    why = instability(multipliers, period)
    if why:
        how = f"the periodic orbit of {key} is {why}"
        if not allowed:
            raise SimulationError(f"{how}, so its {what} describe no steady state; run pcsuite bifurcation to see "
                                  "where it settles, or pass --unstable to analyse the orbit all the same")
        print(f"warning: {how}: its {what} are the unstable orbit's (--unstable)", file=sys.stderr)
    if warning:
        print(f"warning: {warning}: its {what} are that orbit's", file=sys.stderr)
    if border:
        check = " (--check compares finite differences)" if what == "sensitivities" else ""
        print(f"warning: {border}: its {what} are one-sided there, and differ across it{check}", file=sys.stderr)
    return {"spectral_radius": rho, "stable": not why, **({"orbit_warning": warning} if warning else {}),
            **({"border": border} if border else {})}


def circuit_notes(model, params: dict) -> dict:
    """What a netlist's circuit says with every run (:attr:`converters.circuits.compile.Compiled.notes`: a
    comparator's ramp taken as a sawtooth, a start moved onto a loop's invariant), said on stderr for an analysis
    that reads its orbit as ``simulate`` says it, and kept in the JSON as ``warnings``."""
    import sys
    compiled = getattr(model, "compiled", None)
    notes = list(compiled(model.resolve(params)).notes) if compiled is not None else []
    for note in notes:
        print(f"warning: {note}", file=sys.stderr)
    return {"warnings": notes} if notes else {}


def on_exact_orbit(command: str, run):
    """``run`` (a command's) with the event method's refusal of a circuit's stiffest mode said for ``command``,
    which reads the exact orbit and has no other method: its remedies (--method lcp, a shorter --t-end) are
    simulate's, not this command's."""
    from converters.errors import ResourceError

    def wrapped(args):
        try:
            return run(args)
        except ResourceError as error:
            text = str(error)
            if not text.startswith("--method event: "):
                raise
            reason = text.removeprefix("--method event: ").split("; use --method lcp")[0]
            raise ResourceError(f"{command} works on the exact event method's orbit, which cannot take this circuit: "
                                f"{reason.replace(', or a long --t-end', '')}; simulate --steady runs it with the "
                                "stepper") from None
    return wrapped


def add_spice_options(parser) -> None:
    """ngspice's transient settings on a command that runs it."""
    parser.add_argument("--spice-tmax", default=None,
                        help="ngspice .tran TMAX in s (default T/200; SPICE suffixes: 50n)")
    parser.add_argument("--spice-reltol", default=None, help="ngspice RELTOL (default 1e-3)")
    parser.add_argument("--spice-method", default=None, choices=["trap", "gear"], help="ngspice METHOD (default gear)")


def spice_options(args, period: float):
    """The SpiceOptions the --spice-* flags ask for (None: none given)."""
    from ..ngspice import spice_settings
    return spice_settings(period, args.spice_tmax, args.spice_reltol, args.spice_method)


def check_out(path: Path | None, suffixes=(".csv", ".parquet"), flag: str = "--out") -> None:
    """A waveform file option, before the run: its suffix, and a target pcsuite may write (a new or regular file in
    a writable directory: :func:`validation.io.check_output_file`); a CSV's metadata sidecar FILE.csv.json too."""
    if path is None:
        return
    if path.suffix.lower() not in suffixes:
        raise ParameterError(f"{flag} must end in {' or '.join(suffixes)}; got {str(path)!r}")
    from ..io import check_output_file
    check_output_file(flag, path)
    if path.suffix.lower() == ".csv":
        check_output_file(flag, path.with_name(path.name + ".json"))


#: Units of waveform columns by name (states by their first letter: i* currents, v* voltages).
_UNITS = {"time": "s", "vout": "V", "iref": "A", "switch": "1", "mode": ""}


def column_units(columns) -> dict:
    return {c: _UNITS.get(c, "A" if c.startswith("i") else "V" if c.startswith("v") else "") for c in columns}


#: Rows pandas formats at a time while a CSV streams to its file: its text takes ~800 bytes a row while formatted,
#: so pandas' default (100,000 rows over the columns) held ~1.3 times the file; 4,000 rows hold a few MB and write
#: as fast (1 M rows of four waveforms: 6.0 s against 5.9 s).
CSV_CHUNK_ROWS = 4000


def write_frame(frame, path: Path, meta: dict | None = None) -> None:
    """A waveform table as CSV or Parquet, written atomically (never a partial file in place of a good one).
    ``meta`` (converter, parameters, method and its options) and the columns' units (default: a converter's,
    by :func:`column_units`) travel with it: in the
    Parquet schema's metadata (key ``pcsuite``), or in a JSON sidecar ``FILE.csv.json`` beside a CSV. A CSV
    streams to its file (:data:`CSV_CHUNK_ROWS`): built whole as text, then as bytes, a sliding-mode boost's 60 ms
    (577 MB of CSV) had peaked at 2.4 GB; streamed, 1.4 GB."""
    from ..io import atomic_write_bytes, atomic_write_files, parquet_bytes
    meta = dict(meta or {})
    meta.setdefault("units", column_units(frame.columns))
    info = json_text(meta).encode()
    if path.suffix.lower() == ".csv":
        if "mode" in frame:
            frame = frame.assign(mode=frame["mode"].astype(str))
        atomic_write_files({path: lambda handle: frame.to_csv(handle, index=False, encoding="utf-8",
                                                              chunksize=CSV_CHUNK_ROWS),
                            path.with_name(path.name + ".json"): info})        # streamed, and landing together
        return
    atomic_write_bytes(path, parquet_bytes(frame, info))


def _plain(value):
    try:
        return float(value)
    except (TypeError, ValueError):
        return str(value)


def json_text(value) -> str:
    """Strict JSON (RFC 8259: what json.loads with parse_constant refusing, jq and browsers all read): NaN and the
    infinities, which JSON has no words for, become null (an efficiency at D = 0, a z that overflows); numpy
    scalars and arrays become numbers and lists; anything else its float, else its str."""
    import json
    return json.dumps(_finite(value), allow_nan=False, default=lambda v: _finite(_plain(v)))


def _finite(value):
    import math

    import numpy as np
    if isinstance(value, dict):
        return {key: _finite(v) for key, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    if isinstance(value, np.ndarray):
        return _finite(value.tolist())
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    return value
