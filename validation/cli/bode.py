"""``pcsuite bode CONVERTER|FILE.cir --input D|Vin|control|loop --output vout``: the exact small-signal frequency
response about the periodic orbit (:mod:`converters.analysis.smallsignal`), a loop gain's margins, and the
brute-force injection beside it (``--check``)."""
from __future__ import annotations

import time

from converters.errors import ParameterError

from .common import (add_params, add_unstable_option, circuit_notes, given_path, integer, json_text, on_exact_orbit,
                     orbit_stability)

#: What --input accepts beside a parameter's name: the duty ratio, the input voltage and the load current (the
#: output impedance's input, 0 A unless -p Io= says otherwise) by their usual names.
ALIASES = {"duty": "D", "vin": "Vin", "iload": "Io"}
#: --input's loop gains by where the loop is broken: at the comparator, or at a voltage loop's reference (its
#: outer loop under current-mode control).
LOOPS = {"loop": "comparator", "vloop": "reference"}
#: Frequencies the brute-force check measures (log-spaced over the response's range, the last below fs/2).
CHECK_POINTS = 8


def add(sub) -> None:
    from converters.models import CONTROLS
    bode = sub.add_parser("bode", help="exact small-signal frequency responses and loop gains about the periodic orbit")
    bode.add_argument("converter")
    add_params(bode)
    bode.add_argument("--control", default="pwm", choices=list(CONTROLS),
                      help="the control law around the converter (default pwm: open loop)")
    bode.add_argument("--input", default=None,
                      help="what is perturbed: duty (the duty ratio D), vin, iload (a load current: -vout/iload is the "
                           "output impedance), any source's value or parameter the circuit is affine in (Vref, a "
                           "netlist's V1), control (a comparator's input), loop (the loop gain T of a "
                           "state-driven law broken at its comparator, with its margins) or vloop (a voltage loop's "
                           "gain broken at its reference: the outer loop of --control current-loop)")
    bode.add_argument("--output", default="vout", help="what is read: vout (default), a state (iL, vC) or a signal "
                                                      "(v(NODE), i(ELEMENT) of a netlist)")
    bode.add_argument("--fmin", default=None, help="lowest frequency in Hz (default fs/1000; SPICE suffixes: 10k)")
    bode.add_argument("--fmax", default=None, help="highest frequency in Hz (default fs/2)")
    bode.add_argument("--points", type=integer(1, 100_000), default=200,
                      help="log-spaced frequencies (default 200; 1 with --fmin F --fmax F: that frequency alone)")
    bode.add_argument("--design", default=None, metavar="fc=F,pm=DEG[,type=3]",
                      help="with --control voltage-loop: design its compensator (type III by default, or type=2) by the "
                           "k-factor method on the exact control-to-output response for crossover F (Hz) and phase "
                           "margin DEG, and give the loop gain it closes, with its margins, beside the plant's")
    bode.add_argument("--check", action="store_true",
                      help=f"also inject a sinusoid at {CHECK_POINTS} frequencies, simulate each to its periodic steady "
                           "state (exact event method) and print its fundamental beside the exact response")
    add_unstable_option(bode)
    bode.add_argument("--plot", type=given_path, default=None, help="write the Bode plot to FILE.png or FILE.svg")
    bode.add_argument("--json", action="store_true", help="print one JSON object (frequency_hz, magnitude_db, "
                                                         "phase_deg, margins of a loop gain, the check)")
    bode.set_defaults(run=on_exact_orbit("bode", run), one_run=True)


def run(args) -> int:
    import numpy as np

    from converters.analysis.smallsignal import (FrequencyResponse, SmallSignalModel, frequencies, injection_response,
                                                 loop_from_closed, loop_signals, margins)
    from converters.params import parse_assignments
    from converters.run import resolve_model
    from converters.validate import parse_value, quoted

    from ..io import atomic_write_bytes, check_output_file
    check_output_file("--plot", args.plot)
    if args.plot is not None and args.plot.suffix.lower() not in (".png", ".svg"):
        raise ParameterError(f"--plot must end in .png or .svg; got {str(args.plot)!r}")
    model = resolve_model(args.converter, args.control)
    params = parse_assignments(args.params)
    if args.design is not None:
        return _design(args, model, params)
    if args.input is None:
        raise ParameterError("--input is required (duty, vin, iload, a parameter, control or loop), or --design")
    at = LOOPS.get(args.input.lower())
    loop = at is not None
    if loop and args.output != "vout":
        raise ParameterError(f"--input {args.input} reads the loop's own signal; --output does not apply (got "
                             f"{args.output!r})")
    name, output = loop_signals(at) if loop else (ALIASES.get(args.input.lower(), args.input), args.output)
    if name == "Io" and "Io" in {q.name for q in model.parameters}:
        params.setdefault("Io", 0.0)          # the load current's operating point: none beside R
    fmin = None if args.fmin is None else parse_value("--fmin", args.fmin)
    fmax = None if args.fmax is None else parse_value("--fmax", args.fmax)
    start = time.perf_counter()
    small = SmallSignalModel(model, params, input=name, outputs=(output,))
    stability = orbit_stability("frequency responses", model.key, small.orbit.multipliers, small.T, args.unstable,
                                small.orbit.warning, small.border())
    stability.update(circuit_notes(model, params))
    model_s = time.perf_counter() - start
    start = time.perf_counter()
    f = frequencies(small.T, fmin, fmax, args.points)

    def gain(freq):           # the loop gain from the closed loop's response at the break point (Middlebrook)
        return loop_from_closed(small.response(freq, output), at)
    values = gain(f) if loop else small.response(f, output)
    response = FrequencyResponse(f, values, args.input.lower() if loop else name, output,
                                 "loop gain" if loop else "transfer",
                                 small.T, small.orbit.multipliers, *_units(model, small, name, output, loop))
    exact_s = time.perf_counter() - start
    summary = {"converter": model.key, "params": {k: v for k, v in small.params.items() if v is not None},
               **response.as_dict(), **stability, "model_s": model_s, "response_s": exact_s}
    found = margins(gain, f) if loop else None
    if found is not None:
        summary["margins"] = found.as_dict()
    check = None
    if args.check:
        start = time.perf_counter()
        top = min(f[-1], 0.49 / small.T)
        bottom = min(f[0], top)
        f_check = np.geomspace(bottom, top, CHECK_POINTS if bottom < top else 1)
        f_used, measured = injection_response(small, f_check, output)
        if loop:
            measured = loop_from_closed(measured, at)
        exact = gain(f_used) if loop else small.response(f_used, output)
        check = (f_used, measured)
        summary["check"] = {"frequency_hz": f_used.tolist(), "exact_db": (20 * np.log10(np.abs(exact))).tolist(),
                            "injected_db": (20 * np.log10(np.abs(measured))).tolist(),
                            "difference_db": (20 * np.log10(np.abs(measured / exact))).tolist(),
                            "difference_deg": np.degrees(np.angle(measured / exact)).tolist(),
                            "check_s": time.perf_counter() - start}
    if args.plot is not None:
        from ..plots import bode_figure
        atomic_write_bytes(args.plot, bode_figure(response, check, found, args.plot.suffix.lower().lstrip(".")))
        summary["plot"] = str(args.plot)
    if args.json:
        print(json_text(summary))
        return 0
    _print(response, summary, found)
    if args.plot is not None:
        print(f"wrote {quoted(args.plot)}")
    return 0


def _units(model, small, name, output, loop) -> tuple:
    from converters.analysis.smallsignal import quantity_unit
    if loop:
        return "", ""
    return quantity_unit(model, small.params, name), quantity_unit(model, small.params, output)


def _print(response, summary: dict, found) -> None:
    import numpy as np
    f, mag, phase = response.frequency_hz, response.magnitude_db, response.phase_deg
    what = "loop gain T" if response.kind == "loop gain" else f"{response.output} / {response.input}"
    unit = f" ({response.output_unit}/{response.input_unit})" if response.output_unit and response.input_unit else ""
    rho = float(np.abs(response.multipliers).max())
    print(f"{summary['converter']}: {what}{unit}, exact small-signal model about the periodic orbit (T = "
          f"{response.period:.6g} s, spectral radius {rho:.4g}): the orbit and its linearisation in "
          f"{summary['model_s'] * 1e3:.1f} ms, {f.size} frequenc{'y' if f.size == 1 else 'ies'} in "
          f"{summary['response_s'] * 1e3:.1f} ms")
    rows = np.unique(np.round(np.linspace(0, f.size - 1, min(f.size, 11))).astype(int))
    print(f"  {'f (Hz)':>12} {'|H| (dB)':>10} {'phase (deg)':>12}")
    for i in rows:
        print(f"  {f[i]:12.5g} {mag[i]:10.3f} {phase[i]:12.2f}")
    if rows.size < f.size:
        print(f"  ({rows.size} of the {f.size} frequencies shown; --json holds every one)")
    if np.any(f >= 0.5 / response.period * (1 - 1e-9)):
        # a sampled system's response at fs/2 folds onto itself: an injection's phase decides what it reads (a
        # voltage-mode buck: 9.20 dB with a sine injection, 5.75 dB with a cosine, -3.49 dB at 45 degrees; the
        # model's 4.81 dB is their average over the phase, a tester's injections found)
        print("  (at and above fs/2 an injection's response depends on its phase against the switching: the value "
              "shown is the model's, averaged over that phase)")
    if found is not None:
        print(f"  crossover {found.crossover_hz:.6g} Hz, phase margin {found.phase_margin_deg:.4g} deg; phase crossover "
              f"{found.phase_crossover_hz:.6g} Hz, gain margin {found.gain_margin_db:.4g} dB (nan: none in the range)")
    check = summary.get("check")
    if check:
        print(f"check: a sinusoid injected at {len(check['frequency_hz'])} "
              f"frequenc{'y' if len(check['frequency_hz']) == 1 else 'ies'}, each simulated to its periodic "
              f"steady state (exact event method), in {check['check_s']:.2f} s:")
        print(f"  {'f (Hz)':>12} {'exact (dB)':>11} {'injected (dB)':>14} {'diff (dB)':>10} {'diff (deg)':>11}")
        for row in zip(check["frequency_hz"], check["exact_db"], check["injected_db"], check["difference_db"],
                       check["difference_deg"]):
            print(f"  {row[0]:12.5g} {row[1]:11.4f} {row[2]:14.4f} {row[3]:10.2e} {row[4]:11.2e}")


def _design_options(text: str) -> dict:
    """fc=F,pm=DEG[,type=2|3][,ri=OHM] as {"crossover_hz", "phase_margin_deg", "kind", "ri"} (ri: the op-amp
    circuit's input resistor, 10 kohm unless given)."""
    from converters.validate import parse_value
    out, names = {"kind": "type3", "ri": 10e3}, {"fc": "crossover_hz", "pm": "phase_margin_deg"}
    for part in [x for x in text.split(",") if x.strip()]:
        key, _, value = part.partition("=")
        key = key.strip().lower()
        if key == "type" and value.strip() in ("2", "3"):
            out["kind"] = f"type{value.strip()}"
        elif key in names and value.strip():
            out[names[key]] = parse_value(f"--design {key}", value.strip())
        elif key == "ri" and value.strip():
            out["ri"] = parse_value("--design ri", value.strip())
            if not out["ri"] > 0.0:
                raise ParameterError(f"--design ri (the op-amp circuit's input resistor) must be above 0 ohm; got "
                                     f"{out['ri']!r}")
        else:
            raise ParameterError(f"--design takes fc=HZ,pm=DEGREES[,type=2|3][,ri=OHM]; got {text!r}")
    missing = [k for k, v in names.items() if v not in out]
    if missing:
        raise ParameterError(f"--design needs {' and '.join(missing)} (fc=HZ,pm=DEGREES); got {text!r}")
    return out


def _design(args, model, params: dict) -> int:
    """--design: the compensator of a voltage loop for a crossover and a phase margin, and the loop it closes."""

    from converters.analysis.smallsignal import (FrequencyResponse, SmallSignalModel, design_compensator, frequencies,
                                                 loop_gain)
    from converters.validate import parse_value, quoted

    from ..io import atomic_write_bytes
    from converters.models.compensator import VoltageLoop
    if not isinstance(getattr(model, "loop", None), VoltageLoop):
        raise ParameterError(f"--design designs the compensator of --control voltage-loop; got --control {model.control}")
    if args.input is not None or args.check:
        raise ParameterError("--design gives the loop gain it closes; --input and --check do not apply to it")
    options = _design_options(args.design)
    ri = options.pop("ri")
    p = model.resolve(params)
    design = design_compensator(model.converter, model.plant(p), vref=p["Vref"], carrier=(p["VL"], p["VU"]), **options)
    closed = {**params, **design.compensator.as_dict()}
    fmin = None if args.fmin is None else parse_value("--fmin", args.fmin)
    fmax = None if args.fmax is None else parse_value("--fmax", args.fmax)
    response, found = loop_gain(model, closed, fmin=fmin, fmax=fmax, points=args.points)
    stability = orbit_stability("loop gain", model.key, response.multipliers, model.period(p), args.unstable)
    plant = SmallSignalModel(model.converter, {**model.plant(p), "D": design.duty}, input="D")
    f = frequencies(plant.T, fmin, fmax, args.points)
    before = FrequencyResponse(f, plant.response(f) / (p["VU"] - p["VL"]), "D", "vout", "loop gain", plant.T,
                               plant.orbit.multipliers)
    parts = design.compensator.components(ri)
    summary = {"converter": model.key, "design": design.as_dict(), "components": parts, "margins": found.as_dict(),
               "loop_gain": response.as_dict(), "plant": before.as_dict(), **stability}
    if args.plot is not None:
        from ..plots import bode_figure
        atomic_write_bytes(args.plot, bode_figure(response, None, found, args.plot.suffix.lower().lstrip("."),
                                                  before=before))
        summary["plot"] = str(args.plot)
    if args.json:
        from .common import json_text
        print(json_text(summary))
        return 0
    d = design.as_dict()
    values = ", ".join(f"{k} = {v:.6g} {'rad/s' if k == 'wi' else 'Hz'}" for k, v in design.compensator.as_dict().items()
                       if v)
    print(f"{model.key}: a {d['compensator']} compensator for a crossover of {design.crossover_hz:g} Hz and "
          f"{design.phase_margin_deg:g} degrees of phase margin (k-factor {d['k']:.4g}, boost {d['boost_deg']:.1f} "
          f"degrees), designed on the exact control-to-output at D = {design.duty:.6g} (|Fm Gvd| "
          f"{d['plant_db']:.2f} dB, {d['plant_deg']:.1f} degrees at the crossover):")
    print(f"  {values}")
    print(f"  the loop it closes (exact loop gain): crossover {found.crossover_hz:.6g} Hz, phase margin "
          f"{found.phase_margin_deg:.4g} degrees; gain margin {found.gain_margin_db:.4g} dB (nan: no phase crossover "
          "below fs/2)")
    print(f"  -p {' -p '.join(f'{k}={v:.6g}' for k, v in design.compensator.as_dict().items())}")
    print("  as an op-amp circuit (netlists/circuits/voltage-loop-buck.cir): "
          + ", ".join(f"{k} = {v:.6g} {'F' if k.startswith('C') else 'ohm'}" for k, v in parts.items()))
    if args.plot is not None:
        print(f"wrote {quoted(args.plot)}")
    return 0
