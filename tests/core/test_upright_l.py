"""An L-block standing on its foot (legs 80 and 90 mm) beside the bunny, seen with mixed pixels at its
depth edges (simulate.upright_l): wherever the workpiece or the view hides the longer leg's end, the
half turn that swaps its legs fits the block's region as well as the right pose, and only the scan
beside the region tells them apart."""
from pathlib import Path

import numpy as np
import pytest

from workcal_wb.core import frames
from workcal_wb.core.calibration import CalibrationOptions, calibrate
from workcal_wb.core.geometry import Cloud
from workcal_wb.core.match import match
from workcal_wb.core.simulate.scanner import MIXED_JUMP_MM
from workcal_wb.core.simulate.upright_l import GAP_MM, UprightLSpec, upright_l_block, upright_l_scan
from workcal_wb.core.surface import SurfaceModel
from workcal_wb.core.surroundings import judged_in_surroundings

pytestmark = pytest.mark.slow  # every test here calibrates or matches a whole scene

CASE = Path(__file__).parent.parent / "data" / "verdict-cases" / "upright-l-block-beside-bunny.npz"


def test_mixed_pixels_lie_on_their_rays_between_the_surfaces_of_a_depth_edge():
    """Each mixed pixel lies on the ray of its pixel, between the block (or the figurine) in front and
    what lies behind it: off every object's surface, nearer the scanner than the surface behind."""
    cell = upright_l_scan(UprightLSpec(seed=3, workpiece="figurine", mixed_share=0.02))
    mixed = cell.mask("mixed")
    assert 0.003 < mixed.mean() <= 0.02
    models = [SurfaceModel(m) for m in (cell.reference_model, cell.workpiece_model)]
    in_base = frames.apply(cell.B_S, cell.cloud.points[mixed])
    workpiece = frames.apply(frames.invert(cell.W), in_base)
    off = np.minimum(models[0].nearest(in_base, 50.0)[0], models[1].nearest(workpiece, 50.0)[0])
    platform = in_base[:, 2] - 300.0
    assert np.median(np.minimum(off, np.abs(platform))) > 0.5  # between surfaces, not on one
    assert np.median(np.minimum(off, np.abs(platform))) < 4 * MIXED_JUMP_MM


def test_the_scene_stands_as_specified():
    """The block stands on the table, the workpiece beside it within the gap's range seen from above, the
    scan in the scanner's frame with its truth."""
    cell = upright_l_scan(UprightLSpec(seed=5, workpiece="figurine"))
    block = frames.apply(cell.V, cell.reference_model.points)  # in the scanner's frame
    part = frames.apply(cell.U, cell.workpiece_model.points)
    up = cell.up
    assert abs((block @ up).min() - (part @ up).min()) < 0.5  # both rest on the table
    flat = [p - np.outer(p @ up, up) for p in (block, part)]
    from scipy.spatial import cKDTree

    gap = cKDTree(flat[0][::3]).query(flat[1][::3])[0].min()
    assert GAP_MM[0] - 2.0 <= gap <= GAP_MM[1] + 2.0
    on_block = cell.cloud.points[cell.mask("reference")]
    assert np.median(SurfaceModel(cell.reference_model).nearest(frames.apply(frames.invert(cell.V), on_block),
                                                                5.0)[0]) < 0.3


def test_a_region_without_the_longer_legs_end_is_judged_with_the_scan_beside_it():
    """The block's region as automatic regions picked it (the strip of its foot's top the scanner saw
    past the upright lies apart, so the flipped pose the region fits left it out), and the scan beside
    it: on the region alone the flip is never ok; with the scan beside it the right pose is found."""
    data = np.load(CASE)
    cloud = Cloud(data["scan"].astype(float), name="upright L-block region and the scan beside it")
    region, truth = data["region"].astype(np.int64), data["truth"]
    surface = SurfaceModel(upright_l_block().transformed(data["block"]))
    alone = match(cloud.subset(region), surface)
    assert alone.status != "ok" or frames.rotation_between_deg(alone.matrix, truth) < 0.5, alone.reasons
    judged, grown = judged_in_surroundings(cloud, region, np.empty(0, np.int64), surface, alone,
                                           {"seed": 0}, "reference", float(data["spacing"]))
    assert frames.rotation_between_deg(judged.matrix, truth) < 0.1
    assert np.linalg.norm(judged.matrix[:3, 3] - truth[:3, 3]) < 0.3
    assert len(grown) > len(region) + 500  # the strip joined the region


@pytest.mark.parametrize("seed, noise", [(11, 0.1), (24, 0.2)])
def test_an_l_block_on_its_foot_is_never_ok_turned_over(bunny, seed, noise):
    """Two scenes whose block region alone fit the flip best (the reference match "ok" 180 deg off):
    never "ok" with W or V turned over, and W right or the right reference pose among the candidates."""
    cell = upright_l_scan(UprightLSpec(seed=seed, noise_mm=noise), bunny)
    result = calibrate(cell.cloud, cell.workpiece_model, cell.reference_model, options=CalibrationOptions(seed=0))
    right_w = result.W is not None and frames.rotation_between_deg(result.W, cell.W) < 0.3
    assert result.status != "ok" or right_w, result.reasons
    assert result.reference.status != "ok" or frames.rotation_between_deg(result.V, cell.V) < 0.3
    named = [c for c in result.reference.candidates if frames.rotation_between_deg(c.matrix, cell.V) < 1]
    assert right_w or named, result.reasons


def test_the_bound_covers_a_reference_centred_between_a_fold_edge_and_a_silhouette(bunny):
    """The block's length is held only by its edges: a fold edge seen on both faces at one end, a
    silhouette whose last pixels are mixed with the table behind at the other.  The centred pose is
    0.25 mm off along it, alike in every refit; the bound must still cover the error."""
    cell = upright_l_scan(UprightLSpec(seed=26, noise_mm=0.1), bunny)
    result = calibrate(cell.cloud, cell.workpiece_model, cell.reference_model, options=CalibrationOptions(seed=0))
    model = cell.workpiece_model.points
    error = np.linalg.norm(frames.apply(result.W, model) - frames.apply(cell.W, model), axis=1).max()
    assert 0.15 < error < 0.3 and frames.rotation_between_deg(result.W, cell.W) < 0.05  # right, and off by the bias
    held = result.reference.stability["held_by_edges"]
    assert held and held[0]["bias_mm"] > 0.1
    assert result.uncertainty["surface_bound_mm"] >= error and result.uncertainty["surface_edge_bias_mm"] > 0.15
    assert result.status != "ok" or result.uncertainty["surface_bound_mm"] <= result.tolerance_mm
