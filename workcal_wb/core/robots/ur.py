"""Closed-form kinematics of Universal Robots arms (UR3e, UR5e, UR10e, UR16e: the same DH chain).

The chain is UR's published standard Denavit-Hartenberg table: link i is Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)
with a = (0, a2, a3, 0, 0, 0), d = (d1, 0, 0, d4, d5, d6), alpha = (90, 0, 0, 90, -90, 0) degrees; the joint
values are the DH angles and the end frame is the tool flange (UR's TCP with a zero offset) in the base frame.

The inverse follows K. P. Hawkins, "Analytic Inverse Kinematics for the Universal Robots UR-5/UR-10 Arms"
(Georgia Tech, 2013): joint 1 from the position of the joint-5 origin (two roots), joint 5 from the flange
axis along the joint-1 normal (two roots), joint 6 from the orientation, then joints 2, 3, 4 as a planar
two-link arm (two roots of the elbow).  Joint 2 is derived from the elbow angle found, so the round trip
is exact to rounding even where the elbow angle is ill-conditioned.  Vectorised over poses; branches::

    index = 4 * wrist + 2 * shoulder + elbow
    shoulder 0/1: joint 1 = atan2(p5y, p5x) + 90 + / - acos(d4 / r)
    wrist 0/1:    joint 5 = + / - the angle between the flange axis and the joint-1 normal
    elbow 0/1:    joint 3 = + / - acos of the planar two-link triangle

Wrist singularity (sin q5 = 0: the axes of joints 2, 3, 4 and 6 parallel): joint 6 is set to 0 and joints
2 to 4 take the rest, deterministically; q5 itself comes from the flange axis (not an arccos) so that it
stays accurate there.  Where the joint-5 origin is exactly d4 from the joint-1 axis the two shoulder roots
coincide; nearer than d4 the pose is out of reach.  Returned joints lie in (-180, 180]; UR joints turn
+-360 degrees, see kinematics.wrap_into_limits.
"""
from __future__ import annotations

import numpy as np

from . import model
from .model import UrParameters
from .opw import WRIST_SINGULAR_SIN, arccos_within_rounding, solved_in_chunks, wrap_degrees

# The DH twists of every UR arm (the e-Series and CB3 tables differ only in lengths).
_ALPHA = np.radians([90.0, 0.0, 0.0, 90.0, -90.0, 0.0])


def parameters_of(robot_or_params) -> UrParameters:
    return model.parameters_of(robot_or_params, UrParameters)


def forward(robot_or_params, joints_deg) -> np.ndarray:
    """(..., 4, 4) flange pose in the base frame, mm, for (..., 6) joints in degrees."""
    p = parameters_of(robot_or_params)
    joints = np.asarray(joints_deg, dtype=float)
    if joints.shape[-1:] != (6,):
        raise ValueError(f"joints must have shape (..., 6), got {joints.shape}")
    q = np.radians(joints.reshape(-1, 6))
    a = (0.0, p.a2, p.a3, 0.0, 0.0, 0.0)
    d = (p.d1, 0.0, 0.0, p.d4, p.d5, p.d6)
    pose = np.broadcast_to(np.eye(4), (len(q), 4, 4))
    for i in range(6):
        pose = pose @ _dh(q[:, i], a[i], d[i], _ALPHA[i])
    return pose.reshape(joints.shape[:-1] + (4, 4))


def dh_frames(robot_or_params, joints_deg) -> np.ndarray:
    """(..., 7, 4, 4) DH frames 0 (the base) to 6 (the flange) in the base frame, mm, for (..., 6) joints in
    degrees: frame i is where joint i + 1 turns about its z (frame 6: the flange, ``forward``)."""
    p = parameters_of(robot_or_params)
    joints = np.asarray(joints_deg, dtype=float)
    if joints.shape[-1:] != (6,):
        raise ValueError(f"joints must have shape (..., 6), got {joints.shape}")
    q = np.radians(joints)
    a = (0.0, p.a2, p.a3, 0.0, 0.0, 0.0)
    d = (p.d1, 0.0, 0.0, p.d4, p.d5, p.d6)
    frames = [np.broadcast_to(np.eye(4), joints.shape[:-1] + (4, 4))]
    for i in range(6):
        frames.append(frames[-1] @ _dh(q[..., i], a[i], d[i], _ALPHA[i]))
    return np.stack(frames, axis=-3)


def inverse(robot_or_params, poses) -> np.ndarray:
    """(..., 8, 6) joints in degrees for (..., 4, 4) flange poses, NaN where a branch is unreachable."""
    return solved_in_chunks(_inverse_chunk, parameters_of(robot_or_params), poses)


def _inverse_chunk(p: UrParameters, T: np.ndarray) -> np.ndarray:
    n = len(T)
    x_axis, y_axis, z_axis, position = T[:, :3, 0], T[:, :3, 1], T[:, :3, 2], T[:, :3, 3]
    wrist5 = position - p.d6 * z_axis  # origin of joint 5's frame
    with np.errstate(invalid="ignore", divide="ignore"):
        spread = arccos_within_rounding(p.d4 / np.hypot(wrist5[:, 0], wrist5[:, 1]))
        base_angle = np.arctan2(wrist5[:, 1], wrist5[:, 0]) + np.pi / 2
        q1 = np.stack([base_angle + spread, base_angle - spread], axis=1)  # (n, 2): shoulder
        s1, c1 = np.sin(q1), np.cos(q1)
        # Joint 5 is the angle between the flange axis and the joint-1 normal n = (s1, -c1, 0): cos q5 = z6 . n
        # (Hawkins uses the equal (p . n - d4) / d6); sin q5 from the two other components keeps q5 accurate
        # near the wrist singularity, where an arccos would lose half the digits.  The root's sign is the branch.
        cos5 = z_axis[:, 0, None] * s1 - z_axis[:, 1, None] * c1
        sin5 = np.hypot(z_axis[:, 0, None] * c1 + z_axis[:, 1, None] * s1, z_axis[:, 2, None])
        wrist = np.arctan2(sin5, cos5)
        wrist = np.where(np.isnan(q1), np.nan, wrist)
        q5 = np.stack([wrist, -wrist], axis=1)  # (n, 2 wrist, 2 shoulder)
        s5 = np.sin(q5)
        # Joint 6 from the base axes seen from the flange: x0 and y0 components along the joint-1 normal.
        ny = -x_axis[:, 1, None] * c1 + x_axis[:, 0, None] * s1  # (n, 2 shoulder)
        oy = -y_axis[:, 1, None] * c1 + y_axis[:, 0, None] * s1
        sign5 = np.where(s5 < 0, -1.0, 1.0)
        singular = np.abs(s5) < WRIST_SINGULAR_SIN
        q6 = np.where(singular, 0.0, np.arctan2(-oy[:, None, :] * sign5, ny[:, None, :] * sign5))

        # The planar arm: frame 1 -> frame 4 = T01^-1 T T56^-1 T45^-1, for each (wrist, shoulder) pair.
        q1w = np.broadcast_to(q1[:, None, :], q5.shape)
        T01 = _dh(q1w, 0.0, p.d1, _ALPHA[0])
        T45 = _dh(q5, 0.0, p.d5, _ALPHA[4])
        T56 = _dh(q6, 0.0, p.d6, _ALPHA[5])
        T14 = _invert(T01) @ T[:, None, None] @ _invert(T56) @ _invert(T45)
        x, y = T14[..., 0, 3], T14[..., 1, 3]
        cos3 = (x * x + y * y - p.a2 * p.a2 - p.a3 * p.a3) / (2.0 * p.a2 * p.a3)
        elbow = arccos_within_rounding(cos3)
        q3 = np.stack([elbow, -elbow], axis=-1)  # (n, 2 wrist, 2 shoulder, 2 elbow)
        xs, ys = x[..., None], y[..., None]
        q2 = np.arctan2(ys, xs) - np.arctan2(p.a3 * np.sin(q3), p.a2 + p.a3 * np.cos(q3))
        q234 = np.arctan2(T14[..., 1, 0], T14[..., 0, 0])[..., None]
        q4 = q234 - q2 - q3

    joints = np.empty((n, 2, 2, 2, 6))
    joints[..., 0] = q1[:, None, :, None]
    joints[..., 1] = q2
    joints[..., 2] = q3
    joints[..., 3] = q4
    joints[..., 4] = q5[..., None]
    joints[..., 5] = q6[..., None]
    joints = np.degrees(joints, out=joints)
    joints = wrap_degrees(joints, out=joints).reshape(n, 8, 6)
    joints[np.isnan(joints).any(axis=2)] = np.nan
    return joints


def _dh(theta, a: float, d: float, alpha: float) -> np.ndarray:
    """Rz(theta) Tz(d) Tx(a) Rx(alpha) for an array of theta (radians)."""
    theta = np.asarray(theta, dtype=float)
    ct, st = np.cos(theta), np.sin(theta)
    ca, sa = np.cos(alpha), np.sin(alpha)
    out = np.zeros(theta.shape + (4, 4))
    out[..., 0, 0] = ct
    out[..., 0, 1] = -st * ca
    out[..., 0, 2] = st * sa
    out[..., 0, 3] = a * ct
    out[..., 1, 0] = st
    out[..., 1, 1] = ct * ca
    out[..., 1, 2] = -ct * sa
    out[..., 1, 3] = a * st
    out[..., 2, 1] = sa
    out[..., 2, 2] = ca
    out[..., 2, 3] = d
    out[..., 3, 3] = 1.0
    return out


def _invert(T: np.ndarray) -> np.ndarray:
    R = T[..., :3, :3]
    out = np.zeros_like(T)
    out[..., :3, :3] = np.swapaxes(R, -1, -2)
    out[..., :3, 3] = -np.einsum("...ji,...j->...i", R, T[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out
