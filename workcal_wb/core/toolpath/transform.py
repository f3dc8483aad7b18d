"""Move a toolpath from the workpiece frame X into the robot base frame B.

FreeCAD's ``Path.Command.transform`` does not rotate points, so WorkCal transforms every point, arc
centre, arc normal and tool axis itself.  An arc stays an arc when its rotated plane is still a
machine plane (XY, ZX or YZ); otherwise it becomes line segments within a chordal tolerance.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .. import frames
from ..errors import InputError
from . import arcs
from .model import LINEAR, Move, RotaryTable, Toolpath

DEFAULT_CHORD_TOL_MM = 0.01
_AXIS_COS = 1 - 1e-9  # a rotated arc normal this close to X, Y or Z keeps its arc (round-off only)


def placement(W: np.ndarray, table: RotaryTable | None = None) -> np.ndarray:
    """X -> B for the export: W, or on the rotary table ^B Q Rz(angle) ^Q X with ^Q X = ^B Q^-1 W."""
    if table is None:
        return np.asarray(W, dtype=float)
    try:
        BQ = frames.as_transform(table.frame, table.source)
    except ValueError as exc:
        raise InputError(str(exc)) from None
    return frames.compose(BQ, frames.rigid(frames.rot_z(table.angle_deg)), frames.invert(BQ), W)


def _segments(start: np.ndarray, move: Move, chord_tol_mm: float) -> list[Move]:
    points = arcs.linearise(start, move, chord_tol_mm)
    return [replace(move, kind=LINEAR, end=p, centre=None, normal=None, comment=move.comment if i == 0 else "")
            for i, p in enumerate(points)]


def linearised(toolpath: Toolpath, chord_tol_mm: float = DEFAULT_CHORD_TOL_MM) -> Toolpath:
    """The same path with every arc replaced by chords within ``chord_tol_mm`` of it."""
    moves = []
    for start, move in zip(toolpath.starts(), toolpath.moves):
        moves += _segments(start, move, chord_tol_mm) if move.is_arc else [move]
    return replace(toolpath, moves=moves)


def path_points(toolpath: Toolpath, chord_tol_mm: float = DEFAULT_CHORD_TOL_MM) -> tuple[np.ndarray, np.ndarray]:
    """Every point the tool passes within ``chord_tol_mm`` (arcs sampled), and the index of its move."""
    points, owners = [], []
    for i, (start, move) in enumerate(zip(toolpath.starts(), toolpath.moves)):
        pts = arcs.linearise(start, move, chord_tol_mm) if move.is_arc else move.end[None]
        points.append(pts)
        owners += [i] * len(pts)
    return np.vstack(points) if points else np.empty((0, 3)), np.array(owners, dtype=int)


def _machine_normal(normal: np.ndarray) -> np.ndarray | None:
    """``normal`` snapped to +-X, +-Y or +-Z, or None when it is not along one of them."""
    axis = int(np.argmax(np.abs(normal)))
    if abs(normal[axis]) < _AXIS_COS:
        return None
    snapped = np.zeros(3)
    snapped[axis] = np.sign(normal[axis])
    return snapped


def transformed(toolpath: Toolpath, T: np.ndarray, chord_tol_mm: float = DEFAULT_CHORD_TOL_MM) -> Toolpath:
    """The toolpath in the frame T maps into (p' = T p), with tool axes rotated by T."""
    T = np.asarray(T, dtype=float)
    moves = []
    for start, move in zip(toolpath.starts(), toolpath.moves):
        normal = None if not move.is_arc else _machine_normal(frames.apply_vectors(T, move.normal[None])[0])
        pieces = _segments(start, move, chord_tol_mm) if move.is_arc and normal is None else [move]
        for piece in pieces:
            moves.append(replace(
                piece,
                end=frames.apply(T, piece.end[None])[0],
                tool_axis=frames.apply_vectors(T, piece.tool_axis[None])[0],
                centre=None if not piece.is_arc else frames.apply(T, piece.centre[None])[0],
                normal=normal if piece.is_arc else None,
            ))
    return replace(toolpath, moves=moves)
