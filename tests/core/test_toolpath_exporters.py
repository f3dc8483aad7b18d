"""Every exporter's output parsed back with a small parser of its own and compared with numpy.

Expected poses are rebuilt here from the documented rule (tool Z = -tool axis, tool X = workpiece +X
projected perpendicular to it, +Y when the axis lies along X), not from the exporters' code.
"""
import csv
import re

import numpy as np
import pytest

from workcal_wb.core import frames
from workcal_wb.core.errors import InputError
from workcal_wb.core.result import CalibrationResult
from workcal_wb.core.robots import forward
from workcal_wb.core.toolpath import export, linearised, parse_gcode, read_gcode
from program_checkers import check_fanuc

W = frames.from_euler_zyz(25.0, 35.0, -70.0, (812.5, -143.2, 95.0))
TOL_MM, TOL_DEG = 1e-3, 1e-3
RAPID_FEED = 6000.0
SOURCE = """(test part)
G0 X10 Y0 Z20
G1 Z-1 F300 (plunge)
G3 X0 Y10 I-10 J0 F900
G1 X-5 Y10 A20 B-15
G1 X-5 Y-5 A0 B90
G0 Z20 A0 B0
"""
NUMBER = r"(-?\d+(?:\.\d*)?(?:E[+-]?\d+)?)"


def calibration(status="ok", matrix=W):
    gates = [{"name": "rms_mm", "value": 0.05 if status == "ok" else 0.8, "limit": 0.3, "passed": status == "ok",
              "unit": "mm"}]
    return CalibrationResult(status, matrix, quality_gates=gates,
                             uncertainty={"toolpath_bound_mm": 0.0412, "toolpath_median_mm": 0.0187})


@pytest.fixture(scope="module")
def path():
    return parse_gcode(SOURCE, "part.nc")


def expected(path, T=W):
    """(positions in B, rotations in B, feeds mm/min) along the linearised path."""
    moves = linearised(path, 0.01).moves
    positions = frames.apply(T, np.array([m.end for m in moves]))
    rotations = []
    for m in moves:
        z = -(T[:3, :3] @ m.tool_axis)
        ref = T[:3, :3] @ ([0, 1.0, 0] if abs(m.tool_axis[0]) >= 0.999 else [1.0, 0, 0])
        x = ref - ref.dot(z) * z
        x /= np.linalg.norm(x)
        rotations.append(np.column_stack([x, np.cross(z, x), z]))
    feeds = [RAPID_FEED if m.feed is None else m.feed for m in moves]
    return positions, rotations, feeds


def assert_poses(poses, path, T=W):
    """``poses``: list of (4x4 in B, feed mm/min)."""
    positions, rotations, feeds = expected(path, T)
    assert len(poses) == len(positions)
    for (pose, feed), p, R, f in zip(poses, positions, rotations, feeds):
        assert np.linalg.norm(pose[:3, 3] - p) < TOL_MM
        assert frames.rotation_between_deg(frames.rigid(R), pose) < TOL_DEG
        assert feed == pytest.approx(f, rel=1e-6, abs=1e-6)


def kuka(x, y, z, a, b, c):
    return frames.rigid(frames.rot_z(a) @ frames.rot_y(b) @ frames.rot_x(c), (x, y, z))


def parse_krl(text):
    aggregate = r"\{X %s, Y %s, Z %s, A %s, B %s, C %s\}" % ((NUMBER,) * 6)
    base = re.search(r"\$BASE = \$ROBROOT:" + aggregate, text)
    base = np.eye(4) if base is None else kuka(*map(float, base.groups()))
    poses, speed = [], None
    for line in text.splitlines():
        if m := re.match(r"\s*\$VEL\.CP = " + NUMBER, line):
            speed = float(m.group(1)) * 60000
        elif m := re.match(r"\s*(LIN|PTP) " + aggregate[:-2] + r"(?:, S \d+, T \d+)?\}", line):
            poses.append((base @ kuka(*map(float, m.groups()[1:])), speed if m.group(1) == "LIN" else RAPID_FEED))
    return poses


def parse_rapid(text):
    def pose(xyz, q):
        return frames.from_quaternion_wxyz([float(v) for v in q.split(",")], [float(v) for v in xyz.split(",")])

    xyz_q = r"\[([^\]]*)\],\[([^\]]*)\]"
    uframe = pose(*re.search(r"PERS wobjdata wobjWorkCal := \[FALSE,TRUE,\"\",\[" + xyz_q, text).groups())
    speeds = {name: float(v) * 60 for name, v in re.findall(r"CONST speeddata (\w+) := \[" + NUMBER, text)}
    return [(uframe @ pose(xyz, q), speeds[v])
            for xyz, q, v in re.findall(r"Move[JL] \[" + xyz_q + r",\[-?\d+,-?\d+,-?\d+,\d\],\[[^\]]*\]\], (\w+), "
                                        r"\w+, tWorkCal\d+\\WObj:=wobjWorkCal;", text)]


def parse_urscript(text, robot=None):
    """The poses in B; a first movej to joint values (radians) is turned into its flange pose by ``robot``'s
    forward kinematics (the tests give no tool then)."""
    def pose(values):
        x, y, z, rx, ry, rz = map(float, values.split(","))
        return frames.from_rotvec([rx, ry, rz], np.array([x, y, z]) * 1000)

    base = pose(re.search(r"workcal_base = p\[([^\]]*)\]", text).group(1))
    poses = []
    if joints := re.search(r"^  movej\(\[([^\]]*)\], a=", text, flags=re.M):
        poses.append((forward(robot, np.degrees([float(v) for v in joints.group(1).split(",")])), RAPID_FEED))
    for move, values, v in re.findall(r"(movej|movel)\(pose_trans\(workcal_base, p\[([^\]]*)\]\), a=[\d.]+, "
                                      r"v=" + NUMBER, text):
        poses.append((base @ pose(values), RAPID_FEED if move == "movej" else float(v) * 60000))
    return poses


def parse_fanuc(text):
    positions = {}
    pattern = r"P\[(\d+)\]\{.*?X = %s mm,\tY = %s mm,\tZ = %s mm,\s*W = %s deg,\tP = %s deg,\tR = %s deg"
    for i, x, y, z, w, p, r in re.findall(pattern % ((NUMBER,) * 6), text, flags=re.S):
        R = frames.rot_z(float(r)) @ frames.rot_y(float(p)) @ frames.rot_x(float(w))
        positions[int(i)] = frames.rigid(R, (float(x), float(y), float(z)))
    moves = re.findall(r"(J|L) P\[(\d+)\] (?:(\d+)cm/min|\d+%)", text)
    return [(positions[int(i)], RAPID_FEED if kind == "J" else float(speed) * 10) for kind, i, speed in moves]


def parse_csv(text):
    rows = list(csv.DictReader(line for line in text.splitlines() if not line.startswith("#")))
    poses = []
    for row in rows:
        p = [float(row[k]) for k in ("x_mm", "y_mm", "z_mm")]
        by_quaternion = frames.from_quaternion_wxyz([float(row[k]) for k in ("qw", "qx", "qy", "qz")], p)
        by_abc = kuka(*p, *(float(row[k]) for k in ("a_deg", "b_deg", "c_deg")))
        assert frames.rotation_between_deg(by_quaternion, by_abc) < TOL_DEG
        poses.append((by_quaternion, float(row["feed_mm_min"])))
    return poses


PARSERS = {"krl": parse_krl, "rapid": parse_rapid, "urscript": parse_urscript, "csv": parse_csv,
           "fanuc": parse_fanuc}
EXTENSIONS = {"krl": ".src", "rapid": ".mod", "urscript": ".script", "fanuc": ".ls", "csv": ".csv", "gcode": ".nc"}


@pytest.mark.parametrize("fmt", sorted(PARSERS))
def test_exported_poses_parse_back(fmt, path, tmp_path):
    out = tmp_path / f"prog{EXTENSIONS[fmt]}"
    export(path, calibration(), fmt, out)
    assert_poses(PARSERS[fmt](out.read_text()), path)


def test_fanuc_poses_parse_back_with_whole_cm_per_min_speeds(path, tmp_path):
    out = tmp_path / "prog.ls"
    export(path, calibration(), "fanuc", out)
    poses = parse_fanuc(out.read_text())
    positions, rotations, feeds = expected(path)
    assert len(poses) == len(positions)
    for (pose, speed), p, R, f in zip(poses, positions, rotations, feeds):
        assert np.linalg.norm(pose[:3, 3] - p) < TOL_MM
        assert frames.rotation_between_deg(frames.rigid(R), pose) < TOL_DEG
        assert speed == pytest.approx(f, abs=5.0)  # 1 cm/min resolution


def test_fanuc_configuration_is_the_integrators(path, tmp_path):
    out = tmp_path / "prog.ls"
    export(path, calibration(), "fanuc", out, fanuc_config="F D B, 1, 0, -1")
    text = out.read_text()
    assert text.count("CONFIG : 'F D B, 1, 0, -1'") == len(parse_fanuc(text)) and "N U T" not in text
    check_fanuc(text, "PROG")
    with pytest.raises(InputError, match="Fanuc configuration 'X U T, 0, 0, 0'"):
        export(path, calibration(), "fanuc", tmp_path / "bad.ls", fanuc_config="X U T, 0, 0, 0")
    assert not (tmp_path / "bad.ls").exists()


def test_krl_transformed_mode_writes_base_frame_points(path, tmp_path):
    out = tmp_path / "prog.src"
    export(path, calibration(), "krl", out, krl_mode="transformed")
    text = out.read_text()
    assert "$BASE = $ROBROOT\n" in text
    assert_poses(parse_krl(text), path)


def test_krl_base_mode_keeps_workpiece_coordinates(path, tmp_path):
    out = tmp_path / "prog.src"
    export(path, calibration(), "krl", out)
    text = out.read_text()
    first = re.search(r"PTP \{X %s, Y %s, Z %s" % ((NUMBER,) * 3), text).groups()
    np.testing.assert_allclose([float(v) for v in first], path.moves[0].end, atol=TOL_MM)
    assert re.search(r"^DEF prog\( \)$", text, flags=re.M) and text.rstrip().endswith("END")


def test_gcode_parses_back_with_tool_axis_angles(path, tmp_path):
    out = tmp_path / "prog.nc"
    export(path, calibration(), "gcode", out, machine="5axis-tcp")
    again = linearised(read_gcode(out), 0.01)
    positions, _, _ = expected(path)
    np.testing.assert_allclose(again.points(), positions, atol=TOL_MM)
    for moved, original in zip(again.moves, linearised(path, 0.01).moves):
        expected_axis = W[:3, :3] @ original.tool_axis
        angle = np.degrees(np.arccos(np.clip(moved.tool_axis @ expected_axis, -1, 1)))
        assert angle < TOL_DEG
        assert moved.feed == original.feed
    assert " A" in out.read_text().splitlines()[-5]


def test_gcode_keeps_arcs_when_w_keeps_their_plane(path, tmp_path):
    flat = parse_gcode(SOURCE.replace(" A20 B-15", "").replace(" A0 B90", "").replace(" A0 B0", ""), "flat.nc")
    turned = frames.rigid(frames.rot_z(-60.0), (300.0, 20.0, 5.0))
    out = tmp_path / "prog.nc"
    export(flat, calibration(matrix=turned), "gcode", out)
    text = out.read_text()
    assert re.search(r"^G3 ", text, flags=re.M) and " A" not in text.split("G21 G90 G17")[1]
    assert re.search(r"^G0 G43 X\S+ Y\S+ Z\S+ H1$", text, flags=re.M)  # with the first Z move
    again = read_gcode(out)
    np.testing.assert_allclose(linearised(again, 0.01).points(), expected(flat, turned)[0], atol=TOL_MM)


def test_rapid_wobj_is_w_and_targets_are_in_workpiece_frame(path, tmp_path):
    out = tmp_path / "prog.mod"
    export(path, calibration(), "rapid", out)
    text = out.read_text()
    uframe = re.search(r"wobjWorkCal := \[FALSE,TRUE,\"\",\[\[([^\]]*)\]", text).group(1)
    np.testing.assert_allclose([float(v) for v in uframe.split(",")], W[:3, 3], atol=TOL_MM)
    assert text.startswith("MODULE MOD_prog\n") and text.rstrip().endswith("ENDMODULE")
    assert "PROC prog()" in text and "PROC main()" not in text


@pytest.mark.parametrize("fmt, units, angles", [
    ("krl", "units: mm", "Z-Y'-X''"), ("rapid", "units: mm", "q1..q4 = w, x, y, z"),
    ("urscript", "METRES and RADIANS", "rotation vector"), ("fanuc", "units: mm", "fixed axes X then Y then Z"),
    ("csv", "units: mm", "quaternion qw qx qy qz"), ("gcode", "units: mm G21", "A about X, then B about Y"),
])
def test_headers_state_units_angles_w_and_quality(fmt, units, angles, path, tmp_path):
    out = tmp_path / f"prog{EXTENSIONS[fmt]}"
    export(path, calibration(), fmt, out, machine="5axis-tcp" if fmt == "gcode" else None)
    text = out.read_text()
    head = " ".join(re.sub(r"^\s*(?:\d+:\s*!|[;#!(]|\s)\s*|\s*[;)]?\s*$", "", line)
                    for line in text.splitlines())
    for needle in (units, angles, "tool orientation" if fmt != "gcode" else "tool tip",
                   f"{W[0, 3]:.6f}", f"{W[2, 0]:.6f}", "gate rms_mm = 0.05 mm, limit 0.3: passed",
                   "displacement uncertainty at the toolpath: bound 0.0412 mm, median 0.0187 mm"):
        assert needle in head, needle


@pytest.mark.parametrize("fmt", sorted(EXTENSIONS))
def test_output_is_deterministic(fmt, path, tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir(), b.mkdir()
    machine = "5axis-tcp" if fmt == "gcode" else None
    export(path, calibration(), fmt, a / f"prog{EXTENSIONS[fmt]}", machine=machine)
    export(path, calibration(), fmt, b / f"prog{EXTENSIONS[fmt]}", machine=machine)
    assert (a / f"prog{EXTENSIONS[fmt]}").read_bytes() == (b / f"prog{EXTENSIONS[fmt]}").read_bytes()


@pytest.mark.parametrize("name", ["my-prog.src", "3axis.ls"])
def test_program_names_that_must_match_the_file_are_checked(name, path, tmp_path):
    with pytest.raises(InputError, match="valid program name"):
        export(path, calibration(), "krl" if name.endswith(".src") else "fanuc", tmp_path / name)
    assert not (tmp_path / name).exists()


def test_comments_are_carried_into_robot_programs(path, tmp_path):
    out = tmp_path / "prog.src"
    export(path, calibration(), "krl", out)
    assert ";plunge" in out.read_text() and ";test part" not in out.read_text().split("DEF")[1]


def test_a_spindle_speed_of_any_size_is_written_as_a_number_the_reader_takes_back(tmp_path):
    """S1000000 was written S1e+06 (read back as an E word)."""
    path = parse_gcode("G0 X0 Y0 Z20\nS1000000 M3\nG1 Z-1 F300\nS2500.5\nG1 X5\n", "part.nc")
    out = tmp_path / "prog.nc"
    export(path, calibration(), "gcode", out, machine="5axis-tcp")
    again = read_gcode(out)
    assert [e.number for e in again.events if e.kind == "spindle"] == [1000000.0, 2500.5]


@pytest.mark.parametrize("name", ["wobjWorkCal.mod", "TWORKCAL1.mod", "vWorkCal1.mod", "fine.mod", "z50.mod",
                                  "workcal_tcp_1.script"])
def test_a_program_named_like_data_it_declares_is_refused(name, path, tmp_path):
    with pytest.raises(InputError, match="a name the program declares itself"):
        export(path, calibration(), "rapid" if name.endswith(".mod") else "urscript", tmp_path / name)
    assert not (tmp_path / name).exists()
