"""Hostile input on the command line: every argument checked before the work starts, one exit status per
cause across all subcommands, a message that names what is wrong, never a traceback."""
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import workcal_wb.cli.calibrate as calibrate_cli
from workcal_wb.cli import EXIT_STATUS, build_parser, main
from workcal_wb.cli.simulate import write_simulation
from workcal_wb.core import frames
from workcal_wb.core.geometry import Cloud
from workcal_wb.core.readers import read_cloud
from workcal_wb.core.result import CalibrationResult
from workcal_wb.core.writers import write_ply, write_xyz

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    folder = tmp_path_factory.mktemp("scene")
    write_simulation(folder, "car", seed=5, pitch=0.8)
    (folder / "ok.json").write_text(json.dumps(CalibrationResult("ok", np.eye(4)).to_dict()))
    return folder


@pytest.fixture(scope="module")
def coarse_scene(tmp_path_factory):
    """The same scene seen at twice the pitch (a quarter of the points), for the runs whose point is a
    search that finds nothing: it tries every turn, and each costs in proportion to the scan."""
    folder = tmp_path_factory.mktemp("coarse-scene")
    write_simulation(folder, "car", seed=5, pitch=1.6)
    return folder


def calibrate(scene, out, *extra, scan=None, workpiece=None):
    return ["calibrate", "--scan", str(scan or scene / "scan.ply"), "--workpiece", str(workpiece or scene / "workpiece.ply"),
            "--reference", str(scene / "reference.ply"), "--out", str(out), *extra]


def run_in_a_process(argv, tmp_path, timeout, setup="") -> tuple:
    """(exit status, stderr) of ``main(argv)`` in a new Python process; output goes through files, so that
    a helper process the run leaves behind cannot hold a pipe open."""
    script = f"import sys; sys.path.insert(0, {str(ROOT)!r}); {setup}from workcal_wb.cli import main; sys.exit(main({argv!r}))"
    with open(tmp_path / "stderr.txt", "w+") as err:
        done = subprocess.run([sys.executable, "-c", script], stdout=subprocess.DEVNULL, stderr=err, timeout=timeout)
        err.seek(0)
        return done.returncode, err.read()


def one_line_error(capsys, *words) -> str:
    """stderr holds one error line naming all ``words`` and no traceback."""
    err = capsys.readouterr().err
    errors = [line for line in err.splitlines() if ": error: " in line]
    assert len(errors) == 1 and "Traceback" not in err, err
    for word in words:
        assert word in errors[0], (word, errors[0])
    return errors[0]


@pytest.fixture
def no_calibration(monkeypatch):
    """Fails the test if the calibration starts: the argument should have been refused before."""
    def refuse(*args, **kwargs):
        raise AssertionError("the calibration ran although an argument was bad")
    monkeypatch.setattr(calibrate_cli, "calibrate", refuse)


# --- the tracebacks of the finding, each now a clear error with its exit status -----------------------

def test_a_scan_of_points_on_a_line_fails_in_calibrate_as_in_match(scene, tmp_path, capsys):
    t = np.linspace(0, 100, 5000)
    write_xyz(tmp_path / "line.xyz", Cloud(np.column_stack([t, 0 * t, 0 * t])))
    assert main(calibrate(scene, tmp_path / "out", scan=tmp_path / "line.xyz")) == 1
    result = json.loads((tmp_path / "out" / "result.json").read_text())
    assert result["status"] == "failed" and [r["code"] for r in result["reasons"]] == ["not_found"]
    assert "the scan points lie on a line" in result["reasons"][0]["text"]
    assert main(["match", str(tmp_path / "line.xyz"), str(scene / "workpiece.ply")]) == 1
    assert "Traceback" not in capsys.readouterr().err


@pytest.mark.slow
def test_a_sub_millimetre_model_fails_with_a_unit_warning(scene, tmp_path, capsys):
    write_xyz(tmp_path / "tiny.xyz", Cloud(np.random.default_rng(0).normal(size=(2000, 3)) * 0.01))
    assert main(["match", str(scene / "scan.ply"), str(tmp_path / "tiny.xyz")]) == 1
    err = capsys.readouterr().err
    assert "tiny.xyz: only" in err and "--model-units" in err and "Traceback" not in err


MALFORMED_RESULTS = {"array": [1, 2], "null": None, "gates a string": {"quality_gates": "yes"},
                     "gates of numbers": {"quality_gates": [1, 2]}, "uncertainty a list": {"uncertainty": [1]},
                     "reasons a number": {"reasons": 5}}


@pytest.mark.parametrize("case", MALFORMED_RESULTS)
def test_a_malformed_result_json_exits_2_naming_it(scene, tmp_path, capsys, case):
    content = MALFORMED_RESULTS[case]
    if isinstance(content, dict):
        content = {**json.loads((scene / "ok.json").read_text()), **content}
    (tmp_path / "bad.json").write_text(json.dumps(content))
    assert main(["toolpath", "--in", str(scene / "toolpath.nc"), "--calibration", str(tmp_path / "bad.json"),
                 "--out", str(tmp_path / "prog.nc")]) == 2
    one_line_error(capsys, "bad.json")
    assert not (tmp_path / "prog.nc").exists()


@pytest.mark.parametrize("command", ["calibrate", "simulate", "demo"])
def test_out_that_is_an_existing_file_exits_3_before_any_work(scene, tmp_path, capsys, command, no_calibration):
    (tmp_path / "taken").write_text("a file\n")
    argv = calibrate(scene, tmp_path / "taken") if command == "calibrate" else [command, "--out", str(tmp_path / "taken")]
    assert main(argv) == 3
    one_line_error(capsys, "taken", "is a file")
    assert (tmp_path / "taken").read_text() == "a file\n"


@pytest.mark.parametrize("argv", [["toolpath", "--format", "gcode", "--out"], ["match", "--json"]])
def test_out_that_is_a_folder_where_a_file_is_wanted_exits_3(scene, tmp_path, capsys, argv):
    (tmp_path / "folder").mkdir()
    if argv[0] == "toolpath":
        argv = argv + [str(tmp_path / "folder"), "--in", str(scene / "toolpath.nc"), "--calibration", str(scene / "ok.json")]
    else:
        argv = ["match", str(scene / "scan.ply"), str(scene / "workpiece.ply")] + argv[1:] + [str(tmp_path / "folder")]
    assert main(argv) == 3
    one_line_error(capsys, "folder", "is a folder")


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs /proc")
def test_out_under_proc_exits_3_before_any_work(scene, tmp_path, capsys, no_calibration):
    assert main(calibrate(scene, "/proc/workcal-out")) == 3
    one_line_error(capsys, "/proc/workcal-out", "cannot write")
    assert main(["toolpath", "--in", str(scene / "toolpath.nc"), "--calibration", str(scene / "ok.json"),
                 "--out", "/proc/prog.nc"]) == 3
    one_line_error(capsys, "/proc/prog.nc")


@pytest.mark.slow
def test_a_file_size_limit_while_writing_exits_3_and_leaves_nothing(scene, tmp_path):
    out = tmp_path / "out"
    code, err = run_in_a_process(calibrate(scene, out), tmp_path, 600,
                                 "import resource; resource.setrlimit(resource.RLIMIT_FSIZE, (200000, 200000)); ")
    assert code == 3, err
    assert "File too large" in err and "Traceback" not in err
    assert not out.exists() or sorted(p.name for p in out.iterdir()) == []


@pytest.mark.parametrize("argv", [
    ["calibrate", "--tolerance", "inf"], ["calibrate", "--tolerance", "nan"], ["calibrate", "--tolerance", "-1e-3"],
    ["calibrate", "--seed", "-5"], ["calibrate", "--seed", "1.5"], ["match", "--tolerance", "inf"],
    ["match", "--seed", "-5"], ["simulate", "--seed", "-5"], ["simulate", "--noise", "nan"],
    ["simulate", "--pitch", "inf"], ["simulate", "--positions", "0"], ["demo", "--seed", "-5"],
    ["study", "--seed", "-5"], ["study", "--tolerance", "inf"], ["bench", "--seed", "-5"],
    ["toolpath", "--table-angle", "nan"], ["toolpath", "--chord-tol", "inf"], ["toolpath", "--rapid-feed", "inf"],
    ["toolpath", "--rapid-feed", "-6000"], ["toolpath", "--envelope", "-1,-1,-1,nan,1,1"],
])
def test_a_number_out_of_range_exits_2_naming_the_option(scene, tmp_path, capsys, argv):
    command, option, value = argv
    base = {"calibrate": calibrate(scene, tmp_path / "out"),
            "match": ["match", str(scene / "scan.ply"), str(scene / "workpiece.ply")],
            "simulate": ["simulate", "--out", str(tmp_path / "out")], "demo": ["demo", "--out", str(tmp_path / "out")],
            "study": ["study", "placement", "--out", str(tmp_path / "out")],
            "bench": ["bench", "--out", str(tmp_path / "bench.md")],
            "toolpath": ["toolpath", "--in", str(scene / "toolpath.nc"), "--calibration", str(scene / "ok.json"),
                         "--out", str(tmp_path / "prog.nc"), "--table-frame", str(scene / "ok.json")]}[command]
    assert main(base + [option, value]) == 2
    one_line_error(capsys, f"argument {option}", value)
    assert not (tmp_path / "out").exists() and not (tmp_path / "prog.nc").exists()


def test_the_table_angle_nan_is_not_blamed_on_a_move(scene, tmp_path, capsys):
    (tmp_path / "table.json").write_text(json.dumps({"matrix": np.eye(4).tolist()}))
    assert main(["toolpath", "--in", str(scene / "toolpath.nc"), "--calibration", str(scene / "ok.json"),
                 "--out", str(tmp_path / "prog.nc"), "--table-frame", str(tmp_path / "table.json"),
                 "--table-angle", "nan"]) == 2
    assert "move 1" not in one_line_error(capsys, "--table-angle")


# --- every option takes negative numbers -------------------------------------------------------------

def test_negative_numbers_are_values_in_every_form(scene, tmp_path, capsys):
    # --envelope with a leading minus parses as the value it is (it used to need --envelope=-1,...).
    out = tmp_path / "prog.csv"
    assert main(["toolpath", "--in", str(scene / "toolpath.nc"), "--calibration", str(scene / "ok.json"),
                 "--out", str(out), "--envelope", "-1e4,-10000,-.5e4,10000,10000,10000"]) == 0
    assert out.exists()
    table = tmp_path / "table.json"
    table.write_text(json.dumps(np.eye(4).tolist()))
    assert main(["toolpath", "--in", str(scene / "toolpath.nc"), "--calibration", str(scene / "ok.json"),
                 "--out", str(out), "--table-frame", str(table), "--table-angle", "-1e1"]) == 0
    box = build_parser().parse_args(calibrate(scene, tmp_path / "o") + ["--workpiece-box", "-1e3", "-2", "-.5", "1",
                                                                       "2", "3", "--reference-box", "-1", "-1", "-1",
                                                                       "1", "1", "1"])
    assert box.workpiece_box == [-1000.0, -2.0, -0.5, 1.0, 2.0, 3.0]
    # A negative value where only positive ones make sense is refused for its value, not taken for an option.
    assert main(calibrate(scene, tmp_path / "o", "--tolerance", "-1e-3")) == 2
    assert "expected one argument" not in one_line_error(capsys, "argument --tolerance", "must be a number > 0")


# --- misleading messages -----------------------------------------------------------------------------

def test_a_fifo_as_the_scan_is_refused_at_once(scene, tmp_path):
    fifo = tmp_path / "scan.ply"
    os.mkfifo(fifo)
    for argv in (["match", str(fifo), str(scene / "workpiece.ply")], calibrate(scene, tmp_path / "o", scan=fifo)):
        code, err = run_in_a_process(argv, tmp_path, 120)
        assert code == 2 and "not a regular file" in err, err


def test_an_index_that_is_not_a_whole_number_names_its_line(scene, tmp_path, capsys, no_calibration):
    (tmp_path / "workpiece.txt").write_text("1\n2\n1.5\n")
    (tmp_path / "reference.txt").write_text("7 8 9\n")
    assert main(calibrate(scene, tmp_path / "o", "--workpiece-indices", str(tmp_path / "workpiece.txt"),
                          "--reference-indices", str(tmp_path / "reference.txt"))) == 2
    one_line_error(capsys, "workpiece.txt: line 3", "'1.5'")


@pytest.mark.slow
def test_a_model_in_the_wrong_unit_is_warned_about_with_the_option_to_use(scene, tmp_path, capsys):
    model = read_cloud(scene / "workpiece.ply")
    write_ply(tmp_path / "workpiece_m.ply", Cloud(model.points / 1000, triangles=model.triangles))
    assert main(calibrate(scene, tmp_path / "o", workpiece=tmp_path / "workpiece_m.ply")) == 1
    err = capsys.readouterr().err
    assert "workpiece_m.ply: only" in err and "read it with --model-units m" in err and "units='m'" not in err
    reasons = json.loads((tmp_path / "o" / "result.json").read_text())["reasons"]
    assert [r["code"] for r in reasons] == ["not_found"], reasons
    assert "no object on the platform is the size of the model" in reasons[0]["text"]
    assert "objects tried: 0" not in reasons[0]["text"]


@pytest.mark.slow
def test_a_tolerance_below_the_scan_noise_says_so(coarse_scene, tmp_path):
    assert main(calibrate(coarse_scene, tmp_path / "o", "--tolerance", "0.01")) == 1
    reasons = json.loads((tmp_path / "o" / "result.json").read_text())["reasons"]
    assert [r["code"] for r in reasons] == ["not_found"], reasons
    assert "below the scan's noise" in reasons[0]["text"] and "is the reference in view" not in reasons[0]["text"]


@pytest.mark.slow
def test_one_absurd_point_is_dropped_with_a_warning_not_taken_for_a_unit(scene, tmp_path, capsys):
    scan = read_cloud(scene / "scan.ply")
    write_ply(tmp_path / "scan.ply", Cloud(np.vstack([scan.points, [[1e308, 0, 0]]])))
    assert main(calibrate(scene, tmp_path / "o", scan=tmp_path / "scan.ply")) == 0
    err = capsys.readouterr().err
    assert "ignored 1 points" in err and "1000 km" in err
    assert "micrometres" not in err and "inf m" not in err
    W = np.array(json.loads((tmp_path / "o" / "result.json").read_text())["W"])
    truth = np.array(json.loads((scene / "truth.json").read_text())["W"])
    assert frames.rotation_between_deg(W, truth) < 0.05 and np.linalg.norm(W[:3, 3] - truth[:3, 3]) < 0.1


def test_stray_points_far_from_the_rest_are_named_not_taken_for_a_unit(tmp_path):
    points = np.random.default_rng(1).uniform(0, 200, size=(5000, 3))
    write_xyz(tmp_path / "scan.xyz", Cloud(np.vstack([points, [[5e7, 0, 0], [0, -4e7, 0]]])))
    warnings = read_cloud(tmp_path / "scan.xyz", unit_option="--units").warnings
    assert any("2 of 5002 points lie far from all the others" in w for w in warnings), warnings
    assert not any("micrometres" in w for w in warnings)


@pytest.mark.slow
def test_the_same_cause_has_the_same_exit_status_in_match_and_calibrate(coarse_scene, tmp_path):
    """A model that is not in the scan: the job ran and failed (1) in both, not 'bad input' in one."""
    u, v = np.meshgrid(np.linspace(0, np.pi, 40), np.linspace(0, 2 * np.pi, 80))
    ball = 60 * np.column_stack([np.sin(u).ravel() * np.cos(v).ravel(), np.sin(u).ravel() * np.sin(v).ravel(),
                                 np.cos(u).ravel()])
    write_xyz(tmp_path / "ball.xyz", Cloud(np.unique(np.round(ball, 6), axis=0)))
    assert main(["match", str(coarse_scene / "scan.ply"), str(tmp_path / "ball.xyz")]) == 1
    assert main(calibrate(coarse_scene, tmp_path / "o", workpiece=tmp_path / "ball.xyz")) == 1


def test_an_internal_error_is_one_line_with_its_own_exit_status(scene, tmp_path, capsys, monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("something WorkCal did not foresee")
    monkeypatch.setattr(calibrate_cli, "merge_scans", broken)
    assert main(calibrate(scene, tmp_path / "o")) == 70
    err = capsys.readouterr().err
    assert "internal error: RuntimeError: something WorkCal did not foresee" in err and "Traceback" not in err
    assert err.count("\n") == 1


def test_exit_status_is_documented_in_every_help_and_in_the_readme(capsys):
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    codes = re.findall(r"^\s+(\d+)\s", EXIT_STATUS, re.M)
    assert codes == ["0", "1", "2", "3", "4", "70", "130"]
    for command in ["", "calibrate", "match", "toolpath", "robots", "simulate", "demo", "study", "bench"]:
        assert main([command, "--help"] if command else ["--help"]) == 0
        shown = capsys.readouterr().out
        assert "exit status (the same for every subcommand):" in shown, command
        for code in codes:
            assert re.search(rf"^\s+{code}\s", shown, re.M), (command, code)
    for code, words in (("0", "ok"), ("1", "failed"), ("2", "bad input"), ("3", "cannot be written"),
                        ("4", "missing"), ("70", "internal error"), ("130", "interrupted"), ("143", "SIGTERM")):
        assert re.search(rf"\|\s*{code}\s*\|[^\n]*{words}", readme, re.I), (code, words)
