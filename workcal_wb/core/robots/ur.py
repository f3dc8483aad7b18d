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
    params = parameters_of(robot_or_params)
    return solved_in_chunks(lambda chunk: inverse_by_joint(params, chunk), poses)


def inverse_by_joint(p: UrParameters, T: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """(8, 6, n) joints in degrees, branch by joint by pose, for (n, 4, 4) flange poses: ``inverse`` laid out
    so that each joint of each branch is one contiguous row (written into ``out`` if given)."""
    n = len(T)
    xx, yx, zx, px, xy, yy, zy, py, xz, yz, zz, pz = T[:, :3, :].reshape(n, 12).T.copy()
    # The origin of joint 5's frame.
    w5x, w5y, w5z = px - p.d6 * zx, py - p.d6 * zy, pz - p.d6 * zz
    with np.errstate(invalid="ignore", divide="ignore"):
        spread = arccos_within_rounding(p.d4 / np.hypot(w5x, w5y))
        base_angle = np.arctan2(w5y, w5x) + np.pi / 2
        q1 = np.stack([base_angle + spread, base_angle - spread])  # (2 shoulder, n)
        s1, c1 = np.sin(q1), np.cos(q1)
        # Joint 5 is the angle between the flange axis and the joint-1 normal n = (s1, -c1, 0): cos q5 = z6 . n
        # (Hawkins uses the equal (p . n - d4) / d6); sin q5 from the two other components keeps q5 accurate
        # near the wrist singularity, where an arccos would lose half the digits.  The root's sign is the branch.
        cos5 = zx * s1 - zy * c1
        sin5 = np.hypot(zx * c1 + zy * s1, zz)
        wrist = np.arctan2(sin5, cos5)
        q5 = np.stack([wrist, -wrist])  # (2 wrist, 2 shoulder, n)
        s5, c5 = np.sin(q5), np.cos(q5)
        # Joint 6 from the base axes seen from the flange: x0 and y0 components along the joint-1 normal.
        ny = -xy * c1 + xx * s1  # (2 shoulder, n)
        oy = -yy * c1 + yx * s1
        sign5 = np.where(s5 < 0, -1.0, 1.0)
        q6 = np.arctan2(-oy * sign5, ny * sign5)
        q6[np.abs(s5) < WRIST_SINGULAR_SIN] = 0.0
        s6, c6 = np.sin(q6), np.cos(q6)

        # The planar arm in frame 1 (T01^-1 T T56^-1 T45^-1, written out): the origin of frame 4 is
        # the joint-5 origin moved d5 along the flange's -y turned by -q6, and the angle q2 + q3 + q4 that
        # of frame 4's x axis, c5 (c6 x6 - s6 y6) - s5 z6, in the arm's plane.
        p4x, p4y, p4z = w5x + p.d5 * (s6 * xx + c6 * yx), w5y + p.d5 * (s6 * xy + c6 * yy), \
            w5z + p.d5 * (s6 * xz + c6 * yz)
        x = c1 * p4x + s1 * p4y
        y = p4z - p.d1
        x4x, x4y, x4z = (c5 * (c6 * xx - s6 * yx) - s5 * zx, c5 * (c6 * xy - s6 * yy) - s5 * zy,
                         c5 * (c6 * xz - s6 * yz) - s5 * zz)
        q234 = np.arctan2(x4z, c1 * x4x + s1 * x4y)[:, :, None]
        cos3 = (x * x + y * y - p.a2 * p.a2 - p.a3 * p.a3) / (2.0 * p.a2 * p.a3)
        elbow = arccos_within_rounding(cos3)
        q3 = np.stack([elbow, -elbow], axis=2)  # (2 wrist, 2 shoulder, 2 elbow, n)
        q2 = np.arctan2(y, x)[:, :, None] - np.arctan2(p.a3 * np.sin(q3), p.a2 + p.a3 * np.cos(q3))
        q4 = q234 - q2 - q3

    out = np.empty((8, 6, n)) if out is None else out
    joints = out.view()
    joints.shape = (2, 2, 2, 6, n)  # (wrist, shoulder, elbow, joint, pose), a view of out
    joints[:, :, :, 0] = q1[None, :, None]
    joints[:, :, :, 1] = q2
    joints[:, :, :, 2] = q3
    joints[:, :, :, 3] = q4
    joints[:, :, :, 4] = q5[:, :, None]
    joints[:, :, :, 5] = q6[:, :, None]
    np.degrees(out, out=out)
    wrap_degrees(out, out=out)
    np.copyto(out, np.nan, where=np.isnan(out).any(axis=1)[:, None])  # a branch is whole or absent
    return out


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
