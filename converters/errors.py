"""Exception types of pcsuite.

Every error subclasses a built-in (``ValueError`` or ``RuntimeError``) so callers can catch
them naturally, and every message names the parameter, its valid range and the value received.
"""


class PcsuiteError(Exception):
    """Base class of every pcsuite error."""


class ParameterError(PcsuiteError, ValueError):
    """A parameter is missing, of the wrong shape, non-finite or outside its valid range."""


class LCPError(PcsuiteError, ValueError):
    """A linear complementarity problem is malformed or could not be solved."""


class SimulationError(PcsuiteError, RuntimeError):
    """A run failed part-way (the message says where and what to try)."""


class ResourceError(ParameterError):
    """A run would exceed a resource limit (memory it would allocate, or an LCP solve's time); the message names the
    limit and the flag that raises it (``--max-memory``, ``--time-limit``)."""


class TimeLimitReached(BaseException):
    """A command's --time-limit passed while it ran (raised by the alarm the command line sets). A BaseException, as
    KeyboardInterrupt is: the alarm lands anywhere, and a handler of a failed trial, point or section (``except
    ParameterError``, ``except Exception``) must not take the command's end for its own failure and carry on."""


class SignalError(KeyError, ParameterError):
    """A signal or state name a trajectory does not have: a KeyError (a lookup by name) that is also a
    ParameterError, so the command line reports it in one line; its text is the message, not its repr."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""
