"""Problems: linear complementarity systems and the laws that switch their configurations."""
from .lcs import Configuration, Jump, LCSProblem, Sinusoids
from .schedule import Schedule
from .switching import Comparators, Ramp, Relay, StateSwitching, SwitchingFunction

__all__ = ["Configuration", "Jump", "LCSProblem", "Sinusoids", "Schedule", "StateSwitching", "Comparators", "Relay", "SwitchingFunction", "Ramp"]
