"""``workcal match``: place a model into one scan (U = ^S X) and say how far to trust it."""
from __future__ import annotations

import json
import sys

from workcal_wb.cli import EXIT_FAILED, EXIT_OK
from workcal_wb.cli.arguments import add_cache_options, finite, input_file, keep_models, model_cache, positive, seed
from workcal_wb.core.match import METHODS, match
from workcal_wb.core.outputs import check_file
from workcal_wb.core.readers import LARGE_SCAN_POINTS, read_cloud
from workcal_wb.core.result import FAILED
from workcal_wb.core.units import mm_per_unit

UNITS = ("mm", "m", "in")


def add_parser(subparsers):
    p = subparsers.add_parser(
        "match", help="find U = ^S X, the pose that places MODEL into SCAN, with its quality",
        description="Match a model (mesh or point cloud, frame X) into a scan (frame S) without an initial guess "
                    "and print U and its quality.")
    p.add_argument("scan", metavar="SCAN", type=input_file, help="the scan (PLY, PCD, XYZ/ASC/PTS/CSV, STL/OBJ/OFF)")
    p.add_argument("model", metavar="MODEL", type=input_file, help="the model X-A (mesh or point cloud)")
    p.add_argument("--units", choices=UNITS, default="mm", help="units of the scan file (default mm)")
    p.add_argument("--model-units", choices=UNITS, help="units of the model file (default: as --units)")
    p.add_argument("--method", choices=METHODS, default="robust",
                   help="robust (point-to-plane, robust kernel, global search; default), or the paper's "
                        "least-squares closest-point ICP (icp) or mean directed Hausdorff distance (hausdorff)")
    p.add_argument("--json", metavar="FILE", help="also write the full result as JSON (matrix = U, row-major, mm)")
    p.add_argument("--tolerance", type=positive, default=0.3, metavar="MM",
                   help="deviation tolerance for the within-tolerance figure and the fit check (default 0.3 mm)")
    p.add_argument("--viewpoint", type=finite, nargs=3, metavar=("X", "Y", "Z"),
                   help="where the scanner was, in the scan's frame and units (e.g. 0 0 0 for a scan in the scanner's "
                        "own coordinates); by default it is estimated from the matched surface")
    p.add_argument("--seed", type=seed, default=0, help="seed for the random parts (repeatable runs)")
    add_cache_options(p)
    return p


def run(args) -> int:
    if args.json:
        check_file(args.json)
    cache = model_cache(args)
    scan = read_cloud(args.scan, units=args.units, unit_option="--units", max_points=LARGE_SCAN_POINTS)
    model = cache.model_file(args.model, units=args.model_units or args.units, seed=args.seed,
                             unit_option="--model-units")
    for warning in scan.warnings + model.warnings:
        print(f"warning: {warning}", file=sys.stderr)
    viewpoint = None if args.viewpoint is None else tuple(v * mm_per_unit(args.units) for v in args.viewpoint)
    result = match(scan, model, method=args.method, tolerance_mm=args.tolerance, seed=args.seed, viewpoint=viewpoint)
    print(result.summary())
    if args.json:
        from workcal_wb.core.atomic import atomic_write_text

        atomic_write_text(args.json, json.dumps(result.to_dict(), indent=2, allow_nan=True) + "\n")
        print(f"wrote {args.json}")
    keep_models(cache)
    return EXIT_FAILED if result.status == FAILED else EXIT_OK
