"""``workcal bench``: WorkCal's matcher against stock Open3D on real and simulated scans; writes a Markdown table."""
from __future__ import annotations

import os
from pathlib import Path

from workcal_wb.cli import EXIT_FAILED, EXIT_OK
from workcal_wb.cli.arguments import add_runner_options, runner_from, seed
from workcal_wb.core.outputs import check_file

# The shared data (Stanford bunny scans) lives beside the checkout, as for the tests.
DEFAULT_SHARED = Path(__file__).resolve().parents[2].parent / "shared"


def add_parser(subparsers):
    p = subparsers.add_parser(
        "bench", help="benchmark the matcher against stock Open3D and write the table (docs/benchmarks.md)",
        description="Match the benchmark cases (Stanford bunny scans with noise, partial overlap, clutter and clay "
                    "changes; simulated scans with exact truth) with WorkCal and "
                    "with Open3D's tutorial pipeline in the same run, and write success rates, errors, times, "
                    "peak memory and the time ratio as Markdown; then the large-scan table (match as a process on "
                    "5M- and 20M-point files), the verdicts table (real Stanford dragon and "
                    "bunny scans, simulated nearly symmetric parts: how often each status comes with the right pose), the "
                    "whole-process table (match and calibrate as processes, cold and warm, beside stock Open3D and "
                    "KISS-Matcher + small_gicp), the scenes table, the L-block on its foot's and the reach check's. "
                    "Exit status 1 when WorkCal misses a target or reports a wrong pose as ok.")
    p.add_argument("--out", required=True, metavar="FILE", help="Markdown file to write (e.g. docs/benchmarks.md)")
    p.add_argument("--quick", action="store_true", help="a small subset, for a smoke test (a minute or two)")
    p.add_argument("--only", choices=("matcher", "large", "processes", "verdicts", "scenes", "lblock", "reach"),
                   help="run only this table and replace its section of FILE (matcher: WorkCal's matcher beside "
                        "stock Open3D on the bunny and simulated cases, with the G-code throughput; verdicts: how often each match status "
                        "comes with the right pose, on real scans and nearly symmetric parts; scenes: cell scans in "
                        "any frame, touching objects, any view, calibrated with automatic regions; lblock: an L-block "
                        "standing on its foot (legs 80 and 90 mm) beside the bunny, any view, mixed pixels, calibrated "
                        "with automatic regions; processes: the "
                        "match and calibrate commands as whole processes, cold and warm, beside the peers; large: "
                        "match as a whole process on 5M- and 20M-point scan files, written once into build/; reach: "
                        "the robot reach check on a million poses beside py-opw-kinematics' inverse kinematics)")
    p.add_argument("--seed", type=seed, default=0, help="seed for the case generation and the matchers")
    add_runner_options(p, "verdicts' and scenes' matches and calibrations")
    p.add_argument("--shared", metavar="DIR", type=Path,
                   default=Path(os.environ.get("WORKCAL_SHARED", DEFAULT_SHARED)),
                   help="folder holding data/stanford-bunny (default ../shared beside the checkout, or "
                        "$WORKCAL_SHARED); the bunny cases are skipped with a note when it is absent")
    return p


def run(args) -> int:
    from workcal_wb.core.benchmark.run import run as run_benchmark

    check_file(args.out)
    report = run_benchmark(args.shared, Path(args.out), seed=args.seed, quick=args.quick, only=args.only,
                           runner=runner_from(args))
    print(f"wrote {args.out}")
    for line in report.missed:
        print(f"target missed: {line}")
    return EXIT_FAILED if report.missed else EXIT_OK
