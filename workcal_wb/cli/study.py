"""``workcal study``: the paper's experiments on simulated scenes with exact truth (docs/studies.md)."""
from __future__ import annotations

from pathlib import Path

from workcal_wb.cli import EXIT_FAILED, EXIT_OK
from workcal_wb.cli.arguments import add_runner_options, count, positive, runner_from, seed
from workcal_wb.core.errors import InputError
from workcal_wb.core.outputs import check_folder

CHOICES = ("repeatability", "placement", "point-count", "object-size", "all")


def add_parser(subparsers):
    p = subparsers.add_parser(
        "study", help="run the paper's experiments (repeatability, scanner placement, point count, object size)",
        description="Run a study on simulated scenes whose true U, V and W are known: repeatability (one scan pair "
                    "matched N times, paper Fig. 7), placement (W from K scanner positions, Table 1, Fig. 9, and the "
                    "predicted uncertainty against the actual error), point-count (accuracy against cloud size) or "
                    "object-size (2 cm figurine against 25 cm car).  Writes <study>.png, .csv and .json into --out.")
    p.add_argument("study", choices=CHOICES, help="which study (all: one after the other)")
    p.add_argument("--out", required=True, metavar="DIR", help="folder for the figures and tables (created if missing)")
    p.add_argument("--quick", action="store_true",
                   help="small settings for a smoke run (smaller scan image, fewer runs and positions)")
    p.add_argument("--seed", type=seed, default=0, help="seed of the scene, scanner placement and matches (default 0)")
    p.add_argument("--n", type=count, metavar="N",
                   help="runs per setting: matches for repeatability (default 10), subsamples per size for "
                        "point-count (default 3)")
    p.add_argument("--positions", type=count, metavar="K",
                   help="scanner positions for placement and object-size (default 5)")
    p.add_argument("--arc", type=positive, default=360.0, metavar="DEG",
                   help="placement: azimuth range the scanner positions are spread over (default 360)")
    p.add_argument("--regions", choices=["truth", "auto"], default="truth",
                   help="truth: the simulator's object masks, like the paper's hand-picked regions (default); "
                        "auto: calibrate finds the regions itself")
    p.add_argument("--tolerance", type=positive, default=0.3, metavar="MM", help="calibration tolerance (default 0.3 mm)")
    add_runner_options(p, "calibrations")
    p.add_argument("--report", action="store_true", help="also write studies.html with every study's figure")
    p.add_argument("--quiet", action="store_true", help="no line per calibration while running")
    return p


def run(args) -> int:
    from workcal_wb.core.studies import STUDIES, StudySettings, run_study, summary_lines
    from workcal_wb.core.studies.placement import table1_lines

    if args.arc > 360:
        raise InputError(f"--arc must be in (0, 360] degrees, got {args.arc}")
    check_folder(args.out)
    settings = StudySettings(quick=args.quick, seed=args.seed, regions=args.regions, tolerance_mm=args.tolerance)
    out = Path(args.out)
    names = list(STUDIES) if args.study == "all" else [args.study]
    progress = None if args.quiet else (lambda message: print(f"  {message}", flush=True))
    runner = runner_from(args)
    results = []
    for name in names:
        print(f"study {name}{' (quick)' if args.quick else ''}, calibrations {runner.describe()} ...", flush=True)
        result = run_study(name, out, settings=settings, n=args.n, positions=args.positions,
                           arc_deg=args.arc, progress=progress, runner=runner)
        results.append(result)
        print("\n".join(summary_lines(result)))
        if name == "placement":
            print("\n".join(table1_lines(result)))
        print(f"wrote {', '.join(str(p) for p in result.files.values())}")
    if args.report:
        from workcal_wb.core.report import write_study_report

        page = write_study_report(results, out)
        print(f"wrote {page['html']}")
    missed = [f"{r.name}: {t['name']}" for r in results for t in r.targets if not t["passed"]]
    if missed:
        print("targets missed: " + "; ".join(missed))
        return EXIT_FAILED
    print("every target met")
    return EXIT_OK
