"""``pcsuite report [SUITE | FILE.toml | DIR]``: run a suite of scenes, or a user's own scene files, and write the
validation report."""
from __future__ import annotations

import argparse
from pathlib import Path

from converters.errors import ParameterError

from .common import MAX_WORKERS, check_workers, given_path, integer

DESCRIPTION = """\
Run the scenes of a named suite (and the suite's other sections), or your own scene files, and write the
HTML validation report (index.html, metrics.json, summary.csv, scenes.csv, scenes/NAME/...) into --out.
Sections with a quick form (fewer points than the full study, the same checks: the mechanics' chattering windows,
continuations and two blocks) run it unless --full is given; the report's summary says which ran quick.

TARGET is a suite name (default: "default"), a scene file FILE.toml, or a directory DIR whose *.toml files are
all run (a name that is both a suite and a path is the suite: write ./NAME for the path). Scene files are
checked completely before anything runs (unknown keys, types, ranges; a scene's name must be 1-64 letters,
digits, '.', '_' or '-'); a bad one is refused with one line.

--out (default reports/SUITE, reports/bench-report for the bench suite, or reports/STEM for FILE.toml or DIR) must be a new directory, an empty one, or
an earlier pcsuite report holding nothing else (it carries .pcsuite-report.json, the list of what pcsuite
wrote); that report is then replaced whole, atomically. Anything else (a directory with other files, a
report of an older pcsuite without the manifest, a file, a device, a symbolic link, the current directory or
one of its ancestors) is refused before the run. Exit status: 0 every section passes or is skipped, 1 a
section fails, 2 bad input."""


def add(sub) -> None:
    report = sub.add_parser("report", help="run a suite of scenes (or your own scene files) and write the "
                                           "validation report", description=DESCRIPTION,
                            formatter_class=argparse.RawDescriptionHelpFormatter)
    report.add_argument("suite", nargs="?", default="default", metavar="TARGET",
                        help="a suite name (default: default), a scene file FILE.toml, or a directory of them")
    report.add_argument("--out", type=given_path, default=None,
                        help="output directory (default reports/SUITE or reports/STEM); new, empty, or an earlier "
                             "pcsuite report, which is replaced whole")
    report.add_argument("--workers", type=integer(1, MAX_WORKERS), default=2, help="parallel processes (default 2)")
    report.add_argument("--full", action="store_true",
                        help="run every section at full size: the sections with a quick form (the mechanics' "
                             "chattering windows and two blocks, ...) run it by default, and the report says which")
    report.set_defaults(run=run)


def run(args) -> int:
    from ..io import check_output_dir, safe_name
    from ..report import write_report
    from ..scenes import all_suites, load_scenes, scene_files
    from ..sections import EXTRA_SECTIONS
    from ..suite import run_suite, scene_section, scenes_summary
    check_workers(args.workers)
    suites = all_suites()
    if args.suite in suites:
        label, scenes, extra = args.suite, None, EXTRA_SECTIONS.get(args.suite, ())
        # the bench suite's report must not land on `pcsuite bench`'s own results (reports/bench), which it reads
        default_out = Path("reports") / ("bench-report" if args.suite == "bench" else args.suite)
        options = {"suite": args.suite, "workers": args.workers, "full": args.full}
    else:
        if not args.suite.strip() or not Path(args.suite).exists():      # '' would be read as '.'
            raise ParameterError(f"TARGET must be a suite ({', '.join(suites)}), a scene file FILE.toml or a "
                                 f"directory of them; got {args.suite!r}")
        files = scene_files(args.suite)
        scenes, extra = load_scenes(files), ()
        label = args.suite
        options = {"scenes": [str(f) for f in files], "workers": args.workers}
        default_out = None
        if args.out is None:
            stem = Path(args.suite).stem if Path(args.suite).is_file() else Path(args.suite).resolve().name
            default_out = Path("reports") / safe_name(f"the default --out reports/STEM (give --out): STEM of "
                                                      f"{args.suite!r}", stem)
    if args.full and not any(getattr(builder, "quick_form", False) for _, builder in extra):
        quick = sorted(name for name, sections in EXTRA_SECTIONS.items()
                       if any(getattr(builder, "quick_form", False) for _, builder in sections))
        raise ParameterError(f"--full runs the quick-form sections of a suite at full size; {args.suite!r} has none "
                             f"(the suites with some: {', '.join(quick)})")
    out = args.out or default_out
    check_output_dir("--out", out, "report")             # before the run; write_report checks again
    scene_results, extras = run_suite(label, extra, workers=args.workers, scenes=scenes, full=args.full)
    sections = (([scenes_summary(scene_results)] if scene_results else []) + [scene_section(r) for r in scene_results]
                + list(extras))
    index = write_report(sections, out, label, options=options)
    failed = [s for s in sections if s.status == "fail"]
    skipped = [s for s in sections if s.status == "skipped"]
    from converters.validate import quoted
    print(f"wrote {quoted(index)} ({sum(s.status == 'pass' for s in sections)}/{len(sections)} sections pass"
          + (f", {len(skipped)} skipped" if skipped else "") + (f", {len(failed)} FAIL" if failed else "") + ")")
    for section in failed:
        print(f"  failed: {section.title}: {section.why}")
    for section in skipped:
        print(f"  skipped: {section.title}: {section.why}")
    return EXIT_FAILED if failed else 0


#: The exit status of a report with a failing section (make report fails with it).
EXIT_FAILED = 1
