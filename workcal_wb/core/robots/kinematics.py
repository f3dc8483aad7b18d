"""Forward and inverse kinematics in the controller's frames, and joint limits with turn variants.

Callers work in the frames a robot program speaks of: a pose is the controller's flange frame in the
controller's base frame (mm), joints are the controller's joint values (degrees).  The robot's ``base``
and ``flange`` frames connect these to the kinematic model (OPW or UR), which this module picks.

``inverse`` gives eight branches per pose, each joint in (-180, 180]; their index keeps its meaning from
pose to pose (see opw.py and ur.py).  A joint whose range spans more than 360 degrees (KUKA A4 and A6 at
+-350, ABB axis 6 at +-400, every UR joint at +-360) reaches the same pose at other turns:
``turn_candidates`` lists them, ``wrap_into_limits`` picks per joint the turn within limits nearest to a
reference (joint by joint, so a branch stays the branch it was).
"""
from __future__ import annotations

import numpy as np

from .. import frames
from . import opw, ur
from .model import Robot


def forward(robot: Robot, joints_deg) -> np.ndarray:
    """(..., 4, 4) controller flange in the controller base frame (mm) for (..., 6) controller joints."""
    model_pose = _solver(robot).forward(robot, joints_deg)
    return frames.invert(robot.base_transform) @ model_pose @ robot.flange_transform


def inverse(robot: Robot, poses) -> np.ndarray:
    """(..., 8, 6) controller joints (degrees) for (..., 4, 4) controller flange poses in the controller
    base frame; NaN rows are branches that cannot reach the pose."""
    return opw.solved_in_chunks(lambda chunk: inverse_by_joint(robot, chunk), poses)


def inverse_by_joint(robot: Robot, poses: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """(8, 6, n) for (n, 4, 4) poses: ``inverse`` laid out branch by joint by pose, each joint of each
    branch one contiguous row (as a caller that works on one joint at a time along a path wants them),
    written into ``out`` if given."""
    solver = _solver(robot)
    return solver.inverse_by_joint(solver.parameters_of(robot), _model_poses(robot, poses), out)


def within_limits(robot: Robot, joints_deg) -> np.ndarray:
    """Boolean mask (...) for (..., 6) joints: every joint within its limits (NaN joints are not)."""
    joints = np.asarray(joints_deg, dtype=float)
    with np.errstate(invalid="ignore"):
        return np.all((joints >= robot.limits[:, 0]) & (joints <= robot.limits[:, 1]), axis=-1)


def joint_margins_deg(robot: Robot, joints_deg) -> np.ndarray:
    """(..., 6) each joint's distance in degrees to its nearer limit; negative outside its limits, NaN for
    NaN joints."""
    joints = np.asarray(joints_deg, dtype=float)
    return np.minimum(joints - robot.limits[:, 0], robot.limits[:, 1] - joints)


def limit_margin_deg(robot: Robot, joints_deg) -> np.ndarray:
    """(...) smallest distance in degrees from any joint to its nearer limit; negative when a joint is
    outside its limits, NaN for NaN joints."""
    return np.min(joint_margins_deg(robot, joints_deg), axis=-1)  # NaN propagates


def turn_offsets(robot: Robot) -> np.ndarray:
    """(6, T) multiples of 360 degrees that can bring a joint value in (-180, 180] within each joint's limits,
    NaN-padded; T is the largest count over the joints (1 when no range exceeds 360 degrees)."""
    per_joint = []
    for low, high in robot.limits:
        # A value v in (-180, 180] shifted by 360 k lies in (360 k - 180, 360 k + 180]; keep k where that
        # interval meets [low, high].
        first = int(np.ceil((low - 180.0) / 360.0))
        last = int(np.floor((high + 180.0) / 360.0))
        per_joint.append([360.0 * k for k in range(first, last + 1) if 360.0 * k + 180.0 >= low
                          and 360.0 * k - 180.0 < high])
    width = max(len(offsets) for offsets in per_joint)
    table = np.full((6, width), np.nan)
    for axis, offsets in enumerate(per_joint):
        table[axis, :len(offsets)] = sorted(offsets, key=abs)
    return table


def turn_candidates(robot: Robot, joints_deg) -> np.ndarray:
    """(..., 6, T) for (..., 6) joints: each joint's values at every turn (joint + 360 k) that lie within its
    limits, NaN elsewhere; the turns are ordered by |k| (the given turn first)."""
    joints = np.asarray(joints_deg, dtype=float)
    candidates = opw.wrap_degrees(joints)[..., None] + turn_offsets(robot)
    with np.errstate(invalid="ignore"):
        inside = (candidates >= robot.limits[:, :1]) & (candidates <= robot.limits[:, 1:])
    return np.where(inside, candidates, np.nan)


def wrap_into_limits(robot: Robot, joints_deg, reference_deg=0.0) -> np.ndarray:
    """(..., 6) joints moved by whole turns, joint by joint, to the value within limits nearest to
    ``reference_deg`` (broadcast against the joints: 0 by default, or e.g. the previous pose's joints of the
    same branch to follow a path); a joint with no turn within its limits becomes NaN, and so its row."""
    joints = np.asarray(joints_deg, dtype=float)
    candidates = turn_candidates(robot, joints)
    reference = np.broadcast_to(np.asarray(reference_deg, dtype=float), joints.shape)[..., None]
    distance = np.where(np.isnan(candidates), np.inf, np.abs(candidates - reference))
    best = np.argmin(distance, axis=-1)[..., None]
    chosen = np.take_along_axis(candidates, best, axis=-1)[..., 0]
    chosen[np.isnan(chosen).any(axis=-1)] = np.nan
    return chosen


def _model_poses(robot: Robot, poses: np.ndarray) -> np.ndarray:
    """The model's end frame in the model's base frame for controller flange poses (..., 4, 4)."""
    if not np.array_equal(robot.base_transform, np.eye(4)):
        poses = robot.base_transform @ poses
    if not np.array_equal(robot.flange_transform, np.eye(4)):
        poses = poses @ frames.invert(robot.flange_transform)
    return poses


def _solver(robot: Robot):
    return opw if robot.kinematics == "opw" else ur
