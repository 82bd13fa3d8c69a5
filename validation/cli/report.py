"""``pcsuite report [SUITE]``: run a suite of scenes and write the validation report."""
from __future__ import annotations

from pathlib import Path

from converters.errors import ParameterError


def add(sub) -> None:
    report = sub.add_parser("report", help="run a suite of scenes and write the validation report")
    report.add_argument("suite", nargs="?", default="default")
    report.add_argument("--out", type=Path, default=None, help="output directory (default reports/SUITE)")
    report.add_argument("--workers", type=int, default=2, help="parallel processes (default 2)")
    report.set_defaults(run=run)


def run(args) -> int:
    from ..report import write_report
    from ..scenes import suite_names
    from ..sections import EXTRA_SECTIONS
    from ..suite import run_suite, scene_section, scenes_summary
    suites = sorted(set(suite_names()) | set(EXTRA_SECTIONS))
    if args.suite not in suites:
        raise ParameterError(f"SUITE must be one of {', '.join(suites)}; got {args.suite!r}")
    out = args.out or Path("reports") / args.suite
    scenes, extras = run_suite(args.suite, EXTRA_SECTIONS.get(args.suite, ()), workers=args.workers)
    sections = ([scenes_summary(scenes)] if scenes else []) + [scene_section(r) for r in scenes] + list(extras)
    index = write_report(sections, out, args.suite, options={"suite": args.suite, "workers": args.workers})
    failed = [s for s in sections if s.status == "fail"]
    skipped = [s for s in sections if s.status == "skipped"]
    print(f"wrote {index} ({sum(s.status == 'pass' for s in sections)}/{len(sections)} sections pass"
          + (f", {len(skipped)} skipped" if skipped else "") + (f", {len(failed)} FAIL" if failed else "") + ")")
    for section in failed:
        print(f"  failed: {section.title}: {section.why}")
    for section in skipped:
        print(f"  skipped: {section.title}: {section.why}")
    return EXIT_FAILED if failed else 0


#: The exit status of a report with a failing section (make report fails with it).
EXIT_FAILED = 1
