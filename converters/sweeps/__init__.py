"""Ensembles of runs over parameter points and the backends that carry them out (today: one machine's
processes, :mod:`.local`)."""
from .local import default_workers, parallel_map

__all__ = ["parallel_map", "default_workers"]
