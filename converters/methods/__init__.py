"""Methods: each validates its options, declares its order and solves a problem into a Trajectory.

Importing this package registers them in :data:`converters.methods.base.METHODS` (``lcp``, ``event``,
``smooth``), the names the command line offers."""
from .base import METHODS, Method, get_method
from .theta import BackwardEuler, Theta
from .event import EventDriven
from .smoothing import Smoothing

__all__ = ["Method", "METHODS", "get_method", "Theta", "BackwardEuler", "EventDriven", "Smoothing"]
