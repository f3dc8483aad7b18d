"""A plausible finishing pass over the workpiece: the toolpath X-m the calibration must carry into B.

A zig-zag raster over a patch of the top of the workpiece, a fixed clearance above the surface,
computed in the workpiece's model frame X (as a CAM package would); the lead writes it as G-code.
"""
from __future__ import annotations

import numpy as np

from .. import frames
from ..errors import InputError
from ..geometry import Cloud
from .raster import heights_above

FINISHING_FEED_MM_MIN = 600.0


def sample_toolpath_points(workpiece, upright=None, patch_fraction: float = 0.4, rows: int = 16,
                           points_per_row: int = 64, clearance_mm: float = 1.0,
                           feed_mm_min: float = FINISHING_FEED_MM_MIN) -> tuple[np.ndarray, float]:
    """Points (N, 3) in X, mm, in cutting order, and the feed in mm/min.

    workpiece: a Scene (its unchanged model and upright frame are used) or the model X-A itself (a Cloud
    with triangles, in X) with ``upright`` = ^X N, its body frame with z up (default: X itself).
    The patch is ``patch_fraction`` of the workpiece's length and width, centred on it seen from above;
    each row runs along x of the upright frame, alternating direction, ``clearance_mm`` above the
    surface; raster points with no surface below are skipped (at most rows * points_per_row points).
    """
    if isinstance(workpiece, Cloud):
        mesh, upright = workpiece, np.eye(4) if upright is None else upright
    else:
        mesh, upright = workpiece.workpiece_model(), workpiece.workpiece_upright
    local = frames.apply(frames.invert(upright), mesh.points)
    lo, hi = local[:, :2].min(axis=0), local[:, :2].max(axis=0)
    middle, half = 0.5 * (lo + hi), 0.5 * patch_fraction * (hi - lo)
    xs = np.linspace(middle[0] - half[0], middle[0] + half[0], points_per_row)
    ys = np.linspace(middle[1] - half[1], middle[1] + half[1], rows)
    heights = heights_above(local, mesh.triangles, xs, ys)
    gx, gy = np.meshgrid(xs, ys)
    gx[1::2], gy[1::2], heights[1::2] = gx[1::2, ::-1], gy[1::2, ::-1], heights[1::2, ::-1]  # zig-zag
    path = np.column_stack([gx.ravel(), gy.ravel(), heights.ravel() + clearance_mm])
    path = path[np.isfinite(path[:, 2])]
    if len(path) == 0:
        raise InputError(f"{mesh.name}: no surface under the toolpath patch")
    return frames.apply(upright, path), feed_mm_min


def sample_toolpath(scene, retract_mm: float = 20.0):
    """The finishing pass as a Toolpath in X: rapid above the first point, the raster at the feed,
    rapid back up; the tool axis is the workpiece's up direction (z of its upright frame) in X."""
    from ..toolpath.model import LINEAR, RAPID, Move, Toolpath

    points, feed = sample_toolpath_points(scene)
    up = scene.workpiece_upright[:3, 2]
    moves = [Move(RAPID, points[0] + retract_mm * up, tool_axis=up)]
    moves += [Move(LINEAR, p, feed=feed, tool_axis=up) for p in points]
    moves.append(Move(RAPID, points[-1] + retract_mm * up, tool_axis=up))
    return Toolpath.from_moves(moves, header=[f"WorkCal sample finishing pass over {scene.workpiece_original.name}, "
                                   "workpiece frame X, mm"], source="sample toolpath")
