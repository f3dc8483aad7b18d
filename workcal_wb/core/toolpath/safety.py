"""What keeps a bad program off a controller: finite numbers, a sane W, a work envelope, the machine's
axes, the calibration's gates.

Every check runs before a single byte is written; together with atomic writing this means a refused
export leaves no file behind and an older file untouched.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

from scipy.spatial import cKDTree

from .. import frames
from ..errors import InputError, WorkCalError
from ..pointops import sample_triangles
from ..result import CHOSEN, CalibrationResult, status_gate_code
from ..surface import SurfaceModel
from . import orientation
from .model import CODE, RAPID, RotaryTable, Toolpath
from .transform import DEFAULT_CHORD_TOL_MM, MIN_CHORD_TOL_MM, path_points, placement

# No robot cell or machine tool reaches past this (mm from the base frame's origin): a W or a point
# beyond it is a broken calibration or a unit mix-up, refused even without an --envelope.
SANITY_MM = 50_000.0
MACHINES = ("3axis", "5axis-tcp", "robot")
# Largest tilt of the tool axis from the machine's Z that a 3-axis export accepts unless told otherwise.
DEFAULT_VERTICAL_TOL_DEG = 0.05
DEFAULT_FANUC_CONFIG = "N U T, 0, 0, 0"
# The fewest lines a program part may be cut to: its frame (header, declarations, END) takes that many.
MIN_PART_LINES = 10
FANUC_CONFIG = re.compile(r"[NF] [UD] [TB], -?[0-9], -?[0-9], -?[0-9]")
# How far (mm) a toolpath's cutting moves may run from the workpiece model, as their median: finishing and
# roughing passes run within a cutter's length of it, a toolpath made for another part runs far off.
DEFAULT_PATH_REACH_MM = 25.0
# Points along the cutting moves whose distances to the model give that median (evenly by length; a
# median of this many is known to a fraction of a percent of the distances' spread).
PATH_SAMPLES = 20_000


class ExportRefused(WorkCalError):
    """The inputs were readable but exporting them would be unsafe (failed gates, envelope, NaN)."""


class PathOffModel(ExportRefused):
    """The toolpath's cutting moves run a median ``median_mm`` from the workpiece model, more than
    ``reach_mm``: the toolpath was made for another part (or the model is not the workpiece's)."""

    def __init__(self, message: str, median_mm: float, reach_mm: float):
        super().__init__(message)
        self.median_mm, self.reach_mm = median_mm, reach_mm


class CalibrationNotOk(ExportRefused):
    """The calibration's status is not "ok": the one refusal that forcing the export overrides."""

    def __init__(self, message: str, status: str):
        super().__init__(message)
        self.status = status


class ReachRefused(ExportRefused):
    """The robot cannot follow the program (robots/reach.py): ``report`` says where and why (its
    ``problem`` code), ``suggestion`` (robots.placement.PartMove, or None) where to put the part
    instead.  Forcing the export overrides it, as it does a calibration that is not ok."""

    def __init__(self, message: str, report, suggestion=None):
        super().__init__(message)
        self.report, self.suggestion = report, suggestion


class ToolTilted(ExportRefused):
    """A 3-axis export whose tool axis leaves the machine's Z by ``tilt_deg``, more than ``tolerance_deg``:
    tilted by W, or a 5-axis toolpath (``five_axis_path``: only a 5-axis machine can follow it).  The
    ways out (level the part, allow the tilt, export for 5 axes) are the caller's to offer."""

    def __init__(self, message: str, tilt_deg: float, tolerance_deg: float, five_axis_path: bool = False):
        super().__init__(message)
        self.tilt_deg, self.tolerance_deg, self.five_axis_path = tilt_deg, tolerance_deg, five_axis_path


def number(value: float, decimals: int) -> str:
    """Fixed-point text of a finite number; every single number an exporter writes goes through here
    or through ``numbers`` (the same rule for a column) or ``writable`` (the same, for a whole line)."""
    if not math.isfinite(value):
        raise ExportRefused(f"refusing to write a non-finite number ({value})")
    text = f"{value:.{decimals}f}"
    return text.lstrip("-") if float(text) == 0 else text  # "0.000", never "-0.000"


def numbers(values, decimals: int) -> list[str]:
    """``number`` for a whole array (read in C order): values that round to zero are written unsigned."""
    form = f"%.{decimals}f"
    return [form % v for v in writable(values, decimals).reshape(-1).tolist()]


def writable(values, decimals: int) -> np.ndarray:
    """The values ``numbers`` writes, as floats (refused when one is not finite, those that round to
    zero made 0.0): for an exporter that writes whole lines at once with the same ``%.{decimals}f``."""
    values = np.asarray(values, dtype=float)
    if not np.all(np.isfinite(values)):
        raise ExportRefused("refusing to write a non-finite number")
    return np.where(np.abs(values) < 0.5 * 10.0 ** -decimals, 0.0, values)


@dataclass
class Envelope:
    """Axis-aligned box in the robot base frame B (mm) that every written position must lie in."""

    lower: np.ndarray
    upper: np.ndarray

    @classmethod
    def parse(cls, text: str) -> "Envelope":
        """From "xmin,ymin,zmin,xmax,ymax,zmax" (mm)."""
        try:
            values = [float(v) for v in text.split(",")]
        except ValueError:
            values = []
        if len(values) != 6 or not all(map(math.isfinite, values)):
            raise InputError(f"work envelope {text!r}: expected six numbers xmin,ymin,zmin,xmax,ymax,zmax in mm")
        lower, upper = np.array(values[:3]), np.array(values[3:])
        if np.any(lower >= upper):
            raise InputError(f"work envelope {text!r}: each minimum must be below its maximum")
        return cls(lower, upper)

    def describe(self) -> str:
        return ", ".join(f"{a} [{lo:g}, {hi:g}]" for a, lo, hi in zip("xyz", self.lower, self.upper))


SANITY_ENVELOPE = Envelope(np.full(3, -SANITY_MM), np.full(3, SANITY_MM))


@dataclass
class ExportOptions:
    """How to export: safety settings, the target machine and each language's choices (settings as data)."""

    force: bool = False
    envelope: Envelope | None = None
    table: RotaryTable | None = None
    chord_tol_mm: float = DEFAULT_CHORD_TOL_MM
    machine: str | None = None  # None: "3axis" for G-code, "robot" for the robot formats
    vertical_tol_deg: float = DEFAULT_VERTICAL_TOL_DEG
    rotary: str = "ab"  # 5-axis G-code: the machine's two rotary axes (orientation.ROTARY)
    krl_mode: str = "base"
    fanuc_config: str = DEFAULT_FANUC_CONFIG  # flip, elbow, base side, turns of J1 J4 J6: the robot's, not computed
    rapid_feed_mm_min: float = 6000.0
    max_lines: int | None = None  # lines per program part; None: the language's own limit
    calibration_source: str = "calibration"
    workpiece_model: object = None  # the workpiece model X-A (a Cloud or a prepared SurfaceModel), to hold the path to
    path_reach_mm: float = DEFAULT_PATH_REACH_MM
    robot: object = None  # robots.Robot whose reach a robot program is checked against (None: not checked)
    tool: np.ndarray = field(default_factory=lambda: np.eye(4))  # the TCP in the robot's flange frame, 4x4, mm

    def check(self) -> None:
        if not (math.isfinite(self.chord_tol_mm) and self.chord_tol_mm >= MIN_CHORD_TOL_MM):
            raise InputError(f"chordal tolerance (--chord-tol) must be at least {MIN_CHORD_TOL_MM:g} mm (positions are "
                             f"written to that), not {self.chord_tol_mm:g}")
        if self.machine is not None and self.machine not in MACHINES:
            raise InputError(f"unknown machine {self.machine!r}; use one of {', '.join(MACHINES)}")
        if not (math.isfinite(self.vertical_tol_deg) and 0 <= self.vertical_tol_deg < 90):
            raise InputError(f"vertical tolerance must be between 0 and 90 degrees, not {self.vertical_tol_deg}")
        if self.rotary not in orientation.ROTARY:
            raise InputError(f"unknown rotary axes {self.rotary!r}; use one of {', '.join(orientation.ROTARY)}")
        if not FANUC_CONFIG.fullmatch(self.fanuc_config):
            raise InputError(f"Fanuc configuration {self.fanuc_config!r}: expected flip (N/F), elbow (U/D), "
                             "base side (T/B) and the turn numbers of J1, J4, J6, as in 'N U T, 0, 0, 0'")
        if not (math.isfinite(self.rapid_feed_mm_min) and self.rapid_feed_mm_min > 0):
            raise InputError(f"rapid feed must be a positive number of mm/min, not {self.rapid_feed_mm_min}")
        if not (math.isfinite(self.path_reach_mm) and self.path_reach_mm > 0):
            raise InputError(f"the toolpath's reach from the workpiece model must be a positive number of mm, "
                             f"not {self.path_reach_mm}")
        try:
            tool = frames.as_transform(self.tool, "tool")
        except (ValueError, TypeError) as exc:
            raise InputError(f"the tool (the TCP in the robot's flange frame) is not a rigid 4x4 transform: "
                             f"{exc}") from None
        if not np.linalg.norm(tool[:3, 3]) <= SANITY_MM:
            raise InputError(f"the tool (the TCP in the robot's flange frame) is {np.linalg.norm(tool[:3, 3]):.6g} mm "
                             f"from the flange, more than any tool ({SANITY_MM / 1000:g} m): check the units")
        if self.robot is not None and self.fanuc_config != DEFAULT_FANUC_CONFIG:
            raise InputError(f"Fanuc configuration {self.fanuc_config!r} given with robot {self.robot.id}: with a "
                             "robot every position's configuration comes from its solution; give one or the other")
        if self.max_lines is not None and self.max_lines < MIN_PART_LINES:
            raise InputError(f"lines per program part (--max-lines) must be at least {MIN_PART_LINES}, "
                             f"not {self.max_lines}")


def check_moves(toolpath: Toolpath) -> None:
    """Refuse non-finite feeds and tool axes (positions are checked in B by ``check_positions``)."""
    bad_feed = np.isinf(toolpath.feed) | (~np.isnan(toolpath.feed) & ~np.isfinite(toolpath.feed))
    bad_axis = ~np.all(np.isfinite(toolpath.axes()), axis=1)
    bad = np.flatnonzero(bad_feed | bad_axis | (np.isnan(toolpath.feed) & (toolpath.kind > 0)))
    if bad.size:
        raise ExportRefused(f"{toolpath.source}: {toolpath.where(int(bad[0]))} has a non-finite feed or tool axis; "
                            "nothing was written")


def check_positions(points_B: np.ndarray, where, source: str, envelope: Envelope | None) -> None:
    """Refuse the first non-finite or out-of-envelope point; ``where(k)`` names point k in the message."""
    for box, what in ((SANITY_ENVELOPE, None), (envelope, "envelope")):
        if box is None:
            continue
        finite = np.all(np.isfinite(points_B), axis=1)
        inside = finite & np.all((points_B >= box.lower) & (points_B <= box.upper), axis=1)
        bad = np.flatnonzero(~inside)
        if bad.size == 0:
            continue
        k = int(bad[0])
        if not finite[k]:
            raise ExportRefused(f"{source}: {where(k)} has a non-finite position; nothing was written")
        x, y, z = points_B[k]
        reach = (f"outside the work envelope {box.describe()}" if what else
                 f"more than {SANITY_MM / 1000:g} m from the base frame, which no machine reaches (check the "
                 "calibration and the units)")
        raise ExportRefused(f"{source}: {where(k)} reaches ({x:.3f}, {y:.3f}, {z:.3f}) mm in the robot base "
                            f"frame, {reach}; nothing was written")


def check_sanity(T: np.ndarray, source: str) -> None:
    """Refuse a placement that moves the workpiece farther than any machine reaches."""
    distance = float(np.linalg.norm(T[:3, 3]))
    if not distance <= SANITY_MM:
        raise ExportRefused(f"{source}: W moves the workpiece {distance:.6g} mm from the robot base frame, farther "
                            f"than any machine reaches ({SANITY_MM / 1000:g} m): the calibration is broken or in the "
                            "wrong units; nothing was written")


def check_vertical(toolpath: Toolpath, T: np.ndarray, tolerance_deg: float) -> float:
    """For a 3-axis machine: the largest tilt (deg) of the tool axis from the machine's Z; refuses past
    ``tolerance_deg`` with what to do."""
    axes = orientation.VERTICAL[None] if toolpath.tool_axis is None else toolpath.tool_axis
    tilts = orientation.tilt_deg(axes @ T[:3, :3].T)
    i = int(np.argmax(tilts))
    tilt = float(tilts[i])
    if tilt <= tolerance_deg:
        return tilt
    if len(np.unique(np.round(axes, 9), axis=0)) > 1:
        raise ToolTilted(f"{toolpath.source}: {toolpath.where(i)} tilts the tool {tilt:.3f} deg from the machine's "
                         "Z: a 3-axis machine cannot follow this 5-axis toolpath; export for a 5-axis machine "
                         "(--machine 5axis-tcp); nothing was written", tilt, tolerance_deg, five_axis_path=True)
    raise ToolTilted(
        f"{toolpath.source}: W tilts the tool axis {tilt:.4f} deg from the machine's Z, more than the 3-axis "
        f"tolerance {tolerance_deg:g} deg, so a 3-axis machine cannot hold the tool as the toolpath means. "
        "Level the part on the table (shim it) and calibrate again, accept the tilt for your tool with "
        f"--vertical-tol {math.ceil(tilt * 100) / 100:g} or more, or export for a 5-axis machine "
        "(--machine 5axis-tcp); nothing was written", tilt, tolerance_deg)


def value_text(value) -> str:
    """A value for a comment: as it is, but "n/a" for NaN/inf (no non-finite number reaches a file)."""
    return "n/a" if isinstance(value, float) and not math.isfinite(value) else str(value)


def gate_text(gate: dict) -> str:
    """One quality gate in words: "gate rms_mm = 0.8 mm, limit 0.3"."""
    unit = f" {gate['unit']}" if gate.get("unit") else ""
    value, limit = value_text(gate.get("value")), value_text(gate.get("limit"))
    return f"gate {gate.get('name', '?')} = {value}{unit}, limit {limit}"


def failed_checks(calibration: CalibrationResult) -> list[str]:
    """The failed quality gates (or, without gates, the reasons) in words."""
    words = [gate_text(g) for g in calibration.quality_gates if not g.get("passed", False)]
    return words or [str(r) for r in calibration.reasons] or ["no reason recorded"]


def check_calibration(calibration: CalibrationResult, force: bool, source: str = "calibration") -> bool:
    """True when the export goes ahead only because it was forced; refuses a non-"ok" result otherwise."""
    if calibration.W is None:
        raise InputError(f"{source}: calibration has no transform W (status {calibration.status!r}); nothing to export")
    failed = [g for g in calibration.quality_gates if g.get("passed") is False]
    if calibration.status == CHOSEN:  # a person chose among the poses: only that match's status gate stays failed
        failed = [g for g in failed if g.get("code") != status_gate_code(calibration.choice.role)]
    if calibration.ok and failed:
        raise InputError(f"{source}: status {calibration.status!r} while its {gate_text(failed[0])} failed: the file "
                         "contradicts itself (edited, or not written by WorkCal); calibrate again")
    if calibration.ok:
        return False
    if not force:
        raise CalibrationNotOk(
            f"{source}: calibration status is {calibration.status!r} ({'; '.join(failed_checks(calibration))}); "
            "refusing to export. Fix the calibration, or force the export (--force) "
            "and the file says FORCED at its top", calibration.status)
    return True


def forced_banner(calibration: CalibrationResult) -> list[str]:
    """The lines a forced export starts with."""
    return [
        f"FORCED EXPORT: the calibration did NOT pass its quality gates, status {calibration.status!r}.",
        "Failed: " + "; ".join(failed_checks(calibration)),
        "Do not run this program before checking the workpiece position by hand.",
    ]


def cutting_points(toolpath: Toolpath, chord_tol_mm: float, count: int = PATH_SAMPLES) -> np.ndarray:
    """Up to ``count`` points evenly spaced along the path's cutting (non-rapid) moves, arcs followed
    within ``chord_tol_mm``; the cutting moves' end points when they have no length."""
    points, owners = path_points(toolpath, chord_tol_mm)
    cutting = toolpath.kind[owners] != CODE[RAPID]
    if not cutting.any():
        return np.empty((0, 3))
    starts, ends = points[:-1][cutting[1:]], points[1:][cutting[1:]]
    lengths = np.linalg.norm(ends - starts, axis=1)
    total = float(lengths.sum())
    if not total > 0:
        return points[cutting][:count]
    along = (np.arange(count) + 0.5) * (total / count)
    cumulative = np.cumsum(lengths)
    k = np.minimum(np.searchsorted(cumulative, along), len(lengths) - 1)
    share = 1.0 - (cumulative[k] - along) / np.where(lengths[k] > 0, lengths[k], 1.0)
    return starts[k] + np.clip(share, 0.0, 1.0)[:, None] * (ends[k] - starts[k])


def _surface_samples(model, spacing_mm: float) -> np.ndarray:
    """Points on the model's surface at most about ``spacing_mm`` apart (a prepared model's own samples)."""
    if isinstance(model, SurfaceModel):
        return model.points
    if model.is_mesh:
        return sample_triangles(model.points, model.triangles, spacing_mm)[0]
    return model.points


def check_on_model(toolpath: Toolpath, model, reach_mm: float, chord_tol_mm: float) -> str:
    """The header's line on how the toolpath lies on the workpiece model (both in X); refuses
    (PathOffModel) when its cutting moves run a median of more than ``reach_mm`` from the surface."""
    points = cutting_points(toolpath, chord_tol_mm)
    if not len(points):
        return "toolpath on the workpiece model: no cutting moves to hold to it"
    surface = _surface_samples(model, reach_mm / 5)
    distances = cKDTree(surface).query(points)[0]
    median = float(np.median(distances))
    within = 100.0 * float(np.mean(distances <= reach_mm))
    if median <= reach_mm:
        return (f"toolpath on the workpiece model {getattr(model, 'name', '')}: cutting moves a median "
                f"{median:.2f} mm from its surface, {within:.0f} % within the reach {reach_mm:g} mm")
    raise PathOffModel(
        f"{toolpath.source}: its cutting moves run a median {median:.1f} mm from the workpiece model "
        f"{getattr(model, 'name', '')} ({within:.0f} % within {reach_mm:g} mm of its surface): the toolpath was "
        "made for another part, or the model is not this part's (mirrored? another file?); nothing was written",
        median, reach_mm)


@dataclass(frozen=True)
class Placement:
    """What the checks of an export found: the X -> B transform to use, whether the export goes ahead only
    because it was forced (``banner``: the lines that say why, first in the header), the facts the
    program's header states, and the robot's reach (robots.reach.ReachReport, None when not checked)."""

    transform: np.ndarray
    forced: bool
    notes: tuple = ()
    banner: tuple = ()
    reach: object = None


def checked_placement(toolpath: Toolpath, calibration: CalibrationResult, options: ExportOptions,
                      machine: str = "robot") -> Placement:
    """Every check an export needs, in one place.

    Positions are checked in B along the whole path (arcs sampled within the chordal tolerance), so a
    program written in workpiece coordinates is held to the same envelope as one written in B; the
    sanity bound applies whether or not an envelope is given.  With the workpiece model, the path's
    cutting moves are held to its surface (``check_on_model``); without, the header says so."""
    options.check()
    if not len(toolpath):
        raise InputError(f"{toolpath.source}: no moves to export")
    forced = check_calibration(calibration, options.force, options.calibration_source)
    T = placement(calibration.W, options.table)
    check_sanity(T, options.calibration_source)
    check_moves(toolpath)
    if machine == "3axis":
        check_vertical(toolpath, T, options.vertical_tol_deg)
    points, owners = path_points(toolpath, options.chord_tol_mm)
    check_positions(frames.apply(T, points), lambda k: toolpath.where(int(owners[k])), toolpath.source,
                    options.envelope)
    if options.workpiece_model is None:
        note = "toolpath on the workpiece model: not checked (no model given)"
    else:
        note = check_on_model(toolpath, options.workpiece_model, options.path_reach_mm, options.chord_tol_mm)
    return Placement(T, forced, (note,), tuple(forced_banner(calibration)) if forced else ())
