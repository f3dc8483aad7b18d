"""``workcal choose``: a person's choice of one pose of an ambiguous calibration, made on its stored
result.json (never by calibrating again): without N the poses are listed, each by how it differs from
the best; with N the result with that pose chosen (status "ok (chosen)" and the record of who chose it)
is written as calibrate writes its result, into a folder of its own."""
from __future__ import annotations

import os
import sys
from pathlib import Path

from workcal_wb.cli import EXIT_OK
from workcal_wb.cli.arguments import UNITS, add_cache_options, count, input_file, keep_models, model_cache, read_model
from workcal_wb.core import choice
from workcal_wb.core.errors import InputError
from workcal_wb.core.outputs import OutputFolder, check_whole_set
from workcal_wb.core.result import CalibrationResult

# What a choice writes into --out (the calibration's result.json and its region indices, the choice recorded).
OUTPUTS = ("result.json", "result.regions.npz")


def add_parser(subparsers):
    p = subparsers.add_parser(
        "choose", help="choose one pose of an ambiguous calibration's result.json, or list them",
        description="Read an ambiguous calibration's result.json and list the poses its match could not tell "
                    "apart, each by how it differs from the best; with N, write that result with pose N chosen "
                    "(status 'ok (chosen)', result.json recording who chose which among the poses) into --out, "
                    "as calibrate writes its result (manifest.json lists it).  Only a tie between poses is "
                    "settled so: a result in doubt for any other reason is refused.")
    p.add_argument("result", metavar="RESULT", type=input_file, help="the calibration's result.json")
    p.add_argument("number", metavar="N", type=count, nargs="?", help="the pose to choose (1: the best), as listed")
    p.add_argument("--model", required=True, metavar="FILE", type=input_file,
                   help="the model of the match in doubt (workpiece X-A or reference B-P, as calibrated): the poses' "
                        "differences are named along its axes")
    p.add_argument("--model-units", choices=UNITS, default="mm", help="units of the model file (default mm)")
    p.add_argument("--out", metavar="DIR",
                   help="folder for the chosen result (default: RESULT's folder with '-chosen' added); never "
                        "RESULT's own folder, whose set stays as the calibration wrote it")
    add_cache_options(p)
    return p


def _out_folder(args) -> Path:
    source = Path(args.result).resolve().parent
    out = Path(args.out) if args.out else source.with_name(source.name + "-chosen")
    if out.resolve() == source:
        raise InputError(f"--out {args.out}: the calibration's own folder keeps its run's outputs as they were "
                         "written; give another folder for the chosen result")
    return out


def run(args) -> int:
    check_whole_set(args.result)
    result = CalibrationResult.from_json(args.result)
    try:
        role = choice.role_to_choose(result)
    except InputError as why:
        raise InputError(f"{args.result}: {why}") from None
    cache = model_cache(args)
    model = read_model(args.model, args.model_units, cache, result.seed)
    axes = choice.part_axes(model.points)
    poses = choice.poses(result, role)
    if args.number is None:
        print(f"the {role} match left {len(poses)} poses the scan cannot tell apart:")
        print_poses(poses, axes, sys.stdout)
        print(f"choose one: python3 -m workcal_wb choose {args.result} N --model {args.model}")
        keep_models(cache)
        return EXIT_OK
    if args.number > len(poses):
        raise InputError(f"pose {args.number}: the {role} match has {len(poses)} poses (1 to {len(poses)})")
    out = _out_folder(args)
    chosen = choice.choose(result, role, args.number - 1, axes, choice.user_name())
    with OutputFolder(out, "choose", OUTPUTS, keep=[os.path.abspath(args.result), args.model]) as outputs:
        chosen.to_json(outputs.file("result.json"))
        manifest = outputs.commit(chosen.status)
    print(chosen.summary())
    print(f"wrote {out}: {', '.join(manifest['files'])}")
    keep_models(cache)
    return EXIT_OK


def print_poses(poses, axes, stream) -> None:
    """Each pose (1: the best) by how it differs from the best, with what the match weighed of it."""
    for i, pose in enumerate(poses):
        shown = choice.evidence(pose, i, choice.difference(poses[0].matrix, pose.matrix, axes))
        numbers = (f" (score {shown['score_ratio']:.0%} of the best, {shown['standard_errors_below_best']:.1f} "
                   "standard errors below it)" if i and "score_ratio" in shown else "")
        symmetry = f" (the model's symmetry: {shown['symmetry']})" if "symmetry" in shown else ""
        print(f"  pose {i + 1}: {shown['difference']}{numbers}{symmetry}", file=stream)
