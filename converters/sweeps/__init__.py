"""Ensembles of runs over parameter points and the backends that carry them out: serial, batched, this
machine's processes (:mod:`.local`, the default) or a Dask cluster (:mod:`.cluster`)."""
from .engine import BACKENDS, backend_for, run_ensemble
from .ensemble import ModelSweep, failed_row
from .local import LocalBackend, Lost, ProcessSlot, default_workers, parallel_map
from .points import Axis, Grid, LatinHypercube

__all__ = ["run_ensemble", "backend_for", "BACKENDS", "ModelSweep", "failed_row", "LocalBackend", "Lost",
           "ProcessSlot", "default_workers", "parallel_map", "Axis", "Grid", "LatinHypercube"]
