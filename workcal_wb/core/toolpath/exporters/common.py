"""What every exporter shares: the job, the header (W, quality, conventions), robot poses, names."""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from workcal_wb import __version__

from ... import frames
from ...errors import InputError
from ...result import CalibrationResult
from ..model import RotaryTable, Toolpath
from ..orientation import tool_rotation
from ..safety import forced_banner, gate_text, number, value_text
from ..transform import linearised

# Robots have no G0: rapids become linear moves at this speed unless the caller says otherwise.
DEFAULT_RAPID_FEED_MM_MIN = 6000.0
# Corner blending for robot moves (KRL $APO.CDIS, RAPID zone): well inside a 0.3 mm calibration tolerance.
BLEND_MM = 0.1
ORIENTATION_NOTE = ("tool orientation: tool Z = -tool axis, along the approach into the part; tool X = workpiece +X "
                    "projected perpendicular to tool Z, or workpiece +Y when the tool axis lies along X")


@dataclass
class ExportJob:
    """Everything an exporter renders from; every check has passed before one is made."""

    toolpath: Toolpath  # in the workpiece frame X, mm
    calibration: CalibrationResult
    transform: np.ndarray  # X -> B actually used (W, or the rotary-table chain)
    forced: bool
    out: Path
    chord_tol_mm: float
    table: RotaryTable | None = None
    krl_mode: str = "base"
    rapid_feed_mm_min: float = DEFAULT_RAPID_FEED_MM_MIN


@dataclass
class Pose:
    """One robot target: 4x4 tool pose in the output frame, speed, and where it came from."""

    matrix: np.ndarray
    feed_mm_min: float
    rapid: bool
    comment: str
    line: int | None


def robot_poses(toolpath: Toolpath, T: np.ndarray, chord_tol_mm: float, rapid_feed_mm_min: float) -> list[Pose]:
    """Robot targets along the linearised path, carried by T (workpiece frame -> output frame).

    The orientation is built in the workpiece frame and then carried by T, so a program in workpiece
    coordinates and one in B describe the same physical tool pose."""
    out = []
    for move in linearised(toolpath, chord_tol_mm).moves:
        pose = T @ frames.rigid(tool_rotation(move.tool_axis), move.end)
        rapid = move.feed is None
        out.append(Pose(pose, rapid_feed_mm_min if rapid else move.feed, rapid, move.comment, move.line))
    return out


def poses(job: ExportJob, in_base_frame: bool) -> list[Pose]:
    """The job's robot targets in B, or (``in_base_frame=False``) in the workpiece frame."""
    return robot_poses(job.toolpath, job.transform if in_base_frame else np.eye(4), job.chord_tol_mm,
                       job.rapid_feed_mm_min)


def matrix_rows(T: np.ndarray, indent: str = "  ") -> list[str]:
    return [indent + " ".join(f"{number(v, 6):>12}" for v in row) for row in np.asarray(T)]


def _calibration_lines(calibration: CalibrationResult) -> list[str]:
    displacement = calibration.uncertainty.get("toolpath_displacement_mm") or {}
    moved = ", ".join(f"{k} {value_text(v)} mm" for k, v in displacement.items()) or "not estimated"
    lines = [f"calibration: status {calibration.status}, tolerance {value_text(calibration.tolerance_mm)} mm, "
             f"toolpath displacement uncertainty {moved}"]
    lines += [f"{gate_text(g)}: {'passed' if g.get('passed') else 'FAILED'}" for g in calibration.quality_gates]
    return lines + [f"reason: {r}" for r in calibration.reasons]


def header_lines(job: ExportJob, format_name: str, notes: list[str]) -> list[str]:
    """The comment lines every exported file starts with (FORCED banner first when forced)."""
    lines = forced_banner(job.calibration) if job.forced else []
    lines += [f"WorkCal {__version__} toolpath export to {format_name}: {job.out.name}",
              f"toolpath: {job.toolpath.source}, {len(job.toolpath)} moves", *notes,
              "W = ^B X, the workpiece frame X in the robot base frame B, 4x4, mm:", *matrix_rows(job.calibration.W)]
    if job.table is not None:
        lines += [f"rotary table at {number(job.table.angle_deg, 4)} deg; table frame ^B Q, 4x4, mm:",
                  *matrix_rows(job.table.frame),
                  f"transform used = {placement_name(job)}, 4x4, mm:", *matrix_rows(job.transform)]
    return lines + _calibration_lines(job.calibration)


def placement_name(job: ExportJob) -> str:
    """How the header names the transform used: W, or the rotary-table chain."""
    return "W" if job.table is None else "^B Q Rz(angle) ^B Q^-1 W"


def robot_notes(job: ExportJob) -> list[str]:
    """The conventions all robot formats share."""
    return [ORIENTATION_NOTE,
            f"arcs: linearised into chords within {job.chord_tol_mm} mm",
            f"rapids (G0): linear moves at {number(job.rapid_feed_mm_min, 1)} mm/min"]


def program_name(job: ExportJob, max_len: int, must_match_file: bool = False) -> str:
    """A controller-safe program name from the output file name (letters, digits, _; starts with a letter).

    KRL and Fanuc load a program only under its own file name, so there a mismatch is an error."""
    stem = job.out.stem
    name = re.sub(r"\W", "_", stem, flags=re.ASCII)[:max_len]
    if not name[:1].isalpha():
        name = ("P" + name)[:max_len]
    if must_match_file and name.lower() != stem.lower():
        raise InputError(f"{job.out}: the file name must be a valid program name (a letter, then letters, digits or _, "
                         f"at most {max_len} characters), e.g. {name}{job.out.suffix}")
    return name
