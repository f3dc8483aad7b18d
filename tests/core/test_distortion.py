"""The scan's strain against its models (distortion.py), measured at the true poses of a cell scan."""
from dataclasses import replace

import numpy as np
import pytest

from workcal_wb.core import frames
from workcal_wb.core.distortion import READING, _linearised, distortion
from workcal_wb.core.simulate import shapes
from workcal_wb.core.simulate.cell import CellSpec, cell_scan
from workcal_wb.core.surface import SurfaceModel


@pytest.fixture(scope="module")
def cell():
    cell = cell_scan(CellSpec(frame="arbitrary", seed=5))
    return cell, [SurfaceModel(m, 0) for m in (cell.workpiece_model, cell.reference_model)]


def _measured(cell, linear: np.ndarray) -> dict:
    """The scan's regions moved by ``linear``, each about its own middle: the same strain to within a
    rigid shift per region, which its match takes up (so the points stay as near their models at the
    true poses as after a match: the fit is linearised)."""
    scan, surfaces = cell
    regions = [scan.cloud.points[scan.mask(role)] for role in ("workpiece", "reference")]
    moved = [r.mean(axis=0) + (r - r.mean(axis=0)) @ linear.T for r in regions]
    return distortion(moved, surfaces, [scan.U, scan.V], surfaces[0].points, [1.0, 1.0])


@pytest.mark.slow
def test_a_scale_is_measured(cell, monkeypatch):
    """What a scale adds to what the undistorted scan shows (its noise, counted here however small:
    0.005-0.013 % over eight such scenes at 0.1 mm of noise, 0.006-0.013 % before the foot became the
    lever) is that scale, to 3 %: the scanner's commonest error, shown by both objects."""
    monkeypatch.setattr("workcal_wb.core.distortion.READING", replace(READING, significance=0.0))
    undistorted, found = (_measured(cell, np.eye(3) * scale) for scale in (1.0, 1.001))
    assert np.abs(undistorted["strain"]).max() < 2e-4 and undistorted["shift_mm"] < 0.05, undistorted
    assert np.abs(found["strain"] - undistorted["strain"] - 0.001 * np.eye(3)).max() < 3e-5, found["strain"]
    assert found["shift_mm"] > 0.2  # 0.1 % over the 300 mm between the objects, and their turns


def test_a_strain_is_measured_as_far_as_the_reference_shows_it(cell):
    """Stretches and shears as well as a scale: the L-shaped reference shows five of the six strains, so
    what leaks from the sixth leaves the largest strain within a fifth."""
    strain = np.array([[0.0008, 0.0004, 0], [0.0004, -0.0006, 0.0002], [0, 0.0002, 0.001]])
    found = _measured(cell, np.eye(3) + strain)
    largest = 100 * np.abs(np.linalg.eigvalsh(strain)).max()
    assert found["largest_strain_pct"] == pytest.approx(largest, rel=0.2), found
    assert found["shift_mm"] > 0.2


@pytest.mark.parametrize("linear, scale, largest", [
    (np.diag([1.0, 1.0, 1.01]), 1 / 3, 1.0),  # read as 0.44 % and 1.09 % once
    (np.eye(3) * 1.02, 2.0, 2.0),  # read as 1.39 % once, and the workpiece's 2 % taken as its own
    (np.eye(3) + np.array([[0.008, 0.004, 0], [0.004, -0.006, 0.002], [0, 0.002, 0.01]]), 0.4, 1.04),
], ids=["depth 1 %", "scale 2 %", "mixed 1 %"])
def test_a_large_strain_is_read_whole_not_taken_as_the_parts_own(cell, linear, scale, largest):
    """Linearised once at the matched poses, a strain of a percent read short: it moves the ends of a
    region beyond the gates, and what is left near the middle shows less of it; the workpiece then read
    more than the reference and its strain went as its own.  The fit is linearised again where each
    step leaves the points."""
    found = _measured(cell, linear)
    assert found["scale_pct"] == pytest.approx(scale, rel=0.05), found
    assert found["largest_strain_pct"] == pytest.approx(largest, rel=0.05), found
    assert found["workpiece_own_pct"] == 0.0


def test_a_turned_scan_is_not_strained(cell):
    """A whole-scan turn (0.06 deg) is a rigid motion: each match takes it up, W does not move."""
    turn = frames.from_rotvec(np.array([0.0004, -0.0006, 0.0007]))[:3, :3]
    found = _measured(cell, turn)
    undistorted = _measured(cell, np.eye(3))
    assert np.abs(found["strain"] - undistorted["strain"]).max() < 3e-5, found  # 1e-3 rad turns: 3 % of it
    assert abs(found["shift_mm"] - undistorted["shift_mm"]) < 0.01, found


@pytest.mark.slow
def test_strains_a_small_part_beside_flat_faces_cannot_show_are_not_read_from_noise(monkeypatch):
    """A 15 mm figurine beside the L-shaped reference: some stretches and shears are nearly rigid on both,
    and read along those the undistorted scan's noise came out as a 0.2 % strain (a tester's figurine
    scene: 1-4 %, W "moved" 1-2 mm, truly 0.02 mm).  Only the directions the scan shows count; and each
    point's lever is its foot on its face, not the point, whose noise moved lever and residual together:
    now with every direction counted and nothing left out as noise the scan reads none."""
    scan = cell_scan(CellSpec(workpiece="figurine", frame="arbitrary", seed=1))
    surfaces = [SurfaceModel(m, 0) for m in (scan.workpiece_model, scan.reference_model)]
    regions = [scan.cloud.points[scan.mask(role)] for role in ("workpiece", "reference")]
    found = distortion(regions, surfaces, [scan.U, scan.V], surfaces[0].points, [1.0, 1.0])
    assert found["largest_strain_pct"] < 0.03 and found["shift_mm"] < 0.02, found
    # every direction counts, however little it explains
    monkeypatch.setattr("workcal_wb.core.distortion.READING", replace(READING, shown_mm=0.0, significance=0.0))
    assert distortion(regions, surfaces, [scan.U, scan.V], surfaces[0].points, [1.0, 1.0])["largest_strain_pct"] < 0.03


@pytest.mark.slow
def test_noise_at_a_blocks_edges_is_not_read_as_a_strain():
    """The L-block seen low (25 deg) through 0.35 mm of range noise, at the true poses: near its edges a
    point pushed into the block is nearer the side face, so measured against its closest face its noise
    reads short on one side: a 0.04 % scale, a 0.17 mm "shift" (0.20 mm against the nearest samples'
    planes with the points as levers, the check before).  The points near its edges are left out (with
    the few beyond the gate, about a tenth of them).  One scene's draw of noise: the mean over many draws
    is in distortion.FIT.edge_deg's comment."""
    scan = cell_scan(CellSpec(frame="arbitrary", seed=5, noise_mm=0.35, elevation_deg=25.0))
    surfaces = [SurfaceModel(m, 0) for m in (scan.workpiece_model, scan.reference_model)]
    regions = [scan.cloud.points[scan.mask(role)] for role in ("workpiece", "reference")]
    gates = [1.65, 1.65]  # as wide as the calibration's (its matches' gates: 1.3-1.65 mm in such scenes)
    found = distortion(regions, surfaces, [scan.U, scan.V], surfaces[0].points, gates)
    assert found["shift_mm"] == 0.0 and not np.any(found["strain"]), found
    counted = _linearised(regions[1], surfaces[1], scan.V, gates[1], regions[1].mean(axis=0))[0]
    assert 0.8 * len(regions[1]) < len(counted) < 0.95 * len(regions[1])


def test_a_wall_thinner_than_two_gates_is_not_taken_for_an_edge():
    """A plate 2 mm thick under a 1.65 mm gate: the face nearest a probe a gate inside a point on its top is
    the bottom, turned right round; that is the wall's back, not an edge, and the point counts (were it
    taken for an edge every point of a shell or a plate would be left out, and the check fall silent)."""
    plate = SurfaceModel(shapes.box(size=(200.0, 200.0, 2.0), edge_mm=5.0), 0)
    rng = np.random.default_rng(0)
    top = np.column_stack([rng.uniform(-90, 90, (2000, 2)), rng.normal(0, 0.1, 2000)])  # its top face: z = 0
    counted = _linearised(top, plate, np.eye(4), 1.65, top.mean(axis=0))[0]
    assert len(counted) == len(top)


def test_regions_with_no_point_near_their_models_measure_no_strain(cell):
    scan, surfaces = cell
    far = [scan.cloud.points[scan.mask(role)] + 50.0 for role in ("workpiece", "reference")]
    found = distortion(far, surfaces, [scan.U, scan.V], surfaces[0].points, [1.0, 1.0])
    assert found["shift_mm"] == 0.0 and not np.any(found["strain"])


def test_a_strain_within_the_noise_of_few_points_is_none(cell):
    """250 points per region: their noise alone reads as a strain of up to 0.1 %, not significant; a
    0.3 % scale is."""
    scan, surfaces = cell
    rng = np.random.default_rng(3)
    regions = [rng.choice(scan.cloud.points[scan.mask(role)], 250, replace=False) for role in ("workpiece", "reference")]
    undistorted = distortion(regions, surfaces, [scan.U, scan.V], surfaces[0].points, [1.0, 1.0])
    assert undistorted["shift_mm"] == 0.0 and not np.any(undistorted["strain"])
    about = regions[0].mean(axis=0)
    scaled = distortion([about + 1.003 * (r - about) for r in regions], surfaces, [scan.U, scan.V],
                        surfaces[0].points, [1.0, 1.0])
    assert scaled["scale_pct"] == pytest.approx(0.3, abs=0.05) and scaled["shift_mm"] > 0.3, scaled


def test_the_check_costs_a_calibrate_process_no_scipy_stats():
    """scipy.stats for one chi-square quantile cost every calibrate process 0.22 s and 23 MB at start-up;
    scipy.special, loaded anyway, has it."""
    import subprocess
    import sys
    from pathlib import Path

    done = subprocess.run([sys.executable, "-c", "import sys; import workcal_wb.core.calibration; "
                           "print('scipy.stats' in sys.modules)"], capture_output=True, text=True,
                          cwd=Path(__file__).resolve().parents[2])
    assert done.returncode == 0 and done.stdout.strip() == "False", done.stderr[-2000:]
