"""``python3 -m workcal_wb`` as a process: it ends without the interpreter's teardown (``__main__``),
so what it prints must still arrive whole through a pipe, and its exit status must be main's."""
import os
import subprocess
import sys
from pathlib import Path

from workcal_wb import __version__
from workcal_wb.cli import EXIT_BAD_INPUT

ROOT = Path(__file__).resolve().parents[2]
PYTHON = sys.executable if Path(sys.executable).name.startswith("python") else "/usr/bin/python3"


def _run(*args):
    # Buffered as a user's shell leaves it (PYTHONUNBUFFERED, set by some CI runners, would hide a lost buffer).
    env = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}
    return subprocess.run([PYTHON, "-m", "workcal_wb", *args], cwd=ROOT, capture_output=True, text=True, timeout=60,
                          env=env)


def test_output_through_a_pipe_arrives_whole():
    """stdout to a pipe is block-buffered: ending the process must flush it first."""
    done = _run("--version")
    assert done.returncode == 0
    assert done.stdout == f"WorkCal {__version__}\n"


def test_exit_status_and_message_of_a_failed_run(tmp_path):
    done = _run("calibrate", "--scan", str(tmp_path / "missing.ply"), "--workpiece", str(tmp_path / "w.ply"),
                "--reference", str(tmp_path / "r.ply"), "--out", str(tmp_path / "out"))
    assert done.returncode == EXIT_BAD_INPUT
    assert "missing.ply" in done.stderr and "Traceback" not in done.stderr
    assert not (tmp_path / "out").exists()
