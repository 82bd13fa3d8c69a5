"""Where the heat goes: devices mounted on heatsinks, heatsinks to the ambient, and the junction temperatures in
steady state.

A device's junction reaches its case through its description's chain (R_jc), its case the heatsink through an
interface (R_ch), the heatsink the ambient through R_ha; devices on one heatsink share it. A device with no
heatsink has its case held at the ambient. In the periodic steady state the thermal time constants (ms to
minutes) are far longer than a switching period (us), so the temperatures follow the period's average losses
(time-scale separation): T_hs = T_a + R_ha sum P, T_c = T_hs + R_ch P, T_j = T_c + R_jc P. The losses depend on
T_j through the tables, so the two are iterated to a fixed point (:meth:`ThermalSetup.steady`); a loop whose
loss grows faster with T_j than the heat can leave (R dP/dT_j >= 1) runs away and is refused.

The setup file (TOML; paths relative to it)::

    ambient = 40.0                       # degC
    [heatsinks.hs1]  R = 2.0, C = 50.0   # K/W to the ambient, J/K (C: the heatsink's time constant R C)
    [devices.s1]     description = "q1.toml", heatsink = "hs1", interface = 0.5    # K/W case to heatsink
"""
from __future__ import annotations

import tomllib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ParameterError, SimulationError
from ..validate import quoted
from .description import MAX_BYTES, DeviceDescription, read_description

#: The fixed point stops when no junction temperature moves more than this (K).
TJ_TOL = 1e-6
MAX_ITERATIONS = 200


@dataclass(frozen=True)
class Heatsink:
    R: float            # K/W to the ambient
    C: float = 0.0      # J/K


@dataclass(frozen=True)
class Mount:
    description: DeviceDescription
    heatsink: str | None = None      # None: the case held at the ambient
    interface: float = 0.0           # K/W, case to heatsink


@dataclass(frozen=True)
class ThermalSteady:
    """Temperatures (degC) and average losses (W) per device at the fixed point, and how it was reached."""

    junction: dict[str, float]
    case: dict[str, float]
    heatsink: dict[str, float]
    losses: dict[str, Any]
    iterations: int
    moved: float                      # the last iteration's largest change of a junction temperature (K)


@dataclass(frozen=True)
class ThermalSetup:
    ambient: float
    devices: dict[str, Mount]
    heatsinks: dict[str, Heatsink] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not np.isfinite(self.ambient) or not -273.15 < self.ambient < 1000.0:
            raise ParameterError(f"ambient must be a temperature in (-273.15, 1000) degC; got {self.ambient!r}")
        for name, mount in self.devices.items():
            if mount.heatsink is not None and mount.heatsink not in self.heatsinks:
                raise ParameterError(f"device {name}: heatsink {mount.heatsink!r} is not defined (heatsinks: "
                                     f"{', '.join(self.heatsinks) or 'none'})")
            if not (np.isfinite(mount.interface) and mount.interface >= 0):
                raise ParameterError(f"device {name}: interface must be a resistance >= 0 K/W; got {mount.interface!r}")
            if mount.description.thermal is None:
                raise ParameterError(f"device {name}: its description ({mount.description.name}) has no thermal chain "
                                     "(junction to case)")
        for name, sink in self.heatsinks.items():
            if not (np.isfinite(sink.R) and sink.R > 0 and np.isfinite(sink.C) and sink.C >= 0):
                raise ParameterError(f"heatsink {name}: R must be > 0 K/W and C >= 0 J/K; got R = {sink.R!r}, "
                                     f"C = {sink.C!r}")

    def temperatures(self, power: Mapping[str, float]) -> tuple[dict[str, float], dict[str, float], dict[str, float]]:
        """(junction, case, heatsink) temperatures (degC) in steady state at the devices' average losses (W)."""
        sinks = {name: self.ambient + sink.R * sum(power[d] for d, m in self.devices.items() if m.heatsink == name)
                 for name, sink in self.heatsinks.items()}
        case = {d: (sinks[m.heatsink] if m.heatsink else self.ambient) + m.interface * power[d]
                for d, m in self.devices.items()}
        junction = {d: case[d] + m.description.thermal.resistance * power[d]   # type: ignore[union-attr]
                    for d, m in self.devices.items()}
        return junction, case, sinks

    @cached_property
    def resistances(self) -> np.ndarray:
        """M (K/W): the junctions' rises over the ambient are M P for the devices' losses P (in ``devices``' order)."""
        names = list(self.devices)
        zero = {d: 0.0 for d in names}
        return np.column_stack([np.array([self.temperatures({**zero, d: 1.0})[0][k] for k in names]) - self.ambient
                                for d in names])

    def steady(self, losses_at: Callable[[dict[str, float]], Mapping[str, Any]],
               totals_at: Callable[[dict[str, float]], Mapping[str, float]] | None = None) -> ThermalSteady:
        """The junction temperatures and the losses at them: ``losses_at(tj)`` gives each device's losses (an
        object with ``total_W``) at junction temperatures ``tj`` (``totals_at(tj)``, where given, only their
        totals: the iterations need no more). The losses are linear in T_j between the tables' temperatures, so a
        first step solves the linear system their values at T_a and T_a + 1 K give (T = T_a + M (P_a + B (T -
        T_a)), M the resistances from the devices' powers to their junctions); from there the fixed point T = T_a +
        M P(T) is iterated until no temperature moves more than TJ_TOL."""
        names = list(self.devices)
        if totals_at is None:
            def totals_at(tj: dict[str, float]) -> dict[str, float]:
                return {d: losses.total_W for d, losses in losses_at(tj).items()}
        ambient = {d: self.ambient for d in names}
        M = self.resistances
        at_a = totals_at(ambient)
        above = totals_at({d: self.ambient + 1.0 for d in names})
        P_a = np.array([at_a[d] for d in names])
        B = np.diag([above[d] - at_a[d] for d in names])
        gain = M @ B
        tj = ambient
        # the spectral radius below 1 (a row-sum norm below 1 bounds it: no eigenvalues needed)
        if gain.size and (np.abs(gain).sum(axis=1).max() < 1.0 or np.max(np.abs(np.linalg.eigvals(gain))) < 1.0):
            rise = np.linalg.solve(np.eye(len(names)) - gain, M @ P_a)
            tj = {d: self.ambient + float(r) for d, r in zip(names, rise)}
        moved, previous = np.inf, np.inf
        for iteration in range(1, MAX_ITERATIONS + 1):
            totals = totals_at(tj)
            power = np.array([totals[d] for d in names])
            junction = dict(zip(names, (self.ambient + M @ power).tolist()))
            moved = max(abs(junction[d] - tj[d]) for d in names)
            if moved <= TJ_TOL:
                return ThermalSteady(tj, *self.temperatures(dict(zip(names, power.tolist())))[1:],
                                     dict(losses_at(tj)), iteration + 2, moved)
            tj = junction
            if iteration > 3 and moved >= previous:
                break
            previous = moved
        raise SimulationError(f"thermal runaway: the junction temperatures do not settle (the last step moved them "
                              f"{moved:.3g} K after {iteration} iterations): the losses grow with the temperature "
                              "faster than the heat can leave (R_th dP/dT_j >= 1); a larger heatsink or a lower load")


def read_setup(path: str | Path) -> ThermalSetup:
    """A thermal setup file (TOML): its devices' descriptions are read relative to it. Read once per process while
    the file is unchanged (a sweep's points read it at each)."""
    path = Path(path)
    try:
        stat = path.stat()
    except OSError as error:
        raise ParameterError(f"cannot read the thermal setup {quoted(path)}: {error.strerror}") from None
    return _read_setup(str(path), stat.st_size, stat.st_mtime_ns)


@lru_cache(maxsize=8)
def _read_setup(name: str, size: int, mtime: int) -> ThermalSetup:
    path = Path(name)
    try:
        if path.stat().st_size > MAX_BYTES:
            raise ParameterError(f"{quoted(path)}: larger than a thermal setup holds ({MAX_BYTES} bytes at most)")
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as error:
        raise ParameterError(f"cannot read the thermal setup {quoted(path)}: {error.strerror}") from None
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as error:
        raise ParameterError(f"{quoted(path)}: not a TOML file ({error})") from None
    where = quoted(path)
    unknown = set(doc) - {"ambient", "heatsinks", "devices"}
    if unknown:
        raise ParameterError(f"{where}: unknown key {sorted(unknown)[0]!r} (read: ambient, [heatsinks.NAME], "
                             "[devices.NAME])")
    if not isinstance(doc.get("devices"), dict) or not doc["devices"]:
        raise ParameterError(f"{where}: at least one [devices.NAME] table (NAME a switch or diode of the netlist)")
    heatsinks = {}
    for name, table in doc.get("heatsinks", {}).items():
        _keys(table, {"R", "C"}, f"{where} [heatsinks.{name}]")
        heatsinks[name] = Heatsink(_number(table, "R", where, name), _number(table, "C", where, name, 0.0))
    devices = {}
    for name, table in doc["devices"].items():
        _keys(table, {"description", "heatsink", "interface"}, f"{where} [devices.{name}]")
        text = table.get("description")
        if not isinstance(text, str) or not text:
            raise ParameterError(f"{where} [devices.{name}]: description = \"FILE.xml\" or \"FILE.toml\" (relative to "
                                 "the setup file) is needed")
        devices[name.lower()] = Mount(read_description(path.parent / text), table.get("heatsink"),
                                      _number(table, "interface", where, name, 0.0))
    return ThermalSetup(_number(doc, "ambient", where, "", 25.0), devices, heatsinks)


def _keys(table: Any, known: set[str], where: str) -> None:
    if not isinstance(table, dict):
        raise ParameterError(f"{where} must be a table")
    unknown = set(table) - known
    if unknown:
        raise ParameterError(f"{where}: unknown key {sorted(unknown)[0]!r} (read: {', '.join(sorted(known))})")


def _number(table: Mapping[str, Any], key: str, where: str, name: str, default: float | None = None) -> float:
    value = table.get(key, default)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(f"{where}{f' {name}' if name else ''}: {key} must be a number; got {value!r}")
    return float(value)


#: A netlist names its thermal setup on a comment line (ngspice reads it as a comment): ``*pcsuite thermal FILE``.
DIRECTIVE = "*pcsuite thermal"


@lru_cache(maxsize=16)
def declared_setup(text: str, source: str | Path) -> Path | None:
    """The thermal setup a netlist (its ``text``, read from ``source``) names on a ``*pcsuite thermal FILE.toml``
    line: a file beside the netlist, by its bare name; None where it names none. Kept per text (a sweep's points
    ask at each)."""
    for number, line in enumerate(text.splitlines(), 1):
        if line.lower().startswith(DIRECTIVE):
            name = line[len(DIRECTIVE):].strip()
            if not name or Path(name).name != name or name in (".", ".."):
                raise ParameterError(f"{quoted(source)}:{number}: {DIRECTIVE} takes the bare name of a file beside "
                                     f"the netlist; got {name!r}")
            return Path(source).with_name(name)
    return None


@dataclass(frozen=True)
class ThermalTransient:
    """Temperatures (degC) at times t (s) after a change of the losses: per device its junction, per heatsink its
    own; and each device's losses (W) along them."""

    t: np.ndarray
    junction: dict[str, np.ndarray]
    heatsink: dict[str, np.ndarray]
    losses: dict[str, np.ndarray]


def thermal_transient(setup: ThermalSetup, losses_at: Callable[[dict[str, float]], Mapping[str, Any]],
                      start: Mapping[str, float], t_end: float, points: int = 400) -> ThermalTransient:
    """The temperatures after the losses change at t = 0 from a steady state with junctions at ``start``
    (degC; the chains and heatsinks in equilibrium there) to ``losses_at(tj)`` (the losses of the circuit after the
    change at junction temperatures tj), over [0, t_end] on a logarithmic grid of ``points`` from t_end / 1e7.

    Each device's chain is read relative to its case (a Foster chain has no physical inner nodes: the usual reading;
    a Cauer ladder the same way), the case an interface R above its heatsink, a heatsink with its C an R C to the
    ambient (with C = 0, at its steady value at once). The network is linear with the losses as its input, so each
    step of the grid is the exact exponential of the network with the losses held at the step's start (exponential
    Euler: exact for losses that do not change with the temperature)."""
    if not (np.isfinite(t_end) and t_end > 0):
        raise ParameterError(f"t_end must be a duration > 0 s; got {t_end!r}")
    grid = np.concatenate([[0.0], np.geomspace(t_end * 1e-7, t_end, points - 1)])
    return _integrate(setup, grid, lambda tj, step: losses_at(tj), _steady_losses(setup, start), dict(start))


def _integrate(setup: ThermalSetup, grid: np.ndarray, losses_at: Callable[[dict[str, float], int], Mapping[str, Any]],
               power: np.ndarray, tj: dict[str, float]) -> ThermalTransient:
    """The network from equilibrium at the losses ``power`` (junctions at ``tj``) over ``grid``: over each of its
    intervals the exact exponential of the network with the losses ``losses_at(tj, k)`` held (k the interval's
    index, tj the junctions at its start; exponential Euler)."""
    from scipy.linalg import expm
    names = list(setup.devices)
    blocks, index = [], {}
    for d in names:
        chain = setup.devices[d].description.thermal
        assert chain is not None                      # ThermalSetup refuses a device without one
        if chain.kind == "foster":
            R, tau = chain.foster()
            A = np.diag(-1.0 / tau)
            b = R / tau                               # C_k d theta_k/dt = P - theta_k / R_k, C_k = tau_k / R_k
        else:
            A, b = chain._ladder()
        index[d] = (sum(len(x[1]) for x in blocks), len(b))
        blocks.append((A, b))
    sinks = [h for h in setup.heatsinks if setup.heatsinks[h].C > 0]
    n = sum(len(b) for _, b in blocks) + len(sinks)
    A = np.zeros((n, n))
    B = np.zeros((n, len(names)))
    for k, (d, (a, b)) in enumerate(zip(names, blocks)):
        i, m = index[d]
        A[i:i + m, i:i + m] = a
        B[i:i + m, k] = b
    offset = n - len(sinks)
    for j, h in enumerate(sinks):
        sink = setup.heatsinks[h]
        A[offset + j, offset + j] = -1.0 / (sink.R * sink.C)
        for k, d in enumerate(names):
            if setup.devices[d].heatsink == h:
                B[offset + j, k] = 1.0 / sink.C

    def temperatures(x: np.ndarray, power: np.ndarray) -> tuple[dict[str, float], dict[str, float]]:
        total = {h: sum(power[k] for k, d in enumerate(names) if setup.devices[d].heatsink == h)
                 for h in setup.heatsinks}
        sink = {h: setup.ambient + (x[offset + sinks.index(h)] if h in sinks else setup.heatsinks[h].R * total[h])
                for h in setup.heatsinks}
        junction = {}
        for k, d in enumerate(names):
            mount, (i, m) = setup.devices[d], index[d]
            case = (sink[mount.heatsink] if mount.heatsink else setup.ambient) + mount.interface * power[k]
            rise = x[i:i + m].sum() if mount.description.thermal.kind == "foster" else x[i]
            junction[d] = case + rise
        return junction, sink

    # the start: the network in equilibrium at ``power``
    x = np.linalg.solve(A, -B @ power)
    points = grid.size
    junction = {d: np.empty(points) for d in names}
    heat = {h: np.empty(points) for h in setup.heatsinks}
    lost = {d: np.empty(points) for d in names}
    propagators: dict[float, np.ndarray] = {}          # equal intervals (a run's periods): one exponential
    for step, t in enumerate(grid):
        if step:
            h = float(t - grid[step - 1])
            if h not in propagators:
                propagators[h] = expm(A * h)
            E = propagators[h]
            x = E @ x + np.linalg.solve(A, (E - np.eye(n)) @ (B @ power))
            tj, sink = temperatures(x, power)
        losses = losses_at(tj, step)
        power = np.array([losses[d].total_W for d in names])
        tj, sink = temperatures(x, power)
        for k, d in enumerate(names):
            junction[d][step], lost[d][step] = tj[d], power[k]
        for h in setup.heatsinks:
            heat[h][step] = sink[h]
    return ThermalTransient(grid, junction, heat, lost)


def thermal_cosimulation(setup: ThermalSetup, windows: Sequence[tuple[float, float, Mapping[str, Any]]],
                         start: Mapping[str, float] | None = None) -> ThermalTransient:
    """The temperatures along an electrical run, the thermal network stepped with it: ``windows`` are the run's
    consecutive intervals (t0, t1, {device: its :class:`.losses.Waveforms` there}), each device's losses over an
    interval read from its tables at its junction temperature at the interval's start and held over it (the
    network's exact exponential: exact for losses that do not change with the temperature). From the network in
    equilibrium with the junctions at ``start`` (default: every node at the ambient, a cold start). The times are the
    windows' bounds; the junctions' ripple within a window (a switching period) is not resolved, its average
    heating is."""
    if not windows:
        raise ParameterError("a thermal co-simulation needs at least one window of the run")
    names = list(setup.devices)
    tj = {d: setup.ambient for d in names} if start is None else dict(start)
    power = _steady_losses(setup, tj)
    grid = np.array([windows[0][0]] + [t1 for _, t1, _ in windows])

    def losses_at(tj: dict[str, float], k: int) -> dict[str, Any]:
        read = windows[min(k, len(windows) - 1)][2]          # at the last bound: the last window's
        return {d: read[d].losses(tj[d]) for d in names}
    out = _integrate(setup, grid - grid[0], losses_at, power, tj)
    return ThermalTransient(grid, out.junction, out.heatsink, out.losses)


def _steady_losses(setup: ThermalSetup, start: Mapping[str, float]) -> np.ndarray:
    """The devices' losses (W) in the steady state whose junctions are at ``start``: the temperatures are linear in
    the losses (T = T_a + M P), so P = M^-1 (T - T_a)."""
    return np.linalg.solve(setup.resistances, np.array([start[d] for d in setup.devices]) - setup.ambient)
