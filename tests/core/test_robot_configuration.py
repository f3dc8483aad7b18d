"""Controller configuration data from joint values: KUKA Status and Turn, ABB confdata, Fanuc configuration
strings, on the vendors' definitions and on properties every pose must have (its eight branches are eight
configurations, Turn bits are joint signs)."""
import dataclasses

import numpy as np
import pytest

from robot_files import ABB_IRB2400, FANUC_M10IA, write_robot
from workcal_wb.core.errors import InputError
from workcal_wb.core.robots import builtin_robots, forward, inverse, load_robot
from workcal_wb.core.robots.configuration import (abb_confdata, arm_configuration, fanuc_config,
                                                  fanuc_turn_number, kuka_status_turn)

ROBOTS = {robot_id: load_robot(robot_id) for robot_id in builtin_robots()}
OPW_ROBOTS = [robot_id for robot_id, robot in ROBOTS.items() if robot.kinematics == "opw"]
KUKA_ROBOTS = [robot_id for robot_id in OPW_ROBOTS if ROBOTS[robot_id].controller == "kuka"]
# Every built-in ABB and FANUC arm, and the test's own (which the library may not hold).
ABB_ROBOTS = [robot_id for robot_id in OPW_ROBOTS if ROBOTS[robot_id].controller == "abb"] + [ABB_IRB2400["id"]]
FANUC_ROBOTS = ([robot_id for robot_id in OPW_ROBOTS if ROBOTS[robot_id].controller == "fanuc"]
                + [FANUC_M10IA["id"]])


@pytest.fixture(scope="module")
def file_robots(tmp_path_factory):
    folder = tmp_path_factory.mktemp("robots")
    return {data["id"]: write_robot(folder, data) for data in (ABB_IRB2400, FANUC_M10IA)}


def robot_named(name, file_robots):
    return file_robots.get(name) or ROBOTS[name]


def branches_of_random_poses(robot, count=200, seed=3):
    """The eight inverse branches (count, 8, 6) of random poses, and which of them exist."""
    rng = np.random.default_rng(seed)
    solutions = inverse(robot, forward(robot, rng.uniform(-180, 180, (count, 6))))
    return solutions, ~np.isnan(solutions).any(axis=-1)


# --------------------------------------------------------------------------- shared geometry


@pytest.mark.parametrize("robot_id", OPW_ROBOTS + [ABB_IRB2400["id"], FANUC_M10IA["id"]])
def test_the_inverse_branches_are_the_eight_arm_configurations(robot_id, file_robots):
    """Branch b: behind axis 1 = bit 1 of b, behind the lower arm = bit 0, model theta5 < 0 = b >= 4."""
    robot = robot_named(robot_id, file_robots)
    solutions, exists = branches_of_random_poses(robot)
    behind_axis1, behind_arm, _ = arm_configuration(robot, np.where(exists[..., None], solutions, 0.0))
    branch = np.arange(8)
    assert np.array_equal(behind_axis1[exists], np.broadcast_to((branch & 2) > 0, exists.shape)[exists])
    assert np.array_equal(behind_arm[exists], np.broadcast_to((branch & 1) > 0, exists.shape)[exists])


# --------------------------------------------------------------------------- KUKA


@pytest.mark.parametrize("robot_id", KUKA_ROBOTS)
def test_kuka_the_eight_branches_of_a_pose_have_eight_statuses(robot_id):
    robot = ROBOTS[robot_id]
    solutions, exists = branches_of_random_poses(robot)
    all_eight = exists.all(axis=1) & (np.abs(solutions[..., 4]) > 1e-6).all(axis=1)
    assert all_eight.sum() > 20
    status, turn = kuka_status_turn(robot, solutions[all_eight])
    assert all(len(set(row)) == 8 for row in status.tolist())
    # and the same status for the same branch, whatever the pose: bit 0 = reaching back, bit 1 = the elbow
    # root in front of the link arm, bit 2 = A5 negative (A5 = theta5 for KUKA).
    branch = np.arange(8)
    expected = ((branch & 2) > 0) * 1 + ((branch & 1) == 0) * 2 + (branch >= 4) * 4
    assert np.array_equal(status, np.broadcast_to(expected, status.shape))
    assert np.array_equal(turn, np.sum((solutions[all_eight] < 0) * [1, 2, 4, 8, 16, 32], axis=-1))


def test_kuka_status_and_turn_by_the_definitions():
    robot = ROBOTS["kuka_kr6_r700_sixx"]
    # The mastering pose with A5 tilted: basic area, A3 beyond the stretched angle, A5 positive: S 'B010'.
    # A2 is the only negative axis: T 'B000010'.
    status, turn = kuka_status_turn(robot, [0, -90, 90, 0, 30, 0])
    assert (int(status), int(turn)) == (0b010, 0b000010)
    assert int(kuka_status_turn(robot, [0, -90, 90, 0, -30, 0])[0]) == 0b110
    # Turn: every axis negative is 'B111111' = 63, every axis positive 0 (Beckhoff TF5200's KUKA examples).
    assert int(kuka_status_turn(robot, [-1, -2, -3, -4, -5, -6])[1]) == 63
    assert int(kuka_status_turn(robot, [1, 2, 3, 4, 5, 6])[1]) == 0
    assert int(kuka_status_turn(robot, [10, -90, 90, -5, 30, -120])[1]) == 0b101010
    # Bit 1 switches where the arm is stretched, not at A3 = 0: the 35 mm A3-A4 offset over the 365 mm
    # arm puts the wrist centre on the line through A2 and A3 at A3 = atan(35 / 365) = 5.48 degrees.
    stretched = np.degrees(np.arctan2(35.0, 365.0))
    for a3, bit1 in ((stretched - 0.01, 0), (stretched + 0.01, 1), (0.0, 0), (-90.0, 0), (120.0, 1)):
        assert (int(kuka_status_turn(robot, [0, -45, a3, 0, 30, 0])[0]) >> 1) & 1 == bit1, a3


def test_kuka_overhead_bit_follows_the_wrist_root_point_formula():
    """For a KUKA arm with no A3-A4 offset the x of the wrist root point in the A1 frame is
    a1 + c2 cos(A2) + c3 cos(A2 + A3) (the formula a KUKA forum thread gives for the KR 3); bit 0 is 1
    where it is negative."""
    robot = ROBOTS["kuka_kr16_2"]
    opw = dataclasses.replace(robot.opw, a1=100.0, a2=0.0, c2=265.0, c3=270.0)
    kr3_like = dataclasses.replace(robot, opw=opw)
    joints = np.random.default_rng(1).uniform(-180, 180, (2000, 6))
    a2, a3 = np.radians(joints[:, 1]), np.radians(joints[:, 2])
    x = 100.0 + 265.0 * np.cos(a2) + 270.0 * np.cos(a2 + a3)
    status, _ = kuka_status_turn(kr3_like, joints)
    assert np.array_equal(status & 1, (x < 0).astype(int))


# --------------------------------------------------------------------------- ABB


@pytest.mark.parametrize("robot_id", ABB_ROBOTS)
def test_abb_the_eight_branches_of_a_pose_have_eight_cfx(robot_id, file_robots):
    robot = robot_named(robot_id, file_robots)
    solutions, exists = branches_of_random_poses(robot)
    all_eight = exists.all(axis=1) & (np.abs(solutions[..., 4]) > 1e-6).all(axis=1)
    assert all_eight.sum() > 20
    conf = abb_confdata(robot, solutions[all_eight])
    branch = np.arange(8)
    assert np.array_equal(conf[..., 3], np.broadcast_to(4 * ((branch & 2) > 0) + 2 * (branch & 1) + (branch >= 4),
                                                         conf.shape[:2]))
    assert np.array_equal(conf[..., :3], np.floor(solutions[all_eight][..., [0, 3, 5]] / 90).astype(int))


def test_abb_quadrants_and_cfx_by_the_definitions(file_robots):
    robot = file_robots[ABB_IRB2400["id"]]
    # Quadrant n is [90 n, 90 (n + 1)): 0 is 0..90, 1 is 90..180, -1 is 0..-90, -2 is -90..-180; axis 6
    # of the IRB 2400 turns +-400 degrees, so 200 is quadrant 2 and -300 quadrant -4.
    conf = abb_confdata(robot, [[45, 0, 0, 135, 30, 200], [-45, 0, 0, -135, -30, -300], [0, 0, 0, 0, 30, 0]])
    assert conf.tolist() == [[0, 1, 2, 0], [-1, -2, -4, 1], [0, 0, 0, 0]]
    # Axis 1 at -120 (quadrant -2), axis 4 at 120 (1), axis 6 at 200 (2), wrist centre in front of axis 1
    # and of the lower arm, axis 5 negative: [-2, 1, 2, 1].
    assert abb_confdata(robot, [-120, 10, 20, 120, -30, 200]).tolist() == [-2, 1, 2, 1]


# --------------------------------------------------------------------------- Fanuc


@pytest.fixture
def fanuc_m10ia(file_robots):
    return file_robots[FANUC_M10IA["id"]]


def test_fanuc_turn_numbers():
    values = [0, 179.9, -179.9, 180, -180, 359, 539.9, 540, -540, -541]
    assert fanuc_turn_number(values).tolist() == [0, 0, 0, 1, -1, 1, 1, 2, -2, -2]


def test_fanuc_tool_down_is_n_u_t(fanuc_m10ia):
    # Zero joints but J5 = -90: arm up and forward, tool pointing down, the posture taught as N U T.
    assert fanuc_config(fanuc_m10ia, [0, 0, 0, 0, -90, 0]) == "N U T, 0, 0, 0"
    assert fanuc_config(fanuc_m10ia, [0, 0, 0, 0, 30, 0]) == "F U T, 0, 0, 0"
    assert fanuc_config(fanuc_m10ia, [[200, 0, 0, -190, -30, 250]]).tolist() == ["N U T, 1, -1, 1"]


@pytest.mark.parametrize("robot_id", FANUC_ROBOTS)
def test_fanuc_the_eight_branches_of_a_pose_have_eight_configurations(robot_id, file_robots):
    robot = robot_named(robot_id, file_robots)
    assert robot.opw.signs[4] == -1  # J5 = -theta5 on FANUC arms, as below
    solutions, exists = branches_of_random_poses(robot)
    all_eight = exists.all(axis=1) & (np.abs(solutions[..., 4]) > 1e-6).all(axis=1)
    assert all_eight.sum() > 20
    config = fanuc_config(robot, solutions[all_eight])
    letters = np.vectorize(lambda text: text.split(",")[0])(config)
    assert all(len(set(row)) == 8 for row in letters.tolist())
    # N where J5 <= 0; J5 = -theta5, so the theta5 >= 0 branches (0-3) are N.
    assert np.all(np.char.startswith(letters[:, :4].astype(str), "N"))
    assert np.all(np.char.startswith(letters[:, 4:].astype(str), "F"))


def test_configuration_needs_an_opw_arm():
    with pytest.raises(InputError, match="ur5e: configuration data is defined for OPW arms"):
        kuka_status_turn(ROBOTS["ur5e"], np.zeros(6))


def test_unreachable_branches_must_be_dropped_first(file_robots):
    with pytest.raises(ValueError, match="drop unreachable"):
        abb_confdata(file_robots[ABB_IRB2400["id"]], [np.nan] * 6)
