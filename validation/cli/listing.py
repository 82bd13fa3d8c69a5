"""``pcsuite list``: models with their parameters (defaults, units, ranges), methods, scenes, suites."""
from __future__ import annotations

import json


def add(sub) -> None:
    listing = sub.add_parser("list", help="converters with their parameters, methods, scenes")
    listing.add_argument("--json", action="store_true")
    listing.set_defaults(run=run, no_time_limit=True)


def _parameters(model) -> list[dict]:
    return [{"name": p.name, "default": p.default, "unit": p.unit, "doc": p.doc, "range": p.range_text(),
             "optional": p.default is None} for p in model.parameters]


def run(args) -> int:
    from converters.methods.base import load_methods
    from converters.models import CONVERTERS, DEFAULT_CONTROL, MODELS

    METHODS = load_methods()

    from ..scenes import SCENE_DIR, all_suites, load_scene
    info = {"converters": {name: {"title": c.title, "states": list(c.state_names), "parameters": _parameters(c)}
                           for name, c in CONVERTERS.items()},
            "methods": {key: cls.description for key, cls in METHODS.items()},
            "controls": {control: {"converter": name, "title": m.title, "parameters": _parameters(m)}
                         for (name, control), m in MODELS.items() if control != DEFAULT_CONTROL},
            "scenes": {p.stem: load_scene(p).converter for p in sorted(SCENE_DIR.glob("*.toml"))},
            "suites": all_suites()}
    if args.json:
        print(json.dumps(info, indent=2))
        return 0
    for name, conv in info["converters"].items():
        print(f"{name}: {conv['title']}  (states: {', '.join(conv['states'])})")
        _print_parameters(conv["parameters"])
    print("methods:")
    for name, doc in info["methods"].items():
        print(f"    {name}: {doc}")
    for control, entry in info["controls"].items():
        print(f"{entry['converter']} --control {control}: {entry['title']}")
        _print_parameters(entry["parameters"])
    print("scenes: " + ", ".join(f"{k} ({v})" for k, v in info["scenes"].items()))
    print("report suites: " + ", ".join(info["suites"]))
    return 0


def _print_parameters(parameters) -> None:
    for p in parameters:
        default = "only when given" if p["optional"] else f"{p['default']:g}"
        print(f"    {p['name']:<6} {default:>16} {p['unit']:<7} {p['doc']}  range {p['range']}")
