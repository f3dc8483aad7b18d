"""An output folder a cell can trust: a run leaves one consistent set (result, report, program and the
manifest that ties them), a failed or refused run leaves no program, an interrupted run leaves the
previous set whole, and no temporary file survives a signal."""
import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from workcal_wb.cli import main
from workcal_wb.cli.simulate import write_simulation
from workcal_wb.core import report as report_module
from workcal_wb.core.outputs import OutputFolder

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    folder = tmp_path_factory.mktemp("scene")
    write_simulation(folder, "car", seed=7, pitch=0.8)
    return folder


def calibrate_args(scene, out, *extra, workpiece=None):
    return ["calibrate", "--scan", str(scene / "scan.ply"), "--workpiece", str(workpiece or scene / "workpiece.ply"),
            "--reference", str(scene / "reference.ply"), "--toolpath", str(scene / "toolpath.nc"), "--format", "krl",
            "--out", str(out), *extra]


def snapshot(folder: Path) -> dict:
    """Every file below ``folder`` (hidden ones too) with its SHA-256."""
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def programs(folder: Path) -> list:
    return sorted(p.name for p in folder.glob("toolpath_calibrated.*"))


def assert_manifest_is_the_folder(out: Path, status: str):
    """manifest.json lists exactly the set in the folder, with the right hashes."""
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["status"] == status and manifest["command"] == "calibrate"
    files = snapshot(out)
    assert {name: entry["sha256"] for name, entry in manifest["files"].items()} == {
        name: digest for name, digest in files.items() if name in manifest["files"]}
    assert set(files) - set(manifest["files"]) <= {"manifest.json", "notes.txt", "indices.txt"}


@pytest.fixture(scope="module")
def ok_run(scene, tmp_path_factory) -> Path:
    """The folder of an ok calibration with a KRL program, as the first run leaves it: calibrated once
    for the module, and never changed (each test works on a copy)."""
    out = tmp_path_factory.mktemp("ok") / "cell"
    assert main(calibrate_args(scene, out)) == 0
    assert programs(out) == ["toolpath_calibrated.src"]
    assert json.loads((out / "result.json").read_text())["status"] == "ok"
    return out


def fresh_copy(ok_run: Path, tmp_path) -> Path:
    """A folder holding the ok run's set (a copy: the same files as a run into it, but for the program's
    header naming the ok run's result.json), plus a user's own file."""
    out = tmp_path / "cell"
    shutil.copytree(ok_run, out)
    (out / "notes.txt").write_text("the operator's notes\n")
    assert_manifest_is_the_folder(out, "ok")
    return out


@pytest.mark.slow
def test_a_failed_calibration_leaves_no_program_of_the_earlier_run(ok_run, scene, tmp_path):
    # The finding: the first run's program, "status ok", stayed beside a result.json that says "failed".
    out = fresh_copy(ok_run, tmp_path)
    (tmp_path / "indices.txt").write_text("\n".join(str(i) for i in range(3000)))  # bare platform: gates fail
    box = ["-10000", "-10000", "0", "10000", "10000", "10000"]
    code = main(calibrate_args(scene, out, "--workpiece-indices", str(tmp_path / "indices.txt"), "--reference-box", *box))
    assert code == 1
    assert programs(out) == []
    assert json.loads((out / "result.json").read_text())["status"] == "failed"
    assert_manifest_is_the_folder(out, "failed")
    assert (out / "notes.txt").read_text() == "the operator's notes\n"  # not an output: never touched


@pytest.mark.slow
def test_a_run_that_finds_no_workpiece_leaves_no_earlier_result(ok_run, scene, tmp_path):
    # The finding: exit 2 and the whole old set, result.json "ok" included, stayed.
    out = fresh_copy(ok_run, tmp_path)
    sphere = tmp_path / "sphere.xyz"
    u, v = np.meshgrid(np.linspace(0, np.pi, 60), np.linspace(0, 2 * np.pi, 120))
    np.savetxt(sphere, 90 * np.column_stack([np.sin(u).ravel() * np.cos(v).ravel(),
                                             np.sin(u).ravel() * np.sin(v).ravel(), np.cos(u).ravel()]))
    args = calibrate_args(scene, out, workpiece=sphere)
    del args[args.index("--toolpath"):args.index("--toolpath") + 2]  # a toolpath would not fit a sphere anyway
    code = main(args)
    assert code == 1  # the calibration ran and found nothing: failed, as match says for the same cause
    result = json.loads((out / "result.json").read_text())
    assert result["status"] == "failed" and [r["code"] for r in result["reasons"]] == ["not_found"]
    assert "sphere.xyz: not found" in result["reasons"][0]["text"]
    assert programs(out) == []
    assert_manifest_is_the_folder(out, "failed")


@pytest.mark.slow
def test_bad_input_after_an_ok_run_removes_the_earlier_set(ok_run, scene, tmp_path, capsys):
    out = fresh_copy(ok_run, tmp_path)
    broken = tmp_path / "broken.ply"
    data = (scene / "scan.ply").read_bytes()
    broken.write_bytes(data[:len(data) // 2])
    code = main(["calibrate", "--scan", str(broken), "--workpiece", str(scene / "workpiece.ply"),
                 "--reference", str(scene / "reference.ply"), "--out", str(out)])
    assert code == 2 and "broken.ply" in capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt"]  # nothing stale beside the error


@pytest.mark.slow
def test_an_interrupt_before_the_program_leaves_the_earlier_set_whole(ok_run, scene, tmp_path, monkeypatch):
    # The finding: SIGINT between the writes left a new result.json beside the old program.
    out = fresh_copy(ok_run, tmp_path)
    before = snapshot(out)

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt  # Ctrl-C after result.json, before the program

    monkeypatch.setattr("workcal_wb.cli.calibrate.export", interrupted)
    assert main(calibrate_args(scene, out, "--seed", "3")) == 130
    assert snapshot(out) == before


@pytest.mark.slow
def test_the_result_and_program_are_in_before_the_report(ok_run, scene, tmp_path, monkeypatch, capsys):
    """The critical path first: result.json and the program are committed as a set before the report's
    figures are drawn; an interrupt while drawing them leaves that set (never the earlier report)."""
    out = fresh_copy(ok_run, tmp_path)
    seen = {}

    def interrupted(calibration, folder, **kwargs):
        seen["then"] = sorted(p.name for p in out.iterdir() if not p.name.startswith("."))  # not the staging
        raise KeyboardInterrupt  # Ctrl-C while the figures are drawn

    monkeypatch.setattr(report_module, "write_report", interrupted)
    assert main(calibrate_args(scene, out, "--seed", "3")) == 130
    assert seen["then"] == ["manifest.json", "notes.txt", "result.json", "result.regions.npz",
                            "toolpath_calibrated.src"]
    assert sorted(p.name for p in out.iterdir()) == seen["then"]
    assert json.loads((out / "result.json").read_text())["seed"] == 3  # this run's, not the earlier one
    assert_manifest_is_the_folder(out, "ok")
    assert "the report was not written" in capsys.readouterr().err


@pytest.mark.slow
def test_a_program_in_another_format_replaces_the_earlier_one(ok_run, scene, tmp_path):
    out = fresh_copy(ok_run, tmp_path)
    args = calibrate_args(scene, out)
    args[args.index("krl")] = "rapid"
    assert main(args) == 0
    assert programs(out) == ["toolpath_calibrated.mod"]
    assert_manifest_is_the_folder(out, "ok")


@pytest.mark.slow
def test_an_export_refused_as_unsafe_exits_1_and_leaves_no_program(ok_run, scene, tmp_path, capsys):
    out = fresh_copy(ok_run, tmp_path)
    assert main(calibrate_args(scene, out, "--method", "icp", "--tolerance", "0.001")) == 1
    assert programs(out) == [] and "toolpath not written" in capsys.readouterr().err


def test_runs_into_one_folder_commit_one_after_the_other(tmp_path):
    """Two runs staged at the same time: the folder ends with one of the sets, whole."""
    first, second = (OutputFolder(tmp_path / "out", "calibrate", ("result.json", "toolpath_calibrated.*"))
                     for _ in range(2))
    with first, second:
        (first.file("result.json")).write_text("first")
        (first.file("toolpath_calibrated.src")).write_text("first")
        (second.file("result.json")).write_text("second")
        (second.file("toolpath_calibrated.nc")).write_text("second")
        first.commit("ok")
        second.commit("ok")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["manifest.json", "result.json",
                                                                    "toolpath_calibrated.nc"]
    assert (tmp_path / "out" / "result.json").read_text() == "second"


# --- signals: a real process, stopped in the middle of writing a program ------------------------------

PAUSED_WRITE = """
import os, sys, time
sys.path.insert(0, {root!r})
from workcal_wb.core import atomic
real_fsync = atomic.os.fsync
def paused_fsync(fd):
    open({marker!r}, "w").close()  # the program's bytes are in the .part file now
    time.sleep(60)
    real_fsync(fd)
atomic.os.fsync = paused_fsync
from workcal_wb.cli import main
sys.exit(main({argv!r}))
"""


@pytest.fixture
def toolpath_files(tmp_path):
    (tmp_path / "part.nc").write_text("G21 G90\nG0 X0 Y0 Z10\nG1 Z0 F500\nG1 X20\n")
    from workcal_wb.core.result import CalibrationResult

    CalibrationResult("ok", np.eye(4)).to_json(tmp_path / "result.json")
    return tmp_path


def start_paused_export(folder: Path, name: str) -> subprocess.Popen:
    marker = folder / f"{name}.writing"
    argv = ["toolpath", "--in", str(folder / "part.nc"), "--calibration", str(folder / "result.json"),
            "--out", str(folder / "out" / name)]
    process = subprocess.Popen([sys.executable, "-c", PAUSED_WRITE.format(root=str(ROOT), marker=str(marker),
                                                                          argv=argv)],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 60
    while not marker.exists():
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline, "the export never started writing"
        time.sleep(0.05)
    return process


def parts(folder: Path) -> list:
    return sorted(p.name for p in folder.rglob("*.part"))


@pytest.mark.parametrize("signum, code", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_a_signal_during_a_write_removes_the_temporary_file(toolpath_files, signum, code):
    # The finding: SIGTERM during a write left a hidden .part file (74 MB for a 5M-point result).
    (toolpath_files / "out").mkdir()
    (toolpath_files / "out" / "prog.nc").write_text("the previous program\n")
    process = start_paused_export(toolpath_files, "prog.nc")
    assert parts(toolpath_files / "out")  # caught in the middle of the write
    process.send_signal(signum)
    _, err = process.communicate(timeout=60)
    assert process.returncode == code, err
    assert parts(toolpath_files / "out") == []
    assert (toolpath_files / "out" / "prog.nc").read_text() == "the previous program\n"
    assert b"Traceback" not in err


def test_a_part_left_by_a_killed_write_is_removed_by_the_next_run(toolpath_files):
    (toolpath_files / "out").mkdir()
    process = start_paused_export(toolpath_files, "first.nc")
    process.kill()  # SIGKILL: nothing can clean up
    process.communicate(timeout=60)
    stale = parts(toolpath_files / "out")
    assert stale and stale[0].startswith(".first.nc.")
    assert main(["toolpath", "--in", str(toolpath_files / "part.nc"), "--calibration",
                 str(toolpath_files / "result.json"), "--out", str(toolpath_files / "out" / "second.nc")]) == 0
    assert parts(toolpath_files / "out") == []
    assert sorted(p.name for p in (toolpath_files / "out").iterdir()) == ["second.nc"]


def test_a_part_being_written_by_a_running_process_is_left_alone(toolpath_files):
    (toolpath_files / "out").mkdir()
    process = start_paused_export(toolpath_files, "first.nc")
    try:
        assert main(["toolpath", "--in", str(toolpath_files / "part.nc"), "--calibration",
                     str(toolpath_files / "result.json"), "--out", str(toolpath_files / "out" / "second.nc")]) == 0
        assert len(parts(toolpath_files / "out")) == 1  # still the other run's
    finally:
        process.kill()
        process.communicate(timeout=60)
    os.sync()


@pytest.mark.slow
def test_the_program_names_the_result_json_beside_it(scene, tmp_path):
    """The program's header carries the SHA-256 of the result.json of its set (as the manifest lists
    it), also when the program is written later from that file by ``toolpath``."""
    out = tmp_path / "cell"
    assert main(calibrate_args(scene, out)) == 0  # a run of its own: the program names its result.json's path
    digest = hashlib.sha256((out / "result.json").read_bytes()).hexdigest()
    assert json.loads((out / "manifest.json").read_text())["files"]["result.json"]["sha256"] == digest
    assert f"result sha256 {digest[:16]}" in (out / "toolpath_calibrated.src").read_text()
    later = tmp_path / "later.src"
    assert main(["toolpath", "--in", str(scene / "toolpath.nc"), "--calibration", str(out / "result.json"),
                 "--out", str(later)]) == 0
    assert f"result sha256 {digest[:16]}" in later.read_text()


# --- SIGKILL at every step of a commit: the folder holds a whole set, or none a reader accepts --------

KILLED_COMMIT = """
import os, shutil, signal, sys
sys.path.insert(0, {root!r})
from workcal_wb.core.outputs import OutputFolder
steps, limit = [0], {limit}

def counted(operation):
    def step(*args, **kwargs):
        if steps[0] == limit:
            os.kill(os.getpid(), signal.SIGKILL)
        steps[0] += 1
        return operation(*args, **kwargs)
    return step

with OutputFolder({folder!r}, "calibrate", {owned!r}) as outputs:
    for name, text in {files!r}.items():
        with open(outputs.file(name), "w") as fh:
            fh.write(text)
    os.replace, os.unlink, os.rename, shutil.rmtree = map(counted, (os.replace, os.unlink, os.rename, shutil.rmtree))
    outputs.commit("ok")
"""
OWNED = ("result.json", "report.html", "toolpath_calibrated.*")


def test_a_commit_killed_at_any_step_leaves_a_whole_set_or_none_a_reader_takes(tmp_path):
    """A folder holding a set (result, report, KRL program) gets another (result, G-code program) from a
    process killed (SIGKILL) at each file operation of its commit in turn, until one is not: at every
    step the folder holds a manifest listing exactly its outputs with their hashes, or no manifest and a
    result.json that `workcal toolpath` refuses, naming the folder."""
    from workcal_wb.core.errors import InputError
    from workcal_wb.core.outputs import check_whole_set

    first = {"result.json": "first", "report.html": "first", "toolpath_calibrated.src": "first"}
    second = {"result.json": "second", "toolpath_calibrated.nc": "second"}
    for limit in range(100):
        folder = tmp_path / f"kill{limit}"
        with OutputFolder(folder, "calibrate", OWNED) as outputs:
            for name, text in first.items():
                outputs.file(name).write_text(text)
            outputs.commit("ok")
        script = KILLED_COMMIT.format(root=str(ROOT), folder=str(folder), owned=OWNED, files=second, limit=limit)
        done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
        outputs = sorted(p.name for p in folder.iterdir() if p.name != "manifest.json" and not p.name.startswith("."))
        if (folder / "manifest.json").exists():
            listed = json.loads((folder / "manifest.json").read_text())["files"]
            assert sorted(listed) == outputs, (limit, listed, outputs)
            assert all(hashlib.sha256((folder / n).read_bytes()).hexdigest() == e["sha256"] for n, e in listed.items())
            check_whole_set(folder / "result.json")
        elif (folder / "result.json").exists():
            with pytest.raises(InputError, match=f"{folder} holds no whole set"):
                check_whole_set(folder / "result.json")
        if done.returncode == 0:
            assert {n: (folder / n).read_text() for n in outputs} == second
            break
        assert done.returncode == -signal.SIGKILL, done.stderr
    else:
        pytest.fail("the commit never ran to its end")
    assert limit >= 4  # the manifest, the old program and report, the two new files: every step was killed once


@pytest.mark.slow
def test_a_result_json_that_its_manifest_does_not_list_is_refused(ok_run, scene, tmp_path, capsys):
    out = fresh_copy(ok_run, tmp_path)
    result = json.loads((out / "result.json").read_text())
    result["warnings"].append("edited by hand")
    (out / "result.json").write_text(json.dumps(result))
    assert main(["toolpath", "--in", str(scene / "toolpath.nc"), "--calibration", str(out / "result.json"),
                 "--out", str(tmp_path / "again.nc")]) == 2
    assert f"{out / 'result.json'}: not the file {out / 'manifest.json'} lists" in capsys.readouterr().err
    assert not (tmp_path / "again.nc").exists()
