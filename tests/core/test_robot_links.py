"""Where a robot's links are at given joints (robots/links.py), and the pose of a program to look at
(robots/reach.py worst_pose): the drawn arm ends at the flange the kinematics give, its links are the
model's lengths, its joints are where an independent chain (the URDF's) puts them."""
import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from workcal_wb.core import frames
from workcal_wb.core.robots import builtin_robots, forward, joint_margins_deg, load_robot
from workcal_wb.core.robots.links import ARM_END, OPW_POINTS, UR_POINTS, arm_points
from workcal_wb.core.robots.model import LIBRARY, xyzabc_transform
from workcal_wb.core.robots.reach import JOINT_LIMIT, OUT_OF_REACH, check_reach, worst_pose

# The points are sums of the model's lengths turned by the joints: exact to rounding.
POINT_MM = 1e-9
# KR 6 R700 sixx, ROS-Industrial kuka_experimental kr6r700sixx_macro.xacro: each joint's origin (m) from the
# one before and its axis, joint values = KUKA's.
KR6_URDF_CHAIN = [((0, 0, 0.4), (0, 0, -1)), ((0.025, 0, 0), (0, 1, 0)), ((0.315, 0, 0), (0, 1, 0)),
                  ((0, 0, 0.035), (-1, 0, 0)), ((0.365, 0, 0), (0, 1, 0)), ((0.080, 0, 0), (-1, 0, 0))]


def random_joints(robot, count, seed=3):
    return np.random.default_rng(seed).uniform(robot.limits[:, 0], robot.limits[:, 1], size=(count, 6))


def expected_lengths(robot) -> list:
    """The links' lengths as the model's parameters give them, base to flange."""
    if robot.opw is not None:
        p = robot.opw
        return [p.c1, np.hypot(p.a1, p.b), p.c2, abs(p.a2), p.c3, p.c4]
    p = robot.ur
    return [p.d1, abs(p.a2), abs(p.a3), p.d4, p.d5, p.d6]


@pytest.mark.parametrize("robot_id", builtin_robots())
def test_the_arm_ends_at_the_flange_the_kinematics_give(robot_id):
    robot = load_robot(robot_id)
    joints = random_joints(robot, 200)
    arm = arm_points(robot, joints)
    assert arm.points.shape == (200, 7, 3) and arm.names[-1] == "flange"
    assert arm.names == (OPW_POINTS if robot.opw is not None else UR_POINTS)
    assert np.abs(arm.point("flange") - forward(robot, joints)[:, :3, 3]).max() < POINT_MM


@pytest.mark.parametrize("robot_id", builtin_robots())
def test_the_links_are_the_models_lengths_at_any_joints(robot_id):
    """|base -> axis 1 at shoulder height| = c1, |shoulder -> elbow| = c2, ... (UR: d1, |a2|, |a3|, d4, d5, d6)."""
    robot = load_robot(robot_id)
    arm = arm_points(robot, random_joints(robot, 200))
    np.testing.assert_allclose(arm.lengths(), np.broadcast_to(expected_lengths(robot), (200, 6)), atol=POINT_MM)


def test_the_joints_are_where_the_urdf_chain_puts_them():
    """The KR 6 R700 sixx's URDF, joint by joint: the origin of joint_a1 (axis 1 at shoulder height) to
    joint_a6 (the flange) are the arm's points after its base."""
    robot = load_robot("kuka_kr6_r700_sixx")
    joints = random_joints(robot, 50, seed=8)
    for row, arm in zip(joints, arm_points(robot, joints).points):
        T, origins = np.eye(4), []
        for (origin, axis), angle in zip(KR6_URDF_CHAIN, np.radians(row)):
            step = np.eye(4)
            step[:3, 3] = np.array(origin) * 1000.0
            step[:3, :3] = Rotation.from_rotvec(np.array(axis, float) * angle).as_matrix()
            T = T @ step
            origins.append(T[:3, 3])
        np.testing.assert_allclose(arm[1:], origins, atol=POINT_MM)
        np.testing.assert_allclose(arm[0], 0.0, atol=POINT_MM)


def test_the_base_and_flange_frames_of_the_robot_file_are_applied(tmp_path):
    """FANUC's World frame lies at the height of J2: the foot is c1 below it.  A controller flange offset from
    the model's end frame adds the arm's end, and the last point is still the controller's flange."""
    fanuc = load_robot("fanuc_m20ia")
    arm = arm_points(fanuc, np.zeros(6))
    np.testing.assert_allclose(arm.point("base"), [0.0, 0.0, -fanuc.opw.c1], atol=POINT_MM)
    np.testing.assert_allclose(arm.point("axis 1 at shoulder height"), 0.0, atol=POINT_MM)
    data = json.loads((LIBRARY / "kuka_kr16_2.json").read_text())
    data.update(id="kr16_with_adapter", flange=[0.0, 0.0, 40.0, 0.0, 0.0, 0.0], base=[0.0, 0.0, 100.0, 0.0, 0.0, 30.0])
    path = tmp_path / "kr16_with_adapter.json"
    path.write_text(json.dumps(data))
    robot = load_robot(path)
    joints = random_joints(robot, 20)
    arm = arm_points(robot, joints)
    assert arm.names[-2:] == (ARM_END, "flange")
    np.testing.assert_allclose(arm.point("flange"), forward(robot, joints)[:, :3, 3], atol=POINT_MM)
    np.testing.assert_allclose(arm.lengths()[:, -1], 40.0, atol=POINT_MM)  # the adapter
    np.testing.assert_allclose(arm.lengths()[:, :-1], np.broadcast_to(expected_lengths(robot), (20, 6)),
                               atol=POINT_MM)


def test_one_pose_and_many_poses_give_the_same_points():
    robot = load_robot("ur5e")
    joints = random_joints(robot, 12).reshape(3, 4, 6)
    many = arm_points(robot, joints).points
    assert many.shape == (3, 4, 7, 3)
    np.testing.assert_allclose(many[2, 1], arm_points(robot, joints[2, 1]).points, atol=POINT_MM)
    with pytest.raises(ValueError, match=r"\(\.\.\., 6\)"):
        arm_points(robot, np.zeros(5))


# --------------------------------------------------------------------------- the pose to look at

def line_of_poses(start, end, count=20):
    """TCP poses pointing down along a straight line in the robot base frame."""
    poses = np.tile(np.eye(4), (count, 1, 1))
    poses[:, :3, :3] = frames.rot_y(180.0)
    poses[:, :3, 3] = np.linspace(start, end, count)
    return poses


TOOL = xyzabc_transform([0.0, 0.0, 150.0, 0.0, 0.0, 0.0])


def test_a_program_the_robot_follows_is_shown_where_its_margin_is_smallest():
    robot = load_robot("kuka_kr16_2")
    report = check_reach(robot, line_of_poses((900.0, -300.0, 300.0), (1300.0, 300.0, 300.0)), TOOL,
                         source_lines=np.arange(20) + 10)
    pose = worst_pose(robot, report)
    assert report.reachable and pose.where == report.margin.where
    margins = joint_margins_deg(robot, pose.joints)
    assert margins.min() == pytest.approx(report.margin.value) and int(np.argmin(margins)) == report.margin.joint
    assert pose.text == f"at line {pose.where.line} (A{report.margin.joint + 1} {report.margin.value:.1f} deg from " \
                        "its limit)"


def test_a_program_past_a_joint_limit_is_shown_past_it():
    """The tool turned 40 deg per target about its axis in linear moves: A6 runs out of its +-350 deg."""
    robot = load_robot("kuka_kr16_2")
    poses = line_of_poses((1200.0, 0.0, 300.0), (1200.0, 0.0, 300.0))
    poses[:, :3, :3] = [frames.rot_z(40.0 * i) @ frames.rot_y(180.0) for i in range(20)]
    report = check_reach(robot, poses, TOOL, source_lines=np.arange(20) + 10)
    pose = worst_pose(robot, report)
    assert report.problem == JOINT_LIMIT and pose.where == report.problem_at
    margins = joint_margins_deg(robot, pose.joints)
    assert margins.min() < 0 and int(np.argmin(margins)) == 5
    assert pose.text.endswith(f"(A6 {-margins.min():.1f} deg past its limit)")
    # Every target puts the TCP at one point, pointing down: so does the pose shown, turned past the limit.
    tcp = forward(robot, pose.joints) @ TOOL
    np.testing.assert_allclose(tcp[:3, 3], [1200.0, 0.0, 300.0], atol=1e-6)
    np.testing.assert_allclose(tcp[:3, 2], [0.0, 0.0, -1.0], atol=1e-9)


def test_a_program_out_of_reach_is_shown_at_the_last_pose_the_robot_follows():
    robot = load_robot("kuka_kr16_2")
    report = check_reach(robot, line_of_poses((1000.0, 0.0, 300.0), (2400.0, 0.0, 300.0)), TOOL,
                         source_lines=np.arange(20) + 10)
    pose = worst_pose(robot, report)
    assert report.problem == OUT_OF_REACH and "just before going out of reach" in pose.text
    assert pose.where.target <= report.problem_at.target
    assert (joint_margins_deg(robot, pose.joints) >= 0).all()
    nothing = check_reach(robot, line_of_poses((3000.0, 0.0, 300.0), (3100.0, 0.0, 300.0)), TOOL)
    assert worst_pose(robot, nothing) is None
