"""``python3 -m workcal_wb simulate``: every file written, and each reads back as what the API gives."""
import json

import numpy as np

from workcal_wb.cli import EXIT_BAD_INPUT, EXIT_OK, main
from workcal_wb.core import frames
from workcal_wb.core.readers import read_cloud
from workcal_wb.core.simulate.scanner import scanner_ring
from workcal_wb.core.simulate.scene import build_scene
from workcal_wb.core.simulate.toolpath_sample import sample_toolpath_points
from workcal_wb.core.toolpath import read_gcode


def test_simulate_writes_scans_models_and_truth(tmp_path, capsys):
    out = tmp_path / "sim"
    assert main(["simulate", "--out", str(out), "--workpiece", "figurine", "--seed", "3", "--positions", "2",
                 "--noise", "0.05", "--lump"]) == EXIT_OK
    printed = capsys.readouterr().out
    assert "W = ^B X" in printed and "Omega" in printed and "scan_2.ply" in printed
    assert sorted(p.name for p in out.iterdir()) == ["manifest.json", "reference.ply", "scan_1.ply", "scan_2.ply",
                                                      "toolpath.nc", "truth.json", "workpiece.ply"]
    truth = json.loads((out / "truth.json").read_text())
    scene = build_scene("figurine", seed=3, clay_change=["lump"])
    assert np.allclose(truth["W"], scene.W) and truth["clay_change"]["vertices"] > 0

    ring = scanner_ring(scene, 2, seed=3, noise_sigma_mm=0.05)
    for entry, scanner in zip(truth["scans"], ring):
        scan = read_cloud(out / entry["file"])
        expected = scanner.scan(scene)
        assert len(scan) == entry["points"]["total"] == len(expected.points)
        assert np.allclose(scan.points, expected.points)
        assert np.allclose(np.array(entry["W"]), frames.invert(np.array(entry["V"])) @ np.array(entry["U"]))
        assert entry["scanner"]["noise_sigma_mm"] == 0.05

    workpiece, reference = read_cloud(out / "workpiece.ply"), read_cloud(out / "reference.ply")
    assert workpiece.is_mesh and np.allclose(workpiece.points, scene.workpiece_model().points)
    assert np.array_equal(workpiece.triangles, scene.workpiece_model().triangles)
    assert reference.is_mesh and np.allclose(reference.points, scene.reference_model().points)
    toolpath = read_gcode(out / "toolpath.nc")
    assert np.allclose(toolpath.points()[1:-1], sample_toolpath_points(scene)[0], atol=1e-4)


def test_simulate_single_position_and_bad_input(tmp_path, capsys):
    assert main(["simulate", "--out", str(tmp_path), "--pitch", "1.5", "--clutter", "--carve"]) == EXIT_OK
    truth = json.loads((tmp_path / "truth.json").read_text())
    assert [s["file"] for s in truth["scans"]] == ["scan.ply"]
    assert truth["scans"][0]["scanner"]["pixel_pitch_mm"] == 1.5
    assert truth["scans"][0]["points"]["clutter"] > 0
    assert len(read_cloud(tmp_path / "scan.ply")) == truth["scans"][0]["points"]["total"]
    assert main(["simulate", "--out", str(tmp_path), "--positions", "0"]) == EXIT_BAD_INPUT
    assert "--positions" in capsys.readouterr().err
