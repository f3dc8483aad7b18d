"""`python3 -m workcal_wb calibrate` and `demo` from files, as a user runs them."""
import hashlib
import json
import re

import numpy as np
import pytest

from workcal_wb.cli import main
from workcal_wb.cli.simulate import write_simulation
from workcal_wb.core import frames
from workcal_wb.core.toolpath import Move, Toolpath, read_gcode
from workcal_wb.core.toolpath.exporters.gcode import format_gcode


@pytest.fixture(scope="module")
def scene_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("scene")
    write_simulation(folder, "car", seed=7, pitch=0.6)
    truth = json.loads((folder / "truth.json").read_text())
    return folder, np.array(truth["W"])


def _args(folder, out, *extra):
    return ["calibrate", "--scan", str(folder / "scan.ply"), "--workpiece", str(folder / "workpiece.ply"),
            "--reference", str(folder / "reference.ply"), "--out", str(out), *extra]


@pytest.mark.slow
def test_calibrate_writes_W_report_and_calibrated_toolpath(scene_files, tmp_path, capsys):
    folder, W_true = scene_files
    assert main(_args(folder, tmp_path, "--toolpath", str(folder / "toolpath.nc"), "--machine", "5axis-tcp")) == 0
    result = json.loads((tmp_path / "result.json").read_text())
    W = np.array(result["W"])
    assert result["status"] == "ok" and W.shape == (4, 4)
    assert frames.rotation_between_deg(W, W_true) < 0.02 and np.linalg.norm(W[:3, 3] - W_true[:3, 3]) < 0.05
    assert np.allclose(W, np.linalg.inv(np.array(result["V"])) @ np.array(result["U"]))
    assert (tmp_path / "report.html").stat().st_size > 1000
    original = read_gcode(folder / "toolpath.nc").points()
    calibrated = read_gcode(tmp_path / "toolpath_calibrated.nc").points()
    assert np.abs(calibrated - frames.apply(W, original)).max() < 1e-3  # written to 4 decimals
    # the program names its result and shows the bound result.json holds
    program = (tmp_path / "toolpath_calibrated.nc").read_text()
    digest = hashlib.sha256((tmp_path / "result.json").read_bytes()).hexdigest()[:16]
    assert f"result sha256 {digest}" in program
    assert f"bound {result['uncertainty']['toolpath_bound_mm']} mm" in program
    assert re.search(r"on the workpiece model workpiece.ply: cutting moves a median \d\.\d\d mm from its surface",
                     re.sub(r"\)\n\(", " ", program))
    assert "calibration OK" in capsys.readouterr().out


@pytest.mark.slow
def test_a_toolpath_made_for_another_part_is_not_written(scene_files, tmp_path, capsys):
    """A larger variant's toolpath: this one's pass 40 mm off the part's surface (close enough to pass as
    the same part's in the model's unit and frame, too far for any cut on it)."""
    folder, _ = scene_files
    path = read_gcode(folder / "toolpath.nc")
    lifted = Toolpath.from_moves([Move(m.kind, m.end + 40 * m.tool_axis, feed=m.feed, tool_axis=m.tool_axis)
                                  for m in path.moves])
    (tmp_path / "other.nc").write_text(format_gcode(lifted))
    out = tmp_path / "out"
    assert main(_args(folder, out, "--toolpath", str(tmp_path / "other.nc"), "--machine", "5axis-tcp")) == 1
    assert json.loads((out / "result.json").read_text())["status"] == "ok"
    err = capsys.readouterr().err
    assert re.search(r"toolpath not written: .*other.nc: its cutting moves run a median [\d.]+ mm from the workpiece "
                     r"model workpiece.ply .* allow it with --path-reach \d+", err)
    assert not list(out.glob("toolpath_calibrated.*"))


@pytest.mark.slow
def test_calibrate_with_a_robot_plots_its_joint_margins_in_the_report(scene_files, tmp_path, capsys):
    """The program checked against the robot: the report shows each joint's margin at every robot target
    (the same margins the program's header states), and what the robot cannot follow it says, and where."""
    folder, _ = scene_files
    robot_args = ("--toolpath", str(folder / "toolpath.nc"), "--format", "krl", "--tool", "0,0,150,0,0,0")
    assert main(_args(folder, tmp_path / "kr16", *robot_args, "--robot", "kuka_kr16_2")) == 0
    page = (tmp_path / "kr16" / "report.html").read_text(encoding="utf-8")
    lines = re.findall(r'<polyline data-joint="(A\d)" points="([^"]+)"', page)
    assert [joint for joint, _ in lines] == ["A1", "A2", "A3", "A4", "A5", "A6"]
    reach = json.loads((tmp_path / "kr16" / "report.json").read_text())["reach"]
    program = (tmp_path / "kr16" / "toolpath_calibrated.src").read_text()
    smallest = reach["smallest_margin"]
    assert not smallest["on_the_way"]  # at a robot target, so a point of its joint's line
    assert f"smallest joint-limit margin {smallest['deg']:.1f} deg ({smallest['joint']} at" in program
    worst = dict(pair.split(",") for pair in dict(lines)[smallest["joint"]].split())
    assert float(worst[str(smallest["target"])]) == pytest.approx(smallest["deg"], abs=1e-3)
    assert min(float(v) for _, points in lines for v in points.replace(" ", ",").split(",")[1::2]) == \
        pytest.approx(smallest["deg"], abs=1e-3)
    # A robot too small for where the part sits: no program, and the report says why.
    assert main(_args(folder, tmp_path / "kr6", *robot_args, "--robot", "kuka_kr6_r700_sixx")) == 1
    page = (tmp_path / "kr6" / "report.html").read_text(encoding="utf-8")
    assert "KUKA KR 6 R700 sixx (kuka_kr6_r700_sixx) cannot follow the calibrated program: robot target 1" in page
    assert json.loads((tmp_path / "kr6" / "report.json").read_text())["reach"]["problem"] == "out_of_reach"
    capsys.readouterr()


@pytest.mark.slow
def test_failed_calibration_writes_no_toolpath(scene_files, tmp_path):
    folder, _ = scene_files
    # The workpiece "region" is the first image rows: bare platform, nothing to fix a pose on.
    box = ["-10000", "-10000", "0", "10000", "10000", "10000"]  # the reference region: the whole scan
    code = main(_args(folder, tmp_path, "--toolpath", str(folder / "toolpath.nc"), "--workpiece-indices",
                      str(_indices(tmp_path, range(0, 3000))), "--reference-box", *box))
    assert code == 1
    result = json.loads((tmp_path / "result.json").read_text())
    assert result["status"] == "failed" and any(r["code"] == "scan_not_solid" and "planar" in r["text"]
                                                for r in result["reasons"]), result["reasons"]
    assert not (tmp_path / "toolpath_calibrated.nc").exists()


def _indices(folder, values):
    path = folder / "indices.txt"
    path.write_text("\n".join(str(v) for v in values))
    return path


def test_bad_input_exits_2_and_writes_nothing(scene_files, tmp_path, capsys):
    folder, _ = scene_files
    empty = tmp_path / "empty.ply"
    empty.write_text("")
    out = tmp_path / "out"
    code = main(["calibrate", "--scan", str(folder / "scan.ply"), "--workpiece", str(empty),
                 "--reference", str(folder / "reference.ply"), "--out", str(out)])
    assert code == 2 and not out.exists()
    assert "empty.ply" in capsys.readouterr().err


@pytest.mark.slow
def test_demo_runs_the_whole_job(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path)]) == 0
    check = json.loads((tmp_path / "truth_check.json").read_text())
    assert check["rotation_deg"] < 0.02 and check["translation_mm"] < 0.05
    for name in ("result.json", "report.html", "toolpath_calibrated.nc", "toolpath_calibrated.src"):
        assert (tmp_path / name).exists(), name
        # Every path a file names is one the user can open: none in the folder the run staged it in.
        assert ".workcal-staging" not in (tmp_path / name).read_text(), name
    assert f"{tmp_path}/input/toolpath.nc," in (tmp_path / "toolpath_calibrated.src").read_text()
    assert "error against the known truth" in capsys.readouterr().out


def test_scanner_origin_and_up_options_reach_the_calibration(monkeypatch, tmp_path):
    """--scanner-origin and --up are checked by argparse and handed to the calibration as options."""
    from workcal_wb.cli import build_parser
    from workcal_wb.cli import calibrate as command

    scan = tmp_path / "scan.xyz"
    scan.write_text("0 0 0\n1 0 0\n0 1 0\n0 0 1\n")
    args = build_parser().parse_args(["calibrate", "--scan", str(scan), "--workpiece", str(scan), "--reference",
                                      str(scan), "--scanner-origin", "1", "-2", "3e2", "--up", "0", "0", "1"])
    seen = {}

    def fake(scans, workpiece, reference, *, regions=None, toolpath_points=None, options=None):
        seen["options"] = options
        raise SystemExit(0)

    monkeypatch.setattr(command, "calibrate", fake)
    with pytest.raises(SystemExit):
        command.run(args)
    assert seen["options"].scanner_origin == (1.0, -2.0, 300.0) and seen["options"].up == (0.0, 0.0, 1.0)
    assert build_parser().parse_args(["calibrate", "--scan", str(scan), "--workpiece", str(scan), "--reference",
                                      str(scan)]).up is None
