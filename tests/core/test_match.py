"""The matcher on scans whose pose is known: recovered U against the truth, and every way it must refuse.

Simulated scans give the exact U; each is moved by a random rigid motion first, so no match can
profit from a scan that already sits near its model.  The Stanford bunny scans give a reference pose
good to about 0.1 deg (see the data README).
"""
import functools
import json
import re

import numpy as np
import pytest

from workcal_wb.core import frames
from workcal_wb.core.benchmark.cases import bunny_cases, with_clutter, with_overlap, zoomed_on_workpiece
from workcal_wb.core.benchmark.tables import pose_errors
from workcal_wb.core.errors import InputError, Stopped
from workcal_wb.core.geometry import Cloud
from workcal_wb.core.match import match
from workcal_wb.core.benchmark.verdicts import right
from workcal_wb.core.result import (FEW_POINTS, MISFIT, NOT_A_SURFACE, RMS, SCAN_NOT_SOLID, SYMMETRIC, UNDER_CONSTRAINED,
                                     Candidate, MatchResult, codes)
from workcal_wb.core.simulate import shapes
from workcal_wb.core.simulate.scanner import scan_part
from workcal_wb.core.simulate.scene import build_scene
from workcal_wb.core.surface import SurfaceModel


def _capture(workpiece, seed, azimuth=-30.0, **scene_options):
    """The workpiece region of a zoomed capture, moved by a random motion: (points, model, U)."""
    scene = build_scene(workpiece, seed=seed, **scene_options)
    scan = zoomed_on_workpiece(scene, azimuth, seed).scan(scene)
    motion = frames.random_motion(np.random.default_rng(seed))
    return frames.apply(motion, scan.points[scan.mask("workpiece")]), scene.workpiece_model(), motion @ scan.U


@pytest.fixture(scope="module")
def car():
    points, model, U = _capture("car", seed=3)
    return points, SurfaceModel(model), U


def _errors(result, U, surface):
    return pose_errors(result.matrix, U, surface.vertices)


@pytest.mark.slow
@pytest.mark.parametrize("workpiece, seed, max_deg, max_mm", [
    ("car", 1, 0.01, 0.03), ("car", 2, 0.01, 0.03), ("figurine", 1, 0.3, 0.05)])
def test_recovers_U_from_a_random_pose_without_a_guess(workpiece, seed, max_deg, max_mm):
    points, model, U = _capture(workpiece, seed)
    result = match(Cloud(points, name="scan"), model)
    rotation, displacement = pose_errors(result.matrix, U, model.points)
    assert result.status == "ok", result.reasons
    assert rotation < max_deg and displacement < max_mm
    assert result.fitness > 0.99 and result.rms_mm < 0.15  # 0.1 mm scanner noise


def test_a_match_nothing_waits_for_stops_at_its_next_phase(car, monkeypatch):
    """A match whose ``stop`` is set starts no further phase: set before it, it raises errors.Stopped at
    once; set during the global search, the refinement never starts.  One whose stop stays unset finds
    the pose as without it."""
    import threading

    from workcal_wb.core import match as match_module

    points, model, U = car
    stop = threading.Event()
    stop.set()
    with pytest.raises(Stopped, match="before its model"):
        match(Cloud(points, name="scan"), model, stop=stop)

    stop, searched = threading.Event(), match_module._global_candidates

    def search_then_stop(*args, **kwargs):
        found = searched(*args, **kwargs)
        stop.set()
        return found

    monkeypatch.setattr(match_module, "_global_candidates", search_then_stop)
    with pytest.raises(Stopped, match="before its refine"):
        match(Cloud(points, name="scan"), model, stop=stop)
    monkeypatch.undo()
    result = match(Cloud(points, name="scan"), model, stop=threading.Event())
    rotation, displacement = _errors(result, U, model)
    assert result.status == "ok" and rotation < 0.05 and displacement < 0.1


def test_a_search_whose_best_misfits_searches_again_unless_told_not_to(monkeypatch):
    """A ball's cap holds no pose of the L-block: the verdict's best misfits, and the match searches
    once more with more hypotheses; with search_again off (a calibration's clusters that may hold
    another object) it fails the same way after one search."""
    from workcal_wb.core import match as match_module

    rng = np.random.default_rng(3)
    directions = rng.normal(size=(1500, 3))
    directions[:, 2] = np.abs(directions[:, 2]) + 1.0  # the upper cap of a 40 mm ball
    cap = 40.0 * directions / np.linalg.norm(directions, axis=1, keepdims=True) + rng.normal(0, 0.02, (1500, 3))
    searches, search = [], match_module._global_candidates

    def counted(*args, **kwargs):
        searches.append(kwargs.get("min_voxel"))
        return search(*args, **kwargs)

    monkeypatch.setattr(match_module, "_global_candidates", counted)
    model = SurfaceModel(shapes.l_block())
    for search_again, expected in ((True, 2), (False, 1)):
        searches.clear()
        result = match(Cloud(cap, name="cap"), model, search_again=search_again)
        assert result.status == "failed" and MISFIT in codes(result.reasons), result.reasons
        assert len(searches) == expected


# Poses a feature search handed over for the L-block of the car scene as the large-scan bench's scanner
# sees it (in random draws of its 5M-point scan; here the scene is captured at 0.5 mm pixels), as model ->
# model motions from the truth: slid 29 mm along a face, and turned half about the vertical; each fits what
# it explains as tightly as the right pose (72 % of the block's points against 99 %).
_SLID = frames.from_rotvec(np.radians([0.02, -0.01, 0.09]), (-27.86, 9.56, -0.18))
_TURNED = frames.rigid(frames.rot_z(180.0), (1023.04, 307.31, 0.0))


@pytest.mark.slow
@pytest.mark.parametrize("handed_over", [_SLID, _TURNED], ids=["slid", "turned"])
def test_a_block_seen_in_part_is_found_from_a_slid_or_turned_pose_the_search_hands_over(monkeypatch, handed_over):
    """A block seen on a few faces maps onto itself about another axis than the whole block does: its
    best pose's turns land a few centimetres from home, where refining settles on a face slid along
    another, as tight a fit as the right pose's but explaining less of the scan.  From such a pose alone
    the right one is found, "ok": the pose, its rivals and their turns are each moved first by the shift
    that puts most scan points on the model."""
    from workcal_wb.core import match as match_module
    from workcal_wb.core.benchmark.cases import large_scanner

    scene = build_scene("car", seed=0)
    capture = large_scanner(scene, 0, 0.5, (0.0, 0.0)).scan(scene)
    block = capture.points[capture.mask("reference")]
    V = frames.invert(capture.B_S)  # the reference model (in B) placed in the scanner's frame
    start = handed_over @ frames.invert(V)
    monkeypatch.setattr(match_module, "_global_candidates", lambda *args, **kwargs: [(start, 1.0)])
    model = scene.reference_model()
    result = match(Cloud(block, name="L-block"), SurfaceModel(model))
    assert result.status == "ok", result.reasons
    rotation, displacement = pose_errors(result.matrix, V, model.points)
    assert rotation < 0.05 and displacement < 0.05


@pytest.mark.slow
def test_partial_overlap(car):
    points, surface, U = car
    part = with_overlap(points, np.random.default_rng(4), fraction=0.4)
    result = match(Cloud(part), surface)
    rotation, displacement = _errors(result, U, surface)
    assert result.status == "ok" and rotation < 0.03 and displacement < 0.06


def test_clutter_table_box_and_stray_points(car):
    points, surface, U = car
    up = frames.apply_vectors(shapes.CAR_BODY_IN_X, np.array([[0.0, 0.0, 1.0]]))[0]
    scene = with_clutter(points, U, Cloud(surface.vertices, triangles=surface.triangles), up, np.random.default_rng(5))
    assert len(scene) > 2.4 * len(points)  # as much table and box as part, then 20 % stray points
    result = match(Cloud(scene), surface)
    rotation, displacement = _errors(result, U, surface)
    assert result.status == "ok" and rotation < 0.02 and displacement < 0.05
    assert 0.3 < result.fitness < 0.5  # the part is about 40 % of the scene


@pytest.mark.slow
def test_clay_added_and_carved_does_not_pull_the_pose():
    points, model, U = _capture("car", seed=6, clay_change=["lump", "carve"])
    result = match(Cloud(points), model)
    rotation, displacement = pose_errors(result.matrix, U, model.points)
    assert result.status == "ok" and rotation < 0.02 and displacement < 0.05
    assert result.within_tolerance_pct < 99  # the changed clay is there, just not followed


def test_an_initial_guess_is_refined_and_a_wrong_one_is_not_trusted(car):
    points, surface, U = car
    nudge = frames.from_euler_zyz(1.0, 1.5, -1.0, (2.0, -1.0, 1.5))
    result = match(Cloud(points), surface, init=U @ nudge)
    rotation, displacement = _errors(result, U, surface)
    assert result.status == "ok" and rotation < 0.01 and displacement < 0.03
    wrong = match(Cloud(points), surface, init=U @ frames.from_euler_zyz(0.0, 90.0, 0.0))
    assert wrong.status == "failed" or _errors(wrong, U, surface)[0] < 0.1


def test_same_seed_same_answer(car):
    points, surface, _ = car
    first, second = (match(Cloud(points), surface, seed=11) for _ in range(2))
    assert np.array_equal(first.matrix, second.matrix)


def _axes(result, kind):
    pattern = rf"{kind} about axis \(([-\d.]+), ([-\d.]+), ([-\d.]+)\) through \(([-\d.]+), ([-\d.]+), ([-\d.]+)\)"
    return [np.array(m.groups(), float) for m in map(re.compile(pattern).search, result.stability["free_motions"]) if m]


def _symmetric_capture(mesh, seed=1):
    scene = build_scene(mesh, seed=seed)
    scan = zoomed_on_workpiece(scene, -30.0, seed, pixel_pitch_mm=0.4).scan(scene)
    return scan.points[scan.mask("workpiece")], scan.U


@pytest.mark.slow
def test_cylinder_is_under_constrained_about_its_axis():
    points, _ = _symmetric_capture(shapes.cylinder())
    result = match(Cloud(points), shapes.cylinder())
    assert result.status == "ambiguous"
    assert UNDER_CONSTRAINED in codes(result.reasons)
    axes = _axes(result, "rotation")
    assert len(axes) == 1 and abs(axes[0][2]) > 0.99 and np.hypot(*axes[0][3:5]) < 1.0  # the z axis


@pytest.mark.slow
def test_sphere_leaves_three_rotations_about_its_centre_free():
    points, _ = _symmetric_capture(shapes.sphere())
    result = match(Cloud(points), shapes.sphere())
    assert result.status == "ambiguous" and len(result.stability["free_motions"]) == 3
    for axis in _axes(result, "rotation"):  # each axis passes (nearly) through the centre, the origin
        direction, point = axis[:3] / np.linalg.norm(axis[:3]), axis[3:]
        assert np.linalg.norm(point - (point @ direction) * direction) < 2.0
    assert len(_axes(result, "rotation")) == 3


@pytest.mark.slow
@pytest.mark.parametrize("mesh, orders", [(shapes.box((80.0, 50.0, 30.0), edge_mm=2.0), [2, 2, 2]),
                                           (shapes.ellipsoid(), [2, 2, 2]), (shapes.vase(), [0])],
                         ids=["box", "ellipsoid", "vase"])
def test_symmetric_part_is_ambiguous_and_names_its_symmetries(mesh, orders):
    points, U = _symmetric_capture(mesh)
    result = match(Cloud(points), mesh)
    assert result.status == "ambiguous"
    assert sorted(s["order"] for s in result.symmetries) == sorted(orders)
    assert SYMMETRIC in codes(result.reasons)
    assert all(c.matrix.shape == (4, 4) for c in result.candidates)
    # Whatever pose was picked, it is one the part cannot be told from: model points land on the
    # surface (to a few tenths: the box is seen almost edge-on on one face, which pins it weakly).
    surface = SurfaceModel(mesh)
    moved = frames.apply(frames.invert(U) @ result.matrix, surface.points[::50])
    _, idx, found = surface.nearest(moved, 5.0)
    assert found.all() and np.percentile(np.abs(surface.plane_residuals(moved, idx)), 95) < 0.3
    # Candidates are distinct up to the symmetries: no twin that a symmetry maps onto the best.
    for candidate in result.candidates[1:]:
        twin = candidate.matrix
        assert not surface.maps_onto_itself(frames.invert(twin) @ result.matrix)


@pytest.mark.slow
def test_scan_of_something_else_fails(car):
    _, surface, _ = car
    points, _ = _symmetric_capture(shapes.sphere(60.0))
    result = match(Cloud(points), surface)
    assert result.status == "failed"
    assert {FEW_POINTS, MISFIT} & set(codes(result.reasons)), result.reasons


@pytest.mark.slow
def test_flat_face_of_a_block_on_a_car_panel_is_not_trusted(car):
    """One face of the L-block fits a gently curved panel of the car to 0.3 mm; what gives it away
    is that such a fit can slide: it must not come back "ok"."""
    _, surface, _ = car
    points, _ = _symmetric_capture(shapes.l_block())
    result = match(Cloud(points), surface)
    assert result.status in ("failed", "ambiguous") and result.reasons


def test_planar_and_line_scans_fail_with_the_cause(car):
    _, surface, _ = car
    u, v = np.meshgrid(np.linspace(0, 100, 40), np.linspace(0, 80, 40))
    plane = np.column_stack([u.ravel(), v.ravel(), 0.01 * np.random.default_rng(0).normal(size=u.size)])
    line = np.column_stack([np.linspace(0, 200, 500), np.zeros(500), np.zeros(500)])
    for points, words in ((plane, "lie on a plane"), (line, "lie on a line")):
        reason = match(Cloud(points), surface).reasons[0]
        assert reason.code == SCAN_NOT_SOLID and words in str(reason)
    assert match(Cloud(plane), surface).status == "failed"


def test_a_volume_of_points_is_not_a_scan(car):
    _, surface, _ = car
    blob = np.random.default_rng(1).normal(0.0, 40.0, (20000, 3))
    result = match(Cloud(blob), surface)
    assert result.status == "failed" and result.reasons[0].code == NOT_A_SURFACE


def test_bad_input_is_refused_with_the_cause(car):
    points, surface, _ = car
    with pytest.raises(InputError, match="only 10 usable points"):
        match(Cloud(points[:10], name="scan"), surface)
    with pytest.raises(InputError, match="contains no points"):
        match(Cloud(np.empty((0, 3)), name="scan"), surface)
    with pytest.raises(InputError, match="NaN or infinite"):
        match(Cloud(np.full((100, 3), np.nan), name="scan"), surface)
    with pytest.raises(InputError, match="flat model: the model has its points on a plane"):
        match(Cloud(points), Cloud(np.column_stack([points[:, :2], np.zeros(len(points))]), name="flat model"))
    with pytest.raises(InputError, match="unknown match method"):
        match(Cloud(points), surface, method="magic")
    with pytest.raises(InputError, match="tolerance"):
        match(Cloud(points), surface, tolerance_mm=0.0)
    with pytest.raises(InputError, match="viewpoint must be three finite"):
        match(Cloud(points), surface, viewpoint=(0.0, float("nan"), 1.0))


def test_nan_and_duplicate_points_are_dropped_with_a_warning(car):
    points, surface, U = car
    dirty = np.vstack([points, points[:500], np.full((300, 3), np.inf)])
    result = match(Cloud(dirty, name="scan"), surface)
    assert result.status == "ok" and _errors(result, U, surface)[0] < 0.01
    assert any("300 points with NaN" in w for w in result.warnings)
    assert any("500 duplicate" in w for w in result.warnings)


def test_result_round_trips_through_json(car):
    points, surface, _ = car
    result = match(Cloud(points, name="scan"), surface)
    data = json.loads(json.dumps(result.to_dict()))
    again = MatchResult.from_dict(data)
    assert again.status == result.status and np.array_equal(again.matrix, result.matrix)
    assert json.dumps(again.to_dict(), sort_keys=True) == json.dumps(result.to_dict(), sort_keys=True)
    assert np.allclose(np.array(data["inverse"]) @ np.array(data["matrix"]), np.eye(4))


@functools.lru_cache(maxsize=1)
def _bunny_set(folder):
    return bunny_cases(folder, seed=3, scans=("bun045.ply", "top2.ply"))


@pytest.fixture
def bunny_set(bunny):
    return _bunny_set(bunny)


@pytest.mark.slow
def test_bunny_scans_every_degradation(bunny_set):
    """Every degradation is matched; the noisy one (0.5 mm added) only at a tolerance above its noise."""
    surface = SurfaceModel(bunny_set[0].model)
    for case in bunny_set:
        noisy = "noise" in case.name
        result = match(Cloud(case.scan, name=case.name), surface, tolerance_mm=1.0 if noisy else 0.3)
        rotation, displacement = pose_errors(result.matrix, case.truth, case.model.points)
        assert result.status == "ok", (case.name, result.reasons)
        assert rotation < 1.0 and displacement < 1.0, case.name
        if noisy:
            assert 0.4 < result.noise_mm < 0.7
            assert match(Cloud(case.scan), surface).status == "failed"


@pytest.mark.slow
def test_bunny_scan_against_the_car_model_fails(bunny_set, car):
    result = match(Cloud(bunny_set[0].scan), car[1])
    assert result.status == "failed"


def test_a_duplicate_is_found_when_another_point_shares_its_key():
    """The duplicate search compares points that share a key with their neighbour in key order: two
    different points with the same key could sort between two copies of one point and hide them (the
    key is linear in the coordinates' bits: 1000003 - 999983 - 20 = 0).  Found by a reviewer (helper):
    [P, Q, P] kept all three, and 96 copies on a 0.5 mm lattice were missed."""
    from workcal_wb.core import geometry

    one = np.float64(1.0).view(np.int64)
    p = np.ones(3)
    q = np.array([one + 1, one - 1, one - 20]).view(np.float64)
    assert geometry._duplicates(np.array([p, q, p])).tolist() == [False, False, True]
    assert geometry._duplicates(np.array([p, 2 * p])).tolist() == [False, False]  # no candidate left
    assert geometry._duplicates(p[None]).tolist() == [False]
    lattice = np.random.default_rng(0).integers(0, 17, (5000, 3)) * 0.5
    first = np.zeros(len(lattice), bool)
    first[np.unique(lattice, axis=0, return_index=True)[1]] = True
    assert np.array_equal(geometry._duplicates(lattice), ~first)


def _warped_car_scan(amplitude_mm: float):
    """(the car's model, a scan of it whose surface waves ``amplitude_mm`` up and down: the part
    differs from its model, far less noisy than that) and the truth."""
    mesh = shapes.car()
    captured = scan_part(mesh, np.eye(4), [0.3, -0.5, 0.8], noise_sigma_mm=0.05, seed=0, samples=20000)
    points = captured.cloud().points.copy()
    points[:, 2] += amplitude_mm * np.sin(points[:, 0] / 9.0) * np.cos(points[:, 1] / 7.0)
    return mesh, Cloud(points, name="warped car"), captured.V


@pytest.mark.slow
@pytest.mark.parametrize("amplitude_mm, status", [(0.5, "ok"), (1.0, "failed")])
def test_a_match_is_ok_only_as_a_calibration_gate_would_pass_its_region(amplitude_mm, status):
    """A car scanned at 0.05 mm noise whose surface waves against its model: at 0.5 mm the fit's RMS is
    0.19 mm, under the 0.3 mm tolerance; at 1.0 mm it is 0.37 mm, which a calibration refuses of either
    region, and so does a match (its fit, 9 noises, is not far enough off to be a misfit)."""
    mesh, scan, truth = _warped_car_scan(amplitude_mm)
    surface = SurfaceModel(mesh, 0)
    result = match(scan, surface, tolerance_mm=0.3, seed=0)
    assert right(surface, result.matrix, truth)
    assert result.status == status, result.reasons
    if status == "failed":
        assert RMS in codes(result.reasons) and result.rms_mm > 0.3


@pytest.mark.slow
def test_a_fit_worse_than_the_noise_asks_more_standard_errors_of_a_rival():
    """The car whose surface waves 1 mm against its model, matched to a 1 mm tolerance: the fit is
    several times its 0.05 mm noise, so a rival must be more standard errors behind the best than
    rival_significance (3) to be ruled out, by as many times as the fit is past twice the noise (as a
    least-squares fit's standard errors stretch with its residual); a pose 3.2 behind is then a rival,
    by the view and by the points it leaves far off."""
    from workcal_wb.core.match import MatchOptions, _mark_rivals

    mesh, scan, truth = _warped_car_scan(1.0)
    result = match(scan, SurfaceModel(mesh, 0), tolerance_mm=1.0, seed=0)
    required = result.view["required_standard_errors"]
    assert required > 2 * MatchOptions().rival_significance
    assert all(c.rival for c in result.candidates[1:] if c.standard_errors_below_best < required)

    best = Candidate(np.eye(4), score=1.0, fits=True)
    turned = Candidate(frames.rigid(frames.rot_z(180.0)), score=0.9, standard_errors_below_best=3.2,
                       far_off_standard_errors=3.2, turn_of_best=True, fits=True)
    _mark_rivals([best, turned], True, required, MatchOptions())
    assert turned.rival


def test_a_scan_of_denormal_numbers_is_said_to_lie_at_one_point():
    """Coordinates of about 1e-310 mm: every point within a nanometre of one, said in words."""
    scan = Cloud(np.random.default_rng(0).normal(size=(500, 3)) * 1e-310, name="tiny.xyz")
    result = match(scan, SurfaceModel(shapes.sphere(), 0))
    assert result.status == "failed" and codes(result.reasons) == [SCAN_NOT_SOLID]
    assert "tiny.xyz: the scan points lie all at one point (or within a nanometre of it)" in result.reasons[0].text


def test_a_model_of_denormal_numbers_is_said_to_lie_at_one_point():
    model = Cloud(np.random.default_rng(0).normal(size=(500, 3)) * 1e-310, name="tiny.xyz")
    with pytest.raises(InputError, match=r"tiny.xyz: the model has its points all at one point \(or within a "
                                         r"nanometre of it\); a pose cannot be fitted to it"):
        SurfaceModel(model)
