"""A period map's Floquet multipliers from its Jacobian. Plain numpy, in a module of its own: compiled callers
(:mod:`converters.sweeps.batch`) wrap :func:`spectral_radius` with numba's njit, and numba caches that beside this
file, so an edit to the shooting code (:mod:`.periodic`) leaves every compiled kernel current."""
from __future__ import annotations

import numpy as np


def multipliers_of(jacobian: np.ndarray) -> np.ndarray:
    """Eigenvalues sorted by decreasing modulus."""
    values = np.linalg.eigvals(jacobian)
    return values[np.argsort(-np.abs(values), kind="stable")]


def spectral_radius(jac: np.ndarray) -> float:
    """max |eigenvalue| of jac, in complex arithmetic (a real matrix may have complex roots)."""
    return np.abs(np.linalg.eigvals(jac.astype(np.complex128))).max()
