"""Move a toolpath from the workpiece frame X into the robot base frame B (whole columns at once).

FreeCAD's ``Path.Command.transform`` does not rotate points, so WorkCal transforms every point, arc
centre, arc normal and tool axis itself.  An arc stays an arc when its rotated plane is still a
machine plane (XY, ZX or YZ) closely enough that the machine's arc in that plane stays within the
chordal tolerance of the true one; otherwise it becomes line segments within that tolerance.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .. import frames
from ..errors import InputError
from . import arcs
from .model import CODE, LINEAR, ARC_CCW, RotaryTable, Toolpath

DEFAULT_CHORD_TOL_MM = 0.01
# The finest chordal tolerance taken: programs write positions to 0.0001 mm, and a finer one only
# multiplies the segments.
MIN_CHORD_TOL_MM = 1e-4


def placement(W: np.ndarray, table: RotaryTable | None = None) -> np.ndarray:
    """X -> B for the export: W, or on the rotary table ^B Q Rz(angle) ^Q X with ^Q X = ^B Q^-1 W."""
    if table is None:
        return np.asarray(W, dtype=float)
    try:
        BQ = frames.as_transform(table.frame, table.source)
    except ValueError as exc:
        raise InputError(str(exc)) from None
    return frames.compose(BQ, frames.rigid(frames.rot_z(table.angle_deg)), frames.invert(BQ), W)


def _arc_rows(toolpath: Toolpath):
    """Start, end, ccw flag of every arc, in the order of ``arc_centre``."""
    index = np.flatnonzero(toolpath.arc_mask)
    return toolpath.starts()[index], toolpath.end[index], toolpath.kind[index] == CODE[ARC_CCW], index


def _remap(mapping: dict, first: np.ndarray) -> dict:
    return {int(first[i]): v for i, v in mapping.items()}


def _expand(toolpath: Toolpath, split: np.ndarray, chord_tol_mm: float) -> Toolpath:
    """The path with the arcs marked in ``split`` (one flag per arc) replaced by chords."""
    if not split.any():
        return toolpath
    starts, ends, ccw, index = _arc_rows(toolpath)
    points, pieces = arcs.linearise(starts[split], ends[split], toolpath.arc_centre[split],
                                    toolpath.arc_normal[split], ccw[split], chord_tol_mm)
    n = len(toolpath)
    counts = np.ones(n, dtype=np.int64)
    counts[index[split]] = pieces
    owner = np.repeat(np.arange(n), counts)
    first = np.append(np.cumsum(counts) - counts, counts.sum())
    chords = np.zeros(n, dtype=bool)
    chords[index[split]] = True
    chord_rows = chords[owner]
    kind, end = toolpath.kind[owner], toolpath.end[owner]
    kind[chord_rows] = CODE[LINEAR]
    end[chord_rows] = points
    axes = toolpath.tool_axis
    return toolpath.with_columns(
        kind=kind, end=end, feed=toolpath.feed[owner], line=toolpath.line[owner],
        tool_axis=axes if axes is None or len(axes) == 1 else axes[owner],
        arc_centre=toolpath.arc_centre[~split], arc_normal=toolpath.arc_normal[~split],
        comments=_remap(toolpath.comments, first), partial=_remap(toolpath.partial, first),
        events=[replace(e, before=int(first[e.before])) for e in toolpath.events])


def linearised(toolpath: Toolpath, chord_tol_mm: float = DEFAULT_CHORD_TOL_MM) -> Toolpath:
    """The same path with every arc replaced by chords within ``chord_tol_mm`` of it."""
    return _expand(toolpath, np.ones(len(toolpath.arc_centre), dtype=bool), chord_tol_mm)


def path_points(toolpath: Toolpath, chord_tol_mm: float = DEFAULT_CHORD_TOL_MM) -> tuple[np.ndarray, np.ndarray]:
    """Every point the tool passes within ``chord_tol_mm`` (arcs sampled), and the index of its move."""
    starts, ends, ccw, index = _arc_rows(toolpath)
    if not len(index):
        return toolpath.end, np.arange(len(toolpath))
    points, pieces = arcs.linearise(starts, ends, toolpath.arc_centre, toolpath.arc_normal, ccw, chord_tol_mm)
    counts = np.ones(len(toolpath), dtype=np.int64)
    counts[index] = pieces
    owner = np.repeat(np.arange(len(toolpath)), counts)
    out = toolpath.end[owner]
    is_arc = np.zeros(len(toolpath), dtype=bool)
    is_arc[index] = True
    out[is_arc[owner]] = points
    return out, owner


def _machine_normals(normals: np.ndarray, radii: np.ndarray, chord_tol_mm: float) -> tuple[np.ndarray, np.ndarray]:
    """Normals snapped to +-X, +-Y or +-Z, and whether the arc may keep it: the machine's arc in that
    plane strays from the true one by at most 2 r sin(angle between the planes)."""
    axis = np.argmax(np.abs(normals), axis=1)
    along = np.abs(normals[np.arange(len(normals)), axis])
    sine = np.sqrt(np.clip(1 - along ** 2, 0, None))
    keep = (sine < 1e-9) | (2 * radii * sine <= chord_tol_mm)
    snapped = np.zeros_like(normals)
    snapped[np.arange(len(normals)), axis] = np.sign(normals[np.arange(len(normals)), axis])
    return snapped, keep


def transformed(toolpath: Toolpath, T: np.ndarray, chord_tol_mm: float = DEFAULT_CHORD_TOL_MM) -> Toolpath:
    """The toolpath in the frame T maps into (p' = T p), with tool axes rotated by T."""
    T = np.asarray(T, dtype=float)
    R, t = T[:3, :3], T[:3, 3]
    axes = toolpath.tool_axis
    moved = toolpath.with_columns(
        end=toolpath.end @ R.T + t,
        tool_axis=(np.array([[0.0, 0.0, 1.0]]) if axes is None else axes) @ R.T,
        arc_centre=toolpath.arc_centre @ R.T + t, arc_normal=toolpath.arc_normal @ R.T)
    if not len(moved.arc_centre):
        return moved
    starts, _, _, _ = _arc_rows(moved)
    radii = arcs.radius(starts, moved.arc_centre, moved.arc_normal).reshape(-1)
    snapped, keep = _machine_normals(moved.arc_normal, radii, chord_tol_mm)
    rise = np.sum((moved.arc_centre - starts) * snapped, axis=1, keepdims=True)
    centres = np.where(keep[:, None], moved.arc_centre - rise * snapped, moved.arc_centre)
    normals = np.where(keep[:, None], snapped, moved.arc_normal)
    return _expand(moved.with_columns(arc_centre=centres, arc_normal=normals), ~keep, chord_tol_mm)
