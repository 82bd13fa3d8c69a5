"""Parallel resonant converter with a diode-bridge rectifier (Siconos tutorial PowerConverter/PRC), compiled from
``netlists/circuits/prc.cir``.

x = (ir, vr, iLf, vo): resonant-tank current and voltage, output-filter inductor current and output
voltage; the bridge's four diodes in the order D1, D3, D2, D4, each port as the compiler chooses it (D3 and D4
carry their currents in u, D1 and D2 their reverse voltages); the drive is a square wave +-Vin at f_sw
(configuration 0 positive half, 1 negative half). D is skew, so every step is a monotone LCP of size 4
(Siconos' PowerConverter/PRC example, after Merillas, Fossas and Batlle).
"""
from __future__ import annotations

import itertools
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from ..problems import Schedule
from ..params import positive
from .base import Converter
from .netlist import FromNetlist

if TYPE_CHECKING:
    from ..trajectory import Samples


class PRC(FromNetlist, Converter):
    name = "prc"
    title = "parallel resonant converter with diode bridge"
    parameters = (
        positive("Vin", 1.0, "V", "square-wave drive amplitude"),
        positive("Lr", 150e-6, "H", "resonant inductance"),
        positive("Cr", 68e-9, "F", "resonant capacitance"),
        positive("Lf", 0.4e-3, "H", "output-filter inductance"),
        positive("Cf", 2.2e-6, "F", "output-filter capacitance"),
        positive("R", 33.0, "ohm", "load resistance"),
        positive("f_sw", 55e3, "Hz", "drive frequency"),
        positive("n", 1.0, "", "transformer ratio"),
    )
    state_names = ("ir", "vr", "iLf", "vo")
    output_state = "vo"
    pair_names = ("D1", "D3", "D2", "D4")
    netlist_file = "prc.cir"
    netlist_states = ("i(lr)", "v(cr)", "i(lf)", "v(cf)")
    configuration_names = ("drive+", "drive-")
    schedule_parameters = frozenset()

    def schedule(self, p: dict) -> Schedule:
        return Schedule.pwm(self.period(p), 0.5, on=0, off=1)

    #: Every subset of the bridge's diodes that can conduct, by name ("D1+D4"), and DCM (none).
    mode_labels = tuple("+".join(sorted(c)) for k in (1, 2, 3, 4) for c in itertools.combinations(("D1", "D2", "D3", "D4"), k)) + ("DCM",)
    #: The drive's half-periods are not diode turn-offs: no turn-off instants are compared.
    turn_off_label = None
    #: The ideal tank keeps a ~1e-4 V cycle-to-cycle jitter: compare the Siconos scene, 2 ms from rest.
    compare_defaults = {"start": "rest", "periods": 110, "window": 55}

    def output_node_current(self, samples: Samples) -> np.ndarray:
        return samples.x[:, 2]

    def vout(self, samples: Samples, p: dict) -> np.ndarray:
        return samples.x[:, 3]

    def modes(self, conducting: npt.NDArray[np.bool_], switch: npt.NDArray[Any],
              x: npt.NDArray[np.float64]) -> npt.NDArray[Any]:
        """Named by the bridge's conducting diodes (``D1+D4``: the pair that carries the tank current one way,
        ``D2+D3`` the other); all four off is DCM (the output capacitor alone feeds the load)."""
        conducting = np.asarray(conducting, dtype=bool)
        labels = np.full(conducting.shape[0], "DCM", dtype=object)
        for pattern in np.unique(conducting, axis=0):
            if pattern.any():
                name = "+".join(sorted(n for n, on in zip(self.pair_names, pattern) if on))
                labels[(conducting == pattern).all(axis=1)] = name
        return labels
