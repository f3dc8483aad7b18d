"""Closed-form kinematics of ortho-parallel-wrist arms (KUKA, ABB, Fanuc and most six-axis industrial robots).

The model and the inverse solution are those of M. Brandstötter, A. Angerer, M. Hofbaur, "An Analytical
Solution of the Inverse Kinematics Problem of Industrial Serial Manipulators with an Ortho-parallel Basis
and a Spherical Wrist", Austrian Robotics Workshop 2014, as ROS-Industrial's opw_kinematics implements them
(include/opw_kinematics/opw_kinematics_impl.h); joint offsets and sign corrections follow opw_kinematics:
model angle = sign * joint - offset, after the J2/J3 coupling of controllers that have one (model joint 3
= J3 + j23_factor * J2, see model.py).  Poses are the model's end frame (on the flange, z along joint 6,
out of the flange) in the model's base frame, in mm; joints are the controller's, in degrees.

Everything is vectorised over poses: no Python loop runs per pose (large inputs are cut into chunks only
to bound memory).

Branches: ``inverse`` returns eight candidates per pose in a fixed order, as opw_kinematics does::

    index  shoulder (joint 1)                elbow (joint 3)                 wrist (joint 5)
    0      wrist centre in front of axis 1   in front of the line axis 2-3   theta5 >= 0
    1      wrist centre in front of axis 1   behind that line                theta5 >= 0
    2      wrist centre behind axis 1        in front of that line           theta5 >= 0
    3      wrist centre behind axis 1        behind that line                theta5 >= 0
    4..7   as 0..3                                                           theta5 <= 0 (4, 6 turned 180)

(the elbow is the +acos root, theta3 + atan2(a2, c3) in [0, 180], or the -acos root; "behind axis 1" is
joint 1 turned about 180 degrees, the arm reaching back over the top)

so a branch index keeps its meaning from pose to pose.  A branch whose wrist centre is out of reach is
NaN.  Returned joint values lie in (-180, 180]; other turns are the caller's (see kinematics.wrap_into_limits).

Wrist singularity (theta5 = 0, axes 4 and 6 in line): only theta4 + theta6 is defined.  Joint 4 is set to
its model zero (theta4 = 0, on the flipped branches 180) and joint 6 takes the whole turn, as opw_kinematics
does; here that rule applies only where sin(theta5) < ``WRIST_SINGULAR_SIN`` and joint 6 is computed from
the well-conditioned sum theta4 + theta6 (the difference near theta5 = 180), so the returned joints
reproduce the pose to rounding on either side of the threshold.
"""
from __future__ import annotations

import numpy as np

from . import model
from .model import OpwParameters

# Below this sin(theta5) the wrist counts as singular and joint 4 is set to its model zero: the pose
# error that choice makes is at most pi * sin(theta5) rad, under 1e-11 rad.
WRIST_SINGULAR_SIN = 1e-12
# A cosine computed from a reachable pose may exceed 1 by rounding; up to this it is clipped (a pose
# that far out of reach is out by well under a nanometre).
COSINE_ROUNDING = 1e-10
# Poses solved per chunk: bounds the temporaries at a few hundred MB whatever the input size.
CHUNK = 1 << 17


def parameters_of(robot_or_params) -> OpwParameters:
    return model.parameters_of(robot_or_params, OpwParameters)


def model_joints(params: OpwParameters, joints_deg) -> np.ndarray:
    """Controller joints (..., 6) in degrees with the J2/J3 coupling undone: the joint values opw_kinematics
    (and a ROS-Industrial URDF) takes, before offsets and signs."""
    joints = np.array(joints_deg, dtype=float)
    if params.j23_factor:
        joints[..., 2] += params.j23_factor * joints[..., 1]
    return joints


def model_angles(params: OpwParameters, joints_deg) -> np.ndarray:
    """Model angles in radians (..., 6) from controller joints in degrees."""
    joints = model_joints(params, joints_deg)
    return np.radians(joints * np.asarray(params.signs, float) - np.asarray(params.offsets_deg, float))


def controller_joints(params: OpwParameters, model_rad) -> np.ndarray:
    """Controller joints in degrees, wrapped into (-180, 180], from model angles in radians."""
    joints = np.degrees(model_rad)
    joints += np.asarray(params.offsets_deg, float)
    joints *= np.asarray(params.signs, float)
    if params.j23_factor:
        joints[..., 2] -= params.j23_factor * joints[..., 1]
    return wrap_degrees(joints, out=joints)


def wrap_degrees(angles, out=None) -> np.ndarray:
    """Angles in degrees mapped into (-180, 180] (into ``out`` if given)."""
    angles = np.asarray(angles, dtype=float)
    turns = np.ceil((angles - 180.0) / 360.0)
    turns *= 360.0
    return np.subtract(angles, turns, out=out)


def forward(robot_or_params, joints_deg) -> np.ndarray:
    """(..., 4, 4) pose of the model's end frame in the model's base frame, mm, for (..., 6) joints."""
    params = parameters_of(robot_or_params)
    joints = np.asarray(joints_deg, dtype=float)
    if joints.shape[-1:] != (6,):
        raise ValueError(f"joints must have shape (..., 6), got {joints.shape}")
    q = model_angles(params, joints.reshape(-1, 6))
    s, c = np.sin(q), np.cos(q)
    psi3 = np.arctan2(params.a2, params.c3)
    k = np.hypot(params.a2, params.c3)
    q23 = q[:, 1] + q[:, 2]
    s23, c23 = np.sin(q23), np.cos(q23)
    reach = params.c2 * s[:, 1] + k * np.sin(q23 + psi3) + params.a1
    height = params.c2 * c[:, 1] + k * np.cos(q23 + psi3) + params.c1
    s1, c1 = s[:, 0], c[:, 0]
    # Arm rotation R_0c = Rz(theta1) Ry(theta2 + theta3), wrist R_ce = Rz(theta4) Ry(theta5) Rz(theta6).
    r0c = np.empty((len(q), 3, 3))
    r0c[:, 0] = np.stack([c1 * c23, -s1, c1 * s23], axis=1)
    r0c[:, 1] = np.stack([s1 * c23, c1, s1 * s23], axis=1)
    r0c[:, 2] = np.stack([-s23, np.zeros_like(s23), c23], axis=1)
    rce = _zyz(q[:, 3], q[:, 4], q[:, 5])
    rotation = r0c @ rce
    pose = np.zeros((len(q), 4, 4))
    pose[:, :3, :3] = rotation
    pose[:, 0, 3] = reach * c1 - params.b * s1 + params.c4 * rotation[:, 0, 2]
    pose[:, 1, 3] = reach * s1 + params.b * c1 + params.c4 * rotation[:, 1, 2]
    pose[:, 2, 3] = height + params.c4 * rotation[:, 2, 2]
    pose[:, 3, 3] = 1.0
    return pose.reshape(joints.shape[:-1] + (4, 4))


def inverse(robot_or_params, poses) -> np.ndarray:
    """(..., 8, 6) controller joints in degrees for (..., 4, 4) poses, NaN where a branch is unreachable."""
    return solved_in_chunks(_inverse_chunk, parameters_of(robot_or_params), poses)


def solved_in_chunks(solve, params, poses) -> np.ndarray:
    """``solve(params, (n, 4, 4)) -> (n, 8, 6)`` over (..., 4, 4) poses, CHUNK poses at a time."""
    poses = np.asarray(poses, dtype=float)
    if poses.shape[-2:] != (4, 4):
        raise ValueError(f"poses must have shape (..., 4, 4), got {poses.shape}")
    flat = poses.reshape(-1, 4, 4)
    out = np.empty((len(flat), 8, 6))
    for start in range(0, len(flat), CHUNK):
        out[start:start + CHUNK] = solve(params, flat[start:start + CHUNK])
    return out.reshape(poses.shape[:-2] + (8, 6))


def _inverse_chunk(p: OpwParameters, poses: np.ndarray) -> np.ndarray:
    n = len(poses)
    rotation = poses[:, :3, :3]
    centre = poses[:, :3, 3] - p.c4 * rotation[:, :, 2]  # wrist centre
    cx, cy, cz = centre[:, 0], centre[:, 1], centre[:, 2]
    with np.errstate(invalid="ignore"):
        nx1 = np.sqrt(cx * cx + cy * cy - p.b * p.b) - p.a1
        along = np.arctan2(cy, cx)
        side = np.arctan2(p.b, nx1 + p.a1)
        theta1_front = along - side
        theta1_back = along + side - np.pi

        height = cz - p.c1
        s1_sq = nx1 * nx1 + height * height
        back_reach = nx1 + 2.0 * p.a1
        s2_sq = back_reach * back_reach + height * height
        kappa_sq = p.a2 * p.a2 + p.c3 * p.c3
        c2_sq = p.c2 * p.c2
        psi3 = np.arctan2(p.a2, p.c3)
        elbow_scale = 2.0 * p.c2 * np.sqrt(kappa_sq)
        elbow_front = arccos_within_rounding((s1_sq - c2_sq - kappa_sq) / elbow_scale)
        elbow_back = arccos_within_rounding((s2_sq - c2_sq - kappa_sq) / elbow_scale)
        elbow = np.stack([elbow_front, -elbow_front, elbow_back, -elbow_back], axis=1)  # theta3 + psi3
        theta3 = elbow - psi3
        # theta2 aims the arm at the wrist centre for the elbow angle found: the direction from the
        # shoulder to the wrist (from the vertical) minus the angle the bent arm makes with its upper arm.
        # Derived from theta3 rather than from a second law of cosines, the wrist centre is met to rounding
        # even where the elbow angle itself is ill-conditioned (arm nearly stretched or folded).
        toward_front = np.arctan2(nx1, height)
        toward_back = np.arctan2(-back_reach, height)
        toward = np.stack([toward_front, toward_front, toward_back, toward_back], axis=1)
        k = np.sqrt(kappa_sq)
        theta2 = toward - np.arctan2(k * np.sin(elbow), p.c2 + k * np.cos(elbow))

    theta1 = np.stack([theta1_front, theta1_front, theta1_back, theta1_back], axis=1)
    # Wrist rotation R_ce = R_0c^T R with R_0c = Rz(theta1) Ry(theta2 + theta3), for the four arm branches.
    q23 = theta2 + theta3
    s1, c1, s23, c23 = np.sin(theta1), np.cos(theta1), np.sin(q23), np.cos(q23)
    r = rotation[:, None, :, :]  # (n, 1, 3, 3)
    # u = Rz(-theta1) R, then R_ce = Ry(-(theta2 + theta3)) u.
    u0 = c1[..., None] * r[:, :, 0, :] + s1[..., None] * r[:, :, 1, :]
    u1 = -s1[..., None] * r[:, :, 0, :] + c1[..., None] * r[:, :, 1, :]
    u2 = np.broadcast_to(r[:, :, 2, :], u0.shape)
    w0 = c23[..., None] * u0 - s23[..., None] * u2
    w1 = u1
    w2 = s23[..., None] * u0 + c23[..., None] * u2
    theta4, theta5, theta6 = _wrist_angles(w0, w1, w2)

    model = np.empty((n, 8, 6))
    model[:, :4, 0] = theta1
    model[:, :4, 1] = theta2
    model[:, :4, 2] = theta3
    model[:, :4, 3] = theta4
    model[:, :4, 4] = theta5
    model[:, :4, 5] = theta6
    model[:, 4:, :3] = model[:, :4, :3]
    model[:, 4:, 3] = theta4 + np.pi
    model[:, 4:, 4] = -theta5
    model[:, 4:, 5] = theta6 - np.pi
    joints = controller_joints(p, model)
    joints[np.isnan(joints).any(axis=2)] = np.nan  # a branch is whole or absent
    return joints


def _wrist_angles(row0, row1, row2):
    """theta4, theta5 >= 0, theta6 of R = Rz(theta4) Ry(theta5) Rz(theta6) from its rows (..., 3)."""
    sin5 = np.hypot(row0[..., 2], row1[..., 2])
    cos5 = row2[..., 2]
    theta5 = np.arctan2(sin5, cos5)
    singular = sin5 < WRIST_SINGULAR_SIN
    theta4 = np.where(singular, 0.0, np.arctan2(row1[..., 2], row0[..., 2]))
    # theta4 + theta6 from the upper-left block: (1 + cos5) [cos, sin] of the sum; theta4 - theta6 from
    # (cos5 - 1) [cos, sin] of the difference.  Each is well-conditioned on its own half of theta5.
    total = np.arctan2(row1[..., 0] - row0[..., 1], row0[..., 0] + row1[..., 1])
    difference = np.arctan2(-(row1[..., 0] + row0[..., 1]), row1[..., 1] - row0[..., 0])
    theta6 = np.where(cos5 >= 0, total - theta4, theta4 - difference)
    return theta4, theta5, theta6


def _zyz(a, b, c) -> np.ndarray:
    sa, ca, sb, cb, sc, cc = np.sin(a), np.cos(a), np.sin(b), np.cos(b), np.sin(c), np.cos(c)
    out = np.empty(np.shape(a) + (3, 3))
    out[..., 0, 0] = ca * cb * cc - sa * sc
    out[..., 0, 1] = -ca * cb * sc - sa * cc
    out[..., 0, 2] = ca * sb
    out[..., 1, 0] = sa * cb * cc + ca * sc
    out[..., 1, 1] = -sa * cb * sc + ca * cc
    out[..., 1, 2] = sa * sb
    out[..., 2, 0] = -sb * cc
    out[..., 2, 1] = sb * sc
    out[..., 2, 2] = cb
    return out


def arccos_within_rounding(x):
    """arccos that forgives rounding past +-1 (``COSINE_ROUNDING``) and gives NaN beyond."""
    clipped = np.where(np.abs(x) <= 1.0 + COSINE_ROUNDING, np.clip(x, -1.0, 1.0), np.nan)
    return np.arccos(clipped)
