"""The ``pcsuite`` command line: one module per subcommand. Bad input exits 2 with one line naming the
parameter, its valid range and the value received."""
from __future__ import annotations

import argparse
import sys

from converters.errors import ParameterError, PcsuiteError, TimeLimitReached

from . import (bench, bifurcation, bode, compare, gdcm, gdcm_map, lcp, listing, mech, netlist, report, sensitivity,
               simulate, sweep, view)
from .common import EXIT_BAD_INPUT, EXIT_INTERRUPTED

#: A command that is one run stops at a x --time-limit + b s: its ngspice run or LCP solve, timed from its own start,
#: reports its own limit first (with its partial answer); the alarm stops anything else (parsing, a simulation).
ALARM_GRACE = (1.05, 0.5)
#: The subcommands, in the order ``pcsuite --help`` lists them.
SUBCOMMANDS = (listing, simulate, lcp, compare, gdcm, gdcm_map, sweep, bifurcation, bode, sensitivity, mech, netlist,
               report, bench, view)


def main(argv=None) -> int:
    import warnings
    warnings.formatwarning = _one_line          # a warning (a bad tuning variable, ...) is one line, like an error
    code = 1
    stdout = sys.stdout
    # what a command prints of a user's names (a file's, an element's) reaches the terminal with its control
    # characters escaped, as its errors do (an ESC in a netlist's file name recoloured bode's header)
    if stdout is not None:                      # (None where the process has no stdout: print is then a no-op)
        sys.stdout = _Escaping(stdout)
    try:
        code = _main(argv)
        return code
    finally:
        sys.stdout = stdout
        compile_module = sys.modules.get("converters.circuits.compile")
        if argv is None and compile_module is not None and compile_module.ABANDONED:
            # a factorisation the time limit stopped waiting for ran on in LAPACK: the interpreter's exit then
            # faulted (a segmentation fault after the one line, exit 139); end the process as it stands
            import os
            sys.stdout.flush(), sys.stderr.flush()
            os._exit(code)
        import signal
        signal.setitimer(signal.ITIMER_REAL, 0.0)      # a --time-limit alarm ends with its command
        # the interpreter's last collection would walk every large result just to free it at exit (0.2-0.3 s
        # for a 500k-step run): freeze them out of its sight; the OS reclaims the memory
        import gc
        gc.freeze()


def _one_line(message, category, filename, lineno, line=None) -> str:
    return f"pcsuite: warning: {printable(str(message))}\n"


class _Escaping:
    """A text stream that writes what :func:`printable` escapes as escapes, a newline and a tab kept (tables, lines);
    text that is all printable (nearly all of it) is passed as it is."""

    def __init__(self, stream) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        if not text.replace("\n", "").replace("\t", "").isprintable():
            text = "".join(c if c.isprintable() or c in "\n\t" else repr(c)[1:-1] for c in text)
        return self._stream.write(text)

    def writelines(self, lines) -> None:
        for line in lines:
            self.write(line)

    def __getattr__(self, name: str):
        return getattr(self._stream, name)


def printable(text: str) -> str:
    """``text`` with its control characters written as escapes (an ESC byte in an element's name reached the
    terminal raw: a netlist could recolour or rewrite what the user reads)."""
    return "".join(c if c.isprintable() or c == "\n" else repr(c)[1:-1] for c in text)


def _main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not hasattr(args, "run"):
        # as argparse says a missing argument (usage and error on stderr, exit 2), in the project's one line
        usage = " ".join(parser.format_usage().split()).removeprefix("usage: ")
        parser.error(f"a command is required: usage: {usage} (pcsuite --help lists them)")
    try:
        _apply_limits(args)
        return args.run(args) or 0
    except BrokenPipeError:  # e.g. `pcsuite list | head`
        sys.stderr.close()
        return 0
    except (PcsuiteError, ValueError, TimeLimitReached) as exc:
        import signal
        signal.setitimer(signal.ITIMER_REAL, 0.0)       # a time limit's re-armed alarm: its one line is this one
        print(f"pcsuite: error: {printable(str(exc))}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:   # Ctrl-C: one line, the shell's code for SIGINT (outputs are written atomically)
        print("pcsuite: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


class Parser(argparse.ArgumentParser):
    """argparse with the project's one-line errors (no usage dump)."""

    def error(self, message):
        self.exit(EXIT_BAD_INPUT, f"pcsuite: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(prog="pcsuite", description="Power-converter study suite: LCP time-stepping of DC-DC "
                                                "converters cross-checked against ngspice.")
    sub = parser.add_subparsers(title="commands", parser_class=Parser)
    for command in SUBCOMMANDS:
        command.add(sub)
    for command in _leaf_parsers(sub):
        _add_limits(command)
    return parser


def _leaf_parsers(sub):
    """Every subcommand's parser (``mech simulate``, ``lcp solve``, ... included)."""
    for parser in sub.choices.values():
        nested = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        if nested:
            yield from _leaf_parsers(nested[0])
        else:
            yield parser


def _add_limits(parser) -> None:
    from converters.limits import DEFAULT_MAX_MEMORY, human_bytes
    parser.add_argument("--max-memory", default=None, metavar="SIZE",
                        help=f"refuse a run estimated to allocate more than SIZE (default {human_bytes(DEFAULT_MAX_MEMORY)}"
                             "; 512M, 4G, ...; workers inherit it)")
    parser.add_argument("--time-limit", default=None, metavar="S",
                        help="seconds one run may take: the whole of simulate, mech simulate, lcp solve, bode and "
                             "sensitivity; each "
                             "ngspice run and each iterative LCP solve of the other commands (defaults: ngspice 600 s, "
                             "an LCP solve 20 s)")


def _apply_limits(args) -> None:
    """--max-memory and --time-limit, set in the environment so that every worker process sees them. A command
    that is one run (simulate, mech simulate, lcp solve, bode, sensitivity) also gets an alarm just after its
    --time-limit (``ALARM_GRACE``): the run stops there with one line (a compiled loop is stopped when it returns; the memory
    limit bounds its length)."""
    import os

    from converters.limits import TIME_ENV, max_memory, set_max_memory, set_time_limit, time_limit
    time_limit(0.0)             # PCSUITE_TIME_LIMIT (or the variable's absence) checked before anything runs
    if getattr(args, "max_memory", None) is not None:
        set_max_memory(args.max_memory)
    else:
        max_memory()            # PCSUITE_MAX_MEMORY too, whether or not this command checks a run's size
    seconds, source = None, "--time-limit"
    if getattr(args, "time_limit", None) is not None:
        refused = getattr(args, "no_time_limit", False)
        if refused(args) if callable(refused) else refused:
            raise ParameterError(f"--time-limit bounds ngspice runs and LCP solves; this command runs neither (got "
                                 f"--time-limit {args.time_limit})")
        seconds = set_time_limit(args.time_limit)
    elif os.environ.get(TIME_ENV):          # the variable limits one run as the flag does
        seconds, source = time_limit(0.0), TIME_ENV
    if seconds is not None and getattr(args, "one_run", False):
        import signal                       # a backstop: an ngspice run or an LCP solve reports its own limit first
        from converters.limits import install_compile_clock
        install_compile_clock()             # the limit leaves out numba's compiles (importing numba: ~0.3 s)
        signal.signal(signal.SIGALRM, _time_is_up(seconds, source))
        signal.setitimer(signal.ITIMER_REAL, ALARM_GRACE[0] * seconds + ALARM_GRACE[1])


def _time_is_up(seconds: float, source: str = "--time-limit"):
    """The alarm's handler: the run stops with one line, unless this thread spent time in numba's compiler since the
    alarm was set (a first run on a cold cache): then the alarm is put off by that time, which the limit leaves
    out."""
    import signal
    import threading

    from converters.limits import compile_seconds
    thread = threading.get_ident()
    granted = [compile_seconds(thread)]

    def handler(signum, frame):
        owed = compile_seconds(thread) - granted[0]
        if owed > 1e-3:
            granted[0] += owed
            signal.setitimer(signal.ITIMER_REAL, owed)
            return
        # again in a second, should a library's bare except on the way up swallow the stop and carry on
        signal.setitimer(signal.ITIMER_REAL, 1.0)
        raise TimeLimitReached(f"the run did not finish within the time limit of {seconds:g} s ({source}); "
                               "raise it, or ask for a shorter run (--t-end, --periods) or a coarser one")
    return handler
