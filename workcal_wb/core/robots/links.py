"""Where a robot's links are at given joint values: the origin of each joint frame along the arm.

``arm_points(robot, joints)`` gives the points an arm is drawn through, from its foot on the floor to its
flange, in the controller's base frame (the frame ``kinematics.forward`` and robot programs speak in), mm.
Consecutive points are joined by the arm's links, so the distance between them is a length of the
kinematic model:

* OPW arms (opw.py's model and conventions)::

    base -> axis 1 at shoulder height    c1   (along axis 1)
         -> shoulder (axis 2)            hypot(a1, b)   (a1 out from axis 1, b sideways)
         -> elbow (axis 3)               c2   (the lower arm)
         -> forearm offset               |a2| (across the forearm, from axis 3 to the line of axis 4)
         -> wrist centre                 c3   (along axis 4, where axes 4, 5 and 6 meet)
         -> flange                       c4   (along axis 6)

* Universal Robots arms (ur.py's DH chain): the origins of DH frames 0 to 6::

    base -> shoulder d1 -> elbow |a2| -> wrist 1 |a3| -> wrist 2 d4 -> wrist 3 d5 -> flange d6

  (the DH chain puts the arm's sideways offsets together into d4, so the drawn arm is flat where the real
  one steps sideways at the shoulder and the elbow).

A robot file whose ``flange`` frame is offset from the model's end frame gets one more point, the
controller's flange, after the model's end ("arm end").  The last point is always the controller's flange,
``forward(robot, joints)[..., :3, 3]``.  Everything is vectorised over (..., 6) joint values in degrees.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import opw, ur
from .model import OpwParameters, Robot

# The names of the points, base to flange, in the order the arm is drawn (see above for the lengths between).
OPW_POINTS = ("base", "axis 1 at shoulder height", "shoulder", "elbow", "forearm offset", "wrist centre", "flange")
UR_POINTS = ("base", "shoulder", "elbow", "wrist 1", "wrist 2", "wrist 3", "flange")
# The extra point of a robot file whose controller flange is offset from the model's end frame.
ARM_END = "arm end"
# Below this (mm) the controller's flange counts as the model's end frame: no extra point is drawn.
SAME_POINT_MM = 1e-9


@dataclass(frozen=True)
class ArmPoints:
    """The points an arm is drawn through: ``names`` (K,) and ``points`` (..., K, 3) in mm, in the
    controller's base frame, from the base on the floor to the flange."""

    names: tuple
    points: np.ndarray

    def point(self, name: str) -> np.ndarray:
        """(..., 3) the point called ``name``."""
        return self.points[..., self.names.index(name), :]

    def lengths(self) -> np.ndarray:
        """(..., K - 1) mm between consecutive points: the links' lengths."""
        return np.linalg.norm(np.diff(self.points, axis=-2), axis=-1)


def arm_points(robot: Robot, joints_deg) -> ArmPoints:
    """The joint frames' origins of ``robot`` at (..., 6) controller joints (degrees), from its base to its
    flange, as (..., K, 3) points in the controller's base frame (mm)."""
    joints = np.asarray(joints_deg, dtype=float)
    if joints.shape[-1:] != (6,):
        raise ValueError(f"joints must have shape (..., 6), got {joints.shape}")
    if robot.kinematics == "opw":
        names, model_points = OPW_POINTS, _opw_points(robot.opw, joints)
    else:
        names, model_points = UR_POINTS, ur.dh_frames(robot.ur, joints)[..., :3, 3]
    flange_offset = robot.flange_transform[:3, 3]
    if np.linalg.norm(flange_offset) > SAME_POINT_MM:
        end = (opw if robot.kinematics == "opw" else ur).forward(robot, joints)  # the model's end frame
        flange = end[..., :3, 3] + np.einsum("...ij,j->...i", end[..., :3, :3], flange_offset)
        model_points = np.concatenate([model_points, flange[..., None, :]], axis=-2)
        names = names[:-1] + (ARM_END, names[-1])
    # From the model's base frame into the controller's: p_controller = base^-1 p_model.
    base = robot.base_transform
    points = (model_points - base[:3, 3]) @ base[:3, :3]
    return ArmPoints(tuple(names), points)


def _opw_points(p: OpwParameters, joints: np.ndarray) -> np.ndarray:
    """(..., 7, 3) OPW_POINTS in the model's base frame."""
    q = opw.model_angles(p, joints)
    theta1, theta2, theta23 = q[..., 0], q[..., 1], q[..., 1] + q[..., 2]
    zero, one = np.zeros_like(theta1), np.ones_like(theta1)
    # In the arm's plane before axis 1 turns it: x out from axis 1, y sideways (the offset b), z up.
    base = np.stack([zero, zero, zero], axis=-1)
    column = np.stack([zero, zero, zero + p.c1], axis=-1)
    shoulder = np.stack([zero + p.a1, zero + p.b, zero + p.c1], axis=-1)
    elbow = shoulder + p.c2 * np.stack([np.sin(theta2), zero, np.cos(theta2)], axis=-1)
    # The forearm's axes, turned by theta2 + theta3 about y: a2 runs along its x, c3 along its z (axis 4).
    forearm_x = np.stack([np.cos(theta23), zero, -np.sin(theta23)], axis=-1)
    forearm_z = np.stack([np.sin(theta23), zero, np.cos(theta23)], axis=-1)
    offset = elbow + p.a2 * forearm_x
    wrist = offset + p.c3 * forearm_z
    # Axis 6 in the forearm's frame is the wrist's Rz(theta4) Ry(theta5) z; c4 runs along it.
    s4, c4, s5, c5 = np.sin(q[..., 3]), np.cos(q[..., 3]), np.sin(q[..., 4]), np.cos(q[..., 4])
    axis6 = ((c4 * s5)[..., None] * forearm_x + (s4 * s5)[..., None] * np.stack([zero, one, zero], axis=-1)
             + c5[..., None] * forearm_z)
    flange = wrist + p.c4 * axis6
    in_plane = np.stack([base, column, shoulder, elbow, offset, wrist, flange], axis=-2)
    s1, c1 = np.sin(theta1)[..., None], np.cos(theta1)[..., None]
    x, y = in_plane[..., 0], in_plane[..., 1]
    return np.stack([c1 * x - s1 * y, s1 * x + c1 * y, in_plane[..., 2]], axis=-1)
