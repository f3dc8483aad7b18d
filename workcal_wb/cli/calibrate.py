"""``workcal calibrate``: a scene scan, the workpiece and reference models in; W, the report and the calibrated toolpath out."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from workcal_wb.cli import EXIT_FAILED, EXIT_OK
from workcal_wb.core.calibration import CalibrationOptions, calibrate, merge_scans
from workcal_wb.core.errors import InputError
from workcal_wb.core.geometry import Cloud
from workcal_wb.core.readers import read_cloud
from workcal_wb.core.result import OK
from workcal_wb.core.toolpath import FORMATS, ExportRefused, export, read_gcode
from workcal_wb.core.toolpath.transform import path_points
from workcal_wb.cli.toolpath import add_machine_options, read_options

UNITS = ("mm", "m", "in")
CAD_SUFFIXES = (".step", ".stp", ".iges", ".igs", ".brep", ".brp")


def add_parser(subparsers):
    p = subparsers.add_parser(
        "calibrate", help="find W = ^B X from one scene scan and write result.json, report.html and the toolpath",
        description="Match the workpiece model X-A and the reference model B-P into one scan of the scene (regions "
                    "found automatically unless given), compute U = ^S X, V = ^S B and W = V^-1 U = ^B X, check the "
                    "quality gates, and write result.json, report.html and, with --toolpath, the calibrated program. "
                    "Exit status: 0 ok or ambiguous, 1 failed, 2 bad input.")
    p.add_argument("--scan", nargs="+", required=True, metavar="FILE",
                   help="scene scan(s) from one scanner position (PLY, PCD, XYZ/ASC/PTS/CSV, STL/OBJ/OFF)")
    p.add_argument("--workpiece", required=True, metavar="FILE",
                   help="workpiece model X-A (mesh, point cloud, or STEP/IGES/BREP when run in freecadcmd)")
    p.add_argument("--reference", required=True, metavar="FILE",
                   help="reference model B-P, in robot base frame coordinates (mesh or point cloud)")
    p.add_argument("--units", choices=UNITS, default="mm", help="units of the scan files (default mm)")
    p.add_argument("--model-units", choices=UNITS, help="units of the model files (default: as --units)")
    p.add_argument("--toolpath", metavar="FILE", help="G-code toolpath in workpiece coordinates X (mm unless G20)")
    p.add_argument("--format", choices=list(FORMATS), default="gcode",
                   help="format of the calibrated toolpath (default gcode)")
    p.add_argument("--out", default="workcal-out", metavar="DIR", help="folder for the outputs (default workcal-out)")
    p.add_argument("--tolerance", type=float, default=0.3, metavar="MM",
                   help="quality tolerance for residuals and toolpath uncertainty (default 0.3 mm)")
    p.add_argument("--method", choices=["robust", "icp", "hausdorff"], default="robust", help="matching method")
    p.add_argument("--seed", type=int, default=0, help="seed for the random parts (repeatable runs)")
    for role in ("workpiece", "reference"):
        p.add_argument(f"--{role}-indices", metavar="FILE",
                       help=f"{role} region as a text file of scan point indices (0-based); needs the other region too")
        p.add_argument(f"--{role}-box", type=float, nargs=6, metavar=("XMIN", "YMIN", "ZMIN", "XMAX", "YMAX", "ZMAX"),
                       help=f"{role} region as a box in scanner coordinates, mm")
    p.add_argument("--force", action="store_true",
                   help="write the calibrated toolpath even if the calibration failed its gates (marked FORCED)")
    add_machine_options(p)
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
            try:
                regions[role] = np.loadtxt(indices, dtype=np.int64, ndmin=1)
            except (OSError, ValueError) as exc:
                raise InputError(f"{indices}: not a list of integer point indices ({exc})") from exc
        elif box:
            lo, hi = np.array(box[:3]), np.array(box[3:])
            inside = np.all((scan.points >= lo) & (scan.points <= hi), axis=1)
            regions[role] = np.flatnonzero(inside)
        else:
            raise InputError(f"the {role} region is missing: give both regions, or none for automatic regions")
    return regions


def read_model(path, units: str) -> Cloud:
    """A model file; CAD solids (STEP, IGES, BREP) are tessellated through FreeCAD when it is there."""
    if Path(path).suffix.lower() not in CAD_SUFFIXES:
        return read_cloud(path, units=units)
    try:
        from workcal_wb.fc.models import read_model_file
    except ImportError:
        raise InputError(f"{path}: STEP/IGES/BREP models are read through FreeCAD; run this command inside "
                         "freecadcmd (see the README), or export the model as STL") from None
    return read_model_file(path, units)


def run(args) -> int:
    from workcal_wb.core.report import write_report

    scans = [read_cloud(f, units=args.units) for f in args.scan]
    for cloud in scans:
        for warning in cloud.warnings:
            print(f"warning: {warning}", file=sys.stderr)
    model_units = args.model_units or args.units
    workpiece = read_model(args.workpiece, model_units)
    reference = read_model(args.reference, model_units)
    toolpath = read_gcode(args.toolpath, **read_options(args)) if args.toolpath else None
    merged = merge_scans(scans)
    options = CalibrationOptions(tolerance_mm=args.tolerance, method=args.method, seed=args.seed)
    result = calibrate(merged, workpiece, reference, regions=_regions(args, merged), options=options,
                       toolpath_points=None if toolpath is None else path_points(toolpath)[0])

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    result.to_json(out / "result.json")
    workpiece_points = merged.points[result.regions["workpiece"]] if result.regions.get("workpiece") else None
    report = write_report(result, out, workpiece_points=workpiece_points, workpiece_model=workpiece)
    print(result.summary())
    print(f"wrote {out / 'result.json'}, {report['html']}")
    if toolpath is not None and result.W is None:
        print("workcal calibrate: toolpath not written: the calibration found no W", file=sys.stderr)
    elif toolpath is not None:
        program = out / f"toolpath_calibrated{FORMATS[args.format].EXTENSION}"
        try:
            export(toolpath, result, args.format, program, force=args.force, machine=args.machine,
                   vertical_tol_deg=args.vertical_tol, rotary=args.rotary, calibration_source=str(out / "result.json"))
            print(f"wrote {program}" + (" (FORCED)" if result.status != OK else ""))
        except ExportRefused as exc:
            print(f"workcal calibrate: toolpath not written: {exc}", file=sys.stderr)
    return EXIT_OK if result.W is not None and result.status != "failed" else EXIT_FAILED

