"""Methods: each validates its options and solves a problem into a Trajectory."""
from .event import EventDriven
from .smoothing import Smoothing
from .theta import BackwardEuler, Theta

__all__ = ["Theta", "BackwardEuler", "EventDriven", "Smoothing"]
