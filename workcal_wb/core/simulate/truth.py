"""The ground truth of a simulation as JSON: U = ^S X, V = ^S B, ^B S per scan and W = ^B X (mm).

Matrices are 4x4 row-major lists (the paper's column convention: ^B p = W ^X p), so a checker can
compare a calibration against them directly.
"""
from __future__ import annotations

import json
import re

import numpy as np

from .. import frames
from ..atomic import atomic_write_text


def _pose(T) -> dict:
    """Euler angles, Omega, translation and quaternion of a matrix written beside it (not repeating it)."""
    return {k: v for k, v in frames.describe(T).items() if k != "matrix"}


def scan_truth(result) -> dict:
    """One capture: its frames, scanner settings and points per role."""
    return {
        "U": result.U.tolist(),
        "V": result.V.tolist(),
        "W": result.W.tolist(),
        "B_S": result.B_S.tolist(),
        "U_pose": _pose(result.U),
        "V_pose": _pose(result.V),
        "scanner": result.scanner.to_dict(),
        "points": {"total": len(result.points), **result.counts()},
    }


def scene_truth(scene, scans) -> dict:
    """The whole simulation; ``scans`` is a list of (file name, ScanResult)."""
    changed = None
    if scene.reshaped is not None:
        moved = scene.reshaped.displacement_mm[scene.reshaped.changed]
        changed = {"vertices": int(scene.reshaped.changed.sum()),
                   "max_outward_mm": float(max(moved.max(), 0.0)), "max_inward_mm": float(max(-moved.min(), 0.0))}
    return {
        "format": "workcal-simulation-truth",
        "version": 1,
        "units": {"length": "mm", "angle": "deg"},
        "workpiece": scene.workpiece_original.name,
        "seed": scene.seed,
        "W": scene.W.tolist(),
        "W_pose": _pose(scene.W),
        "workpiece_upright_in_X": np.asarray(scene.workpiece_upright).tolist(),
        "clay_change": changed,
        "objects": [{"name": o.name, "role": o.role, "pose_in_B": o.pose.tolist()} for o in scene.objects],
        "scans": [{"file": name, **scan_truth(result)} for name, result in scans],
    }


def write_truth(path, truth: dict) -> None:
    """Indented JSON with each innermost list of numbers (a matrix row, a vector) on one line."""
    text = re.sub(r"\[\s*(-?[0-9][-+0-9.eE]*(?:,\s*-?[0-9][-+0-9.eE]*)*)\s*\]",
                  lambda m: "[" + re.sub(r",\s*", ", ", m.group(1)) + "]", json.dumps(truth, indent=2))
    atomic_write_text(path, text + "\n")
