"""Closed-form kinematics of ortho-parallel-wrist arms (KUKA, ABB, Fanuc and most six-axis industrial robots).

The model and the inverse solution are those of M. Brandstötter, A. Angerer, M. Hofbaur, "An Analytical
Solution of the Inverse Kinematics Problem of Industrial Serial Manipulators with an Ortho-parallel Basis
and a Spherical Wrist", Austrian Robotics Workshop 2014, as ROS-Industrial's opw_kinematics implements them
(include/opw_kinematics/opw_kinematics_impl.h); joint offsets and sign corrections follow opw_kinematics:
model angle = sign * joint - offset, after the J2/J3 coupling of controllers that have one (model joint 3
= J3 + j23_factor * J2, see model.py).  Poses are the model's end frame (on the flange, z along joint 6,
out of the flange) in the model's base frame, in mm; joints are the controller's, in degrees.

Everything is vectorised over poses: no Python loop runs per pose (inputs are solved ``CHUNK`` poses at a
time, each quantity a contiguous row per branch, so that the temporaries stay in the caches).

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
# Poses solved at a time: the temporaries (a few hundred kB each) then stay in the processor's caches
# and under glibc's mmap threshold, so they are reused rather than mapped and faulted in for every chunk.
CHUNK = 1 << 13


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


def model_angle(params: OpwParameters, joints_deg, joint: int) -> np.ndarray:
    """``model_angles(params, joints_deg)[..., joint]``, one joint's model angle in radians, computed alone."""
    joints = np.asarray(joints_deg, dtype=float)
    value = joints[..., joint]
    if joint == 2 and params.j23_factor:
        value = value + params.j23_factor * joints[..., 1]
    return np.radians(value * float(params.signs[joint]) - float(params.offsets_deg[joint]))


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
    turns = np.subtract(angles, 180.0)
    turns /= 360.0
    np.ceil(turns, out=turns)
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
    params = parameters_of(robot_or_params)
    return solved_in_chunks(lambda chunk: inverse_by_joint(params, chunk), poses)


def solved_in_chunks(solve, poses) -> np.ndarray:
    """``solve((n, 4, 4)) -> (8, 6, n)`` over (..., 4, 4) poses, CHUNK poses at a time, as (..., 8, 6)."""
    poses = np.asarray(poses, dtype=float)
    if poses.shape[-2:] != (4, 4):
        raise ValueError(f"poses must have shape (..., 4, 4), got {poses.shape}")
    flat = poses.reshape(-1, 4, 4)
    out = np.empty((len(flat), 8, 6))
    for start in range(0, len(flat), CHUNK):
        out[start:start + CHUNK] = solve(flat[start:start + CHUNK]).transpose(2, 0, 1)
    return out.reshape(poses.shape[:-2] + (8, 6))


def inverse_by_joint(p: OpwParameters, poses: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """(8, 6, n) controller joints in degrees, branch by joint by pose, for (n, 4, 4) model poses: ``inverse``
    laid out so that each joint of each branch is one contiguous row (written into ``out`` if given)."""
    n = len(poses)
    r00, r01, r02, px, r10, r11, r12, py, r20, r21, r22, pz = poses[:, :3, :].reshape(n, 12).T.copy()
    cx, cy, cz = px - p.c4 * r02, py - p.c4 * r12, pz - p.c4 * r22  # wrist centre
    # Arm branches as (shoulder, elbow, pose): shoulder 0 the wrist centre in front of axis 1, 1 behind it;
    # elbow 0 the +acos root, 1 the -acos root (branch index 2 * shoulder + elbow).
    with np.errstate(invalid="ignore"):
        nx1 = np.sqrt(cx * cx + cy * cy - p.b * p.b) - p.a1
        along = np.arctan2(cy, cx)
        side = np.arctan2(p.b, nx1 + p.a1)
        theta1 = np.stack([along - side, along + side - np.pi])[:, None]  # (2, 1, n)

        height = cz - p.c1
        back_reach = nx1 + 2.0 * p.a1
        kappa_sq = p.a2 * p.a2 + p.c3 * p.c3
        c2_sq = p.c2 * p.c2
        psi3 = np.arctan2(p.a2, p.c3)
        elbow_scale = 2.0 * p.c2 * np.sqrt(kappa_sq)
        elbow = np.empty((2, 2, n))  # theta3 + psi3
        elbow[0, 0] = arccos_within_rounding((nx1 * nx1 + height * height - c2_sq - kappa_sq) / elbow_scale)
        elbow[1, 0] = arccos_within_rounding((back_reach * back_reach + height * height - c2_sq - kappa_sq)
                                             / elbow_scale)
        np.negative(elbow[:, 0], out=elbow[:, 1])
        theta3 = elbow - psi3
        # theta2 aims the arm at the wrist centre for the elbow angle found: the direction from the
        # shoulder to the wrist (from the vertical) minus the angle the bent arm makes with its upper arm.
        # Derived from theta3 rather than from a second law of cosines, the wrist centre is met to rounding
        # even where the elbow angle itself is ill-conditioned (arm nearly stretched or folded).
        toward = np.stack([np.arctan2(nx1, height), np.arctan2(-back_reach, height)])[:, None]  # (2, 1, n)
        k = np.sqrt(kappa_sq)
        theta2 = toward - np.arctan2(k * np.sin(elbow), p.c2 + k * np.cos(elbow))

        # Wrist rotation R_ce = R_0c^T R with R_0c = Rz(theta1) Ry(theta2 + theta3): u = Rz(-theta1) R
        # depends on the shoulder only, then R_ce = Ry(-(theta2 + theta3)) u.  Of its last row only the
        # last element is needed.
        s1, c1 = np.sin(theta1), np.cos(theta1)
        q23 = theta2 + theta3
        s23, c23 = np.sin(q23), np.cos(q23)
        u00, u01, u02 = c1 * r00 + s1 * r10, c1 * r01 + s1 * r11, c1 * r02 + s1 * r12
        minus_s1 = -s1
        u10, u11, u12 = minus_s1 * r00 + c1 * r10, minus_s1 * r01 + c1 * r11, minus_s1 * r02 + c1 * r12
        w00, w01, w02 = c23 * u00 - s23 * r20, c23 * u01 - s23 * r21, c23 * u02 - s23 * r22
        w22 = s23 * u02 + c23 * r22
        theta4, theta5, theta6 = _wrist_angles(w00, w01, w02, u10, u11, u12, w22)

    out = np.empty((8, 6, n)) if out is None else out
    model = out.view()
    model.shape = (2, 2, 2, 6, n)  # (wrist 0 or flipped, shoulder, elbow, joint, pose), a view of out
    unflipped, flipped = model[0], model[1]
    unflipped[:, :, 0] = theta1
    unflipped[:, :, 1] = theta2
    unflipped[:, :, 2] = theta3
    unflipped[:, :, 3] = theta4
    unflipped[:, :, 4] = theta5
    unflipped[:, :, 5] = theta6
    np.add(theta4, np.pi, out=flipped[:, :, 3])
    np.negative(theta5, out=flipped[:, :, 4])
    np.subtract(theta6, np.pi, out=flipped[:, :, 5])
    _to_controller(p, unflipped[:, :, :3], 0)
    _to_controller(p, model[:, :, :, 3:], 3)
    flipped[:, :, :3] = unflipped[:, :, :3]
    absent = np.isnan(unflipped).any(axis=2)  # a branch is whole or absent; the flipped one with it
    np.copyto(model, np.nan, where=absent[None, :, :, None])
    return out


def _to_controller(p: OpwParameters, rows: np.ndarray, first_joint: int) -> None:
    """``controller_joints`` in place on model angles (..., k, n) of joints first_joint .. first_joint + k - 1
    (the J2/J3 coupling applies where they include joints 2 and 3)."""
    np.degrees(rows, out=rows)
    for index in range(rows.shape[-2]):
        joint = first_joint + index
        row = rows[..., index, :]
        if p.offsets_deg[joint]:
            row += p.offsets_deg[joint]
        if p.signs[joint] < 0:
            np.negative(row, out=row)
    if p.j23_factor and first_joint <= 1 < 2 < first_joint + rows.shape[-2]:
        rows[..., 2 - first_joint, :] -= p.j23_factor * rows[..., 1 - first_joint, :]
    wrap_degrees(rows, out=rows)


def _wrist_angles(row00, row01, row02, row10, row11, row12, row22):
    """theta4, theta5 >= 0, theta6 of R = Rz(theta4) Ry(theta5) Rz(theta6) from the elements it takes."""
    sin5 = np.hypot(row02, row12)
    theta5 = np.arctan2(sin5, row22)
    theta4 = np.arctan2(row12, row02)
    theta4[sin5 < WRIST_SINGULAR_SIN] = 0.0
    # theta4 + theta6 from the upper-left block: (1 + cos5) [cos, sin] of the sum; theta4 - theta6 from
    # (cos5 - 1) [cos, sin] of the difference.  Each is well-conditioned on its own half of theta5.
    total = np.arctan2(row10 - row01, row00 + row11)
    difference = np.arctan2(-(row10 + row01), row11 - row00)
    theta6 = np.where(row22 >= 0, total - theta4, theta4 - difference)
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
