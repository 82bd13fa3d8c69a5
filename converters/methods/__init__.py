"""Methods: each validates its options, declares its order and solves a problem into a Trajectory.

Importing this package registers them in :data:`converters.methods.base.METHODS` (``lcp``, ``event``,
``smooth``, ``moreau``), the names the command line offers (each method's ``domains`` says which problems
it takes: the converters' LCS, mechanical problems, or both). Every run allocates its result arrays afresh:
importing the methods asks malloc to keep freed memory for the next run
(:func:`converters.limits.keep_freed_memory`)."""
from ..limits import keep_freed_memory
from .base import METHODS, Method, get_method
from .theta import BackwardEuler, Theta
from .event import EventDriven
from .smoothing import Smoothing
from .moreau import MoreauJean

keep_freed_memory()

__all__ = ["Method", "METHODS", "get_method", "Theta", "BackwardEuler", "EventDriven", "Smoothing", "MoreauJean"]
