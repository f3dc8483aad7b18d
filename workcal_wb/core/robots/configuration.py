"""The configuration data a controller stores with a Cartesian target, from the joint values that reach it.

Every controller needs it to choose among the (up to eight) joint solutions of a pose.  All three
vendors describe the same three geometric choices of an ortho-parallel-wrist arm, which are computed here
from the OPW model (``opw`` in the robot file) and the controller's joint values:

* shoulder: is the wrist centre in front of or behind the axis-1 axis (x of the wrist centre in the frame
  that turns with axis 1: positive is in front);
* elbow: is the wrist centre in front of or behind the line through axes 2 and 3 (the KUKA link arm, the
  ABB lower arm), i.e. is the elbow angle theta3 + atan2(a2, c3) between 0 and 180 degrees; its zero is
  where the arm is stretched, which for an arm with an offset a2 is not axis 3's zero;
* wrist: the sign of axis 5.

Sources and the choices made where they are unclear:

KUKA, Status and Turn (KUKA System Software 8.x, Operating and Programming Instructions for System
Integrators, "Status" and "Turn"; the same rules in Beckhoff TwinCAT CNC TF5200 "Status & Turn (IS, IT)",
which implements KUKA's convention).  Status bit 0 is 1 in the overhead area (the wrist root point's x in
the A1 coordinate system is negative), bit 1 is 1 when A3 is at or beyond the angle at which the arm is
stretched (the wrist centre in front of the line through A2 and A3), bit 2 is 1 when A5 is negative.
Turn bit i is 1 when axis i+1 is negative.  Descriptions of bit 2 differ in wording (users on the KUKA
robot forum report KSS 5 and KSS 8 manuals that speak of the wrist pointing up or down rather than of A5's
sign, and tables that put A5 = 0 on either side); a user who measured it on a KR 60-3 found A5's sign; at A5 = 0, the
wrist singularity, we follow Beckhoff's "A5 < 0".

ABB, confdata [cf1, cf4, cf6, cfx] (ABB RAPID Reference Manual, Instructions, Functions and Data types,
"confdata").  cf1, cf4, cf6 are the quadrants of axes 1, 4, 6: quadrant n covers [n * 90, (n + 1) * 90)
degrees, so 0 is 0 to 90, 1 is 90 to 180, -1 is -90 to 0, -2 is -180 to -90.  cfx for serial arms is
4 * (wrist centre behind axis 1) + 2 * (wrist centre behind the lower arm) + (axis 5 negative), the table
0 = front, front, positive ... 7 = behind, behind, negative of the manual.

Fanuc, the position's configuration ("CONFIG : 'N U T, 0, 0, 0'", Fanuc HandlingTool Operator's Manual,
"Configuration"): F or N (wrist flip: F where J5 > 0, N where J5 <= 0.  Third-party notes disagree on the
sign; this one agrees with Fanuc's usual tool-down posture J4 = 0, J5 = -90 being taught as N, and with
KUKA's and ABB's non-flipped wrist, the same physical branch: theta5 > 0 in the OPW model), U or D
(elbow: U where the wrist centre is in front of the line through J2 and J3, as for ABB's lower arm), T or B
(wrist centre in front of or behind the J1 axis), then the turn numbers of J1, J4, J6: 0 for -180 < J <
180, 1 for 180 <= J < 540, -1 for -540 < J <= -180, and so on.  Fanuc's manual draws U/D only for the
front (T) configuration; behind J1 we keep the same joint-space rule.  Note that Fanuc pendants show J3
relative to the horizontal (the J2/J3 interaction); a Fanuc robot file must give the model the joint values
this module is given.
"""
from __future__ import annotations

import numpy as np

from ..errors import InputError
from .model import Robot
from .opw import model_angles


def arm_configuration(robot: Robot, joints_deg) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Booleans (...) for (..., 6) controller joints: wrist centre behind axis 1, wrist centre behind the line
    through axes 2 and 3, axis 5 negative."""
    params = _opw(robot)
    joints = np.asarray(joints_deg, dtype=float)
    theta = model_angles(params, joints)
    psi3 = np.arctan2(params.a2, params.c3)
    k = np.hypot(params.a2, params.c3)
    elbow = theta[..., 2] + psi3
    wrist_x = params.a1 + params.c2 * np.sin(theta[..., 1]) + k * np.sin(theta[..., 1] + elbow)
    elbow_wrapped = np.remainder(elbow, 2 * np.pi)  # [0, 2 pi): [0, pi) is in front
    behind_axis1 = wrist_x < 0
    behind_lower_arm = elbow_wrapped >= np.pi
    axis5_negative = joints[..., 4] < 0
    return behind_axis1, behind_lower_arm, axis5_negative


def kuka_status_turn(robot: Robot, joints_deg) -> tuple[np.ndarray, np.ndarray]:
    """KUKA Status and Turn as integers (...) for (..., 6) controller joints (write as S 'B010', T 'B000010')."""
    joints = _finite(joints_deg)
    overhead, behind_link_arm, a5_negative = arm_configuration(robot, joints)
    status = overhead.astype(int) + 2 * (~behind_link_arm).astype(int) + 4 * a5_negative.astype(int)
    turn = np.sum((joints < 0) * (1 << np.arange(6)), axis=-1)
    return status, turn


def abb_confdata(robot: Robot, joints_deg) -> np.ndarray:
    """(..., 4) integers [cf1, cf4, cf6, cfx] for (..., 6) controller joints."""
    joints = _finite(joints_deg)
    behind_axis1, behind_lower_arm, axis5_negative = arm_configuration(robot, joints)
    quadrants = np.floor(joints[..., [0, 3, 5]] / 90.0).astype(int)
    cfx = 4 * behind_axis1.astype(int) + 2 * behind_lower_arm.astype(int) + axis5_negative.astype(int)
    return np.concatenate([quadrants, cfx[..., None]], axis=-1)


def fanuc_turn_number(joint_deg) -> np.ndarray:
    """Fanuc turn number of a joint value: 0 within (-180, 180), +-1 one turn further, and so on."""
    joint = np.asarray(joint_deg, dtype=float)
    return (np.sign(joint) * np.floor((np.abs(joint) + 180.0) / 360.0)).astype(int)


def fanuc_config(robot: Robot, joints_deg) -> np.ndarray:
    """(...) strings such as 'N U T, 0, 0, 0' for (..., 6) controller joints."""
    joints = _finite(joints_deg)
    behind_axis1, behind_lower_arm, _ = arm_configuration(robot, joints)
    flip = np.where(joints[..., 4] > 0, "F", "N")
    elbow = np.where(behind_lower_arm, "D", "U")
    front = np.where(behind_axis1, "B", "T")
    turns = fanuc_turn_number(joints[..., [0, 3, 5]])
    text = [f"{f} {u} {t}, {t1}, {t4}, {t6}" for f, u, t, (t1, t4, t6)
            in zip(flip.ravel(), elbow.ravel(), front.ravel(), turns.reshape(-1, 3))]
    return np.array(text, dtype=object).reshape(flip.shape)


def _opw(robot: Robot):
    if robot.opw is None:
        raise InputError(f"robot {robot.id}: configuration data is defined for OPW arms (KUKA, ABB, Fanuc), "
                         f"not for {robot.kinematics} kinematics")
    return robot.opw


def _finite(joints_deg) -> np.ndarray:
    joints = np.asarray(joints_deg, dtype=float)
    if joints.shape[-1:] != (6,):
        raise ValueError(f"joints must have shape (..., 6), got {joints.shape}")
    if not np.all(np.isfinite(joints)):
        raise ValueError("joints must be finite: drop unreachable (NaN) branches first")
    return joints
