"""The match verdict on (nearly) symmetric parts and noisy scans: never "ok" with a wrong pose.

Each scan is a simulated capture of one part alone, from a viewpoint, distance, placement and noise
drawn from the seed, then moved into a frame of its own, so the tests prove the method and not the
generator.  A pose counts as right when it lays the model onto itself within 1 mm where the true
pose does (for a symmetric part: right up to its symmetry).
"""
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from workcal_wb.core import frames, raycast
from workcal_wb.core.benchmark.cases import zoomed_on_workpiece
from workcal_wb.core.geometry import Cloud
from workcal_wb.core.match import match
from workcal_wb.core.result import (FACE_CONTINUED, NOISE_ABOVE_TOLERANCE, OTHER_SIDE, OUTLINE_CONTINUED, RIVAL, SYMMETRIC,
                                     codes)
from workcal_wb.core.simulate import shapes
from workcal_wb.core.simulate.scanner import scan_part
from workcal_wb.core.simulate.scene import build_scene
from workcal_wb.core.surface import SurfaceModel


def _view(mesh, seed, noise=0.1, samples=20000, above=None):
    """(scan points in a frame of their own, true U): ``mesh`` at a random pose, seen 400-900 mm
    away from a random direction, or, with ``above`` (a direction in the mesh's frame), from 35-75
    degrees above the plane across it."""
    rng = np.random.default_rng(seed)
    pose = frames.rigid(Rotation.random(random_state=seed).as_matrix(), rng.uniform(-200, 200, 3))
    direction = rng.normal(size=3)
    if above is not None:
        up = frames.apply_vectors(pose, np.asarray([above], float))[0]
        across = np.cross(up, direction)
        elevation = np.radians(rng.uniform(35, 75))
        direction = np.sin(elevation) * up + np.cos(elevation) * across / np.linalg.norm(across)
    scan = scan_part(mesh, pose, direction, rng.uniform(400, 900), samples=samples, noise_sigma_mm=noise,
                     z_resolution_mm=0.0, seed=seed)
    motion = frames.random_motion(rng)
    return frames.apply(motion, scan.points), motion @ scan.U


def _right(surface, U, truth, limit_mm=1.0) -> bool:
    """Whether U lays the model where the truth does, up to a turn that maps the model onto itself."""
    if U is None:
        return False
    moved = frames.apply(frames.invert(truth) @ U, surface.points[::10])
    return bool(surface.tree.query(moved)[0].max() < limit_mm)


def _turn(surface, axis, degrees):
    """A turn of the model about an axis through its middle (model frame)."""
    centre = surface.points.mean(axis=0)
    R = frames.from_rotvec(np.radians(degrees) * np.asarray(axis, float))[:3, :3]
    return frames.rigid(R, centre - R @ centre)


@pytest.fixture(scope="module")
def near_square_plate():
    """A 100 x 92 x 6 mm plate with a notch off the middle of one edge: turned over or a quarter
    turn about its normal it covers nearly the same outline, and only the notch tells."""
    mesh = shapes.plate(length=100.0, width=92.0, thickness=6.0, notch=(24.0, 10.0), notch_offset=14.0)
    return mesh, SurfaceModel(mesh)


@pytest.mark.slow
@pytest.mark.parametrize("seed, noise", [(0, 0.1), (3, 0.2), (5, 0.3), (11, 0.1)])
def test_near_symmetric_plate_turned_over_is_never_ok(near_square_plate, seed, noise):
    """Seen from one side, the plate turned over (or turned 168 or 90 degrees) leaves part of the
    scan unexplained where the notch moved: the matcher, searching or started at that pose, must
    find the right pose or say the pose is not sure."""
    mesh, surface = near_square_plate
    points, truth = _view(mesh, seed, noise)
    starts = {"search": None,
              "turned over": truth @ _turn(surface, (1, 0, 0), 180.0),
              "168 deg": truth @ _turn(surface, (0, 0, 1), 12.0) @ _turn(surface, (1, 0, 0), 180.0),
              "quarter turn": truth @ _turn(surface, (0, 0, 1), 90.0)}
    for name, start in starts.items():
        result = match(Cloud(points, name="plate"), surface, init=start)
        right = _right(surface, result.matrix, truth)
        assert right or result.status != "ok", (name, result.status, result.reasons)
        assert right or result.reasons, name


@pytest.mark.slow
def test_near_symmetric_plate_seen_well_comes_back_ok_and_right(near_square_plate):
    """The test is not passed by refusing everything: views that show the notch are "ok", right."""
    mesh, surface = near_square_plate
    verdicts = []
    for seed in (0, 3, 4):
        points, truth = _view(mesh, seed, 0.1)
        result = match(Cloud(points), surface)
        verdicts.append((result.status, _right(surface, result.matrix, truth)))
    assert sum(v == ("ok", True) for v in verdicts) >= 2, verdicts
    assert ("ok", False) not in verdicts


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 6])
def test_four_fold_part_is_ambiguous_naming_the_symmetry(seed):
    """A square plate with a square boss: any quarter turn about its normal gives the same surface.
    The model is given in a frame of its own, so the named axis is the normal turned with it."""
    X = frames.from_euler_zyz(25.0 + 40 * seed, 60.0, -35.0, (30.0, -12.0, 44.0))
    mesh = shapes.boss_plate().transformed(X)
    surface = SurfaceModel(mesh)
    normal = frames.apply_vectors(X, np.array([[0.0, 0.0, 1.0]]))[0]
    points, truth = _view(mesh, seed, noise=0.05 * seed, above=normal)
    result = match(Cloud(points), surface)
    assert result.status == "ambiguous", result.reasons
    assert _right(surface, result.matrix, truth)
    fourfold = [s for s in result.symmetries if s["order"] == 4]
    assert len(fourfold) == 1
    assert abs(np.dot(fourfold[0]["axis"], normal)) > 0.999
    assert "turning the part 90 degrees about its axis" in fourfold[0]["description"]
    assert any(r.code == SYMMETRIC and "90 degrees" in str(r) for r in result.reasons)
    # Candidates are listed up to the symmetry: none is the best turned by a quarter turn.
    best = frames.invert(result.matrix)
    for candidate in result.candidates[1:]:
        assert not surface.maps_onto_itself(candidate.to_model @ frames.invert(best))


@pytest.mark.slow
@pytest.mark.parametrize("workpiece, seed", [("car", 2), ("plate", 7)])
def test_noise_above_the_tolerance_is_said_in_one_sentence(workpiece, seed):
    """1.5 mm of sensor noise and a 0.3 mm tolerance: the verdict cannot check the fit to 0.3 mm and
    says so with the measured noise; with a tolerance above the noise the right pose is "ok"."""
    if workpiece == "car":
        scene = build_scene("car", seed=seed)
        scan = zoomed_on_workpiece(scene, -40.0, seed, noise_sigma_mm=1.5, pixel_pitch_mm=0.8).scan(scene)
        motion = frames.random_motion(np.random.default_rng(seed))
        points, truth, model = (frames.apply(motion, scan.points[scan.mask("workpiece")]), motion @ scan.U,
                                scene.workpiece_model())
    else:
        model = shapes.plate(length=160.0, width=100.0, thickness=12.0, notch=(40.0, 25.0), notch_offset=30.0)
        points, truth = _view(model, seed, noise=1.5, samples=40000)
    surface = SurfaceModel(model)
    strict = match(Cloud(points), surface, tolerance_mm=0.3)
    assert strict.status == "failed"
    sentences = [str(r) for r in strict.reasons if r.code == NOISE_ABOVE_TOLERANCE]
    assert len(sentences) == 1 and sentences[0].count(". ") == 0 and "0.3 mm tolerance" in sentences[0]
    assert 0.9 < strict.noise_mm < 1.8  # noise along the rays, measured across the surface
    assert f"{strict.noise_mm:.2f} mm" in sentences[0]
    relaxed = match(Cloud(points), surface, tolerance_mm=2.0)
    assert relaxed.status == "ok", relaxed.reasons
    assert _right(surface, relaxed.matrix, truth, limit_mm=2.0)


@pytest.fixture(scope="module")
def verdict_views():
    """{name: (scan points, true U, surface)}: views of the verdicts table (seed 0) whose right pose
    was reported "ambiguous" or whose search finds a flipped pose first."""
    from workcal_wb.core.benchmark.verdicts import simulated_cases

    wanted = ("notched plate #4,", "curved tile #4,", "rebated plate #1,", "rebated plate #6,")
    surfaces = {}
    return {c.name.split(",")[0]: (c.scan, c.truth, surfaces.setdefault(c.model.name, SurfaceModel(c.model)))
            for c in simulated_cases(0, wanted=wanted)}


@pytest.mark.slow
@pytest.mark.parametrize("name", ["notched plate #4", "curved tile #4", "rebated plate #1"])
def test_right_pose_beats_its_flip_refined_like_it(verdict_views, name, monkeypatch):
    """The half turn puts all but a few tens of the scan's points on the part, and the view's cells
    barely tell it from the right pose.  Never a wrong "ok" (on the same views simulated by ray casting,
    open3d 0.19, the search never proposed the notched plate's right pose and a flip came back "ok"),
    and the right pose is "ok" (both came back ambiguous): the verdict tries the turns of its
    best refined exactly like it, and such a flip, nearly as good by the view's cells, leaves tens of
    scan points ten noises and more off the part where the right pose leaves none: listed, not a rival.
    The rebated plate's flip leaves only ten points off (its search's best was the flip): on the
    ray-cast views, 3.0 standard errors by the normal approximation, one hundredth short."""
    points, truth, surface = verdict_views[name]
    asked, exact = [], surface.exact_distance  # the verdict computes each pose's exact distances once

    def counted(points):
        if sys._getframe(1).f_code.co_name == "_distances":  # the verdict's, not the edge centring's
            asked.append(hash(points.tobytes()))
        return exact(points)

    monkeypatch.setattr(surface, "exact_distance", counted)
    result = match(Cloud(points, name=name), surface)
    assert len(asked) == len(set(asked))
    right = _right(surface, result.matrix, truth)
    assert result.status != "ok" or right, result.reasons
    assert result.status == "ok" and right, result.reasons
    flips = [c for c in result.candidates[1:] if c.rotation_from_best_deg > 170 and c.turn_of_best]
    assert flips and all(c.far_off_standard_errors >= 3 and not c.rival for c in flips)


@pytest.mark.slow
def test_flip_chosen_over_the_right_pose_is_never_ok(verdict_views):
    """The search's best is the flipped plate and the right pose is the rival: the rival leaves no
    point far off that the flip explains, so the flip cannot be "ok"."""
    name = "rebated plate #6"
    points, truth, surface = verdict_views[name]
    result = match(Cloud(points, name=name), surface)
    assert result.status != "ok" or _right(surface, result.matrix, truth), result.reasons


def test_few_points_all_off_one_pose_count_by_their_chance_not_their_sizes():
    """Nine scan points off the rival and none off the best: under two poses that explain the scan
    alike each would be off either pose as likely, so all nine one way has a chance of 2^-9 (mid-p
    2^-10), beyond 3 standard errors however far off each lies (two of them just past the noise
    band scored 2.7 by the normal approximation); eight all one way, or nine and one the other way,
    are within them."""
    from workcal_wb.core.match import far_off_test

    sigma, rng = 0.06, np.random.default_rng(0)
    best = np.abs(rng.normal(0.0, sigma, 4000))
    rival = best.copy()
    rival[:9] = sigma * np.array([3.5, 3.5, 12, 14, 16, 20, 25, 30, 40])
    assert 3.0 < far_off_test(best, rival, sigma) < 3.2
    assert -3.2 < far_off_test(rival, best, sigma) < -3.0
    assert far_off_test(best[1:], rival[1:], sigma) < 3.0
    off_best_too = best.copy()
    off_best_too[10] = 20 * sigma
    assert far_off_test(off_best_too, rival, sigma) < 3.0
    # Poses alike: the points off each one drawn alike, 3 standard errors about as rare as they should be.
    alike = [far_off_test(np.where(rng.random(4000) < 0.003, 20 * sigma, best),
                          np.where(rng.random(4000) < 0.003, 20 * sigma, best), sigma) for _ in range(400)]
    assert np.mean(np.abs(alike) >= 3) <= 0.01


def test_a_right_pose_is_not_pulled_home_by_residuals_of_other_points(near_square_plate):
    """The slide home weighs tries refined on the medium points against the pose's residual scale on
    the same points: a right pose whose own residual scale was taken on other points, five times
    noisier, is left as it is (the tries, back home with the medium points' noise, looked five
    times better and it was "pulled home" onto itself)."""
    from workcal_wb.core.match import _slid_home
    from workcal_wb.core.refine import RefineState
    from workcal_wb.core.robust import MAD_TO_SIGMA

    mesh, surface = near_square_plate
    points, truth = _view(mesh, 5, noise=0.1, samples=4000)
    T = frames.invert(truth)
    noisier = frames.apply(T, points + np.random.default_rng(5).normal(0.0, 0.5, points.shape))
    _, idx, found = surface.nearest_cell(noisier, 2.0)
    sigma = MAD_TO_SIGMA * float(np.median(np.abs(surface.plane_residuals(noisier[found], idx[found]))))
    assert sigma > 0.4
    state = RefineState(T, sigma=sigma, gate=2.0, scale=0.7)
    assert _slid_home(state, points[:3000], surface, 0.1, polish=lambda home: home, hopeless=np.inf) is state


@pytest.mark.slow
def test_view_that_cannot_tell_the_flip_stays_ambiguous(verdict_views):
    """Notched plate #4 with the points the flip leaves off the part cut from the scan: every
    remaining point lies on the part in both poses, so nothing in the scan tells them apart."""
    points, truth, surface = verdict_views["notched plate #4"]
    full = match(Cloud(points), surface)
    flip = min((c for c in full.candidates[1:] if c.rotation_from_best_deg > 90),
               key=lambda c: c.standard_errors_below_best)
    on_flip = surface.exact_distance(frames.apply(flip.to_model, points)) < 0.3
    result = match(Cloud(points[on_flip]), surface)
    assert result.status == "ambiguous", result.reasons
    assert {RIVAL, OTHER_SIDE} & set(codes(result.reasons)), result.reasons


def _thin_mesh_judge():
    """A Judge on a thin cylinder mesh with a flat face (a segment 4 mm out from a corner: no sample
    lies on it) and scan points from on the surface to 30 mm off it, and its saturation distance."""
    from workcal_wb.core.match import FAR_OFF, VERDICT, Judge, MatchOptions

    tube = shapes.cylinder(radius=5.0, height=200.0, edge_mm=4.0)
    corner = tube.points[0]
    tip = corner + 4.0 * (corner - tube.points.mean(axis=0)) / np.linalg.norm(corner - tube.points.mean(axis=0))
    points = np.vstack([tube.points, tip, (corner + tip) / 2])
    flat = [[0, len(points) - 1, len(points) - 2]]
    surface = SurfaceModel(Cloud(points, triangles=np.vstack([tube.triangles, flat]), name="tube"))
    rng = np.random.default_rng(0)
    near = surface.points[rng.choice(len(surface.points), 1500)] + rng.normal(size=(1500, 3)) * rng.uniform(0, 10, (1500, 1))
    by_tip = tip + rng.normal(size=(100, 3)) * 0.5
    sample = np.vstack([near, by_tip])
    judge = Judge(sample, surface, (sample[:50], np.full(50, 0.05)), 1.0, MatchOptions(), [])
    judge.gate = 0.3
    return judge, surface, sample, FAR_OFF.sigmas * judge.gate / VERDICT.evidence_sigmas


def test_far_off_distances_are_exact_wherever_they_can_weigh_less_than_fully():
    judge, surface, sample, saturated = _thin_mesh_judge()
    exact = surface.exact_distance(sample)
    distances = judge._distances(np.eye(4))
    within = exact < saturated
    assert within.sum() > 300 and (~within).sum() > 300, "points on both sides of the saturation distance"
    assert np.array_equal(distances[within], exact[within]), "a point that weighs less than fully got no exact distance"
    assert np.all((distances[~within] == exact[~within]) | np.isposinf(distances[~within]))


def test_far_off_distances_ask_no_exact_query_for_a_pose_far_from_the_mesh():
    judge, surface, sample, _ = _thin_mesh_judge()
    asked = []
    exact = surface.exact_distance
    surface.__dict__["exact_distance"] = lambda points: asked.append(len(points)) or exact(points)
    far = np.eye(4)
    far[:3, 3] = (0.0, 0.0, 500.0)
    assert np.isposinf(judge._distances(far)).all()
    assert sum(asked) == 0, f"{sum(asked)} exact queries for points hundreds of mm off the mesh"


@pytest.mark.slow
def test_a_scale_error_does_not_make_a_wrong_pose_ok():
    """A notched plate seen whole but sparsely (439 points), the scan 1 % too large about its centre (an
    uncalibrated sensor): without the scale error the verdict is "ambiguous" (the plate turned half a
    turn, or seen from its other side, explains the view about as well); with it, a pose 90 deg from
    the truth was reported "ok": it lays the plate's long side face on the model's short one, and the
    64 scan points that run on past that face's end (15 %) were taken for clutter.  Found by a tester
    varying the sensor; the scan is stored, so the test does not depend on the simulator.  On Debian 13,
    with rough poses refined a few steps first (match.SEARCH.pre_refined), the flip is chosen, "ambiguous" with the truth listed as its rival."""
    from workcal_wb.core.benchmark.verdicts import right

    data = np.load(Path(__file__).parent.parent / "data" / "verdict-cases" / "plate-scaled-1pc.npz")
    surface = SurfaceModel(shapes.plate(), 0)
    result = match(Cloud(data["scan"], name="plate scanned 1 % large"), surface, tolerance_mm=0.3, seed=0)
    assert result.status != "ok" or right(surface, result.matrix, data["truth"]), result.candidates[:3]
    if not right(surface, result.matrix, data["truth"]):
        truth_a_rival = any(c.rival and right(surface, c.matrix, data["truth"])
                            for c in result.candidates[1:])  # its flip chosen, the truth listed beside it
        assert truth_a_rival or FACE_CONTINUED in codes(result.reasons), result.reasons


def _plate_rows(x_end: float = 60.0, row_gap: float = 4.0, step: float = 0.7) -> np.ndarray:
    """The points a line scanner leaves on shapes.plate()'s top face and its -y side face (rows
    ``step`` mm apart along x, ``row_gap`` mm across them), the plate running from x = -60 to ``x_end``
    (60: the model's own length): dense along a row, sparse across, exact."""
    xs = np.arange(-60.0, x_end + 1e-9, step)
    top = np.vstack([np.column_stack([xs, np.full_like(xs, y), np.full_like(xs, 6.0)])
                     for y in np.arange(-39.0, 40.0, row_gap)])
    notch = (np.abs(top[:, 0] - 14.0) < 12.0) & (top[:, 1] > 30.0)  # as shapes.plate() cuts it
    side = np.vstack([np.column_stack([xs, np.full_like(xs, -40.0), np.full_like(xs, z)]) for z in (1.0, 3.0, 5.0)])
    return np.vstack([top[~notch], side])


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1, 6])
def test_a_face_running_on_past_the_placed_model_is_never_ok(seed):
    """An exact scan of the notched plate in sparse rows: in the scanner's frame (seed 0) and in
    another (seed 1) the match laid it half a turn round and said "ok", although 220 scan points (6 %)
    then lie in the plane of the top face where the model has its notch or ends: the pixel test of the
    view saw too few of them, the rows leaving the pixels beside the outline empty.  In a third frame
    (seed 6) other evidence already made the pose it found ambiguous."""
    from workcal_wb.core.benchmark.verdicts import right

    rng = np.random.default_rng(seed)
    motion = np.eye(4) if seed == 0 else frames.random_motion(rng)
    surface = SurfaceModel(shapes.plate(), 0)
    result = match(Cloud(frames.apply(motion, _plate_rows()), name="plate rows"), surface, tolerance_mm=0.3, seed=0)
    assert result.status != "ok" or right(surface, result.matrix, motion), result.reasons


@pytest.mark.slow
def test_a_part_longer_than_its_model_is_not_ok():
    """The plate scanned 30 mm longer than its model (another part, or a model of the wrong revision):
    wherever the model is laid, the scanned faces run on past its end."""
    rng = np.random.default_rng(2)
    surface = SurfaceModel(shapes.plate(), 0)
    points = _plate_rows(x_end=90.0, row_gap=6.0) + rng.normal(0, 0.02, (1, 3))
    result = match(Cloud(frames.apply(frames.random_motion(rng), points), name="longer plate"), surface, tolerance_mm=0.3,
                   seed=0)
    assert result.status != "ok"
    assert {FACE_CONTINUED, OUTLINE_CONTINUED} & set(codes(result.reasons)), result.reasons


@pytest.mark.slow
def test_rows_of_the_right_plate_leave_no_face_running_on():
    """The same sparse rows of the plate itself, with noise, in a frame of their own: the right pose is
    found "ok": nothing runs on past its faces (the test that catches a face laid on a shorter one does
    not catch the right pose's edges)."""
    from workcal_wb.core.benchmark.verdicts import right

    rng = np.random.default_rng(1)
    surface = SurfaceModel(shapes.plate(), 0)
    points = _plate_rows()
    points = points + rng.normal(0, 0.02, points.shape)
    motion = frames.from_euler_zyz(*rng.uniform(-180, 180, 3), translation=rng.uniform(-500, 500, 3))
    result = match(Cloud(frames.apply(motion, points), name="plate rows"), surface, tolerance_mm=0.3, seed=0)
    assert result.status == "ok" and right(surface, result.matrix, motion), result.reasons


@pytest.mark.parametrize("seed", [0, 1])
def test_a_low_noise_scan_of_the_right_pose_runs_on_past_no_face(seed):
    """A box seen with 0.01 mm of noise: some points of its faces lie farther than a sample spacing
    from every (randomly placed) mesh sample, and the first test of scan running on past a face
    counted them off the model, in the plane of their face: 106 points (4 %) at the right pose.
    Off now means farther than any point of the mesh can be from its samples (sample_cover)."""
    from workcal_wb.core.benchmark.verdicts import right

    mesh = shapes.box((100.0, 60.0, 40.0), edge_mm=10.0)
    surface = SurfaceModel(mesh, 0)
    points, truth = _view(mesh, seed, noise=0.01)
    result = match(Cloud(points, name="box"), surface, tolerance_mm=0.3, seed=0)
    assert right(surface, result.matrix, truth)
    assert FACE_CONTINUED not in codes(result.reasons), result.reasons


@pytest.mark.slow
def test_a_point_model_is_not_weighed_by_faces_it_does_not_have():
    """An L-block given as points with normals (no faces, so no bound on the gaps its samples leave):
    half the scan points of its right pose lie farther than a spacing from every sample, and were
    counted as running on past its faces (21 %, "ambiguous"); a point model is not weighed so."""
    from workcal_wb.core import pointops
    from workcal_wb.core.benchmark.verdicts import right

    mesh = shapes.l_block()
    points, faces = pointops.sample_triangles(mesh.points, mesh.triangles, 0.8, seed=1)
    normals = pointops.triangle_normals_and_areas(mesh.points, mesh.triangles)[0][faces]
    surface = SurfaceModel(Cloud(points, normals, name="L-block points"), 0)
    scan, truth = _view(mesh, 1, noise=0.05)
    result = match(Cloud(scan, name="L-block"), surface, tolerance_mm=0.3, seed=0)
    assert result.status == "ok" and right(SurfaceModel(mesh, 0), result.matrix, truth), result.reasons


def test_flat_samples_are_those_inside_a_flat_face():
    """SurfaceModel.flat: a plate's samples in the middle of its faces are flat, those along its edges
    are not (the edge band a face's continuation is looked for beyond)."""
    plate = SurfaceModel(shapes.plate(notch=None), 0)
    middle = np.flatnonzero((np.abs(plate.points[:, 2] - 6.0) < 1e-9)
                            & (np.abs(plate.points[:, 0]) < 50) & (np.abs(plate.points[:, 1]) < 30))
    edge = np.flatnonzero((np.abs(np.abs(plate.points[:, 0]) - 60.0) < 0.3) & (np.abs(plate.points[:, 2] - 6.0) < 0.3))
    assert len(middle) > 100 and len(edge) > 10
    assert plate.flat(middle, 2.0).all() and not plate.flat(edge, 2.0).any()


@pytest.mark.slow
@pytest.mark.parametrize("name, model, motion_seed, seed", [
    ("l-block", shapes.l_block, None, 0), ("l-block", shapes.l_block, 103, 1), ("plate", shapes.plate, None, 0)])
def test_a_part_on_a_table_is_not_ok_upside_down(name, model, motion_seed, seed):
    """A part standing on a table that reaches past it, its bottom face in the table's plane, matched in
    the whole scene (no regions, no viewpoint), in the scan's frame and moved to another: with Debian
    12's numpy and scipy the L-block was "ok" half a turn from the truth in both (seeds 0 and 1), turned
    about the vertical, its foot on open table.  Measured: the table
    points under that foot lay on the model's bottom face, whose normals face into the table, so the
    viewpoint estimated from the matched normals came out grazing, 0.2 deg above the table, from where
    the top face does not face the sensor and its 401 scan points past the placed top were not weighed
    as running on from it.  A face resting on the support now has no say in the viewpoint
    (Judge._choose_view), and that pose is "ambiguous" (the top face runs on past its edge).  Neither
    search here finds the right pose (the search of a part on a table in the whole scene: `calibrate`
    takes the platform away first).  The plate's half turn was "ok" until a pose reaching through the
    table stopped being "ok"; that plane is fitted to every scan point within a coarse voxel
    of it, the plate's own lower side points among them, which tilt it 0.6 deg, so that catch is fragile.
    Found by a tester (helper) checking the face-continuation test; the scans are stored."""
    from workcal_wb.core.benchmark.verdicts import right

    data = np.load(Path(__file__).parent.parent / "data" / "verdict-cases" / f"{name}-on-table.npz")
    motion = np.eye(4) if motion_seed is None else frames.random_motion(np.random.default_rng(motion_seed), 500.0)
    surface = SurfaceModel(model(), 0)
    scan = Cloud(frames.apply(motion, data["scan"].astype(float)), name=f"{name} on a table")
    result = match(scan, surface, tolerance_mm=0.3, seed=seed)
    assert result.status != "ok" or right(surface, result.matrix, motion @ data["truth"]), result.reasons


@pytest.mark.parametrize("start_mm", [0.0, 2.2])
def test_a_block_slid_along_a_motion_only_its_edges_hold_is_not_ok(start_mm):
    """The L-block on a table (an exact scan 2.7 mm apart, seen on its top and one long side: only
    the outline holds it along its length), refined from the truth and from the truth slid 2.2 mm
    along that length.  The fit stops 2.2 mm along it, where the count of points off the model is as
    low as anywhere within the reach the edges are looked for in: no edge pins the motion, so it is
    free and the pose no more than "ambiguous", although the faces' eigenvalue ratio along it (0.008)
    is above the one that makes a motion free on its own."""
    from workcal_wb.core.benchmark.verdicts import right

    data = np.load(Path(__file__).parent.parent / "data" / "verdict-cases" / "l-block-on-table.npz")
    surface = SurfaceModel(shapes.l_block(), 0)
    start = data["truth"] @ frames.rigid(translation=[start_mm, 0.0, 0.0])
    result = match(Cloud(data["scan"].astype(float), name="L-block on a table"), surface, tolerance_mm=0.3,
                   seed=0, init=start)
    assert result.status != "ok" or right(surface, result.matrix, data["truth"]), result.reasons


def _standing(mesh: Cloud) -> Cloud:
    """``mesh`` moved to stand on z = 0, centred in x and y (as the tester placed the parts on the slab)."""
    lo, hi = mesh.points.min(axis=0), mesh.points.max(axis=0)
    return Cloud(mesh.points - [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]], triangles=mesh.triangles,
                 name=mesh.name)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_an_l_block_on_a_slab_is_never_ok_upside_down(seed):
    """An L-block on a slab 60 mm wider, seen from 45 deg above (0.1 mm noise): seed 1 on Debian 12
    finds the right pose; the other seeds, and every seed on Debian 13, lay it upside down, and a pose
    half a turn from it explains the view about as well: never "ok" there.  Found by a tester (helper)."""
    from workcal_wb.core.benchmark.verdicts import right

    data = np.load(Path(__file__).parent.parent / "data" / "verdict-cases" / "l-block-on-slab-45deg.npz")
    surface = SurfaceModel(_standing(shapes.l_block()), 0)
    result = match(Cloud(data["scan"].astype(float), name="L-block on a slab"), surface, tolerance_mm=0.3, seed=seed)
    assert result.status != "ok" or right(surface, result.matrix, data["truth"]), result.reasons


def _tilted_shell() -> Cloud:
    shell = shapes.shell()
    return Cloud(shell.points @ frames.rot_y(35.0)[:3, :3].T, triangles=shell.triangles, name="tilted shell")


@pytest.mark.slow
@pytest.mark.parametrize("case, model", [
    ("shell-on-slab-25deg", shapes.shell),
    ("shell-on-slab-20deg", shapes.shell),
    ("tilted-shell-on-slab-25deg", _tilted_shell),
    ("thin-shell-alone-54deg", lambda: shapes.shell(thickness=2.0, bend_radius=90.0)),
    ("long-shell-alone-50deg", lambda: shapes.shell(length=200.0, width=60.0, bend_radius=150.0))])
def test_a_shell_is_never_ok_slid_along_its_bend(case, model):
    """Scans testers (helpers) made of shells, each moved to stand on z = 0, matched with seeds 0-2.  On a
    slab, each came back "ok" for some seed, slid along its bend, its curved faces fitting where they
    overlap the scan; each such pose sinks an end into the slab, and a pose reaching more than 3
    tolerances through the plane the scan stands on is no longer "ok":
    - ``shapes.shell()`` on a slab 60 mm wider, 25 deg above, exact: "ok" with seed 0 on Debian
      12, turned 2.0 deg about its bend and shifted 3.1 mm (4.0 mm at its farthest point).  The right
      pose was found, refined again from a wider gate (Judge.rank), and the slab beside the shell's feet
      pulled it along its bend, its curved faces still fitting to 0.2 um; it sinks an end 2.1 mm;
    - ``shapes.shell()`` on a slab 60 mm wider, 20 deg above, exact: "ok" 33.9 deg along its bend
      (61 mm; it reaches 40-51 mm into the slab).  The scan sees part of the arc and the slid model still
      covers most of it (1111 scan points within 0.1 mm of it, 1169 at the truth); the scanned surface
      runs on past its end along 2.9 % of its outline (the face-continuation test allows 3 %);
    - the same shell turned 35 deg about the y axis, on a slab 80 mm wider, 25 deg above, 0.02 mm
      noise: "ok" 0.65 deg and 1.2 mm off, every seed (1.3 mm into the slab).
    Alone (nothing to sink into):
    - a 2 mm shell bent at 90 mm, 0.1 mm noise, 54 deg above: "ok" 0.59 deg and 2.9 mm off with seed 2 on
      Debian 12, the scan laid on the wall's other face (measured).  Its surface spreads 5.07 %
      of its diagonal across its thinnest axis, just over the 5 % that made a part thin, so the pose laid
      through the wall was never tried; tried (a part is thin by its wall's thickness across that axis,
      SurfaceModel.wall_across: 1.2 % of its diagonal), it fits at 0.95 noises against the best's 1.95,
      and lies 2.1 mm from the best, within two gates, where it was dropped as the best itself.  Kept
      as a rival seen from the other side, it makes the match "ambiguous";
    - a shell 200 x 60 mm bent at 150 mm, exact, 50 deg above: "ok" turned over (179.9 deg) with seed 1
      on Debian 12, at 0.24 mm RMS (the scan's noise 0.001 mm); the right pose was not among the
      candidates (the nearest, a turn of the best, 4.3 deg off; a match from it goes home).  Since rough poses are taken a few steps before the best are chosen
      (match.SEARCH.pre_refined), the right pose is listed as a rival and the match is "ambiguous".
    The tester's scans are in a random frame.  A rule tried in Judge.rank first (a widened pose taken only
    when it keeps as much of the scan on the model) mended the 25 deg shell, but over the tester's 234
    scenes it made two wrong poses "ok" and stopped one: reverted."""
    from workcal_wb.core.benchmark.verdicts import right

    data = np.load(Path(__file__).parent.parent / "data" / "verdict-cases" / f"{case}.npz")
    surface = SurfaceModel(_standing(model()), 0)
    for seed in (0, 1, 2):
        result = match(Cloud(data["scan"].astype(float), name=case), surface, tolerance_mm=0.3, seed=seed)
        assert result.status != "ok" or right(surface, result.matrix, data["truth"]), (seed, result.reasons)


@pytest.mark.slow
@pytest.mark.parametrize("case, model, motion_seed", [
    ("thin-shell-alone-54deg", lambda: shapes.shell(thickness=2.0, bend_radius=90.0), 201),
    ("long-shell-alone-50deg", lambda: shapes.shell(length=200.0, width=60.0, bend_radius=150.0), 202)])
def test_a_shell_moved_to_another_frame_is_not_ok_on_its_other_face(case, model, motion_seed):
    """The shells scanned alone, moved to another frame and matched with seed 2: both came back "ok",
    the thin one 0.6 deg and 2.9 mm off with its scan laid on the wall's other face, the long one turned
    over (Debian 12's numpy and scipy).  Since a part is thin by its wall across (see
    test_a_part_is_thin_by_its_wall_however_far_it_bends), the pose laid through the wall is tried and
    kept as a rival seen from the other side: both "ambiguous"."""
    from workcal_wb.core.benchmark.verdicts import right

    data = np.load(Path(__file__).parent.parent / "data" / "verdict-cases" / f"{case}.npz")
    motion = frames.random_motion(np.random.default_rng(motion_seed), 500.0)
    surface = SurfaceModel(_standing(model()), 0)
    scan = Cloud(frames.apply(motion, data["scan"].astype(float)), name=case)
    result = match(scan, surface, tolerance_mm=0.3, seed=2)
    assert result.status != "ok" or right(surface, result.matrix, motion @ data["truth"]), result.reasons


@pytest.mark.slow
def test_two_copies_of_the_part_in_the_scan_give_a_verdict():
    """Two chamfered pegs in one scan, the second half a turn round and 300 mm away: the viewpoint the
    verdict estimates from the matched copy put the other nearly in the sensor's plane, and framing the
    view around it asked for 640 GB (a MemoryError, no result).  Found by a tester; the scan is stored."""
    data = np.load(Path(__file__).parent.parent / "data" / "verdict-cases" / "peg-two-copies.npz")
    surface = SurfaceModel(shapes.peg(), 0)
    result = match(Cloud(data["scan"].astype(float), name="two pegs"), surface, tolerance_mm=0.3, seed=0)
    assert result.status in ("ambiguous", "failed") and result.reasons, (result.status, result.reasons)


@pytest.mark.parametrize("name, model, wall_mm", [
    ("thin shell bent at 90 mm", lambda: shapes.shell(thickness=2.0, bend_radius=90.0), 2.0),
    ("long shell bent at 150 mm", lambda: shapes.shell(length=200.0, width=60.0, bend_radius=150.0), 4.0),
    ("shell", shapes.shell, 4.0), ("plate", shapes.plate, 6.0), ("L-block", shapes.l_block, None),
    ("peg", shapes.peg, None), ("ellipsoid", shapes.ellipsoid, None)])
def test_a_part_is_thin_by_its_wall_however_far_it_bends(name, model, wall_mm):
    """A plate or shell may be scanned on one face and laid on the other, so the verdict tries that
    pose (match._through_the_wall) on thin parts only.  Thin used to mean a surface spread less than
    5 % of the diagonal across its thinnest axis: the two shells bent furthest spread 5.07 and 5.03 %
    and were left out (the 2 mm one came back "ok" laid on its other face).  Their wall across
    that axis is their thickness; a body's is its depth, 10 % of its diagonal or more."""
    from workcal_wb.core.match import VERDICT

    surface = SurfaceModel(model(), 0)
    if wall_mm is None:
        assert surface.wall_across > VERDICT.thin_part * surface.diagonal, surface.wall_across
    else:
        assert surface.wall_across == pytest.approx(wall_mm, rel=0.1)
        assert surface.wall_across < VERDICT.thin_part * surface.diagonal


@pytest.mark.parametrize("turn_deg", [0.0, 180.0])
def test_depth_through_the_support_is_measured_from_the_side_the_part_stands_on(turn_deg):
    """The shell on its slab at its true pose reaches (nearly) nowhere through the slab; lowered into it
    by 2 mm it reaches 2 mm further, whichever way up the scan's frame is (the side is the one the scan's
    other points lie on, not a fixed up)."""
    from workcal_wb.core.match import Support, _depth_through_support

    data = np.load(Path(__file__).parent.parent / "data" / "verdict-cases" / "shell-on-slab-25deg.npz")
    turn = frames.rigid(frames.rot_x(turn_deg)[:3, :3], [10.0, -20.0, 30.0])
    scan, truth = frames.apply(turn, data["scan"].astype(float)), turn @ data["truth"]
    surface = SurfaceModel(_standing(shapes.shell()), 0)
    down = frames.apply(truth, np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))  # the model's z axis in the scan
    lowered = frames.rigid(translation=-2.0 * (down[1] - down[0])) @ truth
    support = Support.of(scan, 5.0, surface.diagonal, 0)
    at_truth = _depth_through_support(support, surface, frames.invert(truth))
    assert at_truth < 0.5  # its feet on the slab, within the plane's fit through the 5 mm band
    assert _depth_through_support(support, surface, frames.invert(lowered)) == pytest.approx(at_truth + 2.0, abs=0.1)


@pytest.mark.slow
def test_the_grid_clears_points_of_running_on_before_the_samples_tree_weighs_the_rest():
    """Judge.continued_faces asks the cell grid first which scan points may lie off the model (a cell's
    sample is never nearer a point than its nearest sample), and the samples' KD-tree only for those: a
    model loaded from the cache need not build it (~20 ms of a warm bunny match).  The plate's rows
    running on past its end are counted as when the tree weighed every point, and rows on the plate
    leave the tree unbuilt."""
    from workcal_wb.core.match import Judge, MatchOptions, prepare

    def counted(points, grid=True):
        surface = prepare(SurfaceModel(shapes.plate(), 0))
        surface._tree._built = None  # as loaded from the cache: its grids filled, no tree
        if not grid:  # every point found off by the grid, so weighed by the tree
            surface.nearest_cell = lambda moved, gate: (None, None, np.zeros(len(moved), bool))
        judge = Judge(points, surface, (points[:50], np.full(50, 0.01)), 0.7, MatchOptions(), [])
        judge.gate = 0.1
        judge._set_view(np.array([0.0, -300.0, 300.0]), points.mean(axis=0), "given")
        return judge.continued_faces(np.eye(4)), surface._tree._built is not None

    assert counted(_plate_rows()) == (0, False)
    longer = _plate_rows(x_end=90.0)
    count, built = counted(longer)
    assert built and count > 500 and (count, True) == counted(longer, grid=False)  # rows from x = 60 to 90 run on


def test_a_coarse_cad_mesh_is_not_given_a_coarser_grid_to_clear_points_through():
    """A box of twelve faces: its samples lie up to 40 mm from points of its faces (sample_cover), a
    gate several grid levels coarser than prepare fills; clearing the scan's points through such a grid
    would make it for this alone (and the model cache would write the model again), so the KD-tree
    weighs every point.  Found by a reviewer (helper)."""
    from workcal_wb.core.match import Judge, MatchOptions

    surface = SurfaceModel(shapes.box((60.0, 40.0, 20.0), edge_mm=100.0), 0)
    xs, ys = np.meshgrid(np.arange(-30.0, 50.0, 1.0), np.arange(-20.0, 20.0, 1.0))
    points = np.column_stack([xs.ravel(), ys.ravel(), np.zeros(xs.size)])  # the top face, running on 20 mm
    judge = Judge(points, surface, (points[:50], np.full(50, 0.01)), 1.0, MatchOptions(), [])
    judge.gate = 0.1
    judge._set_view(np.array([0.0, -300.0, 300.0]), points.mean(axis=0), "given")
    assert surface.sample_cover > 20.0 and judge.continued_faces(np.eye(4)) == 0  # none lies that far off
    assert not surface._grids


@pytest.mark.slow
@pytest.mark.parametrize("seed, margin, frame", [(0, 10.0, "sensor"), (1, 15.0, "sensor"), (2, 10.0, "arbitrary")])
def test_the_platform_a_block_stands_on_is_no_surface_running_on_past_it(seed, margin, frame):
    """The block with the platform around its foot (a box drawn loosely, or a platform left in a region):
    the platform meets each side face along the line the block rests on, and there it "goes on past the
    outline".  Told the plane the part stands on (a calibration's platform), the right pose is "ok"
    (without it: "ambiguous", the scanned surface going on past 3-7 % of the outline)."""
    from workcal_wb.core import pointops
    from workcal_wb.core.regions import find_platform, standing_on
    from workcal_wb.core.simulate.cell import CellSpec, cell_scan

    cell = cell_scan(CellSpec(seed=seed, frame=frame))
    points = cell.cloud.points
    platform = find_platform(points, pointops.median_spacing(points), np.random.default_rng(0))
    block = points[cell.mask("reference")]
    lo, hi = block.min(axis=0) - margin, block.max(axis=0) + margin
    region = np.all((points >= lo) & (points <= hi), axis=1) & ~cell.mask("workpiece")
    assert cell.mask("platform")[region].sum() > 1000
    for viewpoint in (None, tuple(cell.scanner_origin)):
        result = match(Cloud(points[region]), SurfaceModel(cell.reference_model), viewpoint=viewpoint,
                       support=standing_on(platform))
        assert result.status == "ok", result.reasons
        assert frames.rotation_between_deg(result.matrix, cell.V) < 0.05
