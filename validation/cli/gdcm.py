"""``pcsuite gdcm CONVERTER``: predicted CCM/DCM/GDCM against the modes detected in LCP and ngspice."""
from __future__ import annotations

from .common import add_params, json_text


def add(sub) -> None:
    gd = sub.add_parser("gdcm", help="predicted CCM/DCM/GDCM against the modes detected in LCP and ngspice")
    gd.add_argument("converter")
    add_params(gd)
    gd.add_argument("--h", default=None, help="LCP step in s (default T/1000)")
    gd.add_argument("--json", action="store_true", help="print one JSON object (predicted, lcp, spice, agree, ...)")
    gd.set_defaults(run=run)


def run(args) -> int:
    from converters.params import parse_assignments

    from ..gdcm import gdcm_check
    result = gdcm_check(args.converter, parse_assignments(args.params), h=args.h)
    if args.json:
        print(json_text(result))
        return 0 if result["agree"] else 1
    pred = result.get("prediction")
    print(f"{result['converter']}: predicted {result['predicted']}" + (" (exact, from the matrices)" if pred else ""))
    if pred:
        print(f"  closed form: K = {pred['K']:.4g}, Kcrit(D) = {pred['Kcrit']:.4g} -> {pred['closed_form']}; "
              f"exact (CCM orbit from the matrices): {pred['exact_matrix']}")
        for row in pred["conditions"]:
            print(f"  GDCM condition, {row['configuration']}: {'possible' if row['possible'] else 'impossible'} "
                  f"({row['condition']})")
        T = result["period_s"]
        print(f"  exact orbit (event method): held {result['held_fraction']['exact']:.4g} of T")
        for side in ("lcp", "spice"):
            print(f"  {side}: {result[side]}, held {result['held_fraction'][side]:.4f} of T (it resolves "
                  f"{result['resolution'][side]:.2g} of T)")
            for iv in result["intervals"][side]:
                print(f"      {iv['mode']:<9} {iv['start'] / T:7.4f} T .. {iv['end'] / T:7.4f} T  ({iv['fraction']:.4f} T)")
        for note in result.get("notes", []):
            print(f"  note: {note}")
    else:
        for side in ("lcp", "spice"):
            conduction = f"{result['conduction'][side]}: " if "conduction" in result else ""
            print(f"  {side}: {conduction}" + ", ".join(f"{k} {v:.4f}" for k, v in result[side].items()))
        for note in result.get("notes", []):
            print(f"  note: {note}")
    verdict = "agree" if result["agree"] else "DISAGREE"
    if "max_fraction_difference" in result:      # say what is compared (shorter modes, switching overlaps, are not)
        verdict += (f" (the modes held more than 1 % of the period; largest fraction difference "
                    f"{result['max_fraction_difference']:.2g})")
    print(verdict)
    return 0 if result["agree"] else 1
