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


def test_near_symmetric_plate_has_no_symmetry_but_its_turns_are_tried():
    """The notched plate turned over or about its normal covers nearly the same outline: no symmetry
    (the notch moves), but those turns, refined into its best self-maps, are the flips every match
    tries, and each maps all of the plate but the notch onto itself."""
    surface = SurfaceModel(_in_x(shapes.plate()))
    assert len(surface.flips) == 3
    for flip in surface.flips:
        assert not surface.maps_onto_itself(flip)
        moved = frames.apply(flip, surface.points[::7])
        distance = surface.tree.query(moved)[0]
        assert np.median(distance) < 0.3 and distance.max() > 5.0  # everything lands but the notch
    quarter = frames.rigid(frames.rot_z(90.0))
    assert not SurfaceModel(shapes.boss_plate()).maps_onto_itself(frames.rigid(frames.rot_x(180.0)))
    assert SurfaceModel(shapes.boss_plate()).maps_onto_itself(quarter)


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
