"""A model's symmetries found when it is prepared, and what a viewpoint sees of a surface.

Models are given in frames of their own (turned and moved), so the symmetry axes found must turn
with them; visibility is checked on shapes whose visible faces are known.
"""
import re

import numpy as np
import pytest

from workcal_wb.core import frames, visibility
from workcal_wb.core.simulate import shapes
from workcal_wb.core.simulate.scanner import scan_part
from workcal_wb.core.surface import SurfaceModel

X = frames.from_euler_zyz(40.0, 70.0, -25.0, (15.0, -30.0, 60.0))  # the models' own frame


def _in_x(mesh):
    return mesh.transformed(X)


def _axis_in_x(axis):
    return frames.apply_vectors(X, np.asarray([axis], float))[0]


@pytest.mark.slow
@pytest.mark.parametrize("name, mesh, orders, axes", [
    ("box", shapes.box((80.0, 50.0, 30.0), edge_mm=2.0), [2, 2, 2], [(1, 0, 0), (0, 1, 0), (0, 0, 1)]),
    ("boss plate", shapes.boss_plate(), [4], [(0, 0, 1)]),
    ("D shaft", shapes.d_shaft(), [2], [(0, 1, 0)]),
    ("cylinder", shapes.cylinder(), [0, 2], [(0, 0, 1), None]),  # any turn about z; over, about any axis across
    ("peg", shapes.peg(), [0], [(0, 0, 1)]),
    ("notched plate", shapes.plate(), [], []),
    ("car", shapes.car_body(), [], []),
])
def test_symmetries_found_when_the_model_is_prepared(name, mesh, orders, axes):
    surface = SurfaceModel(_in_x(mesh))
    assert sorted(surface.symmetry_orders.tolist()) == sorted(orders), name
    for attribute in ("symmetry_axes", "symmetry_points", "symmetry_orders", "symmetry_deviations_mm", "flips",
                      "view_order"):
        assert isinstance(getattr(surface, attribute), np.ndarray)  # plain arrays: a cache can store them
    assert (surface.symmetry_deviations_mm <= surface.symmetry_tolerance_mm).all()
    for order, axis in zip(orders, axes):
        if axis is None:
            continue
        found = [a for a, o in zip(surface.symmetry_axes, surface.symmetry_orders) if o == order]
        assert any(abs(a @ _axis_in_x(axis)) > 0.999 for a in found), (name, order, axis)
    centre = frames.apply(X, np.array([0.5 * (mesh.points.min(axis=0) + mesh.points.max(axis=0))]))[0]
    for a, p in zip(surface.symmetry_axes, surface.symmetry_points):  # every axis passes through the middle
        assert np.linalg.norm(np.cross(centre - p, a)) < 0.5, name
    assert len(surface.symmetries()) >= (1 if orders else 0)


@pytest.mark.slow
def test_near_symmetric_plate_has_no_symmetry_but_its_turns_are_tried():
    """The notched plate turned over or about its normal covers nearly the same outline: no symmetry
    (the notch moves), but those turns, refined into its best self-maps, are the first flips every
    match tries, and each maps all of the plate but the notch onto itself; any other flip (a turn
    found by registering the plate against itself) maps most of it onto itself too."""
    from workcal_wb.core.symmetry import MAX_NEAR_SELF_MAPS, NEAR_SELF_SHARE

    surface = SurfaceModel(_in_x(shapes.plate()))
    assert 3 <= len(surface.flips) <= 3 + MAX_NEAR_SELF_MAPS
    for k, flip in enumerate(surface.flips):
        assert not surface.maps_onto_itself(flip)
        moved = frames.apply(flip, surface.points[::7])
        distance = surface.tree.query(moved)[0]
        if k < 3:
            assert np.median(distance) < 0.3 and distance.max() > 5.0  # everything lands but the notch
        else:
            assert np.mean(distance < 2 * surface.spacing) > NEAR_SELF_SHARE - 0.05
    quarter = frames.rigid(frames.rot_z(90.0))
    assert not SurfaceModel(shapes.boss_plate()).maps_onto_itself(frames.rigid(frames.rot_x(180.0)))
    assert SurfaceModel(shapes.boss_plate()).maps_onto_itself(quarter)


@pytest.mark.slow
def test_symmetries_are_named_in_words():
    sentences = SurfaceModel(shapes.boss_plate()).symmetries()
    assert len(sentences) == 1
    assert re.fullmatch(r"turning the part 90 degrees about its axis \(-?0\.00, -?0\.00, -?1\.00\) through "
                        r"\(-?0\.0, -?0\.0, [\d.]+\) mm gives the same surface \(4-fold symmetry\)", sentences[0])
    cylinder = SurfaceModel(shapes.cylinder()).symmetries()
    assert cylinder[0].startswith("turning the part by any angle about its axis")
    assert cylinder[1].startswith("turning the part over, half a turn about any axis across its main axis")
    assert SurfaceModel(shapes.sphere()).symmetries() == [
        "turning the part by any angle about any axis through its centre (0.0, 0.0, 0.0) mm gives the same surface"]


def test_expected_surface_of_a_boss_plate_from_above_and_below():
    """From above: the plate's top around the boss and the boss's top, not the top under the boss nor
    the bottom; from below: the bottom only."""
    surface = SurfaceModel(shapes.boss_plate())
    points, normals = surface.points, surface.normals
    top_face = np.isclose(points[:, 2], 8.0) & (normals[:, 2] > 0.99)
    under_boss = top_face & (np.abs(points[:, 0]) < 14) & (np.abs(points[:, 1]) < 14)  # inside the solid
    boss_top = np.isclose(points[:, 2], 14.0)
    bottom = np.isclose(points[:, 2], 0.0)
    above = visibility.expected_surface(points, normals, (5.0, 3.0, 800.0), pixel_mm=1.5)
    assert above[boss_top].mean() > 0.97 and above[top_face & ~under_boss].mean() > 0.9
    assert not above[bottom].any()
    below = visibility.expected_surface(points, normals, (0.0, 0.0, -800.0), pixel_mm=1.5)
    assert below[bottom].mean() > 0.97 and not below[boss_top].any()


def test_viewing_direction_and_wall_thickness_from_a_real_view():
    """The direction a simulated scanner looked from is recovered from the normals of the surface it
    saw, roughly (it sees the top and one side well: the middle of those is 34 degrees off; the exact
    direction cannot be told from the normals), and the wall it looked at is as thick as the plate."""
    mesh = shapes.plate(length=120.0, width=80.0, thickness=8.0)
    direction = np.array([0.3, -0.4, 0.87])
    direction /= np.linalg.norm(direction)
    scan = scan_part(mesh, np.eye(4), direction, 700.0, samples=20000, noise_sigma_mm=0.05, seed=3)
    seen = frames.apply(scan.B_S, scan.points)  # back in the mesh's frame
    surface = SurfaceModel(mesh)
    _, idx = surface.tree.query(seen)
    estimate = visibility.viewing_direction(surface.normals[idx])
    assert np.degrees(np.arccos(estimate @ direction)) < 40.0
    assert (surface.normals[idx] @ estimate > 0).mean() > 0.99  # the sensor sees what it saw
    view = visibility.View(seen.mean(axis=0) + 700.0 * direction, seen.mean(axis=0), 2.0).framed(seen)
    thickness = visibility.wall_thickness(view, surface.points, surface.normals)
    assert np.median(thickness[np.isfinite(thickness)]) == pytest.approx(8.0, abs=0.5)


def test_a_point_beside_the_sensor_is_outside_its_view():
    """A point off the view's axis by more than any scanner's field (here beside the sensor, nearly in
    its plane) has no pixel, as one behind it has none: its pixel coordinates grow without bound as it
    nears that plane, and a window framed around it asked for hundreds of GB (a second part in the
    scan, seen from a viewpoint estimated from the first)."""
    rng = np.random.default_rng(0)
    part = rng.normal(size=(500, 3)) * 10.0
    view = visibility.View(np.array([0.0, 0.0, 300.0]), np.zeros(3), 1.0)
    beside = np.array([[400.0, 0.0, 299.0], [0.0, -400.0, 299.99]])
    uv, _ = view.coordinates(np.r_[part, beside])
    assert np.isfinite(uv[:500]).all() and np.isnan(uv[500:]).all()
    scan = visibility.ScanView.of(np.r_[part, beside], view)
    rows, cols = scan.view.shape
    assert rows * cols < 10_000 and (scan.pixel[:500] >= 0).all() and (scan.pixel[500:] == -1).all()


@pytest.mark.parametrize("seed", range(4))
def test_a_turn_that_maps_most_of_a_part_onto_itself_is_tried_whatever_its_axis(seed):
    """An L-block standing on its foot, legs 80 and 90 mm: the half turn that swaps them lays it on the
    table again with all but the longer leg's last centimetre where it was, and turns about no
    principal axis (the unequal legs tilt them).  In any frame it is among the flips every match tries,
    refined into the block's best self-map."""
    from workcal_wb.core.simulate.upright_l import upright_l_block

    motion = frames.random_motion(np.random.default_rng(seed), shift_mm=800.0)
    surface = SurfaceModel(upright_l_block().transformed(motion), seed)
    swap = motion @ frames.rigid(np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]])) @ frames.invert(motion)
    shares = []
    for flip in surface.flips:
        distance = surface.tree.query(frames.apply(flip, surface.points[::5]))[0]
        shares.append(np.mean(distance < 2 * surface.spacing))
        if frames.rotation_between_deg(flip, swap) < 2.0:
            assert shares[-1] > 0.8  # all but the longer leg's end lands on the block
            break
    else:
        pytest.fail(f"the leg swap is not among the flips (they land {np.round(shares, 2)} of the block)")


def test_points_past_a_depth_edge_are_no_evidence_of_what_hides_what():
    """A 40 mm square face 50 mm in front of a wall, seen from straight ahead, with mixed pixels strung
    along the rays past its edge, judged from a viewpoint 15 degrees off (an estimated one): under the
    face's true pose the mixed pixels lie behind its outline as seen from there, yet count as nothing
    hidden; a pose slid 20 mm sideways still hides the wall it covers."""
    rng = np.random.default_rng(0)
    step = 0.5
    grid = np.stack(np.meshgrid(np.arange(-60, 60, step), np.arange(-60, 60, step), indexing="ij"), -1).reshape(-1, 2)
    square = np.abs(grid).max(axis=1) < 20
    face = np.c_[grid[square], np.zeros(square.sum())]
    wall = np.c_[grid[~square], np.full((~square).sum(), -50.0)]
    rim = grid[square & (np.abs(grid).max(axis=1) > 19)]
    sensor = np.array([0.0, 0.0, 500.0])
    share = rng.uniform(0.1, 0.9, len(rim))
    mixed = np.c_[rim, np.zeros(len(rim))] + share[:, None] * 50.0 * (np.c_[rim, np.zeros(len(rim))] - sensor) / 500.0
    model = np.c_[grid[square], np.zeros(square.sum())]  # the face's own samples, facing +z
    normals = np.tile([0.0, 0.0, 1.0], (len(model), 1))
    off = 500.0 * np.array([np.sin(np.radians(15.0)), 0.0, np.cos(np.radians(15.0))])
    view = visibility.View(off, np.zeros(3), 2.0)

    def hidden(points, shift):
        scan = visibility.ScanView.of(points, view)
        placed = model + [shift, 0.0, 0.0]
        weights = (np.abs(points[:, 2]) < 0.3).astype(float)
        return visibility.evidence(scan, weights, placed, normals, 0.3, 0.3 + 2 * 2.0, 3.0).hidden

    scene = np.r_[face, wall]
    assert hidden(np.r_[scene, mixed], 0.0) == hidden(scene, 0.0)
    assert hidden(np.r_[scene, mixed], 20.0) > 500  # the wall behind the slid face: seen, so not hidden
