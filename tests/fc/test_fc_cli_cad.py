"""Headless commands under freecadcmd read CAD models (STEP) through the FreeCAD layer."""
import json

import numpy as np
import pytest

FreeCAD = pytest.importorskip("FreeCAD")

import Part  # noqa: E402

from workcal_wb.cli import main  # noqa: E402
from workcal_wb.cli.simulate import write_simulation  # noqa: E402
from workcal_wb.core import frames  # noqa: E402
from workcal_wb.core.simulate.scene import REFERENCE_BOXES  # noqa: E402


def _as_step(scene, step_file):
    """The reference block as a STEP solid, as a CAD user would have it: its two arms (the boxes the
    simulated mesh is made of) fused and placed where the scene has it.  (Sewing the 2 mm mesh into a
    solid instead took minutes.)"""
    arms = [Part.makeBox(*(np.subtract(hi, lo)), FreeCAD.Vector(*lo)) for lo, hi in REFERENCE_BOXES]
    solid = arms[0].fuse(arms[1:]).removeSplitter()
    solid.transformShape(FreeCAD.Matrix(*scene.reference.pose.flatten()))
    solid.exportStep(str(step_file))


@pytest.mark.slow
def test_calibrate_with_a_step_reference(tmp_path):
    scene = tmp_path / "scene"
    simulated, _ = write_simulation(scene, "car", seed=11, pitch=0.6)
    _as_step(simulated, scene / "reference.step")
    documents = set(FreeCAD.listDocuments())
    assert main(["calibrate", "--scan", str(scene / "scan.ply"), "--workpiece", str(scene / "workpiece.ply"),
                 "--reference", str(scene / "reference.step"), "--out", str(tmp_path / "out")]) == 0
    assert set(FreeCAD.listDocuments()) == documents  # the scratch document is gone
    W = np.array(json.loads((tmp_path / "out" / "result.json").read_text())["W"])
    W_true = np.array(json.loads((scene / "truth.json").read_text())["W"])
    assert frames.rotation_between_deg(W, W_true) < 0.02 and np.linalg.norm(W[:3, 3] - W_true[:3, 3]) < 0.05


def test_unreadable_step_is_a_clear_error(tmp_path, capsys):
    bad = tmp_path / "broken.step"
    bad.write_text("ISO-10303-21; this is not a STEP file")
    points = tmp_path / "points.xyz"
    np.savetxt(points, np.random.default_rng(0).normal(size=(200, 3)) * 50)
    code = main(["calibrate", "--scan", str(points), "--workpiece", str(points), "--reference", str(bad),
                 "--out", str(tmp_path / "out")])
    assert code == 2 and "broken.step: cannot be read as a STEP file" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
