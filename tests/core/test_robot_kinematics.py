"""Robot models and their kinematics: files are checked field by field, forward and inverse kinematics agree
to rounding on every branch of every built-in robot, with independent solvers (py-opw-kinematics, FreeCAD's
Robot6Axis, the ROS-Industrial URDF chain) and with the arms' published zero poses; limits and turns."""
import dataclasses
import json
import os
import shutil
import subprocess

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from workcal_wb.core.benchmark.reach import py_opw_kinematics
from workcal_wb.core.errors import InputError
from workcal_wb.core.robots import (builtin_robots, forward, inverse, limit_margin_deg, load_robot,
                                    turn_candidates, turn_offsets, within_limits, wrap_into_limits)
from workcal_wb.core.robots import opw, ur
from workcal_wb.core.robots.model import LIBRARY, OpwParameters, xyzabc_transform
from robot_files import ABB_IRB2400, FANUC_M10IA, write_robot

# A round trip reproduces a pose to this position (mm) and rotation (largest entry of the difference of the
# two rotation matrices): rounding on arms a metre or two long is about 1e-12 mm.
POSITION_TOL_MM = 1e-9
ROTATION_TOL = 1e-9
# The drawn joints are found again to this (degrees): a nearly stretched elbow costs half the digits.
SAME_JOINT_DEG = 1e-6


def wrapped_difference(a, b):
    """a - b in degrees, taken into [-180, 180)."""
    return (np.asarray(a) - np.asarray(b) + 180.0) % 360.0 - 180.0


def pose_errors(computed, expected):
    """Position (mm) and rotation errors of (..., 4, 4) poses."""
    position = np.linalg.norm(computed[..., :3, 3] - expected[..., :3, 3], axis=-1)
    rotation = np.abs(computed[..., :3, :3] - expected[..., :3, :3]).max(axis=(-1, -2))
    return position, rotation


@pytest.fixture(scope="module")
def file_robots(tmp_path_factory):
    """The test's own robot files (ABB and FANUC arms with the J2/J3 coupling), by id."""
    folder = tmp_path_factory.mktemp("robots")
    return {data["id"]: write_robot(folder, data) for data in (ABB_IRB2400, FANUC_M10IA)}


def robot_named(name, file_robots):
    return file_robots[name] if name in file_robots else load_robot(name)


def random_joints(rng, count):
    """Joints over the whole turn of every axis, so that every branch of the inverse is drawn."""
    return rng.uniform(-180.0, 180.0, (count, 6))


def check_round_trip(fk, ik, joints):
    """FK -> IK -> FK: every branch that exists reproduces the pose; the drawn joints are one branch.
    Returns the index of the branch that holds the drawn joints, per draw."""
    poses = fk(joints)
    solutions = ik(poses)
    assert solutions.shape == (len(joints), 8, 6)
    exists = ~np.isnan(solutions).any(axis=-1)
    assert np.array_equal(exists, ~np.isnan(solutions).all(axis=-1)), "a branch is either whole or NaN"
    again = fk(np.where(exists[..., None], solutions, 0.0))
    position, rotation = pose_errors(again, poses[:, None])
    assert position[exists].max() < POSITION_TOL_MM
    assert rotation[exists].max() < ROTATION_TOL
    distance = np.abs(wrapped_difference(solutions, joints[:, None])).max(axis=-1)
    distance = np.where(exists, distance, np.inf)
    assert distance.min(axis=1).max() < SAME_JOINT_DEG
    assert np.all((solutions[exists] > -180.0) & (solutions[exists] <= 180.0))
    return distance.argmin(axis=1)


# --------------------------------------------------------------------------- robot files


def test_the_library_holds_the_robots_the_tests_name():
    ids = builtin_robots()
    for name in ("kuka_kr6_r700_sixx", "kuka_kr16_2", "ur5e", "ur10e"):
        assert name in ids
    assert ids == sorted(ids)


@pytest.mark.parametrize("robot_id", builtin_robots())
def test_every_builtin_robot_loads_with_its_sources(robot_id):
    robot = load_robot(robot_id)
    assert robot.id == robot_id
    assert robot.limits.shape == (6, 2) and np.all(robot.limits[:, 0] < robot.limits[:, 1])
    assert robot.parameters is (robot.opw if robot.kinematics == "opw" else robot.ur)
    assert {"geometry", "joint_limits", "frames"} <= set(dict(robot.sources))
    assert load_robot(LIBRARY / f"{robot_id}.json") == robot  # by path too


def _write(tmp_path, data, name="robot.json"):
    path = tmp_path / name
    path.write_text(json.dumps(data) if not isinstance(data, str) else data)
    return path


def _kr6():
    return json.loads((LIBRARY / "kuka_kr6_r700_sixx.json").read_text())


def _edited(change):
    data = _kr6()
    change(data)
    return data


BAD_FILES = [
    ("not json", "{", "not a JSON robot file"),
    ("a list", [], "one JSON object"),
    ("unknown field", _edited(lambda d: d.update(joint_limit_deg=[])), "unknown field(s) 'joint_limit_deg'"),
    ("missing name", _edited(lambda d: d.pop("name")), "field 'name' is missing"),
    ("bad controller", _edited(lambda d: d.update(controller="yaskawa")), "field 'controller' must be one of"),
    ("bad kinematics", _edited(lambda d: d.update(kinematics="dh")), "field 'kinematics' must be one of"),
    ("ur kinematics on kuka", _edited(lambda d: d.update(kinematics="ur")), "field 'kinematics' is 'ur'"),
    ("missing opw", _edited(lambda d: d.pop("opw")), "field 'opw' is missing"),
    ("opw length not a number", _edited(lambda d: d["opw"].update(c2="315")), "field 'opw.c2' must be a finite"),
    ("opw length NaN", _edited(lambda d: d["opw"].update(a1=float("nan"))), "field 'opw.a1' must be a finite"),
    ("negative forearm", _edited(lambda d: d["opw"].update(c3=-365.0)), "field 'opw.c3' must be a positive"),
    ("negative flange offset", _edited(lambda d: d["opw"].update(c4=-1)), "field 'opw.c4'"),
    ("unknown opw key", _edited(lambda d: d["opw"].update(d4=1)), "field 'opw' has unknown key(s) 'd4'"),
    ("five signs", _edited(lambda d: d["opw"].update(signs=[1, 1, 1, 1, 1])), "field 'opw.signs' must be a list of 6"),
    ("sign of 2", _edited(lambda d: d["opw"].update(signs=[2, 1, 1, 1, 1, 1])), "field 'opw.signs' must hold six"),
    ("offset text", _edited(lambda d: d["opw"].update(offsets_deg=[0, "x", 0, 0, 0, 0])), "field 'opw.offsets_deg'"),
    ("five limits", _edited(lambda d: d["joint_limits_deg"].pop()), "field 'joint_limits_deg' must be a list of six"),
    ("low above high", _edited(lambda d: d["joint_limits_deg"].__setitem__(2, [156, -120])),
     "field 'joint_limits_deg[2]' (axis 3) must have low < high"),
    ("limit pair of three", _edited(lambda d: d["joint_limits_deg"].__setitem__(0, [1, 2, 3])),
     "field 'joint_limits_deg[0] (axis 1)' must be a list of 2"),
    ("base of five", _edited(lambda d: d.update(base=[0, 0, 0, 0, 0])), "field 'base (x, y, z in mm"),
    ("flange infinite", _edited(lambda d: d.update(flange=[0, 0, 1e400, 0, 0, 0])), "field 'flange"),
    ("id with a slash", _edited(lambda d: d.update(id="a/b")), "field 'id' must be letters"),
    ("sources not texts", _edited(lambda d: d.update(sources={"geometry": 1})), "field 'sources'"),
    ("coupling of 2", _edited(lambda d: d["opw"].update(j23_factor=2)), "field 'opw.j23_factor' must be -1, 0 or 1"),
]


@pytest.mark.parametrize("label, data, message", BAD_FILES, ids=[case[0] for case in BAD_FILES])
def test_a_bad_robot_file_is_refused_naming_the_file_and_the_field(tmp_path, label, data, message):
    path = _write(tmp_path, data)
    with pytest.raises(InputError) as error:
        load_robot(path)
    assert str(path) in str(error.value)
    assert message in str(error.value)


def test_ur_lengths_must_have_ur_signs(tmp_path):
    data = json.loads((LIBRARY / "ur5e.json").read_text())
    data["ur"]["a2"] = 425.0
    with pytest.raises(InputError, match=r"field 'ur.a2' must be negative, as Universal Robots publishes it"):
        load_robot(_write(tmp_path, data))
    data["ur"].update(a2=-425.0, d5=0.0)
    with pytest.raises(InputError, match=r"field 'ur.d5' must be a positive length"):
        load_robot(_write(tmp_path, data))


def test_an_unknown_robot_names_the_builtin_ones():
    with pytest.raises(InputError, match=r"no built-in robot of that id and no such file .*kuka_kr6_r700_sixx"):
        load_robot("kuka_kr6_r900")


def test_a_builtin_file_must_carry_its_own_name_as_id(tmp_path, monkeypatch):
    from workcal_wb.core.robots import model
    folder = tmp_path / "library"
    folder.mkdir()
    _write(folder, _kr6(), "kuka_kr6_copy.json")
    monkeypatch.setattr(model, "LIBRARY", folder)
    with pytest.raises(InputError, match=r"field 'id' is 'kuka_kr6_r700_sixx' but the file is named kuka_kr6_copy"):
        load_robot("kuka_kr6_copy")


# --------------------------------------------------------------------------- round trips


@pytest.mark.parametrize("robot_id", builtin_robots())
def test_every_branch_of_every_builtin_robot_round_trips(robot_id):
    """Random joints over whole turns: FK of each branch the inverse returns is the pose to 1e-9 mm and 1e-9,
    the drawn joints are among the branches, and every one of the eight branches is the drawn one sometimes."""
    robot = load_robot(robot_id)
    joints = random_joints(np.random.default_rng(11), 4000)
    branch = check_round_trip(lambda q: forward(robot, q), lambda T: inverse(robot, T), joints)
    assert set(branch) == set(range(8))


@pytest.mark.parametrize("robot_id", [ABB_IRB2400["id"], FANUC_M10IA["id"]])
def test_every_branch_of_a_coupled_arm_round_trips(robot_id, file_robots):
    """Arms whose controller J3 is the forearm's angle (J2/J3 coupling) and FANUC's base frame above J1."""
    robot = file_robots[robot_id]
    joints = random_joints(np.random.default_rng(12), 4000)
    branch = check_round_trip(lambda q: forward(robot, q), lambda T: inverse(robot, T), joints)
    assert set(branch) == set(range(8))


def test_the_j23_coupling_is_applied_before_offsets_and_signs(file_robots):
    """Model joint 3 = J3 + j23_factor * J2: the coupled arm at J is the uncoupled one at the model joints."""
    joints = random_joints(np.random.default_rng(13), 200)
    for robot in file_robots.values():
        factor = robot.opw.j23_factor
        assert factor != 0
        uncoupled = dataclasses.replace(robot, opw=dataclasses.replace(robot.opw, j23_factor=0))
        model_joints = joints.copy()
        model_joints[:, 2] += factor * joints[:, 1]
        assert np.allclose(opw.model_joints(robot.opw, joints), model_joints)
        position, rotation = pose_errors(forward(robot, joints), forward(uncoupled, model_joints))
        assert position.max() < 1e-9 and rotation.max() < 1e-12
        # and the inverse gives the controller's J3 back
        solutions = inverse(robot, forward(robot, joints[:1]))[0]
        uncoupled_solutions = inverse(uncoupled, forward(robot, joints[:1]))[0]
        exists = ~np.isnan(solutions).any(axis=1)
        expected_j3 = uncoupled_solutions[exists, 2] - factor * uncoupled_solutions[exists, 1]
        assert np.allclose(wrapped_difference(solutions[exists, 2], expected_j3), 0, atol=1e-9)


def test_round_trips_through_the_controller_frames():
    """Base and flange frames that are not the identity: the entry point composes them around the model
    (controller pose = base^-1 model pose flange) and the inverse undoes it."""
    rng = np.random.default_rng(5)
    for robot_id in ("kuka_kr16_2", "ur10e"):
        plain = load_robot(robot_id)
        robot = dataclasses.replace(plain, base=(120.0, -40.0, 300.0, 30.0, -10.0, 5.0),
                                    flange=(1.5, -2.0, 33.0, 0.0, 90.0, 180.0))
        joints = random_joints(rng, 500)
        model = opw.forward(robot, joints) if robot.kinematics == "opw" else ur.forward(robot, joints)
        expected = np.linalg.inv(xyzabc_transform(robot.base)) @ model @ xyzabc_transform(robot.flange)
        position, rotation = pose_errors(forward(robot, joints), expected)
        assert position.max() < POSITION_TOL_MM and rotation.max() < ROTATION_TOL
        check_round_trip(lambda q: forward(robot, q), lambda T: inverse(robot, T), joints)


def test_opw_round_trips_for_general_geometry():
    """Offsets b, a1 and a2 all non-zero, odd offsets and signs: the branches still all reproduce the pose."""
    params = OpwParameters(a1=150.0, a2=-110.0, b=35.0, c1=450.0, c2=600.0, c3=640.0, c4=100.0,
                           offsets_deg=(12.0, -90.0, 30.0, 0.0, 45.0, 180.0), signs=(1, -1, 1, -1, -1, 1))
    joints = random_joints(np.random.default_rng(2), 4000)
    branch = check_round_trip(lambda q: opw.forward(params, q), lambda T: opw.inverse(params, T), joints)
    assert set(branch) == set(range(8))


def test_the_inverse_keeps_branch_meaning():
    """Branch index = 4 * (theta5 < 0) + 2 * (reaching back) + elbow root, for every pose: the shoulder
    branches put the wrist centre in front of / behind axis 1, the wrist branches differ by the sign of
    theta5 with joints 4 and 6 turned 180 degrees."""
    robot = load_robot("kuka_kr6_r700_sixx")
    poses = forward(robot, random_joints(np.random.default_rng(9), 300))
    solutions = inverse(robot, poses)
    exists = ~np.isnan(solutions).any(axis=-1)
    theta = opw.model_angles(robot.opw, np.where(exists[..., None], solutions, 0.0))
    p = robot.opw
    elbow = theta[..., 2] + np.arctan2(p.a2, p.c3)
    wrist_x = p.a1 + p.c2 * np.sin(theta[..., 1]) + np.hypot(p.a2, p.c3) * np.sin(theta[..., 1] + elbow)
    index = np.arange(8)
    assert np.all((wrist_x >= 0)[:, index < 2][exists[:, index < 2]])
    assert np.all((wrist_x <= 0)[:, (index == 2) | (index == 3)][exists[:, (index == 2) | (index == 3)]])
    assert np.all((np.sin(theta[..., 4]) >= 0)[:, :4][exists[:, :4]])
    assert np.all((np.sin(theta[..., 4]) <= 0)[:, 4:][exists[:, 4:]])
    both = exists[:, :4] & exists[:, 4:]
    turned = wrapped_difference(solutions[:, 4:, [3, 5]], solutions[:, :4, [3, 5]])
    assert np.allclose(np.abs(turned[both]), 180.0, atol=1e-9)


@pytest.mark.parametrize("robot_id", ["kuka_kr6_r700_sixx", ABB_IRB2400["id"], "ur5e"])
def test_the_wrist_singularity_is_solved_deterministically(robot_id, file_robots):
    """Axis 5 at zero: joint 4 is at its model zero on branches 0-3 (180 on 4-7) and joint 6 takes the whole
    turn; just off the singularity the general solution still reproduces the pose to rounding."""
    robot = robot_named(robot_id, file_robots)
    on = np.array([[10.0, -70.0, 80.0, 35.0, 0.0, -20.0]])
    off = on + np.array([0, 0, 0, 0, 1e-7, 0])
    for joints in (on, off):
        poses = forward(robot, joints)
        solutions = inverse(robot, poses)
        exists = ~np.isnan(solutions).any(axis=-1)
        again = forward(robot, np.where(exists[..., None], solutions, 0.0))
        position, rotation = pose_errors(again, poses[:, None])
        assert position[exists].max() < POSITION_TOL_MM and rotation[exists].max() < ROTATION_TOL
    solutions = inverse(robot, forward(robot, on))[0]
    assert np.array_equal(solutions, inverse(robot, forward(robot, on))[0], equal_nan=True)
    singular = np.abs(np.sin(np.radians(solutions[:, 4]))) < 1e-9  # NaN rows are not
    assert singular.any() and np.array_equal(singular[:4], singular[4:])  # the drawn branch and its flip
    if robot.kinematics == "opw":
        joint4_zero = robot.opw.signs[3] * robot.opw.offsets_deg[3]
        assert np.allclose(solutions[:4][singular[:4], 3], joint4_zero)
        assert np.allclose(np.abs(wrapped_difference(solutions[4:][singular[4:], 3], joint4_zero)), 180.0)
    else:  # UR: joint 6 is set to zero, joints 2-4 take the rest
        assert np.allclose(solutions[singular, 5], 0.0)


def test_an_unreachable_pose_has_no_branch_and_a_near_one_only_the_front_ones():
    robot = load_robot("kuka_kr6_r700_sixx")
    far = np.eye(4)
    far[:3, 3] = (2000.0, 0.0, 400.0)
    assert np.isnan(inverse(robot, far)).all()
    # The wrist centre 700 mm in front of axis 1: reachable facing it, not reaching back over the top.
    near = forward(robot, [0.0, -20.0, 30.0, 0.0, 20.0, 0.0])
    solutions = inverse(robot, near)
    exists = ~np.isnan(solutions).any(axis=-1)
    assert exists[[0, 1, 4, 5]].all() and not exists[[2, 3, 6, 7]].any()


@pytest.mark.slow
def test_one_hundred_thousand_poses_solve_in_one_call():
    """No per-pose loop: 100k poses in one call give the same branches as the same poses solved apart."""
    robot = load_robot("kuka_kr16_2")
    rng = np.random.default_rng(4)
    joints = random_joints(rng, 100_000)
    poses = forward(robot, joints)
    solutions = inverse(robot, poses)
    assert solutions.shape == (100_000, 8, 6)
    # The same to rounding (numpy's vectorised sin and cos may round the last bit differently by length).
    picked = rng.choice(len(poses), 20, replace=False)
    pairs = ((inverse(robot, poses[picked]), solutions[picked]), (inverse(robot, poses[7]), solutions[7]))
    for alone, together in pairs:
        assert np.array_equal(np.isnan(alone), np.isnan(together))
        assert np.allclose(alone, together, rtol=0, atol=1e-9, equal_nan=True)
    ur5e = load_robot("ur5e")
    assert inverse(ur5e, forward(ur5e, joints)).shape == (100_000, 8, 6)


# --------------------------------------------------------------------------- known poses


KNOWN_POSES = [
    # KR 6 R700 sixx at zero: the arm stretched forward, 25 + 315 + 365 + 80 mm out, 400 + 35 mm up (the
    # data sheet's A1-A2 offset, link arm, arm, flange distance, A2 height, A3-A4 offset); flange facing +x.
    ("kuka_kr6_r700_sixx", (0, 0, 0, 0, 0, 0), (785.0, 0.0, 435.0), "ry90"),
    # ... and at the mastering pose A2 = -90, A3 = 90: link arm up, arm forward: 25 + 365 + 80 out, 400 + 315 + 35 up.
    ("kuka_kr6_r700_sixx", (0, -90, 90, 0, 0, 0), (470.0, 0.0, 750.0), "ry90"),
    # KR 16-2: 260 + 680 + 670 + 158 out, 675 - 35 up (its A3-A4 offset points down).
    ("kuka_kr16_2", (0, 0, 0, 0, 0, 0), (1768.0, 0.0, 640.0), "ry90"),
    # IRB 2400 at its calibration position: 100 + 755 + 85 out, 615 + 705 + 135 up.
    (ABB_IRB2400["id"], (0, 0, 0, 0, 0, 0), (940.0, 0.0, 1455.0), "ry90"),
    # ... and with axis 2 at 90 its parallel arm keeps the forearm level (J3 is the forearm's angle):
    # 100 + 705 + 755 + 85 out, 615 + 135 up (the forearm as at calibration, the wrist 135 above the elbow).
    (ABB_IRB2400["id"], (0, 90, 0, 0, 0, 0), (1645.0, 0.0, 750.0), "ry90"),
    # UR5e at zero: the arm along -x (a2 + a3), -(d4 + d6) in y, d1 - d5 in z, flange facing -y.
    ("ur5e", (0, 0, 0, 0, 0, 0), (-817.2, -232.9, 62.8), "ur_zero"),
    ("ur10e", (0, 0, 0, 0, 0, 0), (-1184.25, -290.7, 60.85), "ur_zero"),
]
ROTATIONS = {"ry90": np.array([[0, 0, 1], [0, 1, 0], [-1, 0, 0]], float),
             "ur_zero": np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]], float)}


@pytest.mark.parametrize("robot_id, joints, position, rotation", KNOWN_POSES)
def test_published_poses(robot_id, joints, position, rotation, file_robots):
    pose = forward(robot_named(robot_id, file_robots), np.array(joints, float))
    assert np.allclose(pose[:3, 3], position, atol=1e-9)
    assert np.allclose(pose[:3, :3], ROTATIONS[rotation], atol=1e-12)


def test_kuka_a1_turns_clockwise_and_a2_down():
    """KUKA's directions: positive A1 turns the arm clockwise seen from above, positive A2 lowers it."""
    robot = load_robot("kuka_kr6_r700_sixx")
    assert forward(robot, [10, 0, 0, 0, 0, 0])[1, 3] < 0
    assert forward(robot, [0, 10, 0, 0, 0, 0])[2, 3] < forward(robot, np.zeros(6))[2, 3]


def urdf_chain_forward(joints_deg):
    """KR 6 R700 sixx from ROS-Industrial kuka_experimental kr6r700sixx_macro.xacro: joint origins (m) and
    axes as written there, tool0 = flange turned 90 degrees about y.  Mm out."""
    chain = [((0, 0, 0.4), (0, 0, -1)), ((0.025, 0, 0), (0, 1, 0)), ((0.315, 0, 0), (0, 1, 0)),
             ((0, 0, 0.035), (-1, 0, 0)), ((0.365, 0, 0), (0, 1, 0)), ((0.080, 0, 0), (-1, 0, 0))]
    poses = []
    for row in np.atleast_2d(joints_deg):
        T = np.eye(4)
        for (origin, axis), angle in zip(chain, np.radians(row)):
            step = np.eye(4)
            step[:3, 3] = np.array(origin) * 1000.0
            step[:3, :3] = Rotation.from_rotvec(np.array(axis, float) * angle).as_matrix()
            T = T @ step
        tool0 = np.eye(4)
        tool0[:3, :3] = Rotation.from_euler("y", 90, degrees=True).as_matrix()
        poses.append(T @ tool0)
    return np.array(poses)


def test_kr6_matches_the_ros_industrial_urdf_chain():
    """An independent model of the same arm (the URDF's joint by joint chain, joint values = KUKA's)."""
    robot = load_robot("kuka_kr6_r700_sixx")
    joints = random_joints(np.random.default_rng(8), 200)
    position, rotation = pose_errors(forward(robot, joints), urdf_chain_forward(joints))
    assert position.max() < 1e-9 and rotation.max() < 1e-12


# --------------------------------------------------------------------------- independent solvers


def _py_opw_kinematics():
    """The Rust-backed solver's compiled core (KinematicModel, Robot with forward/batch_forward/reach), as the
    benchmark finds it (where `make test` puts it: $WORKCAL_TEST_PEERS, else build/test-peers/pyXY), or a skip."""
    module = py_opw_kinematics()
    if module is None:
        pytest.skip("py-opw-kinematics is not installed for this Python (make test-peers)")
    return module


OPW_ROBOTS = [robot_id for robot_id in builtin_robots() if load_robot(robot_id).kinematics == "opw"]


@pytest.mark.parametrize("robot_id", OPW_ROBOTS + [ABB_IRB2400["id"], FANUC_M10IA["id"]])
def test_opw_agrees_with_py_opw_kinematics(robot_id, file_robots):
    """Same poses from the same joints; the same set of solutions per pose (here in the same slot order,
    which both take from opw_kinematics).  Its flip_axes are our signs of -1, its offsets ours in degrees;
    it knows no J2/J3 coupling, so it is given and gives the model joints (opw.model_joints)."""
    peer = _py_opw_kinematics()
    robot = robot_named(robot_id, file_robots)
    p = robot.opw
    model = peer.KinematicModel(a1=p.a1, a2=p.a2, b=p.b, c1=p.c1, c2=p.c2, c3=p.c3, c4=p.c4,
                                offsets=tuple(p.offsets_deg), flip_axes=tuple(s < 0 for s in p.signs))
    solver = peer.Robot(model, True)
    joints = random_joints(np.random.default_rng(21), 500)
    model_joints = np.ascontiguousarray(opw.model_joints(p, joints))
    theirs = np.asarray(solver.batch_forward(model_joints, None)).reshape(-1, 4, 4)
    ours = opw.forward(robot, joints)
    position, rotation = pose_errors(ours, theirs)
    assert position.max() < 1e-9 and rotation.max() < 1e-12

    their_solutions = np.asarray(solver.reach(np.ascontiguousarray(ours.reshape(-1, 16)), None, None, 1)[0])
    our_solutions = opw.model_joints(p, opw.inverse(robot, ours))
    for mine, other in zip(our_solutions, their_solutions):
        mine = mine[~np.isnan(mine).any(axis=1)]
        other = other[~np.isnan(other).any(axis=1)]
        assert len(mine) == len(other)
        # Each of ours is one of theirs and each of theirs one of ours (joints compared modulo 360).
        close = np.abs(wrapped_difference(mine[:, None], other[None])).max(axis=-1) < 1e-6
        assert close.any(axis=1).all() and close.any(axis=0).all()


def test_kr16_forward_kinematics_agrees_with_freecad_robot6axis(tmp_path):
    """FreeCAD's Robot workbench ships the KR 16 as a DH table (Mod/Robot/Lib/Kuka/kr_16.csv: per axis a,
    alpha, d, theta, rotDir, max and min angle, velocity; mm and degrees).  Robot6Axis builds a KDL chain of
    Rz(joint) * DH(a, alpha, d, theta) segments and sets each joint to rotDir * the axis value, so rotDir -1
    on axis 1 makes its axis values KUKA's A1..A6 (A1 clockwise), and the theta of -90 on axis 3 and the 180
    degree twists of axis 6 place its zero and its end frame where KUKA's are.  Its Tcp is then our
    controller flange pose in mm with no further mapping: z out of the flange, x down at zero."""
    freecadcmd = shutil.which("freecadcmd")
    if freecadcmd is None:
        pytest.skip("freecadcmd is not installed")
    robot = load_robot("kuka_kr16_2")
    rng = np.random.default_rng(16)
    joints = rng.uniform(robot.limits[:, 0], robot.limits[:, 1], (40, 6))
    (tmp_path / "joints.json").write_text(json.dumps(joints.tolist()))
    script = tmp_path / "robot6axis.py"
    script.write_text(
        "import json, os, traceback\n"
        "out = open(os.environ['WORKCAL_OUT'], 'w')\n"
        "try:\n"
        "    import FreeCAD, Robot\n"
        "except ImportError as exc:\n"
        "    json.dump({'missing': str(exc)}, out)\n"
        "else:\n"
        "    table = FreeCAD.getResourceDir() + 'Mod/Robot/Lib/Kuka/kr_16.csv'\n"
        "    if not os.path.exists(table):\n"
        "        json.dump({'missing': 'this FreeCAD ships no KUKA KR 16 table (' + table + ')'}, out)\n"
        "        out.close()\n"
        "        raise SystemExit(0)\n"
        "    try:\n"
        "        document = FreeCAD.newDocument('kr16')\n"
        "        arm = document.addObject('Robot::RobotObject', 'Robot')\n"
        "        arm.RobotKinematicFile = table\n"
        "        tcp = []\n"
        "        for row in json.load(open(os.environ['WORKCAL_JOINTS'])):\n"
        "            for axis, value in enumerate(row, 1):\n"
        "                setattr(arm, 'Axis%d' % axis, value)\n"
        "            tcp.append(list(arm.Tcp.toMatrix().A))\n"
        "        json.dump({'tcp': tcp}, out)\n"
        "    except Exception:\n"
        "        json.dump({'error': traceback.format_exc()}, out)\n"
        "out.close()\n")
    env = dict(os.environ, WORKCAL_JOINTS=str(tmp_path / "joints.json"), WORKCAL_OUT=str(tmp_path / "out.json"),
               FREECAD_USER_HOME=str(tmp_path / "home"))
    done = subprocess.run([freecadcmd, str(script)], env=env, capture_output=True, text=True, timeout=300)
    if not (tmp_path / "out.json").exists():
        pytest.skip(f"freecadcmd did not run a Python script (exit {done.returncode}): {done.stderr[-500:]}")
    result = json.loads((tmp_path / "out.json").read_text())
    if "missing" in result:
        pytest.skip(f"FreeCAD's Robot workbench or its KR 16 table is not available: {result['missing']}")
    assert "error" not in result, result.get("error")
    theirs = np.array(result["tcp"]).reshape(-1, 4, 4)
    position, rotation = pose_errors(forward(robot, joints), theirs)
    assert position.max() < 1e-9 and rotation.max() < 1e-12


# --------------------------------------------------------------------------- limits and turns


def test_limits_and_margins():
    robot = load_robot("kuka_kr6_r700_sixx")  # A1 +-170, A2 -190..45, A3 -120..156, A4 +-185, A5 +-120, A6 +-350
    joints = np.array([[0, -90, 90, 0, 30, 0],
                       [169, -90, 90, 0, 30, 0],
                       [0, -90, 90, 0, 30, 351],
                       [np.nan] * 6])
    assert within_limits(robot, joints).tolist() == [True, True, False, False]
    margin = limit_margin_deg(robot, joints)
    assert margin[:3].tolist() == [66.0, 1.0, -1.0] and np.isnan(margin[3])


def test_turn_offsets_are_the_turns_a_joint_range_allows():
    kr6 = load_robot("kuka_kr6_r700_sixx")
    offsets = turn_offsets(kr6)
    assert offsets.shape == (6, 3)
    for axis in (0, 2, 4):  # A1 +-170, A3 -120..156, A5 +-120: within one turn, only the value itself
        assert offsets[axis, 0] == 0 and np.isnan(offsets[axis, 1:]).all()
    assert sorted(offsets[1, :2]) == [-360.0, 0.0] and np.isnan(offsets[1, 2])  # A2 -190..45: 170 is also -190
    for axis in (3, 5):  # A4 +-185, A6 +-350
        assert sorted(offsets[axis]) == [-360.0, 0.0, 360.0]
    ur5e = load_robot("ur5e")
    assert np.array_equal(np.sort(turn_offsets(ur5e), axis=1), np.tile([-360.0, 0.0, 360.0], (6, 1)))


def test_turn_candidates_and_wrapping_keep_branches_in_place():
    robot = load_robot("kuka_kr6_r700_sixx")
    solutions = inverse(robot, forward(robot, [10, -60, 80, 20, 40, -30.0]))  # (8, 6)
    candidates = turn_candidates(robot, solutions)
    assert candidates.shape == (8, 6, 3)
    exists = ~np.isnan(solutions).any(axis=-1)
    # Every candidate within limits and the same angle as its joint.
    finite = np.isfinite(candidates)
    low, high = robot.limits[:, :1], robot.limits[:, 1:]
    assert np.all((candidates[finite] >= np.broadcast_to(low, candidates.shape)[finite])
                  & (candidates[finite] <= np.broadcast_to(high, candidates.shape)[finite]))
    assert np.allclose(wrapped_difference(candidates, solutions[..., None])[finite], 0)
    assert np.all(finite[exists][:, :, 0] | ~within_limits(robot, solutions[exists])[:, None])
    wrapped = wrap_into_limits(robot, solutions)
    assert wrapped.shape == solutions.shape
    usable = ~np.isnan(wrapped).any(axis=-1)
    assert np.all(within_limits(robot, wrapped[usable]))
    assert np.allclose(wrapped[usable], solutions[usable])  # nearest to zero: already so
    # A6 at -300 is 60: nearest to 0 is 60, nearest to a previous -290 is -300.
    a6 = np.array([10, -60, 80, 20, 40, -300.0])
    assert wrap_into_limits(robot, a6)[5] == 60.0
    assert wrap_into_limits(robot, a6, reference_deg=[0, 0, 0, 0, 0, -290.0])[5] == -300.0
    # A joint no turn brings within limits makes the row unusable (NaN), in its place.
    assert np.isnan(wrap_into_limits(robot, [175, 0, 0, 0, 0, 0.0])).all()


def test_ur_joints_reach_both_turns():
    robot = load_robot("ur5e")
    joints = np.array([-200.0, 30, -300, 170, -350, 359])
    same = wrap_into_limits(robot, joints, reference_deg=joints)
    assert np.allclose(same, joints)
    assert np.allclose(wrap_into_limits(robot, joints), [160, 30, 60, 170, 10, -1])
