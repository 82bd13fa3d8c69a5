"""Where runs execute: serial, this machine's processes (:mod:`.local`, the default, no server) or a Dask
cluster (:mod:`.cluster`); :func:`.engine.run_ensemble` streams an ensemble's rows over any of them. Below
the analysis layer, so periodic-orbit diagrams and validation maps run on it too."""
from .engine import BACKENDS, backend_for, run_ensemble
from .local import LocalBackend, Lost, ProcessSlot, default_workers, parallel_map

__all__ = ["run_ensemble", "backend_for", "BACKENDS", "LocalBackend", "Lost", "ProcessSlot", "default_workers",
           "parallel_map"]
