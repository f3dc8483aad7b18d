"""The scene and the virtual scanner: geometry on the surfaces, exact occlusion, consistent truth."""
import json

import numpy as np
import open3d
import pytest
from scipy.spatial import cKDTree

from test_simulate_shapes import distances_to
from workcal_wb.core import frames, raycast
from workcal_wb.core.errors import InputError
from workcal_wb.core.geometry import Cloud
from workcal_wb.core.simulate import shapes
from workcal_wb.core.simulate.scanner import Scanner, scanner_ring
from workcal_wb.core.simulate.scene import PLATFORM_TOP_Z, Scene, SceneObject, build_scene
from workcal_wb.core.simulate.toolpath_sample import sample_toolpath_points
from workcal_wb.core.simulate.truth import scan_truth, scene_truth, write_truth

EXACT = {"noise_sigma_mm": 0.0, "z_resolution_mm": 0.0}


@pytest.fixture(scope="module")
def scene():
    return build_scene("car", seed=1, clutter=True)


@pytest.fixture(scope="module")
def exact_scan(scene):
    return Scanner.aimed_at(scene, **EXACT).scan(scene, normals=True)


def in_object_frame(scan, scene, index, points=None):
    """Scan points mapped from S into the frame of scene object ``index``."""
    pose = scene.objects[index].pose
    return frames.apply(frames.invert(pose) @ scan.B_S, scan.points[scan.labels == index] if points is None else points)


def first_hits(origin, directions, vertices, triangles):
    """Brute-force ray casting (Moller-Trumbore against every triangle): distance to the first hit or inf."""
    a, b, c = (vertices[triangles[:, i]] for i in range(3))
    e1, e2 = b - a, c - a
    out = np.full(len(directions), np.inf)
    for i, d in enumerate(directions):
        p = np.cross(d, e2)
        det = np.einsum("ij,ij->i", e1, p)
        ok = np.abs(det) > 1e-12
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        s = origin - a
        u = np.einsum("ij,ij->i", s, p) * inv
        q = np.cross(s, e1)
        v = (q @ d) * inv
        t = np.einsum("ij,ij->i", e2, q) * inv
        hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
        if hit.any():
            out[i] = t[hit].min()
    return out


# ---------------------------------------------------------------------------------------------
# Scene
# ---------------------------------------------------------------------------------------------

def test_scene_layout(scene):
    roles = [o.role for o in scene.objects]
    assert roles.count("platform") == roles.count("reference") == roles.count("workpiece") == 1
    assert roles.count("clutter") == 2
    platform = scene._one("platform").in_base().points
    assert platform[:, 2].max() == pytest.approx(PLATFORM_TOP_Z)
    reference = scene.reference_model()
    assert reference.name == "B-P" and reference.is_mesh
    assert reference.points[:, 2].min() == pytest.approx(PLATFORM_TOP_Z)
    workpiece = scene.workpiece.in_base().points
    assert workpiece[:, 2].min() == pytest.approx(PLATFORM_TOP_Z, abs=1e-9), "rests on the platform top"
    assert np.abs(workpiece[:, :2] - platform[:, :2].mean(axis=0)).max() < 300.0, "on the platform"
    for other in scene.objects:
        if other.role in ("reference", "clutter"):
            gap, _ = cKDTree(other.in_base().points[:, :2]).query(workpiece[:, :2])
            assert gap.min() > 10.0, f"workpiece touches {other.name}"


def test_truth_pose_and_models(scene):
    W = scene.W
    assert frames.omega(W) > 5 and np.linalg.norm(W[:3, 3]) > 100, "no identity by accident"
    model = scene.workpiece_model()
    assert model.name == "car" and np.array_equal(model.points, shapes.car().points)
    assert np.allclose(frames.apply(W, model.points), scene.workpiece.in_base().points)
    up_in_B = (W @ scene.workpiece_upright)[:3, 2]
    assert np.degrees(np.arccos(up_in_B[2])) <= 5.0 + 1e-9, "only a small tilt"


def test_scene_depends_on_the_seed_only():
    a, b, c = build_scene("figurine", seed=4), build_scene("figurine", seed=4), build_scene("figurine", seed=5)
    assert np.array_equal(a.W, b.W)
    assert not np.allclose(a.W, c.W)


def test_scene_takes_a_given_pose_or_mesh():
    pose = frames.from_euler_zyz(10, 20, 30, (700, 0, 400))
    assert np.allclose(build_scene("figurine", workpiece_pose=pose).W, pose)
    vase = build_scene(shapes.vase(edge_mm=4.0), seed=2)
    assert vase.workpiece.in_base().points[:, 2].min() == pytest.approx(PLATFORM_TOP_Z)
    with pytest.raises(InputError):
        build_scene(Cloud(np.random.default_rng(0).normal(size=(50, 3)), name="points only"))
    with pytest.raises(InputError):
        build_scene("boat")


def test_clay_change_reaches_the_scanner_but_not_the_model():
    changed = build_scene("car", seed=1, clay_change=["lump", "carve"])
    assert np.array_equal(changed.workpiece_model().points, shapes.car().points)
    moved = changed.reshaped.changed
    scanned = changed.workpiece.mesh.points
    assert np.array_equal(scanned[~moved], shapes.car().points[~moved])
    assert changed.reshaped.displacement_mm.max() > 4 and changed.reshaped.displacement_mm.min() < -2
    # The scan of the lump stands off the model; the rest of the workpiece lies on it.
    scan = Scanner.aimed_at(changed, **EXACT).scan(changed)
    in_x = frames.apply(frames.invert(scan.U), scan.points[scan.mask("workpiece")])
    off = distances_to(changed.workpiece_model(), in_x)
    assert off.max() > 3.0
    assert np.mean(off < 1e-3) > 0.8


# ---------------------------------------------------------------------------------------------
# Scanner
# ---------------------------------------------------------------------------------------------

def test_points_lie_on_their_objects(scene, exact_scan):
    assert exact_scan.points.dtype == np.float64
    for index, obj in enumerate(scene.objects):
        points = in_object_frame(exact_scan, scene, index)
        if obj.role != "clutter":
            assert len(points) > 1000, obj.name
        if len(points):
            assert distances_to(obj.mesh, points).max() < 1e-3, obj.name


def test_noisy_points_lie_on_their_objects_within_the_noise(scene):
    scan = Scanner.aimed_at(scene).scan(scene)  # defaults: 0.1 mm noise, 0.11 mm steps
    for index, obj in enumerate(scene.objects):
        points = in_object_frame(scan, scene, index)
        if len(points):
            d = distances_to(obj.mesh, points)
            assert np.percentile(d, 99) < 0.35 and np.median(d) < 0.1, obj.name


def test_truth_is_consistent(scene, exact_scan):
    U, V, W = exact_scan.U, exact_scan.V, exact_scan.W
    assert np.allclose(W, frames.invert(V) @ U) and np.allclose(W, scene.W)
    assert np.allclose(V, frames.invert(Scanner.aimed_at(scene).frame()))
    workpiece_in_x = frames.apply(frames.invert(U), exact_scan.points[exact_scan.mask("workpiece")])
    assert distances_to(scene.workpiece_model(), workpiece_in_x).max() < 1e-3
    reference_in_b = frames.apply(frames.invert(V), exact_scan.points[exact_scan.mask("reference")])
    assert distances_to(scene.reference_model(), reference_in_b).max() < 1e-3


def test_scanner_frame_convention():
    scanner = Scanner((0.0, 0.0, 1000.0), (0.0, 500.0, 0.0))
    B_S = scanner.frame()
    frames.as_transform(B_S)
    assert np.allclose(B_S[:3, 3], (0, 0, 1000))
    assert np.allclose(B_S[:3, 2], np.array([0, 500, -1000]) / np.linalg.norm([0, 500, -1000])), "z looks at the target"
    assert B_S[2, 1] < 0, "image y points down"
    assert np.allclose(frames.apply(frames.invert(B_S), np.array([[0.0, 500.0, 0.0]]))[0, :2], 0), "target in the middle"


@pytest.mark.parametrize("cast_rays, within", [(False, 1e-6), (True, 1e-3)], ids=["z-buffer", "open3d rays"])
def test_scanner_agrees_with_brute_force_ray_casting(scene, cast_rays, within):
    """Both ways the scanner finds its surfaces: our z-buffer (exact), and open3d's ray casting where it
    works (single-precision rays at ~1.2 m)."""
    if cast_rays and not raycast.works():
        pytest.skip(f"open3d {open3d.__version__} does not cast rays correctly")
    scanner = Scanner.aimed_at(scene, max_incidence_deg=90.0, image_size=(64, 48), **EXACT)
    scan = scanner.scan(scene, cast_rays=cast_rays)
    S_B = frames.invert(scan.B_S)
    vertices = np.vstack([frames.apply(S_B @ o.pose, o.mesh.points) for o in scene.objects])
    offsets = np.cumsum([0] + [len(o.mesh.points) for o in scene.objects])
    triangles = np.vstack([o.mesh.triangles + k for o, k in zip(scene.objects, offsets)])
    rng = np.random.default_rng(0)
    rows, cols = rng.integers(0, 48, 60), rng.integers(0, 64, 60)
    directions = scanner.ray_directions(rows, cols)
    expected_depth = first_hits(np.zeros(3), directions, vertices, triangles)  # t along a z = 1 direction is depth
    got = np.full(48 * 64, np.inf)
    got[scan.pixels[:, 0] * 64 + scan.pixels[:, 1]] = scan.points[:, 2]
    assert np.isfinite(expected_depth).sum() > 30
    assert got[rows * 64 + cols] == pytest.approx(expected_depth, abs=within)


def test_occluder_hides_what_is_behind_it(scene):
    scanner = Scanner.aimed_at(scene, **EXACT)
    workpiece_centre = scene.workpiece.in_base().points.mean(axis=0)
    B_S = scanner.frame()
    # A 60 x 60 x 4 mm plate facing the scanner, halfway between it and the workpiece.
    plate = shapes.box((60.0, 60.0, 4.0), edge_mm=10.0, name="plate")
    plate_pose = frames.rigid(B_S[:3, :3], 0.5 * (scanner.position + workpiece_centre))
    blocked = Scene(scene.objects + [SceneObject("plate", plate, plate_pose, "clutter")],
                    scene.workpiece_original, scene.workpiece_upright)
    before, after = scanner.scan(scene), scanner.scan(blocked)
    plate_only = scanner.scan(Scene([SceneObject("plate", plate, plate_pose, "workpiece")], plate, np.eye(4)))
    shadow = set(map(tuple, plate_only.pixels))
    behind = [tuple(p) in shadow for p in before.pixels[before.mask("workpiece")]]
    assert sum(behind) > 500, "the plate must cover part of the workpiece for this test to mean anything"
    after_pixels = {tuple(p): label for p, label in zip(after.pixels, after.labels)}
    plate_index = len(blocked.objects) - 1
    assert all(after_pixels.get(p) == plate_index for p in shadow)
    assert not any(tuple(p) in shadow for p in after.pixels[after.mask("workpiece")])
    assert after.mask("workpiece").sum() == before.mask("workpiece").sum() - sum(behind)


def test_pixel_grid_pitch_and_depth_steps(scene):
    scanner = Scanner.aimed_at(scene, pixel_pitch_mm=0.5, z_resolution_mm=0.11)
    scan = scanner.scan(scene)
    direction = scanner.ray_directions(scan.pixels[:, 0], scan.pixels[:, 1])
    assert np.allclose(scan.points[:, :2] / scan.points[:, 2:], direction[:, :2], rtol=0, atol=1e-12)
    steps = scan.points[:, 2] / 0.11
    assert np.abs(steps - np.round(steps)).max() < 1e-6
    # Neighbouring samples are one pitch apart at the focus distance.
    d = scanner.focus_distance_mm
    assert np.linalg.norm(d * (scanner.ray_directions(np.array([10]), np.array([11]))
                               - scanner.ray_directions(np.array([10]), np.array([10])))) == pytest.approx(0.5)
    assert scanner.window_mm == (320.0, 240.0)


def test_noise_sigma_is_what_was_asked(scene):
    clean = Scanner.aimed_at(scene, **EXACT).scan(scene)
    noisy = Scanner.aimed_at(scene, noise_sigma_mm=0.3, z_resolution_mm=0.0, seed=7).scan(scene)
    assert np.array_equal(clean.pixels, noisy.pixels)
    along_ray = np.linalg.norm(noisy.points, axis=1) - np.linalg.norm(clean.points, axis=1)
    assert np.std(along_ray) == pytest.approx(0.3, rel=0.03)
    assert abs(np.mean(along_ray)) < 0.01
    assert np.allclose(np.cross(noisy.points, clean.points), 0, atol=1e-6), "noise moves points along their ray"


def test_same_seed_same_scan_other_seed_other_noise(scene):
    a, b, c = (Scanner.aimed_at(scene, seed=seed, image_size=(320, 240)).scan(scene) for seed in (3, 3, 4))
    assert np.array_equal(a.points, b.points) and np.array_equal(a.labels, b.labels)
    assert np.array_equal(a.pixels, c.pixels) and not np.array_equal(a.points, c.points)


def test_grazing_returns_are_cut():
    ball = shapes.sphere(40.0, edge_mm=1.0)
    only_ball = Scene([SceneObject("ball", ball, np.eye(4), "workpiece")], ball, np.eye(4))
    counts = {}
    for limit in (60.0, 89.9):
        scanner = Scanner((0.0, 0.0, 2000.0), (0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), pixel_pitch_mm=0.5,
                          image_size=(200, 200), max_incidence_deg=limit, **EXACT)
        scan = scanner.scan(only_ball, normals=True)
        rays = scan.points / np.linalg.norm(scan.points, axis=1, keepdims=True)
        incidence = np.degrees(np.arccos(-np.einsum("ij,ij->i", rays, scan.normals)))
        assert incidence.max() <= limit
        counts[limit] = len(scan.points)
    # Seen from far, the part of a sphere's disc within 60 deg of head-on is sin^2(60 deg) of it.
    assert counts[60.0] / counts[89.9] == pytest.approx(np.sin(np.radians(60)) ** 2, rel=0.03)


def test_zoom_is_a_second_capture_from_the_same_place(scene):
    wide = Scanner.aimed_at(scene, **EXACT)
    close = wide.zoomed(wide.pixel_pitch_mm / 2)
    assert np.array_equal(wide.frame(), close.frame())
    a, b = wide.scan(scene), close.scan(scene)
    assert np.array_equal(a.U, b.U) and np.array_equal(a.V, b.V)
    assert b.scanner.window_mm[0] == pytest.approx(a.scanner.window_mm[0] / 2)
    assert b.mask("workpiece").sum() > 2 * a.mask("workpiece").sum()


def test_scanner_ring_sees_both_objects_from_every_position(scene):
    ring = scanner_ring(scene, 5, distance=1200.0, elevation=40.0, seed=2, image_size=(320, 240))
    positions = np.array([s.position for s in ring])
    assert len(ring) == 5 and len({s.seed for s in ring}) == 5
    assert np.min([np.linalg.norm(p - q) for i, p in enumerate(positions) for q in positions[i + 1:]]) > 500
    Ws = []
    for scanner in ring:
        assert scanner.focus_distance_mm == pytest.approx(1200.0, rel=0.06)
        scan = scanner.scan(scene)
        assert scan.mask("workpiece").sum() > 2000 and scan.mask("reference").sum() > 2000
        Ws.append(frames.invert(scan.V) @ scan.U)
    assert all(np.allclose(W, scene.W) for W in Ws)
    assert scanner_ring(scene, 5, seed=2)[0].position == pytest.approx(scanner_ring(scene, 5, seed=2)[0].position)
    with pytest.raises(InputError):
        scanner_ring(scene, 0)


def test_scanner_settings_are_checked():
    with pytest.raises(InputError):
        Scanner((0, 0, 0), (0, 0, 0))
    with pytest.raises(InputError):
        Scanner((0, 0, 100), (0, 0, 0))  # looking straight down the up vector
    with pytest.raises(InputError):
        Scanner((0, 0, 100), (0, 10, 0), pixel_pitch_mm=0)


def test_scan_is_fast(scene):
    scan = Scanner.aimed_at(scene).scan(scene)
    assert len(scan.points) > 80_000
    assert scan.time_s < 3.0  # about 0.2 s on the 2-core development machine


# ---------------------------------------------------------------------------------------------
# Truth file and toolpath sample
# ---------------------------------------------------------------------------------------------

def test_truth_json_round_trip(scene, exact_scan, tmp_path):
    truth = scene_truth(scene, [("scan.ply", exact_scan)])
    write_truth(tmp_path / "truth.json", truth)
    back = json.loads((tmp_path / "truth.json").read_text())
    assert back == json.loads(json.dumps(truth))
    entry = back["scans"][0]
    U, V, W = (np.array(entry[k]) for k in ("U", "V", "W"))
    assert np.allclose(W, frames.invert(V) @ U) and np.allclose(np.array(back["W"]), scene.W)
    assert np.allclose(np.array(entry["B_S"]), exact_scan.B_S)
    assert entry["points"]["total"] == len(exact_scan.points)
    assert scan_truth(exact_scan)["points"]["workpiece"] == exact_scan.mask("workpiece").sum()


def test_toolpath_sample_runs_just_above_the_top(scene):
    points, feed = sample_toolpath_points(scene)
    assert 200 <= len(points) <= 2000 and feed > 0
    model = scene.workpiece_model()
    gap = distances_to(model, points)
    assert gap.max() <= 1.0 + 1e-3 and np.median(gap) > 0.9
    up = frames.apply(frames.invert(scene.workpiece_upright), points)
    assert np.linalg.norm(np.diff(up[:, :2], axis=0), axis=1).max() < 40, "a zig-zag, not jumps across the part"
    same, _ = sample_toolpath_points(model, scene.workpiece_upright)
    assert np.array_equal(points, same)
