"""Closed-form CCM/DCM relations of the PWM converters (small-ripple approximations: Erickson and Maksimovic, Fundamentals of Power Electronics, 2nd ed., ch. 5).

K = 2 L / (R T) (Cuk: L = Le = L1 L2 / (L1 + L2)); DCM when K < Kcrit(D). M = Vout / Vin with its sign.
DCM interval fractions: D1 = D (switch on), D2 (diode conducting, from volt-second balance), D3 =
1 - D - D2 (idle: inductor current, or Cuk's i1 + i2, held at zero).

Each converter states its own four relations beside its model (:class:`SmallRipple`: ``k_crit``, ``ccm_ratio``,
``dcm_ratio``, ``dcm_diode_fraction``, and the inductance K is built on); what follows from them is written once
here, and the functions below look a converter up by its name (the registry its class joins).
"""
from __future__ import annotations

import math
from typing import Any

from ..errors import ParameterError

#: The converters with closed forms, by name (filled as their classes are defined).
CLOSED_FORMS: dict[str, type[SmallRipple]] = {}


class SmallRipple:
    """A converter's CCM/DCM closed forms: the relations a subclass gives, and what follows from them."""

    name: str = ""
    closed_form = True

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if cls.__dict__.get("name"):
            CLOSED_FORMS[cls.name] = cls

    @staticmethod
    def k_inductance(p: dict) -> float:
        """The inductance of K (the converter's L)."""
        return p["L"]

    @staticmethod
    def k_crit(D: float) -> float:
        raise NotImplementedError

    @staticmethod
    def ccm_ratio(D: float) -> float:
        raise NotImplementedError

    @classmethod
    def ccm_duty(cls, ratio: float) -> float | None:
        """The duty ratio whose CCM conversion ratio |M| is ``ratio`` (None where none in (0, 1) gives it): a
        closed loop's starting guess for its operating point."""
        g = lambda D: abs(cls.ccm_ratio(D)) - ratio           # noqa: E731
        if not (math.isfinite(ratio) and g(1e-9) * g(1 - 1e-9) < 0):
            return None
        from scipy.optimize import brentq
        return brentq(g, 1e-9, 1 - 1e-9)

    @staticmethod
    def dcm_ratio(D: float, K: float) -> float:
        raise NotImplementedError

    @staticmethod
    def dcm_diode_fraction(D: float, M: float) -> float:
        """D2 from volt-second balance, |M| the DCM ratio's magnitude."""
        raise NotImplementedError

    @classmethod
    def k_factor(cls, p: dict) -> float:
        return 2.0 * cls.k_inductance(p) * p["f_sw"] / p["R"]

    @classmethod
    def predicted_mode(cls, p: dict) -> str:
        """'CCM' or 'DCM' from K against Kcrit(D). D = 0 never conducts in DCM sense: CCM by convention."""
        return "DCM" if 0.0 < p["D"] < 1.0 and cls.k_factor(p) < cls.k_crit(p["D"]) else "CCM"

    @classmethod
    def conversion_ratio(cls, p: dict, mode: str | None = None) -> float:
        """M = Vout / Vin (signed) in the predicted (or the given) mode."""
        D = p["D"]
        if (mode or cls.predicted_mode(p)) == "CCM":
            return cls.ccm_ratio(D)
        return cls.dcm_ratio(D, cls.k_factor(p))

    @classmethod
    def dcm_fractions(cls, p: dict) -> tuple[float, float, float]:
        """(D1, D2, D3): switch-on, diode-conducting and idle fractions of the period in DCM."""
        D = p["D"]
        M = abs(cls.conversion_ratio(p, "DCM"))
        D2 = cls.dcm_diode_fraction(D, M) if M else 0.0
        return D, D2, max(0.0, 1.0 - D - D2)


def finite_ratio(name: str, D: float) -> None:
    """A CCM ratio with 1 - D in its denominator needs D below 1."""
    if D >= 1.0:
        raise ParameterError(f"D must be below 1 for a finite {name} CCM ratio; got {D!r}")


class InvertingRatios(SmallRipple):
    """The inverting converters' relations (buck-boost; the Cuk's with its effective inductance in K)."""

    @staticmethod
    def k_crit(D: float) -> float:
        return (1.0 - D) ** 2

    @classmethod
    def ccm_ratio(cls, D: float) -> float:
        finite_ratio(cls.name, D)
        return -D / (1.0 - D)

    @staticmethod
    def dcm_ratio(D: float, K: float) -> float:
        return -D / math.sqrt(K)

    @staticmethod
    def dcm_diode_fraction(D: float, M: float) -> float:
        return D / M


def has_closed_form(topology: str) -> bool:
    """True for the converters with CCM/DCM closed forms (buck, boost, buck-boost, Cuk)."""
    return topology in CLOSED_FORMS


def _forms(topology: str) -> type[SmallRipple]:
    if topology not in CLOSED_FORMS:
        raise ParameterError(f"converter must be one of {', '.join(CLOSED_FORMS)} for the CCM/DCM formulas; "
                             f"got {topology!r}")
    return CLOSED_FORMS[topology]


def k_factor(p: dict, topology: str) -> float:
    """K = 2 L / (R T), with the effective Le = L1 L2 / (L1 + L2) for the Cuk converter."""
    return _forms(topology).k_factor(p)


def k_crit(D: float, topology: str) -> float:
    return _forms(topology).k_crit(D)


def predicted_mode(p: dict, topology: str) -> str:
    """'CCM' or 'DCM' from K against Kcrit(D). D = 0 never conducts in DCM sense: CCM by convention."""
    return _forms(topology).predicted_mode(p)


def conversion_ratio(p: dict, topology: str, mode: str | None = None) -> float:
    """M = Vout / Vin (signed) in the predicted (or the given) mode."""
    return _forms(topology).conversion_ratio(p, mode)


def dcm_fractions(p: dict, topology: str) -> tuple[float, float, float]:
    """(D1, D2, D3): switch-on, diode-conducting and idle fractions of the period in DCM."""
    return _forms(topology).dcm_fractions(p)
