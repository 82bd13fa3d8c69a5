"""Problems: linear complementarity systems and the laws that switch their configurations."""
from .lcs import Configuration, Jump, LCSProblem, Sinusoids
from .schedule import Schedule
from .switching import Ramp, Relay, StateSwitching, SwitchingFunction

__all__ = ["Configuration", "Jump", "LCSProblem", "Sinusoids", "Schedule", "StateSwitching", "Relay", "SwitchingFunction", "Ramp"]
