"""Tool orientation from a tool axis, and the angle conventions each controller expects (vectorised).

A 3-axis toolpath gives only the tool axis (tip to spindle, +Z of the workpiece for a spindle pointing
down onto the part); a robot needs a full orientation.  The choice, the same for every exporter:

* tool Z = -tool axis, so the tool frame's Z points along the approach direction, into the part;
* tool X = the workpiece's +X projected perpendicular to tool Z (its +Y when the axis lies within
  ``_PARALLEL_COS`` of X), so the rotation about the axis is fixed by the workpiece, not by the robot.

Every function takes one rotation (3x3 or 4x4) or a stack of them (N, 3, 3) and answers in kind.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

_PARALLEL_COS = 0.999  # |cos| above which the workpiece X is too close to the tool axis to fix tool X
VERTICAL = np.array([0.0, 0.0, 1.0])


def tool_rotations(tool_axes) -> np.ndarray:
    """(N, 3, 3) rotations whose columns are the tool frame's X, Y, Z in the frame of ``tool_axes`` (N, 3)."""
    axes = np.asarray(tool_axes, dtype=float).reshape(-1, 3)
    z = -axes / np.linalg.norm(axes, axis=1, keepdims=True)
    reference = np.where((np.abs(z[:, 0]) < _PARALLEL_COS)[:, None], [1.0, 0, 0], [0, 1.0, 0])
    x = reference - np.sum(reference * z, axis=1, keepdims=True) * z
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    return np.stack([x, np.cross(z, x), z], axis=2)


def _rotation(R) -> Rotation:
    R = np.asarray(R, dtype=float)
    return Rotation.from_matrix(R[..., :3, :3])


def kuka_abc_deg(R) -> np.ndarray:
    """KUKA A, B, C: R = Rz(A) Ry(B) Rx(C), i.e. Z-Y'-X'' intrinsic, degrees."""
    return _rotation(R).as_euler("ZYX", degrees=True)


def fanuc_wpr_deg(R) -> np.ndarray:
    """Fanuc W, P, R: fixed (extrinsic) X, then Y, then Z, degrees: R = Rz(R) Ry(P) Rx(W)."""
    return _rotation(R).as_euler("xyz", degrees=True)


def rotation_vector_rad(R) -> np.ndarray:
    """Universal Robots rotation vector: axis times angle, radians."""
    return _rotation(R).as_rotvec()


def quaternion_wxyz(R) -> np.ndarray:
    """ABB order q1..q4 = w, x, y, z, with w >= 0."""
    xyzw = _rotation(R).as_quat()
    wxyz = np.roll(xyzw, 1, axis=-1)
    return np.where(wxyz[..., :1] < 0, -wxyz, wxyz)


@dataclass(frozen=True)
class Rotary:
    """A 5-axis convention: which two rotary words give the tool axis (tip to spindle) in the workpiece
    frame, and how.  Angles are the tool's turn relative to the workpiece (ISO 841 sense), so the same
    words serve a head or a table machine in tool-centre-point mode: the control's kinematics turns them
    into axis moves."""

    letters: str
    formula: str


ROTARY = {
    "ab": Rotary("AB", "tool axis = Ry(B) Rx(A) (0, 0, 1): A about X, then B about Y"),
    "ac": Rotary("AC", "tool axis = Rz(C) Rx(A) (0, 0, 1): A tilts about X, C turns about Z"),
    "bc": Rotary("BC", "tool axis = Rz(C) Ry(B) (0, 0, 1): B tilts about Y, C turns about Z"),
}


def tool_axis_from_rotary(convention: str, first_deg: float, second_deg: float) -> np.ndarray:
    """The tool axis of one pair of rotary angles (the convention's two letters, in order)."""
    a, b = np.radians(first_deg), np.radians(second_deg)
    if convention == "ab":  # Ry(B) Rx(A) z
        return np.array([np.sin(b) * np.cos(a), -np.sin(a), np.cos(b) * np.cos(a)])
    if convention == "ac":  # Rz(C) Rx(A) z
        return np.array([np.sin(b) * np.sin(a), -np.cos(b) * np.sin(a), np.cos(a)])
    return np.array([np.cos(b) * np.sin(a), np.sin(b) * np.sin(a), np.cos(a)])  # bc: Rz(C) Ry(B) z


def rotary_from_tool_axes(convention: str, tool_axes) -> np.ndarray:
    """(N, 2) rotary angles in degrees for (N, 3) tool axes; the turn about Z (C) is kept continuous
    (no jump at +-180 degrees) and held where the axis is vertical and C is free."""
    t = np.asarray(tool_axes, dtype=float).reshape(-1, 3)
    t = t / np.linalg.norm(t, axis=1, keepdims=True)
    if convention == "ab":
        return np.degrees(np.column_stack([-np.arcsin(np.clip(t[:, 1], -1, 1)), np.arctan2(t[:, 0], t[:, 2])]))
    tilt = np.degrees(np.arccos(np.clip(t[:, 2], -1, 1)))
    turn = np.arctan2(t[:, 0], -t[:, 1]) if convention == "ac" else np.arctan2(t[:, 1], t[:, 0])
    free = tilt < 1e-7
    if free.all():
        return np.column_stack([tilt, np.zeros(len(t))])
    held = np.where(free, 0, np.arange(len(t)))
    held = np.maximum.accumulate(held)
    first = int(np.flatnonzero(~free)[0])
    held[:first] = first
    return np.column_stack([tilt, np.degrees(np.unwrap(turn[held]))])


def tilt_deg(tool_axes) -> np.ndarray:
    """Angle of each tool axis (N, 3) from +Z, degrees."""
    t = np.asarray(tool_axes, dtype=float).reshape(-1, 3)
    return np.degrees(np.arccos(np.clip(t[:, 2] / np.linalg.norm(t, axis=1), -1, 1)))
