"""Closed-form CCM/DCM relations of the PWM converters (small-ripple approximations: Erickson and Maksimovic, Fundamentals of Power Electronics, 2nd ed., ch. 5).

K = 2 L / (R T) (Cuk: L = Le = L1 L2 / (L1 + L2)); DCM when K < Kcrit(D). M = Vout / Vin with its sign.
DCM interval fractions: D1 = D (switch on), D2 (diode conducting, from volt-second balance), D3 =
1 - D - D2 (idle: inductor current, or Cuk's i1 + i2, held at zero).
"""
from __future__ import annotations

import math

from ..errors import ParameterError

TOPOLOGIES = ("buck", "boost", "buck-boost", "cuk")


def has_closed_form(topology: str) -> bool:
    """True for the converters with CCM/DCM closed forms (buck, boost, buck-boost, Cuk)."""
    return topology in TOPOLOGIES


def _check(topology):
    if topology not in TOPOLOGIES:
        raise ParameterError(f"converter must be one of {', '.join(TOPOLOGIES)} for the CCM/DCM formulas; "
                             f"got {topology!r}")


def k_factor(p: dict, topology: str) -> float:
    """K = 2 L / (R T), with the effective Le = L1 L2 / (L1 + L2) for the Cuk converter."""
    _check(topology)
    inductance = p["L1"] * p["L2"] / (p["L1"] + p["L2"]) if topology == "cuk" else p["L"]
    return 2.0 * inductance * p["f_sw"] / p["R"]


def k_crit(D: float, topology: str) -> float:
    _check(topology)
    return {"buck": 1.0 - D, "boost": D * (1.0 - D) ** 2}.get(topology, (1.0 - D) ** 2)


def predicted_mode(p: dict, topology: str) -> str:
    """'CCM' or 'DCM' from K against Kcrit(D). D = 0 never conducts in DCM sense: CCM by convention."""
    return "DCM" if 0.0 < p["D"] < 1.0 and k_factor(p, topology) < k_crit(p["D"], topology) else "CCM"


def conversion_ratio(p: dict, topology: str, mode: str | None = None) -> float:
    """M = Vout / Vin (signed) in the predicted (or the given) mode."""
    D, K = p["D"], k_factor(p, topology)
    mode = mode or predicted_mode(p, topology)
    if mode == "CCM":
        if topology == "buck":
            return D
        if D >= 1.0:
            raise ParameterError(f"D must be below 1 for a finite {topology} CCM ratio; got {D!r}")
        return 1.0 / (1.0 - D) if topology == "boost" else -D / (1.0 - D)
    if topology == "buck":
        return 2.0 / (1.0 + math.sqrt(1.0 + 4.0 * K / D ** 2))
    if topology == "boost":
        return (1.0 + math.sqrt(1.0 + 4.0 * D ** 2 / K)) / 2.0
    return -D / math.sqrt(K)


def dcm_fractions(p: dict, topology: str) -> tuple[float, float, float]:
    """(D1, D2, D3): switch-on, diode-conducting and idle fractions of the period in DCM."""
    D = p["D"]
    M = abs(conversion_ratio(p, topology, "DCM"))
    D2 = {"buck": D * (1.0 - M) / M, "boost": D / (M - 1.0)}.get(topology, D / M) if M else 0.0
    return D, D2, max(0.0, 1.0 - D - D2)
