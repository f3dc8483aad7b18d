"""``workcal demo``: the whole job on the built-in sample scene, checked against its known truth.

Simulates the paper's set-up (platform, L-shaped reference, a 25 cm clay car with a lump added after
it was digitised), writes the inputs a user would have, then calibrates from those files exactly as
``workcal calibrate`` does and compares W with the truth.
"""
from __future__ import annotations

import dataclasses

import json
from pathlib import Path

import numpy as np

from workcal_wb.cli import EXIT_FAILED, EXIT_OK
from workcal_wb.cli.arguments import seed
from workcal_wb.cli.calibrate import OUTPUTS as CALIBRATION_OUTPUTS
from workcal_wb.cli.simulate import write_simulation
from workcal_wb.core import frames
from workcal_wb.core.atomic import atomic_write_text
from workcal_wb.core.calibration import CalibrationOptions, calibrate
from workcal_wb.core.outputs import OutputFolder
from workcal_wb.core.readers import read_cloud
from workcal_wb.core.toolpath import ExportRefused, export, read_gcode
from workcal_wb.core.toolpath.transform import path_points

PROGRAMS = {"gcode": "toolpath_calibrated.nc", "krl": "toolpath_calibrated.src"}
OUTPUTS = (*CALIBRATION_OUTPUTS, "truth_check.json", "input")


def add_parser(subparsers):
    p = subparsers.add_parser(
        "demo", help="simulate the sample scene, calibrate it, write the report and robot programs, compare with truth",
        description="End-to-end run on the built-in sample: a simulated scan of platform, L-block reference and a "
                    "25 cm car body with a clay lump, calibrated with automatic regions; writes inputs, result.json, "
                    "report.html and the calibrated toolpath (G-code and KUKA KRL) into --out.")
    p.add_argument("--out", default="build/demo", metavar="DIR", help="output folder (default build/demo)")
    p.add_argument("--seed", type=seed, default=0, help="seed of the sample scene (default 0)")
    return p


def run(args) -> int:
    from workcal_wb.core.report import write_report

    out = Path(args.out).resolve()
    with OutputFolder(out, "demo", OUTPUTS) as outputs:
        staged = outputs.folder()
        inputs = staged / "input"
        print(f"WorkCal demo: simulating the sample scene into {out / 'input'}")
        scene, _ = write_simulation(inputs, "car", seed=args.seed, clay_change=["lump"])

        scan = read_cloud(inputs / "scan.ply")
        workpiece = read_cloud(inputs / "workpiece.ply")
        reference = read_cloud(inputs / "reference.ply")
        # Read where it is staged, named where the user will find it (the program's header names it).
        toolpath = dataclasses.replace(read_gcode(inputs / "toolpath.nc"), source=str(out / "input" / "toolpath.nc"))
        toolpath_points = path_points(toolpath)[0]
        print(f"calibrating {len(scan)} scan points against {workpiece.name} and {reference.name} (automatic regions)")
        result = calibrate(scan, workpiece, reference, toolpath_points=toolpath_points,
                           options=CalibrationOptions(seed=args.seed))
        result.to_json(staged / "result.json")
        region = result.regions.get("workpiece")
        write_report(result, staged, workpiece_points=None if region is None else scan.points[region],
                     workpiece_model=workpiece, scan_points=scan.points, title="WorkCal demo: sample scene")
        print(result.summary())

        written = []
        for fmt, name in PROGRAMS.items():
            try:
                # the sample scene tilts the part a few degrees: G-code for a 5-axis machine in tool-centre-point mode
                export(toolpath, result, fmt, staged / name, calibration_source=str(out / "result.json"),
                       machine="5axis-tcp" if fmt == "gcode" else None, workpiece_model=workpiece)
                written.append(name)
            except ExportRefused as exc:
                print(f"not written: {name}: {exc}")
        errors = None if result.W is None else error_against_truth(result.W, scene.W, toolpath_points)
        if errors is not None:
            atomic_write_text(staged / "truth_check.json", json.dumps(errors, indent=2) + "\n")
        outputs.commit(result.status)
    if errors is None:
        print("no W: the calibration failed")
        return EXIT_FAILED
    print(f"error against the known truth: rotation {errors['rotation_deg']:.4f} deg, translation "
          f"{errors['translation_mm']:.4f} mm, at the toolpath max {errors['toolpath_max_mm']:.4f} mm "
          f"(predicted bound {result.uncertainty.get('toolpath_bound_mm', float('nan')):.4f} mm)")
    print(f"outputs in {out}: result.json, report.html, {', '.join(written) or 'no program'}")
    return EXIT_OK if result.status != "failed" else EXIT_FAILED


def error_against_truth(W: np.ndarray, W_true: np.ndarray, toolpath_points: np.ndarray) -> dict:
    """How far a calibrated W is from the true one: rotation, translation and displacement at the toolpath."""
    displacement = np.linalg.norm(frames.apply(W, toolpath_points) - frames.apply(W_true, toolpath_points), axis=1)
    return {"rotation_deg": frames.rotation_between_deg(W, W_true),
            "translation_mm": float(np.linalg.norm(W[:3, 3] - W_true[:3, 3])),
            "toolpath_max_mm": float(displacement.max()), "toolpath_median_mm": float(np.median(displacement)),
            "omega_error_deg": abs(frames.omega(W) - frames.omega(W_true))}
