"""The cam-follower at 358 rpm against Siconos' own Moreau-Jean run, and against the event method (the h -> 0 limit).

Run: .venv/bin/python benchmarks/cam_siconos.py [--h H] [--t-end T]. Needs Debian's python3-siconos for the system
Python (``make bench`` installs it); prints measured numbers only.

Siconos' distributed CamFollower example does not drive the follower (its external-force plugin returns -m g with
g = 0), so the follower is written here with siconos.kernel as the problem pcsuite solves: in the gap coordinate
z = x - c(t) (c the cam's lift) the follower is m z'' + k z = F(t), F = -(k c + m c''), with z >= 0 and Newton's
restitution e = 0.8 on z' (LagrangianLinearTIDS, LagrangianLinearTIR, NewtonImpactNSL, MoreauJeanOSI(0.5), LCP,
TimeStepping), the forcing averaged over each step (the mean of c by 4-point Gauss-Legendre, of c'' exactly:
(c'(t + h) - c'(t)) / h) and set as the step's constant external force. pcsuite's Moreau-Jean runs the same h in
the absolute coordinate x with the moving constraint x - c(t) >= 0; the event method locates each impact exactly.
Printed: the largest |x| difference over the run, the impacts each finds (an impact: a step whose impulse is
positive while the gap closes faster than 1e-3 of the largest rate), and how many steps apart they are.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from record import Figures

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
SYSTEM_PYTHON = "/usr/bin/python3"

SICONOS_SCRIPT = r'''
import json, sys, time
import numpy as np
import siconos.kernel as sk
spec = json.load(open(sys.argv[1]))
force = np.load(sys.argv[2])
h, m, k, e = spec["h"], spec["m"], spec["k"], spec["e"]
steps = force.size
clock = time.perf_counter()
ds = sk.LagrangianLinearTIDS([spec["z0"]], [spec["v0"]], [[m]], [[k]], [[0.0]])
ds.setFExtPtr(np.array([force[0]]))
relation = sk.LagrangianLinearTIR(np.array([[1.0]]))
interaction = sk.Interaction(sk.NewtonImpactNSL(e), relation)
nsds = sk.NonSmoothDynamicalSystem(0.0, steps * h)
nsds.insertDynamicalSystem(ds)
nsds.link(interaction, ds)
simulation = sk.TimeStepping(nsds, sk.TimeDiscretisation(0.0, h), sk.MoreauJeanOSI(0.5), sk.LCP())
out = np.zeros((steps + 1, 3))
out[0] = [spec["z0"], spec["v0"], 0.0]
for j in range(steps):
    ds.setFExtPtr(np.array([force[j]]))       # the step's mean force, constant over it
    simulation.computeOneStep()
    out[j + 1] = [ds.q()[0], ds.velocity()[0], interaction.lambda_(1)[0]]
    simulation.nextStep()
np.save(sys.argv[3], out)
print(json.dumps({"wall_s": time.perf_counter() - clock, "steps": steps}))
'''


def impacts(t, rate_before, impulse) -> np.ndarray:
    """Step-end times where an impulse acts on a gap closing faster than 1e-3 of the largest rate (a contact resting
    on the cam, pressed with a small impulse, is not an impact)."""
    closing = rate_before < -1e-3 * np.abs(rate_before).max()
    return t[1:][(impulse[1:] > 0) & closing[:-1]]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--h", type=float, default=1e-4)
    parser.add_argument("--t-end", type=float, default=1.0)
    args = parser.parse_args(argv)
    from converters.methods import EventDriven, MoreauJean
    from converters.models.mechanics import get_mechanical
    from converters.simulate import simulate
    model = get_mechanical("cam-follower")
    p = model.resolve({"rpm": 358})
    h, steps = args.h, int(round(args.t_end / args.h))
    t = h * np.arange(steps + 1)
    cam = model.offset(p)
    nodes, weights = np.polynomial.legendre.leggauss(4)
    mid = t[:-1] + 0.5 * h
    mean_c = sum(w * cam.position(mid + 0.5 * h * x)[0] for x, w in zip(nodes, weights)) / 2.0
    c, c1, _ = cam.position(t)
    force = -(p["k"] * mean_c + p["m"] * np.diff(c1) / h)

    simulate(model.problem(p, 10 * h), MoreauJean(h=h))          # its compiled loop loaded: the run below is timed warm
    ours = simulate(model.problem(p, args.t_end), MoreauJean(h=h))
    assert ours.t.size == t.size and np.allclose(ours.t, t, rtol=0, atol=1e-12 * args.t_end)
    exact = simulate(model.problem(p, args.t_end), EventDriven()).events
    exact_impacts = exact.loc[exact["kind"] == "impact", "time"].to_numpy()
    ours_impacts = ours.events.loc[ours.events["kind"] == "impact", "time"].to_numpy()
    figures = Figures("cam_siconos", "the cam-follower at 358 rpm: pcsuite's Moreau-Jean against Siconos' own")
    case = f"cam-follower, 358 rpm, h = {h:g} s over {args.t_end:g} s ({steps:,} steps)"
    figures.add("pcsuite_loop_ms", ours.wall_s * 1e3, "ms", f"{case}: pcsuite's Moreau-Jean (theta 0.5), warm, one run")
    figures.add("pcsuite_impacts", ours_impacts.size, "", f"{case}: impacts pcsuite's Moreau-Jean finds", digits=1)
    figures.add("event_impacts", exact_impacts.size, "", f"{case}: impacts the event method finds", digits=1)

    probe = subprocess.run([SYSTEM_PYTHON, "-c", "import siconos.kernel"], capture_output=True, text=True)
    if probe.returncode != 0:
        print("Siconos: python3-siconos is not installed for the system Python (make bench installs it); "
              f"pcsuite's Moreau-Jean found {ours_impacts.size} impacts, the event method {exact_impacts.size}")
        figures.save()
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        (work / "cam.py").write_text(SICONOS_SCRIPT)
        (work / "spec.json").write_text(json.dumps({"h": h, "m": p["m"], "k": p["k"], "e": p["e"],
                                                    "z0": 0.0, "v0": 0.0}))
        np.save(work / "force.npy", force)
        done = subprocess.run([SYSTEM_PYTHON, str(work / "cam.py"), str(work / "spec.json"), str(work / "force.npy"),
                               str(work / "out.npy")], capture_output=True, text=True, check=True)
        run = np.load(work / "out.npy")
        wall = json.loads(done.stdout)["wall_s"]
    x_siconos = run[:, 0] + c
    difference = np.abs(x_siconos - ours.x[:, 0])
    siconos_impacts = impacts(t, run[:, 1], run[:, 2])

    def apart(found, reference):
        """For each reference impact, the nearest found one, in steps."""
        if not found.size:
            return np.full(reference.size, np.inf)
        return np.array([np.abs(found - r).min() / h for r in reference])

    print(f"cam-follower, 358 rpm, h = {h:g} s over {args.t_end:g} s ({steps:,} steps); Siconos 4.4 MoreauJeanOSI(0.5) "
          f"in the gap coordinate {1e3 * wall:.0f} ms (its loop), pcsuite Moreau-Jean {1e3 * ours.wall_s:.1f} ms (warm)")
    print(f"  follower position: largest |x_siconos - x_pcsuite| {difference.max():.3g} m (at t = "
          f"{t[np.argmax(difference)]:.4f} s; the lift is {c.max() - c.min():.3g} m)")
    print(f"  impacts: event method {exact_impacts.size}, pcsuite Moreau-Jean {ours_impacts.size}, Siconos "
          f"{siconos_impacts.size}; before the first detachment (0.028 s): pcsuite at "
          f"{[round(float(v), 5) for v in ours_impacts[ours_impacts < 0.028]]} s, Siconos at "
          f"{[round(float(v), 5) for v in siconos_impacts[siconos_impacts < 0.028]]} s")
    for name, found in (("pcsuite Moreau-Jean", ours_impacts), ("Siconos", siconos_impacts)):
        steps_apart = apart(found, exact_impacts[:10])
        print(f"  {name}: its nearest impact to each of the event method's first 10, in steps: "
              + " ".join(f"{s:.1f}" for s in steps_apart))
    both = apart(siconos_impacts, ours_impacts)
    print(f"  pcsuite's impacts against Siconos': {int((both <= 2).sum())} of {both.size} within two steps "
          f"(largest {both.max():.1f} steps)")
    figures.add("siconos_loop_ms", wall * 1e3, "ms",
                f"{case}: Siconos 4.4's MoreauJeanOSI(0.5) in the gap coordinate, its time loop alone, one run")
    figures.add("siconos_ratio", wall / ours.wall_s, "x", f"{case}: Siconos' loop time over pcsuite's Moreau-Jean")
    figures.add("siconos_impacts", siconos_impacts.size, "", f"{case}: impacts Siconos' run shows", digits=1)
    figures.add("impacts_within_two_steps", int((both <= 2).sum()), "",
                f"{case}: pcsuite's impacts within two steps of one of Siconos'", digits=1)
    figures.add("impacts_largest_apart_steps", both.max(), "",
                f"{case}: the largest distance, in steps, from one of pcsuite's impacts to the nearest of Siconos'",
                digits=2)
    figures.save()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
