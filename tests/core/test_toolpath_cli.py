"""``python3 -m workcal_wb toolpath``: exit codes, messages, options (run in-process)."""
import csv
import json
import math
import re

import numpy as np
import pytest

from program_checkers import comment_text
from workcal_wb.cli import main
from workcal_wb.core import frames
from workcal_wb.core.result import CalibrationResult

W = frames.from_euler_zyz(15.0, 5.0, -40.0, (700.0, 200.0, 300.0))
GCODE = "(demo)\nG21 G90\nG0 X0 Y0 Z10\nG1 Z0 F500\nG2 X20 Y0 I10 J0\nG0 Z10\n"


@pytest.fixture
def files(tmp_path):
    (tmp_path / "part.nc").write_text(GCODE)
    for status in ("ok", "failed"):
        gates = [{"name": "rms_mm", "value": 0.1 if status == "ok" else 0.9, "limit": 0.3,
                  "passed": status == "ok", "unit": "mm"}]
        CalibrationResult(status, W, quality_gates=gates).to_json(tmp_path / f"{status}.json")
    return tmp_path


def run(files, *args):
    return main(["toolpath", "--in", str(files / "part.nc"), *args])


def csv_points(path):
    rows = csv.DictReader(line for line in path.read_text().splitlines() if not line.startswith("#"))
    return np.array([[float(r["x_mm"]), float(r["y_mm"]), float(r["z_mm"])] for r in rows])


def test_ok_export_exit_0(files, capsys):
    out = files / "prog.src"
    assert run(files, "--calibration", str(files / "ok.json"), "--format", "krl", "--out", str(out)) == 0
    assert out.exists() and "LIN {" in out.read_text()
    assert capsys.readouterr().out.startswith(f"wrote {out}: KUKA KRL for robot, 4 moves")


def test_format_from_extension(files):
    for ext in (".mod", ".script", ".ls", ".csv", ".nc"):
        assert run(files, "--calibration", str(files / "ok.json"), "--out", str(files / f"prog{ext}"),
                   *(["--machine", "5axis-tcp"] if ext == ".nc" else [])) == 0


def test_failed_calibration_exit_1_says_which_gate_and_how_to_force(files, capsys):
    out = files / "prog.script"
    assert run(files, "--calibration", str(files / "failed.json"), "--out", str(out)) == 1
    err = capsys.readouterr().err
    assert err.startswith("workcal toolpath: refused: ") and err.count("\n") == 1
    assert "gate rms_mm = 0.9 mm, limit 0.3" in err and "--force" in err
    assert not out.exists()


def test_forced_export_exit_0_with_warning_and_banner(files, capsys):
    out = files / "prog.script"
    assert run(files, "--calibration", str(files / "failed.json"), "--out", str(out), "--force") == 0
    assert "FORCED" in capsys.readouterr().err
    assert out.read_text().startswith("def prog():\n  # FORCED EXPORT")


def test_envelope_violation_exit_1(files, capsys):
    out = files / "prog.csv"
    assert run(files, "--calibration", str(files / "ok.json"), "--out", str(out),
               "--envelope", "0,0,0,100,100,100") == 1
    assert "outside the work envelope" in capsys.readouterr().err and not out.exists()


@pytest.mark.parametrize("args, message", [
    (["--in", "missing.nc"], "missing.nc: file does not exist"),
    (["--envelope", "1,2,3"], "work envelope"),
    (["--table-angle", "30"], "--table-angle needs --table-frame"),
    (["--out", "prog.xyz"], "cannot tell the output format"),
    (["--calibration", "nope.json"], "nope.json: file does not exist"),
    (["--in", "part.FCStd"], "FreeCAD documents"),
    (["--fanuc-config", "N U T"], "Fanuc configuration 'N U T'"),
])
def test_bad_input_exit_2(files, capsys, monkeypatch, args, message):
    monkeypatch.chdir(files)
    (files / "part.FCStd").write_bytes(b"PK\3\4")
    options = {"--in": "part.nc", "--calibration": "ok.json", "--out": "prog.csv", **dict(zip(args[::2], args[1::2]))}
    assert main(["toolpath"] + [word for option in options.items() for word in option]) == 2
    err = capsys.readouterr().err
    assert err.startswith("workcal toolpath: error: ") and message in err


def test_bad_gcode_line_exit_2(files, capsys):
    (files / "part.nc").write_text("G0 X0 Y0 Z0\nG2 X10 Y0 I3 J0 F100\n")
    assert run(files, "--calibration", str(files / "ok.json"), "--out", str(files / "p.csv")) == 2
    assert "part.nc: line 2: arc radius mismatch" in capsys.readouterr().err


def test_a_chordal_tolerance_finer_than_the_programs_digits_is_refused_at_once(files, capsys):
    """--chord-tol 1e-9 on an arc cut it into millions of segments (33 s, 1.2 GB, a 124 MB program);
    positions are written to 0.0001 mm, so a finer tolerance is refused naming the option, and no file
    is written."""
    out = files / "p.csv"
    assert run(files, "--calibration", str(files / "ok.json"), "--out", str(out), "--chord-tol", "1e-9") == 2
    assert "chordal tolerance (--chord-tol) must be at least 0.0001 mm" in capsys.readouterr().err
    assert not out.exists()
    assert run(files, "--calibration", str(files / "ok.json"), "--out", str(out), "--chord-tol", "0.0001") == 0


def test_units_in_inches(files):
    (files / "part.nc").write_text("G0 X1 Y0 Z0\nG1 X2 F10\n")
    out = files / "p.csv"
    assert run(files, "--calibration", str(files / "ok.json"), "--out", str(out), "--units-in", "in") == 0
    np.testing.assert_allclose(csv_points(out), frames.apply(W, np.array([[25.4, 0, 0], [50.8, 0, 0]])), atol=1e-3)


def test_rotary_table_frame_and_angle(files):
    BQ = frames.from_euler_zyz(0, 1, 0, (900.0, 100.0, 0.0))
    (files / "table.json").write_text(json.dumps({"matrix": BQ.tolist()}))
    out0, out90 = files / "p0.csv", files / "p90.csv"
    common = ["--calibration", str(files / "ok.json"), "--table-frame", str(files / "table.json")]
    assert run(files, *common, "--out", str(out0)) == 0
    assert run(files, *common, "--table-angle", "90", "--out", str(out90)) == 0
    chain = BQ @ frames.rigid(frames.rot_z(90.0)) @ frames.invert(BQ) @ W
    np.testing.assert_allclose(csv_points(out90), frames.apply(chain, frames.apply(frames.invert(W), csv_points(out0))),
                               atol=2e-3)
    assert "rotary table at 90.0000 deg" in out90.read_text()


def test_fanuc_configuration_option(files):
    out = files / "prog.ls"
    assert run(files, "--calibration", str(files / "ok.json"), "--out", str(out), "--fanuc-config", "F U T, -1, 0, 1") == 0
    text = out.read_text()
    assert text.count("CONFIG : 'F U T, -1, 0, 1'") == len(re.findall(r"^P\[\d+\]\{", text, flags=re.M)) > 4


def test_krl_mode_and_chord_tolerance(files):
    coarse, fine = files / "coarse.src", files / "fine.src"
    common = ["--calibration", str(files / "ok.json"), "--krl-mode", "transformed"]
    assert run(files, *common, "--out", str(coarse), "--chord-tol", "0.5") == 0
    assert run(files, *common, "--out", str(fine), "--chord-tol", "0.001") == 0
    assert "$BASE = $ROBROOT\n" in fine.read_text()
    assert fine.read_text().count("LIN {") > 3 * coarse.read_text().count("LIN {")


def test_too_few_lines_per_part_is_refused_naming_the_option(files, capsys):
    assert run(files, "--calibration", str(files / "ok.json"), "--out", str(files / "p.src"), "--max-lines", "1") == 2
    assert "argument --max-lines: must be at least 10" in capsys.readouterr().err
    assert not (files / "p.src").exists()


def test_a_toolpath_for_the_mirrored_part_is_refused_and_the_right_model_named_in_the_program(files, capsys):
    from workcal_wb.core.geometry import Cloud
    from workcal_wb.core.simulate.shapes import car_body
    from workcal_wb.core.simulate.toolpath_sample import sample_toolpath_points
    from workcal_wb.core.toolpath.exporters.gcode import format_gcode
    from workcal_wb.core.toolpath.model import Move, Toolpath
    from workcal_wb.core.writers import write_stl

    body = car_body(edge_mm=4.0)
    right = Cloud(body.points + [0.0, -300.0, 0.0], None, body.triangles, "right")
    write_stl(files / "right.stl", right)
    write_stl(files / "left.stl", Cloud(right.points * [1.0, -1.0, 1.0], None, right.triangles[:, ::-1], "left"))
    points, feed = sample_toolpath_points(right, rows=8, points_per_row=32)
    path = Toolpath.from_moves([Move("rapid", points[0] + [0, 0, 20])] + [Move("linear", p, feed=feed) for p in points])
    (files / "door.nc").write_text(format_gcode(path))
    out = files / "door.src"
    args = ["toolpath", "--in", str(files / "door.nc"), "--calibration", str(files / "ok.json"), "--out", str(out)]
    assert main([*args, "--workpiece", str(files / "left.stl")]) == 1
    err = capsys.readouterr().err
    median = float(re.search(r"run a median ([\d.]+) mm from the workpiece model left.stl", err).group(1))
    assert median > 400 and re.search(r"allow it with --path-reach \d+$", err.strip()) and not out.exists()
    assert main([*args, "--workpiece", str(files / "right.stl")]) == 0
    assert re.search(r"on the workpiece model right.stl: cutting moves a median \d\.\d\d mm", out.read_text().replace("\n;", " "))
    assert main(args) == 0 and "not checked (no model given)" in out.read_text()
    assert main([*args, "--workpiece", str(files / "left.stl"), "--path-reach", str(math.ceil(median * 1.2))]) == 0


# ---------------------------------------------------------------------------- --robot and --tool


def test_an_unknown_robot_exits_2_listing_the_built_in_ones(files, capsys):
    assert run(files, "--calibration", str(files / "ok.json"), "--out", str(files / "p.src"), "--robot", "kr17") == 2
    err = capsys.readouterr().err
    assert err.startswith("workcal toolpath: error: argument --robot: kr17: no built-in robot of that id and no such file")
    assert "built-in robots: abb_irb2400_16, " in err and "kuka_kr16_2" in err and err.count("\n") == 1
    assert not (files / "p.src").exists()


@pytest.mark.parametrize("tool", ["0,0,150", "0,0,150,0,0,x", "0,0,nan,0,0,0"])
def test_a_bad_tool_exits_2_naming_the_option(files, capsys, tool):
    assert run(files, "--calibration", str(files / "ok.json"), "--out", str(files / "p.src"),
               "--robot", "kuka_kr16_2", "--tool", tool) == 2
    err = capsys.readouterr().err
    assert f"argument --tool: expected six numbers X,Y,Z,A,B,C (mm and degrees, the TCP in the flange frame), got " \
           f"'{tool}'" in err


def test_a_robot_file_of_ones_own_checks_the_program_and_writes_its_configuration(files, capsys):
    from workcal_wb.core.robots.model import LIBRARY

    data = json.loads((LIBRARY / "kuka_kr16_2.json").read_text())
    data.update(id="cell_7_kr16", name="Cell 7 KR 16")
    (files / "cell7.json").write_text(json.dumps(data))
    out = files / "prog.src"
    assert run(files, "--calibration", str(files / "ok.json"), "--out", str(out), "--robot", str(files / "cell7.json"),
               "--tool", "-20,0,150,0,0,0") == 0  # a value starting like a negative number is a value
    text = out.read_text()
    assert "reach: checked for Cell 7 KR 16 (cell_7_kr16) with the TCP X -20.000 Y 0.000 Z 150.000 mm" in \
        comment_text(text)
    assert re.search(r"^PTP \{X [^}]*, S [0-7], T \d+\}$", text, flags=re.M)


def test_a_robot_that_does_not_run_the_format_exits_2(files, capsys):
    assert run(files, "--calibration", str(files / "ok.json"), "--out", str(files / "p.src"), "--robot", "ur5e") == 2
    assert "robot ur5e (Universal Robots UR5e) is a Universal Robots robot: it does not run KUKA KRL programs" in \
        capsys.readouterr().err


def test_a_program_the_robot_cannot_follow_exits_1_with_the_move_the_placement_and_force(files, capsys):
    far = W.copy()
    far[:3, 3] += [3000.0, 0.0, 0.0]
    CalibrationResult("ok", far).to_json(files / "far.json")
    out = files / "prog.src"
    args = ["--calibration", str(files / "far.json"), "--out", str(out), "--robot", "kuka_kr16_2"]
    assert run(files, *args) == 1
    err = capsys.readouterr().err
    assert err.startswith("workcal toolpath: refused: ") and err.count("\n") == 1 and not out.exists()
    assert "robot target 1 (line 3) is out of the robot's reach" in err
    assert re.search(r"move the part \d+ mm along -X .*of the robot base \(towards the robot\)", err)
    assert err.rstrip().endswith("force it (--force): the program then says FORCED and why")
    assert run(files, *args, "--force") == 0
    assert "workcal toolpath: warning: FORCED EXPORT: the reach check failed: KUKA KR 16-2" in capsys.readouterr().err
    assert ";FORCED EXPORT: the reach check failed" in out.read_text()


def test_the_robots_command_lists_the_built_in_robots(capsys):
    from workcal_wb.core.robots import builtin_robots

    assert main(["robots"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == builtin_robots()
    assert any(re.match(r"kuka_kr16_2 +KUKA KR 16-2 +KUKA +limits \(deg\) \[-185, 185\], \[-155, 35\]", line)
               for line in lines)


def test_calibrate_takes_the_robot_and_its_tool_too(files):
    from workcal_wb.cli import build_parser
    from workcal_wb.cli.toolpath import robot_options

    given = [str(files / "part.nc")] * 3
    args = build_parser("calibrate").parse_args(["calibrate", "--scan", given[0], "--workpiece", given[1],
                                                 "--reference", given[2], "--robot", "ur5e", "--tool", "0,0,100,0,90,0"])
    options = robot_options(args)
    assert options["robot"].id == "ur5e"
    np.testing.assert_allclose(options["tool"], frames.rigid(frames.rot_y(90.0), (0.0, 0.0, 100.0)), atol=1e-12)


def test_calibrate_refuses_a_robot_that_does_not_run_the_format_before_it_calibrates(files, capsys):
    given = str(files / "part.nc")
    assert main(["calibrate", "--scan", given, "--workpiece", given, "--reference", given, "--toolpath", given,
                 "--out", str(files / "out"), "--robot", "kuka_kr16_2"]) == 2  # G-code is the default format
    assert "robot kuka_kr16_2: G-code is written for machine tools" in capsys.readouterr().err
    assert not (files / "out").exists()
