"""Robot programs checked against the robot that runs them (robots/reach.py, robots/placement.py,
toolpath/reach.py).

A program the robot follows is written with the configuration it was solved in, and that configuration,
read back from the program (KRL Status and Turn, RAPID confdata, Fanuc CONFIG, URScript movej joints),
selects the joint solution whose forward kinematics give the program's pose.  Each cause of a refusal
(out of reach, a joint limit, a configuration change or a wrist flip inside a linear move) is refused
with its move and source line; a forced export says FORCED and why; the suggested placement brings a
part out of reach back in.
"""
import itertools
import json
import re

import numpy as np
import pytest

from program_checkers import check_fanuc, check_krl, check_rapid, check_urscript, comment_text
from test_toolpath_exporters import expected
from workcal_wb.core import frames
from workcal_wb.core.benchmark.reach import trajectory
from workcal_wb.core.errors import InputError
from workcal_wb.core.result import CalibrationResult
from workcal_wb.core.robots import builtin_robots, forward, inverse, load_robot, turn_candidates
from workcal_wb.core.robots.configuration import abb_confdata, fanuc_config, kuka_status_turn
from workcal_wb.core.robots.model import LIBRARY, xyzabc_transform
from workcal_wb.core.robots.placement import MARGIN_DEG, suggest_placement
from workcal_wb.core.robots.reach import (CONFIGURATION_CHANGE, JOINT_LIMIT, JOINT_MOVE, MAX_JOINT_STEP_DEG,
                                          OUT_OF_REACH, WRIST_SINGULARITY, check_reach, singular_angles)
from workcal_wb.core.toolpath import ReachRefused, export, parse_gcode
from workcal_wb.core.toolpath.orientation import rotary_from_tool_axes

# The TCP in the flange frame: offset and tilted, so that every check must carry the tool.
TOOL = xyzabc_transform([10.0, -5.0, 180.0, 0.0, 20.0, 0.0])
# A pocket with an arc and a tilted stretch (A/B words: the tool axis), in the workpiece frame.
SOURCE = "(pocket)\nG0 X0 Y0 Z30\nG1 Z0 F600\nG1 X80\nG3 X80 Y60 I0 J30\nG1 X0 A10 B-5\nG1 Y0 A0 B0\nG0 Z30\n"
# Where each vendor's robot follows it (W = ^B X), and the format its controller runs.
VENDORS = [("kuka_kr16_2", "krl", frames.rigid(frames.rot_z(25.0), (900.0, -150.0, 250.0))),
           ("abb_irb4600_60_205", "rapid", frames.rigid(frames.rot_z(-30.0), (1300.0, 200.0, 400.0))),
           ("fanuc_m20ia", "fanuc", frames.rigid(frames.rot_z(40.0), (1100.0, -100.0, -300.0))),
           ("ur10e", "urscript", frames.rigid(frames.rot_z(10.0), (650.0, -250.0, 50.0)))]
EXT = {"krl": ".src", "rapid": ".mod", "urscript": ".script", "fanuc": ".ls", "csv": ".csv", "gcode": ".nc"}
NUMBER = r"(-?\d+(?:\.\d+)?)"
# Programs write positions to 1e-4 mm or less; the solved joints reproduce a pose to rounding.
WRITTEN_MM, SOLVED_MM, SOLVED_DEG = 2e-3, 1e-6, 2e-3


def calibration(W):
    return CalibrationResult("ok", W, quality_gates=[{"name": "rms", "value": 0.05, "limit": 0.3, "passed": True}])


def pose(R, p):
    return frames.rigid(R, p)


def first_pose_b(path, W):
    """The first robot target in B, from the documented tool orientation (test_toolpath_exporters.expected)."""
    positions, rotations, _ = expected(path, W)
    return pose(rotations[0], positions[0])


def solutions_within_limits(robot, tcp_pose, tool=TOOL) -> list:
    """Every joint solution of a TCP pose within the robot's limits: each configuration at each whole turn."""
    out = []
    for joints in inverse(robot, tcp_pose @ frames.invert(tool)):
        if np.isnan(joints).any():
            continue
        turns = turn_candidates(robot, joints)
        out += [np.array(c) for c in itertools.product(*[[v for v in row if not np.isnan(v)] for row in turns])]
    return out


def solved_back(robot, tcp_pose, configuration_of, written) -> np.ndarray:
    """The one solution within limits whose configuration (``configuration_of(joints)``) is ``written``."""
    matches = [q for q in solutions_within_limits(robot, tcp_pose) if configuration_of(q) == written]
    assert len(matches) == 1, f"{len(matches)} solutions carry the written configuration {written}"
    return matches[0]


def assert_reproduces(robot, joints, tcp_pose, tolerance_mm):
    got = forward(robot, joints) @ TOOL
    assert np.linalg.norm(got[:3, 3] - tcp_pose[:3, 3]) < tolerance_mm
    assert frames.rotation_between_deg(got, tcp_pose) < 1e-6 + tolerance_mm


def kuka(x, y, z, a, b, c):
    return xyzabc_transform([x, y, z, a, b, c])


def narrowed_kr16(folder, name, limits):
    """A KR 16-2 of the test's own, with some joint limits narrowed (``limits``: {axis index: [low, high]})."""
    data = json.loads((LIBRARY / "kuka_kr16_2.json").read_text())
    data["id"], data["name"] = name, f"KUKA KR 16-2 ({name})"
    for axis, pair in limits.items():
        data["joint_limits_deg"][axis] = pair
    path = folder / f"{name}.json"
    path.write_text(json.dumps(data))
    return load_robot(path)


# ---------------------------------------------------------------------------- the check itself


def _trajectory(robot):
    """Joints (3001, 6) of a smooth path about a posture 60 % out in front, wrist clear of its singularity."""
    return trajectory(robot, 3001)


@pytest.mark.parametrize("robot_id", builtin_robots())
def test_the_check_follows_a_path_drawn_from_joints_and_its_joints_give_the_path_back(robot_id):
    robot = load_robot(robot_id)
    poses = forward(robot, _trajectory(robot)) @ TOOL
    report = check_reach(robot, poses, TOOL, source_lines=np.arange(len(poses)) + 7)
    assert report.reachable and report.problem is None and report.reason == ""
    got = forward(robot, report.joints) @ TOOL
    assert np.abs(got[:, :3, 3] - poses[:, :3, 3]).max() < SOLVED_MM
    assert np.abs(got[:, :3, :3] - poses[:, :3, :3]).max() < 1e-9
    assert np.allclose(report.first_joints, report.joints[0])
    assert np.all(report.branches == report.first_branch)  # one configuration all along
    assert np.abs(np.diff(report.joints, axis=0)).max() < MAX_JOINT_STEP_DEG  # continuous: no turn unwound
    margin = np.minimum(report.joints - robot.limits[:, 0], robot.limits[:, 1] - report.joints)
    assert margin.min() == pytest.approx(report.margin.value) and report.margin.value > 0
    assert report.margin.joint == np.unravel_index(np.argmin(margin), margin.shape)[1]
    assert report.margin.where.line == report.margin.where.target + 7
    wrist, elbow = singular_angles(robot, report.joints)
    assert report.wrist.value == pytest.approx(wrist.min()) and report.elbow.value == pytest.approx(elbow.min())


def _over_the_top():
    """A KR 16-2 line from in front to behind over its top, the tool pointing down (both ends reachable)."""
    down = np.diag([1.0, -1.0, -1.0])
    return np.stack([pose(down, (1350.0, 0.0, 1050.0)), pose(down, (-750.0, 0.0, 1200.0))])


def test_a_joint_move_may_change_configuration_a_linear_move_may_not():
    robot = load_robot("kuka_kr16_2")
    poses = _over_the_top()
    for single in poses:
        assert check_reach(robot, single[None]).reachable
    linear = check_reach(robot, poses, source_lines=[4, 5])
    assert linear.problem == CONFIGURATION_CHANGE
    assert linear.problem_at.target == 1 and linear.problem_at.on_the_way and linear.problem_at.line == 5
    assert "cannot change configuration inside a linear move" in linear.reason and "(line 5)" in linear.reason
    statuses = re.findall(r"Status (\d) \('B[01]{3}'\)", linear.reason)
    assert len(statuses) == 2 and statuses[0] != statuses[1]
    assert check_reach(robot, poses, move_kinds=[JOINT_MOVE, JOINT_MOVE]).reachable


def test_a_path_leaving_the_reach_names_the_first_move_out_of_it():
    robot = load_robot("kuka_kr16_2")
    down = np.diag([1.0, -1.0, -1.0])
    x = np.arange(900.0, 2000.0, 50.0)
    poses = np.stack([pose(down, (v, 0.0, 300.0)) for v in x])
    report = check_reach(robot, poses, source_lines=np.arange(len(x)) + 20)
    solvable = ~np.isnan(inverse(robot, poses)).all(axis=(1, 2))
    first_out = int(np.argmin(solvable))
    assert solvable[:first_out].all() and not solvable[first_out:].any()
    assert report.problem == OUT_OF_REACH and report.unreachable_at.target == first_out
    assert report.problem_at.target == first_out and report.problem_at.line == first_out + 20
    assert f"(line {first_out + 20})" in report.reason and "out of the robot's reach" in report.reason
    assert report.margin is not None and np.isnan(report.joints[first_out:]).all()


def _wrist_flip_robot(folder):
    """A KR 16-2 held to its front, elbow-up configurations (A1 +-90, A3 0..154), so that a path through
    the wrist singularity cannot be followed in another configuration."""
    return narrowed_kr16(folder, "kr16_front_elbow_up", {0: [-90, 90], 2: [0, 154]})


def _through_the_wrist_singularity(robot):
    """Two flange poses with A5 at +20 and -20 deg: the straight move between them turns the tool about
    axis 5 through A5 = 0."""
    start = np.array([0.0, -90.0, 90.0, 0.0, 20.0, 0.0])
    return forward(robot, np.stack([start, start * [1, 1, 1, 1, -1, 1]]))


def test_a_linear_move_through_the_wrist_singularity_is_a_wrist_flip(tmp_path):
    robot = _wrist_flip_robot(tmp_path)
    poses = _through_the_wrist_singularity(robot)
    report = check_reach(robot, poses, source_lines=[3, 4])
    assert report.problem == WRIST_SINGULARITY and report.problem_at.target == 1 and report.problem_at.on_the_way
    assert re.search(r"A4 and A6 would turn 1[78]\d deg", report.reason) and "(line 4)" in report.reason
    assert report.wrist.value < 2.0 and "wrist_singularity" in report.near
    # a joint move there may flip the wrist
    assert check_reach(robot, poses, move_kinds=[JOINT_MOVE, JOINT_MOVE]).reachable


def test_the_suggested_placement_brings_a_part_out_of_reach_back_in():
    robot = load_robot("kuka_kr16_2")
    down = np.diag([1.0, -1.0, -1.0])
    grid = [(x, y) for y in (-50.0, 0.0, 50.0) for x in np.linspace(-100.0, 100.0, 11)]
    poses = np.stack([pose(down, (3700.0 + x, y, 200.0)) for x, y in grid])
    assert check_reach(robot, poses, TOOL).problem == OUT_OF_REACH
    move = suggest_placement(robot, poses, TOOL)
    report = check_reach(robot, move.transform @ poses, TOOL)
    assert report.reachable and report.margin.value >= MARGIN_DEG
    dx, dy = move.translation_mm
    assert dx < -1500 and re.fullmatch(r"move the part \d+ mm along -X( and \d+ mm along [+-]Y)? of the robot base "
                                       r"\(towards the robot\)( and turn it .*)?", move.describe())
    assert np.allclose(move.transform[2], [0, 0, 1, 0]) and np.allclose(move.transform[:3, 2], [0, 0, 1])


# ---------------------------------------------------------------------------- programs


PATH = parse_gcode(SOURCE, "pocket.nc")


def _first_krl(robot, text):
    aggregate = r"\{X %s, Y %s, Z %s, A %s, B %s, C %s" % ((NUMBER,) * 6)
    base = kuka(*map(float, re.search(r"\$BASE = \$ROBROOT:" + aggregate + r"\}", text).groups()))
    m = re.search(r"^PTP " + aggregate + r", S (\d+), T (\d+)\}$", text, flags=re.M)
    target = base @ kuka(*map(float, m.groups()[:6]))
    written = (int(m.group(7)), int(m.group(8)))
    return target, solved_back(robot, target, lambda q: tuple(int(v) for v in kuka_status_turn(robot, q)), written)


def _rapid_targets(text):
    xyz_q = r"\[([^\]]*)\],\[([^\]]*)\]"
    uframe = re.search(r"PERS wobjdata wobjWorkCal := \[FALSE,TRUE,\"\",\[" + xyz_q, text).groups()

    def to_pose(xyz, q):
        return frames.from_quaternion_wxyz([float(v) for v in q.split(",")], [float(v) for v in xyz.split(",")])

    found = re.findall(r"Move[JL] \[" + xyz_q + r",\[(-?\d+),(-?\d+),(-?\d+),(\d)\],", text)
    return [(to_pose(*uframe) @ to_pose(xyz, q), tuple(int(v) for v in cf)) for xyz, q, *cf in found]


def _fanuc_positions(text):
    pattern = (r"P\[\d+\]\{.*?CONFIG : '([^']*)',\s*X = %s mm,\tY = %s mm,\tZ = %s mm,\s*W = %s deg,\tP = %s deg,"
               r"\tR = %s deg" % ((NUMBER,) * 6))
    out = []
    for config, x, y, z, w, p, r in re.findall(pattern, text, flags=re.S):
        R = frames.rot_z(float(r)) @ frames.rot_y(float(p)) @ frames.rot_x(float(w))
        out.append((pose(R, (float(x), float(y), float(z))), config))
    return out


@pytest.mark.parametrize("robot_id, fmt, W", VENDORS, ids=[v[0] for v in VENDORS])
def test_a_reachable_program_carries_the_configuration_it_was_solved_in(robot_id, fmt, W, tmp_path):
    robot = load_robot(robot_id)
    out = tmp_path / f"prog{EXT[fmt]}"
    job = export(PATH, calibration(W), fmt, out, robot=robot, tool=TOOL)
    text = out.read_text()
    {"krl": lambda: check_krl(text, "prog"), "rapid": lambda: check_rapid(text),
     "fanuc": lambda: check_fanuc(text, "PROG"), "urscript": lambda: check_urscript(text)}[fmt]()
    report = job.reach
    assert report.reachable and not job.forced and "FORCED" not in text
    intended = first_pose_b(PATH, W)
    words = comment_text(text)
    assert f"reach: checked for {robot.name} ({robot.id}) with the TCP X 10.000 Y -5.000 Z 180.000 mm, A 0.000 B " \
           "20.000 C 0.000 deg" in words and "reachable in one configuration" in words
    assert f"smallest joint-limit margin {report.margin.value:.1f} deg" in words
    if fmt == "urscript":
        written = re.search(r"^  movej\(\[([^\]]*)\]", text, flags=re.M).group(1)
        joints = np.degrees([float(v) for v in written.split(",")])
        assert_reproduces(robot, joints, intended, SOLVED_MM)  # the joints written give the first pose
        assert np.allclose(joints, report.first_joints, atol=1e-8)
        return
    if fmt == "krl":
        targets = [_first_krl(robot, text)]
    elif fmt == "rapid":
        assert "    ConfJ\\On;\n    ConfL\\On;\n" in text and "\\Off" not in text
        targets = [(t, solved_back(robot, t, lambda q: tuple(int(v) for v in abb_confdata(robot, q)), cf))
                   for t, cf in _rapid_targets(text)]
    else:
        targets = [(t, solved_back(robot, t, lambda q: str(fanuc_config(robot, q)), cf))
                   for t, cf in _fanuc_positions(text)]
    assert len(targets) == (1 if fmt == "krl" else len(report.joints))
    for i, (target, joints) in enumerate(targets):
        assert_reproduces(robot, joints, target, SOLVED_MM)  # the written configuration solves back to the target
        assert np.allclose(joints, report.joints[i], atol=SOLVED_DEG)  # and is the configuration the check chose
    assert np.linalg.norm(targets[0][0][:3, 3] - intended[:3, 3]) < WRITTEN_MM


@pytest.mark.parametrize("fmt", ["krl", "rapid", "urscript", "fanuc", "csv"])
def test_without_a_robot_every_robot_program_says_its_reach_is_not_checked(fmt, tmp_path):
    out = tmp_path / f"prog{EXT[fmt]}"
    job = export(PATH, calibration(VENDORS[0][2]), fmt, out)
    text = out.read_text()
    assert job.reach is None and "reach not checked (no robot given" in comment_text(text)  # ")" ends a comment there
    legacy = {"krl": r"^PTP \{X [^,]+, Y [^,]+, Z [^,]+, A [^,]+, B [^,]+, C [^,]+\}$",
              "rapid": r"ConfL\\Off;[\s\S]*MoveJ \[\[[^\]]*\],\[[^\]]*\],\[0,0,0,0\]",
              "urscript": r"^  movej\(pose_trans\(workcal_base, p\[", "fanuc": r"CONFIG : 'N U T, 0, 0, 0'",
              "csv": r"^1,rapid,"}[fmt]
    assert re.search(legacy, text, flags=re.M)


def test_gcode_says_nothing_of_a_robot_and_takes_none(tmp_path):
    out = tmp_path / "prog.nc"
    export(PATH, calibration(VENDORS[0][2]), "gcode", out, machine="5axis-tcp")
    assert "reach" not in comment_text(out.read_text())
    with pytest.raises(InputError, match="the reach of a robot is checked for robot programs"):
        export(PATH, calibration(VENDORS[0][2]), "gcode", tmp_path / "robot.nc", machine="5axis-tcp",
               robot=load_robot("kuka_kr16_2"))
    assert not (tmp_path / "robot.nc").exists()


@pytest.mark.parametrize("robot_id, fmt", [("ur10e", "krl"), ("kuka_kr16_2", "rapid"), ("abb_irb4600_60_205", "fanuc"),
                                           ("fanuc_m20ia", "urscript")])
def test_a_robot_of_another_maker_is_refused(robot_id, fmt, tmp_path):
    out = tmp_path / f"prog{EXT[fmt]}"
    with pytest.raises(InputError, match=rf"robot {robot_id} \(.*\) is a .* robot: it does not run"):
        export(PATH, calibration(VENDORS[0][2]), fmt, out, robot=load_robot(robot_id))
    assert not out.exists()


def test_a_part_out_of_reach_is_refused_forced_and_placed_back(tmp_path):
    robot, fmt, W = VENDORS[0]
    robot = load_robot(robot)
    far = frames.rigid(None, (3000.0, 0.0, 0.0)) @ W
    out = tmp_path / "prog.src"
    with pytest.raises(ReachRefused) as refused:
        export(PATH, calibration(far), fmt, out, robot=robot, tool=TOOL)
    assert not out.exists()
    exc = refused.value
    assert exc.report.problem == OUT_OF_REACH and exc.report.problem_at.target == 0
    message = str(exc)
    assert message.startswith("pocket.nc: KUKA KR 16-2 (kuka_kr16_2) with the TCP X 10.000")
    assert "robot target 1 (line 2) is out of the robot's reach" in message and "nothing was written" in message
    assert exc.suggestion.describe() in message

    job = export(PATH, calibration(far), fmt, out, robot=robot, tool=TOOL, force=True)
    text = out.read_text()
    check_krl(text, "prog")
    assert job.forced and text.split("\n")[4].startswith(";FORCED EXPORT: the reach check failed: KUKA KR 16-2")
    words = comment_text(text)
    assert "robot target 1 (line 2) is out of the robot's reach" in words and exc.suggestion.describe() in words
    assert re.search(r"^PTP \{[^}]*C [^,]+\}$", text, flags=re.M)  # no configuration claimed for a path not solved

    placed = exc.suggestion.transform @ far
    again = export(PATH, calibration(placed), fmt, out, robot=robot, tool=TOOL)
    assert again.reach.reachable and again.reach.margin.value >= MARGIN_DEG and not again.forced


def test_the_first_move_that_leaves_the_reach_is_named_with_its_line(tmp_path):
    robot, fmt, W = VENDORS[0]
    path = parse_gcode("G0 X0 Y0 Z30\nG1 Z0 F600\nG1 X80\nG1 X2500\nG1 X0\n", "long.nc")
    with pytest.raises(ReachRefused) as refused:
        export(path, calibration(W), fmt, tmp_path / "prog.src", robot=load_robot(robot), tool=TOOL)
    report = refused.value.report
    assert report.problem == OUT_OF_REACH and report.problem_at.line == 4 and report.problem_at.on_the_way
    assert "the linear move to robot target 4 (line 4) is out of the robot's reach" in str(refused.value)
    assert report.unreachable_at.target == 3 and report.margin is not None  # reached up to there


def _gcode_through(W, flange):
    """G-code whose two moves put the TCP (= flange, no tool) at ``flange`` (2, 4, 4) poses in B."""
    Wi = frames.invert(W)
    position = frames.apply(Wi, flange[:, :3, 3])
    angles = rotary_from_tool_axes("ab", -(flange[:, :3, 2] @ Wi[:3, :3].T))
    words = [f"X{x:.6f} Y{y:.6f} Z{z:.6f} A{a:.6f} B{b:.6f}" for (x, y, z), (a, b) in zip(position, angles)]
    return parse_gcode(f"(wrist)\nG0 {words[0]}\nG1 {words[1]} F600\n", "wrist.nc")


def test_a_linear_move_through_the_wrist_singularity_is_refused_naming_the_wrist(tmp_path):
    robot = _wrist_flip_robot(tmp_path)
    W = frames.rigid(frames.rot_z(90.0), (600.0, 0.0, 100.0))  # workpiece X along B's y: the tool's x stays put
    path = _gcode_through(W, _through_the_wrist_singularity(robot))
    out = tmp_path / "wrist.src"
    with pytest.raises(ReachRefused) as refused:
        export(path, calibration(W), "krl", out, robot=robot)
    assert refused.value.report.problem == WRIST_SINGULARITY and not out.exists()
    assert re.search(r"on the linear move to robot target 2 \(line 3\), the wrist passes its singularity \(axes 4 "
                     r"and 6 in line\): A4 and A6 would turn 1[78]\d deg .* \(a wrist flip\)", str(refused.value))


def test_a_configuration_change_inside_a_linear_move_is_refused(tmp_path):
    path = parse_gcode("G0 X1350 Y0 Z1050\nG1 X-750 Z1200 F1000\n", "over.nc")
    with pytest.raises(ReachRefused) as refused:
        export(path, calibration(np.eye(4)), "krl", tmp_path / "over.src", robot=load_robot("kuka_kr16_2"))
    assert refused.value.report.problem == CONFIGURATION_CHANGE
    assert "on the linear move to robot target 2 (line 2)" in str(refused.value)
    assert "a robot cannot change configuration inside a linear move" in str(refused.value)


def test_a_path_past_a_joint_limit_is_refused_naming_the_joint(tmp_path):
    """One and a half turns about the robot: A1 (+-185 deg) cannot follow, A6 (+-350) can."""
    path = parse_gcode("G0 X900 Y0 Z50\nG1 Z0 F1000\nG3 X900 Y0 I-900 J0\nG3 X-900 Y0 I-900 J0\nG0 Z50\n", "turns.nc")
    with pytest.raises(ReachRefused) as refused:
        export(path, calibration(frames.rigid(None, (0.0, 0.0, 200.0))), "krl", tmp_path / "turns.src",
               robot=load_robot("kuka_kr16_2"))
    report = refused.value.report
    assert report.problem == JOINT_LIMIT and report.problem_joint == 0 and report.problem_at.line == 3
    assert re.search(r"A1 would pass its limit -?185 deg", str(refused.value))
    assert refused.value.suggestion is None
    assert "No placement of the part on the platform was found" in str(refused.value)
