"""``workcal toolpath``: a G-code toolpath in workpiece coordinates, out as a calibrated robot or CNC program."""
from __future__ import annotations

import json
import math
import sys

from workcal_wb.cli import EXIT_FAILED, EXIT_OK
from workcal_wb.cli.arguments import (UNITS, envelope, finite, input_file, is_cad_file, non_negative, positive,
                                      program_lines, read_cad_model, robot, tool_frame)
from workcal_wb.core import frames
from workcal_wb.core.errors import InputError
from workcal_wb.core.files import read_text
from workcal_wb.core.outputs import check_file, check_whole_set
from workcal_wb.core.readers import read_cloud
from workcal_wb.core.result import CalibrationResult
from workcal_wb.core.toolpath import (DEFAULT_CHORD_TOL_MM, FORMATS, MACHINES, ExportOptions, ExportRefused, RotaryTable,
                                      export, format_for, read_gcode)
from workcal_wb.core.toolpath.exporters.common import DEFAULT_RAPID_FEED_MM_MIN
from workcal_wb.core.toolpath.exporters.krl import MODES as KRL_MODES
from workcal_wb.core.toolpath.gcode import BLOCK_DELETE, DWELL_P
from workcal_wb.core.toolpath.orientation import ROTARY
from workcal_wb.core.toolpath.safety import (DEFAULT_FANUC_CONFIG, DEFAULT_PATH_REACH_MM, DEFAULT_VERTICAL_TOL_DEG,
                                             PathOffModel, ReachRefused)


def add_parser(subparsers):
    p = subparsers.add_parser(
        "toolpath", help="transform a G-code toolpath by the calibration and write a robot/CNC program",
        description="Read a toolpath in workpiece coordinates (G-code), move it into the robot base frame with "
                    "W from a calibration result, and write KRL, RAPID, URScript, Fanuc LS, G-code or CSV. "
                    "Nothing is written when the calibration failed its gates (unless --force), when a number "
                    "is not finite, when a point leaves the --envelope, or when the --robot cannot follow it.")
    p.add_argument("--in", dest="input", required=True, metavar="FILE", type=input_file,
                   help="G-code file (.nc, .ngc, .gcode, ...)")
    p.add_argument("--calibration", required=True, metavar="FILE", type=input_file,
                   help="calibration result JSON (W = ^B X)")
    p.add_argument("--workpiece", metavar="FILE", type=input_file,
                   help="the workpiece model X-A the calibration matched: the toolpath is refused when its cutting "
                        "moves do not run on it (a mirrored or wrong model); without it the program says 'not checked'")
    p.add_argument("--model-units", choices=UNITS, default="mm", help="units of the --workpiece file (default mm)")
    p.add_argument("--format", choices=list(FORMATS), help="output format (default: from the --out extension)")
    p.add_argument("--out", required=True, metavar="FILE", help="program to write (replaced atomically)")
    p.add_argument("--force", action="store_true",
                   help="export even when the calibration failed its quality gates (the file then says FORCED)")
    p.add_argument("--envelope", metavar="XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX", type=envelope,
                   help="work envelope in the robot base frame, mm: refuse any point outside it")
    p.add_argument("--table-frame", metavar="FILE", type=input_file, help="JSON 4x4 ^B Q of the rotary table (or {\"matrix\": ...})")
    p.add_argument("--table-angle", type=finite, metavar="DEG",
                   help="rotary table angle to export at (needs --table-frame)")
    p.add_argument("--chord-tol", type=positive, default=DEFAULT_CHORD_TOL_MM, metavar="MM",
                   help=f"chordal tolerance for arcs turned into lines (default {DEFAULT_CHORD_TOL_MM} mm)")
    p.add_argument("--units-in", choices=["mm", "in"], default="mm",
                   help="units of the G-code until it says G20/G21 (default mm)")
    p.add_argument("--krl-mode", choices=KRL_MODES, default="base",
                   help="KRL: 'base' sets $BASE = W and keeps workpiece coordinates; 'transformed' writes points in B")
    p.add_argument("--rapid-feed", type=positive, default=DEFAULT_RAPID_FEED_MM_MIN, metavar="MM_PER_MIN",
                   help=f"robot speed for G0 moves (default {DEFAULT_RAPID_FEED_MM_MIN:g} mm/min)")
    add_machine_options(p)
    p.add_argument("--max-lines", type=program_lines, metavar="N",
                   help="lines per program part before a robot program is split into parts called by a main program "
                        "(default: the controller's limit, e.g. 9999 for Fanuc)")
    return p


def add_machine_options(p) -> None:
    """The options of the target machine and of reading the CAM file (shared with ``calibrate``)."""
    p.add_argument("--machine", choices=MACHINES,
                   help="target: 3axis (G-code, refused when W tilts the tool past --vertical-tol), 5axis-tcp "
                        "(G-code with rotary axes in tool-centre-point mode), robot (KRL, RAPID, URScript, Fanuc, "
                        "CSV); default 3axis for G-code, robot otherwise")
    p.add_argument("--vertical-tol", type=non_negative, default=DEFAULT_VERTICAL_TOL_DEG, metavar="DEG",
                   help=f"3-axis: largest tilt of the tool axis from the machine's Z that W may cause "
                        f"(default {DEFAULT_VERTICAL_TOL_DEG} deg)")
    p.add_argument("--rotary", choices=list(ROTARY), default="ab",
                   help="the machine's two rotary axes, for A/B/C words read and written (default ab)")
    p.add_argument("--path-reach", type=positive, default=DEFAULT_PATH_REACH_MM, metavar="MM",
                   help="how far the toolpath's cutting moves may run from the workpiece model's surface, as their "
                        f"median, before it is taken for another part's toolpath (default {DEFAULT_PATH_REACH_MM:g} mm)")
    p.add_argument("--robot", type=robot, metavar="NAME_OR_JSON",
                   help="the robot that runs the program: a built-in id (workcal robots lists them) or a robot JSON "
                        "file (docs/robots.md). The program is refused when the robot cannot follow it (out of "
                        "reach, past a joint limit, a configuration change or a singularity inside a linear move), "
                        "with where to put the part instead, and its first move carries the configuration solved "
                        "(KRL S and T, RAPID confdata with ConfL on, Fanuc CONFIG, URScript movej joints); without "
                        "it the program says 'reach not checked'")
    p.add_argument("--tool", type=tool_frame, default=None, metavar="X,Y,Z,A,B,C",
                   help="the TCP in the robot's flange frame for --robot: mm and degrees, R = Rz(A) Ry(B) Rx(C) "
                        "(KUKA's convention); default 0,0,0,0,0,0, the flange itself")
    p.add_argument("--fanuc-config", default=DEFAULT_FANUC_CONFIG, metavar="'F U T, 0, 0, 0'",
                   help="Fanuc without --robot: the robot's configuration at the workpiece (flip, elbow, base side, "
                        f"turns of J1 J4 J6), written on every position (default '{DEFAULT_FANUC_CONFIG}'); with "
                        "--robot every position's configuration comes from its solution")
    p.add_argument("--block-delete", choices=BLOCK_DELETE,
                   help="the block-delete switch for '/' blocks: on skips them, off runs them "
                        "(required when the file has them)")
    p.add_argument("--dwell-p", choices=DWELL_P, default="auto",
                   help="unit of G4 P: auto = milliseconds without a decimal point (Fanuc, Haas), seconds with one")


def way_out(refusal: ExportRefused) -> str:
    """What the command line can do about a refusal the core states without naming options."""
    if isinstance(refusal, PathOffModel):
        return (f". If this toolpath is this part's (a roughing pass far into the stock), allow it with --path-reach "
                f"{math.ceil(refusal.median_mm * 1.2)}")
    if isinstance(refusal, ReachRefused):
        return ". To write it anyway, force it (--force): the program then says FORCED and why"
    return ""


def robot_options(args) -> dict:
    """The robot and tool export settings from the shared options."""
    return {"robot": args.robot, **({} if args.tool is None else {"tool": args.tool})}


def forced_warnings(job) -> list[str]:
    """One line per reason an export was forced (the first line of each part of its FORCED banner)."""
    return [line for line in job.banner if line.startswith("FORCED EXPORT")]


def read_options(args) -> dict:
    """The reader's settings from the shared options."""
    return {"rotary": args.rotary, "block_delete": args.block_delete, "dwell_p": args.dwell_p}


def _table(args) -> RotaryTable | None:
    if args.table_frame is None:
        if args.table_angle is not None:
            raise InputError("--table-angle needs --table-frame (the table's frame ^B Q)")
        return None
    try:
        data = json.loads(read_text(args.table_frame, "table frame file"))
    except (ValueError, RecursionError) as exc:
        raise InputError(f"{args.table_frame}: not valid JSON ({exc})") from None
    matrix = data.get("matrix") if isinstance(data, dict) else data
    try:
        frame = frames.as_transform(matrix, "table frame")
    except (ValueError, TypeError) as exc:
        raise InputError(f"{args.table_frame}: {exc}") from None
    return RotaryTable(frame, args.table_angle or 0.0, source=args.table_frame)


def _workpiece(args):
    """The --workpiece model as a Cloud (None without one)."""
    if args.workpiece is None:
        return None
    if is_cad_file(args.workpiece):
        return read_cad_model(args.workpiece, args.model_units)
    return read_cloud(args.workpiece, units=args.model_units, unit_option="--model-units")


def run(args) -> int:
    if args.input.lower().endswith(".fcstd"):
        raise InputError(f"{args.input}: FreeCAD documents are read inside FreeCAD (WorkCal workbench); "
                         "export the Job's G-code, or pass a G-code file here")
    fmt = args.format or format_for(args.out)
    check_file(args.out)
    toolpath = read_gcode(args.input, units=args.units_in, **read_options(args))
    check_whole_set(args.calibration)
    calibration = CalibrationResult.from_json(args.calibration, with_regions=False)
    options = ExportOptions(force=args.force, table=_table(args), envelope=args.envelope,
                            chord_tol_mm=args.chord_tol, krl_mode=args.krl_mode, rapid_feed_mm_min=args.rapid_feed,
                            machine=args.machine, vertical_tol_deg=args.vertical_tol, rotary=args.rotary,
                            max_lines=args.max_lines, fanuc_config=args.fanuc_config,
                            calibration_source=args.calibration, workpiece_model=_workpiece(args),
                            path_reach_mm=args.path_reach, **robot_options(args))
    for warning in toolpath.warnings:
        print(f"warning: {warning}", file=sys.stderr)
    try:
        job = export(toolpath, calibration, fmt, args.out, options)
    except ExportRefused as exc:
        print(f"workcal toolpath: refused: {exc}{way_out(exc)}", file=sys.stderr)
        return EXIT_FAILED
    for line in forced_warnings(job):
        print(f"workcal toolpath: warning: {line}", file=sys.stderr)
    print(f"wrote {args.out}: {FORMATS[fmt].NAME} for {job.machine}, {len(toolpath)} moves from {args.input}, "
          f"calibration {calibration.status}")
    return EXIT_OK
