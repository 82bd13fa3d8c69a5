"""The report's section on device losses and junction temperatures: the shipped 48 V synchronous buck
(``netlists/circuits/sync-buck-thermal.cir``), its losses by device and kind, its junction temperatures, and an
efficiency map over input voltage and load, each checked."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from .report import Section, csv_bytes, figure_png, table_html, url

NETLIST = Path(__file__).resolve().parents[1] / "netlists" / "circuits" / "sync-buck-thermal.cir"
TITLE = "Losses and junction temperatures: a 48 V synchronous buck"
#: The efficiency map's grid: input voltage (V) and load (ohm).
MAP_VIN = (36.0, 60.0, 7)
MAP_R = (1.2, 6.0, 7)
#: The checks: the balance's residual against the input (the stepper's own balance), the stepper's losses and
#: temperatures against the exact method's (a second resolution), the junction temperatures against the closed form.
BALANCE_REL = 1e-5
AGREEMENT_REL = 1e-3
TJ_K = 1e-4


def thermal_section() -> Section:
    from converters.models import get_model
    from converters.run import run_converter
    from converters.sweeps import Axis, Grid, ModelSweep
    from converters.parallel import run_ensemble
    from converters.thermal.network import declared_setup, read_setup
    from converters.thermal.summary import thermal_summary
    model = get_model(str(NETLIST))
    p = model.resolve({})
    setup = read_setup(declared_setup(model.netlist.text, model.source))
    # the default stepper, and the exact method as the second resolution of every loss
    lcp, exact = (thermal_summary(model, p, run_converter(model, p, steady=True, method=m), setup)
                  for m in ("lcp", "event"))
    rows = []
    for name, d in lcp["devices"].items():
        off = d.get("recovery_W", d.get("turn_off_W"))
        rows.append({"device": name, "description": d["name"], "conduction (W)": d["conduction_W"],
                     "turn-on (W)": d["turn_on_W"], "turn-off / recovery (W)": off, "total (W)": d["total_W"],
                     "exact method's total (W)": exact["devices"][name]["total_W"], "junction (degC)": d["tj_C"],
                     "case (degC)": d["case_C"]})
    table = pd.DataFrame(rows)
    total = float(table["total (W)"].sum())
    sink = lcp["heatsinks_C"]["hs1"]
    closed = [setup.ambient + setup.heatsinks["hs1"].R * total
              + (setup.devices[d].interface + setup.devices[d].description.thermal.resistance) * w
              for d, w in zip(table["device"], table["total (W)"])]
    tj_error = float(np.max(np.abs(np.array(closed) - table["junction (degC)"].to_numpy())))
    scale = max(total, 1e-300)
    agreement = max(abs(lcp["devices"][d]["total_W"] - exact["devices"][d]["total_W"]) / scale for d in lcp["devices"])
    power = lcp["power"]
    balance = abs(power["balance_W"]) / power["input_W"]
    checks = pd.DataFrame([
        {"check": "power balance: |input - output - losses| / input (the stepper's own balance)", "value": balance,
         "limit": BALANCE_REL, "result": "pass" if balance <= BALANCE_REL else "fail"},
        {"check": "each device's losses, the stepper at T/1000 against the exact method, over the total", "value":
         agreement, "limit": AGREEMENT_REL, "result": "pass" if agreement <= AGREEMENT_REL else "fail"},
        {"check": "junction temperatures against T_a + R_ha sum P + (R_ch + R_jc) P (K)", "value": tj_error,
         "limit": TJ_K, "result": "pass" if tj_error <= TJ_K else "fail"}])
    cycling, settle = _load_step(model, p, setup, lcp)
    checks = pd.concat([checks, pd.DataFrame([
        {"check": "after a step from half to full load, the junctions 5 heatsink time constants on against the full "
                  "load's steady state, over the step's rise", "value": settle, "limit": 0.01,
         "result": "pass" if settle <= 0.01 else "fail"}])], ignore_index=True)
    grid = Grid([Axis.parse(f"Vin={MAP_VIN[0]}:{MAP_VIN[1]}:{MAP_VIN[2]}"),
                 Axis.parse(f"R={MAP_R[0]}:{MAP_R[1]}:{MAP_R[2]}")])
    sweep = ModelSweep(str(NETLIST), h_fraction=1e-3, metrics=("thermal.efficiency", "tj.max"))
    swept = pd.DataFrame(run_ensemble(sweep, grid, backend="serial"))
    failed = int((swept["status"] != "ok").sum())
    files = {"thermal_losses.png": _losses_figure(table), "thermal_efficiency_map.png": _map_figure(swept),
             "thermal_load_step.png": cycling,
             "thermal_devices.csv": csv_bytes(table), "thermal_checks.csv": csv_bytes(checks),
             "thermal_efficiency_map.csv": csv_bytes(swept)}
    text = (f"<p>{NETLIST.name}: 48 V to 12 V, 10 A, 100 kHz, two MOSFETs with their body diodes on one heatsink "
            f"(2 K/W to a {setup.ambient:g} degC ambient), their losses from illustrative thermal descriptions (not "
            "a vendor's parts) read at each junction temperature, the temperatures and the losses iterated to a fixed "
            "point. The switches are ideal in the circuit, as in PLECS: the source delivers the circuit's input plus "
            f"the devices' losses. Efficiency {100 * power['efficiency']:.3f} %, devices' losses {total:.4g} W, "
            f"heatsink {sink:.2f} degC.</p>" + table_html(checks, "result", good=("pass",)) + table_html(table)
            + f'<img src="{url("thermal_losses.png")}" alt="losses by device and kind">'
            + f"<p>The efficiency with the devices' losses over input voltage and load ({len(swept)} steady states, "
              f"{failed} failed), and the hottest junction:</p>"
            + f'<img src="{url("thermal_efficiency_map.png")}" alt="efficiency map">'
            + "<p>A load step from half (2.4 ohm) to full load (1.2 ohm): each junction and the heatsink from the "
              "half load's steady state, the losses after the step read at the junctions' temperatures as they rise "
              "(the electrical steady state is reached in milliseconds, the thermal one in minutes):</p>"
            + f'<img src="{url("thermal_load_step.png")}" alt="junction temperatures after a load step">')
    ok = bool((checks["result"] == "pass").all()) and failed == 0
    return Section(TITLE, text, files, ok=ok, metrics={"efficiency": power["efficiency"], "device_losses_W": total,
                                                       "tj_max_C": float(table["junction (degC)"].max())})


def _load_step(model, p: dict, setup, full: dict) -> tuple[bytes, float]:
    """The junctions after a step from half to full load (the figure) and how far from the full load's steady state
    they are 5 heatsink time constants on, over the step's rise (the check)."""
    import matplotlib.pyplot as plt

    from converters.run import run_converter
    from converters.thermal.losses import waveforms
    from converters.thermal.network import thermal_transient
    from converters.thermal.summary import thermal_summary
    half = {**p, "r": 2.0 * p["r"]}
    start = {d: v["tj_C"] for d, v in thermal_summary(model, half, run_converter(model, half, steady=True),
                                                      setup)["devices"].items()}
    tr = run_converter(model, p, steady=True)
    T, t1 = model.period(p), float(tr.t[-1])
    read = waveforms(model, p, tr, {d: m.description for d, m in setup.devices.items()}, t1 - T, t1)
    tau = max(sink.R * sink.C for sink in setup.heatsinks.values())
    run = thermal_transient(setup, lambda tj: {d: w.losses(tj[d]) for d, w in read.items()}, start, 5.0 * tau)
    settle = max(abs(run.junction[d][-1] - full["devices"][d]["tj_C"]) / max(abs(full["devices"][d]["tj_C"]
                                                                                  - start[d]), 1e-12)
                 for d in setup.devices)
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    for d, values in run.junction.items():
        ax.semilogx(run.t[1:], values[1:], label=f"{d} junction")
    for h, values in run.heatsink.items():
        ax.semilogx(run.t[1:], values[1:], "k--", label=f"heatsink {h}")
    ax.set_xlabel("time after the step (s)")
    ax.set_ylabel("temperature (degC)")
    ax.set_title("half to full load: junctions and heatsink")
    ax.legend(fontsize=8)
    return figure_png(fig), float(settle)


def _losses_figure(table: pd.DataFrame) -> bytes:
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 3.4))
    bottom = np.zeros(len(table))
    for column in ("conduction (W)", "turn-on (W)", "turn-off / recovery (W)"):
        ax.bar(table["device"], table[column], bottom=bottom, label=column.replace(" (W)", ""))
        bottom += table[column].to_numpy()
    for x, (tj, top) in enumerate(zip(table["junction (degC)"], bottom)):
        ax.annotate(f"{tj:.1f} degC", (x, top), ha="center", va="bottom", fontsize=8)
    ax.set_ylabel("loss (W)")
    ax.set_title("losses by device and kind, junction temperatures")
    ax.legend(fontsize=8)
    return figure_png(fig)


def _map_figure(swept: pd.DataFrame) -> bytes:
    import matplotlib.pyplot as plt
    ok = swept[swept["status"] == "ok"]
    vin, load = np.unique(ok["Vin"]), np.unique(ok["R"])
    eff = ok.pivot(index="R", columns="Vin", values="thermal.efficiency").to_numpy()
    tj = ok.pivot(index="R", columns="Vin", values="tj.max").to_numpy()
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6))
    for ax, values, label in ((axes[0], 100 * eff, "efficiency (%)"), (axes[1], tj, "hottest junction (degC)")):
        shown = ax.contourf(vin, load, values, levels=12)
        fig.colorbar(shown, ax=ax, label=label)
        ax.set_xlabel("input voltage (V)")
        ax.set_ylabel("load (ohm)")
    axes[0].set_title("efficiency with the devices' losses (D = 0.25: vout = Vin / 4)")
    axes[1].set_title("hottest junction")
    fig.subplots_adjust(wspace=0.5)
    return figure_png(fig)
