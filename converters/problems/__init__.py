"""Problems: linear complementarity systems and the laws that switch their configurations."""
from .lcs import Configuration, LCSProblem
from .schedule import Schedule

__all__ = ["Configuration", "LCSProblem", "Schedule"]
