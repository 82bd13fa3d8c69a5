"""Parameter sweeps of the converter models: points (a grid, a Latin hypercube) and the converters'
ensemble (:class:`.ensemble.ModelSweep`: a row of steady-state metrics per point, batched where it can be).
The backends they run on are :mod:`converters.parallel`'s (re-exported here)."""
from ..parallel import BACKENDS, LocalBackend, Lost, ProcessSlot, backend_for, default_workers, parallel_map, run_ensemble
from .ensemble import ModelSweep, failed_row
from .points import Axis, Grid, LatinHypercube

__all__ = ["run_ensemble", "backend_for", "BACKENDS", "ModelSweep", "failed_row", "LocalBackend", "Lost",
           "ProcessSlot", "default_workers", "parallel_map", "Axis", "Grid", "LatinHypercube"]
