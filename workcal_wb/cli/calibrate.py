"""``workcal calibrate``: a scene scan, the workpiece and reference models in; W, the report and the calibrated toolpath out."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from workcal_wb.cli import EXIT_FAILED, EXIT_OK
from workcal_wb.cli.arguments import (UNITS, add_cache_options, finite, input_file, keep_models, model_cache, positive,
                                      read_model, seed)
from workcal_wb.cli.toolpath import add_machine_options, forced_warnings, read_options, robot_options, way_out
from workcal_wb.core import choice
from workcal_wb.core.calibration import CalibrationOptions, calibrate, merge_scans
from workcal_wb.core.errors import InputError
from workcal_wb.core.files import read_text
from workcal_wb.core.geometry import Cloud
from workcal_wb.core.outputs import OutputFolder
from workcal_wb.core.readers import LARGE_SCAN_POINTS, read_cloud
from workcal_wb.core.result import AMBIGUOUS, FAILED
from workcal_wb.core.toolpath import FORMATS, ExportRefused, ReachRefused, export, read_gcode
from workcal_wb.core.toolpath.transform import path_points

PROGRAM_STEM = "toolpath_calibrated"
# What a calibration writes into --out; a new run replaces all of it (a program a failed run must not leave too).
OUTPUTS = ("result.json", "result.regions.npz", "report.html", "report.json", f"{PROGRAM_STEM}.*")


def add_parser(subparsers):
    p = subparsers.add_parser(
        "calibrate", help="find W = ^B X from one scene scan and write result.json, report.html and the toolpath",
        description="Match the workpiece model X-A and the reference model B-P into one scan of the scene (regions "
                    "found automatically unless given), compute U = ^S X, V = ^S B and W = V^-1 U = ^B X, check the "
                    "quality gates, and write result.json (region indices in result.regions.npz), report.html and, "
                    "with --toolpath, the calibrated program.  The outputs replace the previous run's as one set "
                    "(manifest.json lists them with their SHA-256); a failed run leaves no program.")
    p.add_argument("--scan", nargs="+", required=True, metavar="FILE", type=input_file,
                   help="scene scan(s) from one scanner position (PLY, PCD, E57, XYZ/ASC/PTS/CSV, STL/OBJ/OFF)")
    p.add_argument("--workpiece", required=True, metavar="FILE", type=input_file,
                   help="workpiece model X-A (mesh, point cloud, or STEP/IGES/BREP when run in freecadcmd)")
    p.add_argument("--reference", required=True, metavar="FILE", type=input_file,
                   help="reference model B-P, in robot base frame coordinates (mesh or point cloud)")
    p.add_argument("--units", choices=UNITS, default="mm", help="units of the scan files (default mm)")
    p.add_argument("--model-units", choices=UNITS, help="units of the model files (default: as --units)")
    p.add_argument("--toolpath", metavar="FILE", type=input_file, help="G-code toolpath in workpiece coordinates X (mm unless G20)")
    p.add_argument("--format", choices=list(FORMATS), default="gcode",
                   help="format of the calibrated toolpath (default gcode)")
    p.add_argument("--out", default="workcal-out", metavar="DIR", help="folder for the outputs (default workcal-out)")
    p.add_argument("--tolerance", type=positive, default=0.3, metavar="MM",
                   help="quality tolerance for residuals and toolpath uncertainty (default 0.3 mm)")
    p.add_argument("--method", choices=["robust", "icp", "hausdorff"], default="robust", help="matching method")
    p.add_argument("--seed", type=seed, default=0, help="seed for the random parts (repeatable runs)")
    for role in ("workpiece", "reference"):
        p.add_argument(f"--{role}-indices", metavar="FILE", type=input_file,
                       help=f"{role} region as a text file of scan point indices (0-based); needs the other region too")
        p.add_argument(f"--{role}-box", type=finite, nargs=6, metavar=("XMIN", "YMIN", "ZMIN", "XMAX", "YMAX", "ZMAX"),
                       help=f"{role} region as a box in scanner coordinates, mm")
    p.add_argument("--scanner-origin", type=finite, nargs=3, metavar=("X", "Y", "Z"),
                   help="where the scanner stood, in the scan's coordinates (mm): says which side of the platform is up "
                        "and lets free space rule out poses (default: from the file, PCD VIEWPOINT, E57 poses or a PLY "
                        "'comment viewpoint X Y Z', else estimated)")
    p.add_argument("--up", type=finite, nargs=3, metavar=("X", "Y", "Z"),
                   help="the platform's up direction in the scan's coordinates (default: from the data, any frame)")
    p.add_argument("--force", action="store_true",
                   help="write the calibrated toolpath even if the calibration failed its gates (marked FORCED)")
    add_machine_options(p)
    add_cache_options(p)
    return p


def _regions(args, scan: Cloud):
    given = {role: (getattr(args, f"{role}_indices"), getattr(args, f"{role}_box")) for role in ("workpiece", "reference")}
    if not any(v for pair in given.values() for v in pair):
        return None
    regions = {}
    for role, (indices, box) in given.items():
        if indices and box:
            raise InputError(f"--{role}-indices and --{role}-box: give one of them, not both")
        if indices:
            regions[role] = read_indices(indices, len(scan))
        elif box:
            lo, hi = np.array(box[:3]), np.array(box[3:])
            inside = np.all((scan.points >= lo) & (scan.points <= hi), axis=1)
            regions[role] = np.flatnonzero(inside)
        else:
            raise InputError(f"the {role} region is missing: give both regions, or none for automatic regions")
    return regions


def read_indices(path, scan_points: int) -> np.ndarray:
    """Scan point indices from a text file: whole numbers separated by white space or commas, # comments;
    the error names the line of the first value that is not an index of the scan."""
    values = []
    for number, line in enumerate(read_text(path, "index file").splitlines(), 1):
        for word in line.split("#", 1)[0].replace(",", " ").split():
            if not (word.isascii() and word.isdigit()):
                raise InputError(f"{path}: line {number}: {word[:40]!r} is not a point index (a whole number >= 0)")
            if int(word) >= scan_points:
                raise InputError(f"{path}: line {number}: index {word} is outside the scan's {scan_points} points")
            values.append(int(word))
    if not values:
        raise InputError(f"{path}: holds no point indices")
    return np.array(values, dtype=np.int64)


def warn(clouds) -> None:
    for cloud in clouds:
        for warning in cloud.warnings:
            print(f"warning: {warning}", file=sys.stderr)


def run(args) -> int:
    from workcal_wb.core.report import write_report
    from workcal_wb.core.toolpath.reach import check_controller

    if args.toolpath:  # a robot that cannot run the format is said before the scan is read, not after calibrating
        check_controller(args.robot, FORMATS[args.format])
    inputs = [*args.scan, args.workpiece, args.reference, args.toolpath, args.workpiece_indices, args.reference_indices]
    cache = model_cache(args)
    with OutputFolder(args.out, "calibrate", OUTPUTS, keep=[p for p in inputs if p]) as outputs:
        scans = [read_cloud(f, units=args.units, unit_option="--units", max_points=LARGE_SCAN_POINTS) for f in args.scan]
        model_units = args.model_units or args.units
        workpiece = read_model(args.workpiece, model_units, cache, args.seed)
        reference = read_model(args.reference, model_units, cache, args.seed)
        warn([*scans, workpiece, reference])
        toolpath = read_gcode(args.toolpath, **read_options(args)) if args.toolpath else None
        merged = merge_scans(scans)
        options = CalibrationOptions(tolerance_mm=args.tolerance, method=args.method, seed=args.seed,
                                     scanner_origin=args.scanner_origin, up=args.up)
        result = calibrate(merged, workpiece, reference, regions=_regions(args, merged), options=options,
                           toolpath_points=None if toolpath is None else path_points(toolpath)[0])

        # What the cell needs first (result.json and the program) goes in first; the report follows.
        result.to_json(outputs.file("result.json"))
        refused, forced, reach = _program(args, toolpath, result, outputs, workpiece)
        outputs.commit(result.status)
        region = result.regions.get("workpiece")
        try:
            write_report(result, outputs.folder(), workpiece_points=None if region is None else merged.points[region],
                         workpiece_model=workpiece, scan_points=merged.points, robot=args.robot, reach=reach)
            manifest = outputs.commit(result.status, adding=True)
        except KeyboardInterrupt as stop:
            stop.outputs = f"{args.out} holds this run's result.json and program; the report was not written"
            raise
    print(result.summary())
    print(f"wrote {args.out}: {', '.join(manifest['files'])}")
    _list_poses(result, {"workpiece": args.workpiece, "reference": args.reference},
                {"workpiece": workpiece, "reference": reference}, Path(args.out) / "result.json")
    if refused:
        print(f"workcal calibrate: toolpath not written: {refused}", file=sys.stderr)
    for line in forced:
        print(f"workcal calibrate: warning: {line}", file=sys.stderr)
    keep_models(cache)
    return EXIT_OK if result.status != FAILED and not refused else EXIT_FAILED


def _list_poses(result, files: dict, models: dict, written: Path) -> None:
    """On stderr, when the result is ambiguous: the poses a person may choose among, each by how it
    differs from the best, and how to choose one (``workcal choose``); or why there is none to choose."""
    from workcal_wb.cli.choose import print_poses

    if result.status != AMBIGUOUS:
        return
    try:
        role = choice.role_to_choose(result)
    except InputError as why:
        print(f"workcal calibrate: {why}", file=sys.stderr)
        return
    poses = choice.poses(result, role)
    print(f"workcal calibrate: the {role} match left {len(poses)} poses the scan cannot tell apart (choose one "
          f"with: python3 -m workcal_wb choose {written} N --model {files[role]}):", file=sys.stderr)
    print_poses(poses, choice.part_axes(models[role].points), sys.stderr)


def _program(args, toolpath, result, outputs, workpiece) -> tuple:
    """Stage the calibrated program: (the reason when it is refused, else None; the reasons it was forced;
    the robot's reach along it, robots.reach.ReachReport, None when no robot was given or it was not checked)."""
    if toolpath is None:
        return None, [], None
    if result.W is None:
        return "the calibration found no W", [], None
    name = f"{PROGRAM_STEM}{FORMATS[args.format].EXTENSION}"
    try:
        job = export(toolpath, result, args.format, outputs.file(name), force=args.force, machine=args.machine,
                     vertical_tol_deg=args.vertical_tol, rotary=args.rotary, fanuc_config=args.fanuc_config,
                     calibration_source=str(Path(args.out) / "result.json"), workpiece_model=workpiece,
                     path_reach_mm=args.path_reach, **robot_options(args))
    except ExportRefused as exc:
        return f"{exc}{way_out(exc)}", [], exc.report if isinstance(exc, ReachRefused) else None
    return None, forced_warnings(job), job.reach
