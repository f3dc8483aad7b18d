"""Tool orientation from a tool axis, and the angle conventions each controller expects.

A 3-axis toolpath gives only the tool axis (tip to spindle, +Z of the workpiece for a spindle pointing
down onto the part); a robot needs a full orientation.  The choice, the same for every exporter:

* tool Z = -tool axis, so the tool frame's Z points along the approach direction, into the part;
* tool X = the workpiece's +X projected perpendicular to tool Z (its +Y when the axis lies within
  ``_PARALLEL_COS`` of X), so the rotation about the axis is fixed by the workpiece, not by the robot.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from .. import frames

_PARALLEL_COS = 0.999  # |cos| above which the workpiece X is too close to the tool axis to fix tool X


def tool_rotation(tool_axis) -> np.ndarray:
    """3x3 rotation whose columns are the tool frame's X, Y, Z in the frame of ``tool_axis``."""
    axis = np.asarray(tool_axis, dtype=float)
    z = -axis / np.linalg.norm(axis)
    reference = np.array([1.0, 0, 0]) if abs(z[0]) < _PARALLEL_COS else np.array([0, 1.0, 0])
    x = reference - np.dot(reference, z) * z
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def kuka_abc_deg(R) -> np.ndarray:
    """KUKA A, B, C: R = Rz(A) Ry(B) Rx(C), i.e. Z-Y'-X'' intrinsic, degrees."""
    return Rotation.from_matrix(np.asarray(R)[:3, :3]).as_euler("ZYX", degrees=True)


def fanuc_wpr_deg(R) -> np.ndarray:
    """Fanuc W, P, R: fixed (extrinsic) X, then Y, then Z, degrees: R = Rz(R) Ry(P) Rx(W)."""
    return Rotation.from_matrix(np.asarray(R)[:3, :3]).as_euler("xyz", degrees=True)


def rotation_vector_rad(R) -> np.ndarray:
    """Universal Robots rotation vector: axis times angle, radians."""
    return Rotation.from_matrix(np.asarray(R)[:3, :3]).as_rotvec()


def quaternion_wxyz(R) -> np.ndarray:
    """ABB order q1..q4 = w, x, y, z, with w >= 0."""
    return frames.quaternion_wxyz(frames.rigid(np.asarray(R)[:3, :3]))


def gcode_ab_deg(tool_axis) -> tuple[float, float]:
    """5-axis G-code angles (A about X, B about Y) with tool axis = Ry(B) Rx(A) (0, 0, 1)."""
    t = np.asarray(tool_axis, dtype=float)
    t = t / np.linalg.norm(t)
    return float(np.degrees(-np.arcsin(np.clip(t[1], -1, 1)))), float(np.degrees(np.arctan2(t[0], t[2])))


def tool_axis_from_ab(a_deg: float, b_deg: float) -> np.ndarray:
    """Inverse of ``gcode_ab_deg``."""
    return frames.rot_y(b_deg) @ frames.rot_x(a_deg) @ np.array([0.0, 0, 1])


def is_vertical(tool_axis) -> bool:
    """True for the 3-axis tool axis +Z (what plain XYZ G-code means)."""
    return bool(np.allclose(tool_axis, (0.0, 0.0, 1.0), atol=1e-9))
