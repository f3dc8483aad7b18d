"""`python3 -m workcal_wb match` and `bench` from files, as a user runs them: exit codes and JSON content."""
import json

import numpy as np
import pytest

from workcal_wb.cli import build_parser, main
from workcal_wb.core import frames
from workcal_wb.core.benchmark.cases import zoomed_on_workpiece
from workcal_wb.core.geometry import Cloud
from workcal_wb.core.simulate import shapes
from workcal_wb.core.simulate.scene import build_scene
from workcal_wb.core.writers import write_ply, write_xyz


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A car scan (moved to a random pose, in metres) and the car model (mm), with the true U."""
    folder = tmp_path_factory.mktemp("match")
    scene = build_scene("car", seed=8)
    scan = zoomed_on_workpiece(scene, -20.0, 8, pixel_pitch_mm=0.6).scan(scene)
    motion = frames.random_motion(np.random.default_rng(8))
    write_ply(folder / "scan_m.ply", Cloud(frames.apply(motion, scan.points[scan.mask("workpiece")])), units="m")
    write_ply(folder / "car.ply", scene.workpiece_model())
    sphere = build_scene(shapes.sphere(60.0), seed=1)
    sphere_scan = zoomed_on_workpiece(sphere, -30.0, 1, pixel_pitch_mm=0.6).scan(sphere)
    write_xyz(folder / "sphere.xyz", Cloud(sphere_scan.points[sphere_scan.mask("workpiece")]))
    return folder, motion @ scan.U


@pytest.mark.slow
def test_match_prints_a_summary_and_writes_U_as_json(files, tmp_path, capsys):
    folder, U = files
    out = tmp_path / "match.json"
    code = main(["match", str(folder / "scan_m.ply"), str(folder / "car.ply"), "--units", "m", "--model-units", "mm",
                 "--json", str(out), "--tolerance", "0.2", "--seed", "3"])
    assert code == 0
    data = json.loads(out.read_text())
    matrix = np.array(data["matrix"])  # U: model -> scan, row-major, mm
    assert data["status"] == "ok" and data["method"] == "robust" and data["tolerance_mm"] == 0.2 and data["seed"] == 3
    assert frames.rotation_between_deg(matrix, U) < 0.02 and np.linalg.norm(matrix[:3, 3] - U[:3, 3]) < 0.1
    assert np.allclose(np.array(data["inverse"]) @ matrix, np.eye(4))
    printed = capsys.readouterr().out
    assert printed.startswith("OK") and "Euler ZYZ" in printed and str(out) in printed


@pytest.mark.slow
def test_a_match_with_no_rival_does_not_import_open3d(files, tmp_path):
    """The far-off test's exact distances to a mesh go through open3d's BVH, whose import alone takes
    ~0.3 s and ~50 MB of a match process; a match whose verdict has no rival to weigh needs none of
    them (its best's distances were computed for nothing: a warm bunny match took 3x the time)."""
    import subprocess
    import sys
    from pathlib import Path

    folder, _ = files
    out = tmp_path / "match.json"
    code = f"""
import sys
from workcal_wb.cli import main
code = main(["match", {str(folder / "scan_m.ply")!r}, {str(folder / "car.ply")!r}, "--units", "m", "--model-units",
             "mm", "--json", {str(out)!r}, "--cache", {str(tmp_path / "cache")!r}])
print(code, "open3d" in sys.modules)
"""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=Path(__file__).resolve().parents[2])
    assert done.returncode == 0, done.stderr[-2000:]
    data = json.loads(out.read_text())
    assert data["status"] == "ok" and len(data["candidates"]) == 1  # the best alone: no rival
    assert done.stdout.split()[-2:] == ["0", "False"]


def test_paper_method_by_name(files, tmp_path):
    folder, U = files
    out = tmp_path / "icp.json"
    assert main(["match", str(folder / "scan_m.ply"), str(folder / "car.ply"), "--units", "m", "--model-units", "mm",
                 "--method", "icp", "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["method"] == "icp" and frames.rotation_between_deg(np.array(data["matrix"]), U) < 0.1


def test_wrong_units_are_a_failed_match_with_a_warning(files, capsys):
    folder, _ = files
    # The scan is in metres: read as millimetres it is 1000 times too small for the car.
    code = main(["match", str(folder / "scan_m.ply"), str(folder / "car.ply")])
    captured = capsys.readouterr()
    assert code in (1, 2) and "metres" in captured.out + captured.err


@pytest.mark.slow
def test_scan_without_the_model_exits_1_and_says_why(files, tmp_path, capsys):
    folder, _ = files
    out = tmp_path / "failed.json"
    assert main(["match", str(folder / "sphere.xyz"), str(folder / "car.ply"), "--json", str(out)]) == 1
    data = json.loads(out.read_text())
    assert data["status"] == "failed" and data["reasons"]
    assert "FAILED" in capsys.readouterr().out


@pytest.mark.parametrize("content, message", [
    (None, "does not exist"),
    (b"", "empty"),
    (b"ply\nformat ascii 1.0\nelement vertex 100\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
     b"1 2 3\n4 5 6\n", "data ends after 2"),
    (b"1 2 3\n4 5 nan\n" * 5, "usable points"),
])
def test_bad_scan_file_exits_2_with_the_cause(files, tmp_path, capsys, content, message):
    folder, _ = files
    path = tmp_path / ("scan.xyz" if content and not content.startswith(b"ply") else "scan.ply")
    if content is not None:
        path.write_bytes(content)
    assert main(["match", str(path), str(folder / "car.ply")]) == 2
    assert message in capsys.readouterr().err


def test_planar_model_exits_2(files, tmp_path, capsys):
    folder, _ = files
    u, v = np.meshgrid(np.arange(50.0), np.arange(40.0))
    write_xyz(tmp_path / "plate.xyz", Cloud(np.column_stack([u.ravel(), v.ravel(), np.zeros(u.size)])))
    assert main(["match", str(folder / "sphere.xyz"), str(tmp_path / "plate.xyz")]) == 2
    assert "plate.xyz: the model has its points on a plane" in capsys.readouterr().err


def test_bench_is_a_subcommand():
    args = build_parser().parse_args(["bench", "--out", "table.md", "--quick"])
    assert args.command == "bench" and args.quick and str(args.out) == "table.md"


@pytest.mark.slow
def test_viewpoint_of_a_scan_in_the_scanner_frame(tmp_path, capsys):
    """A scan left in the scanner's own frame: --viewpoint 0 0 0 (in the scan's units) is used as
    given; a viewpoint behind the part is refused with a warning and the viewpoint estimated."""
    scene = build_scene("car", seed=5)
    scan = zoomed_on_workpiece(scene, 30.0, 5, pixel_pitch_mm=0.6).scan(scene)
    write_ply(tmp_path / "scan.ply", Cloud(scan.points[scan.mask("workpiece")]), units="m")  # written in metres
    write_ply(tmp_path / "car.ply", scene.workpiece_model())
    out = tmp_path / "m.json"
    args = ["match", str(tmp_path / "scan.ply"), str(tmp_path / "car.ply"), "--units", "m", "--model-units", "mm",
            "--json", str(out)]
    assert main(args + ["--viewpoint", "0", "0", "0"]) == 0
    data = json.loads(out.read_text())
    assert data["status"] == "ok" and data["viewpoint"]["source"] == "given"
    assert np.allclose(data["viewpoint"]["position_mm"], 0.0)
    assert frames.rotation_between_deg(np.array(data["matrix"]), scan.U) < 0.02
    behind = 2.5 * np.asarray(scan.points[scan.mask("workpiece")].mean(axis=0)) / 1000.0  # past the part, in m
    assert main(args + ["--viewpoint", *map(str, behind)]) == 0
    data = json.loads(out.read_text())
    assert data["viewpoint"]["source"].startswith("estimated")
    assert any("given viewpoint" in w and "from behind" in w for w in data["warnings"])
