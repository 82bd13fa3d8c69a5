"""Problems: linear complementarity systems and the laws that switch their configurations."""
from .lcs import Configuration, LCSProblem
from .schedule import Schedule
from .switching import Ramp, Relay, StateSwitching, SwitchingFunction

__all__ = ["Configuration", "LCSProblem", "Schedule", "StateSwitching", "Relay", "SwitchingFunction", "Ramp"]
