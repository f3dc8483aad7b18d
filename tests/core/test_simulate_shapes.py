"""Procedural shapes and clay changes: closed, outward, the intended sizes and symmetries."""
import numpy as np
import pytest

from workcal_wb.core import frames
from workcal_wb.core.errors import InputError
from workcal_wb.core.pointops import signed_volume, triangle_normals_and_areas
from workcal_wb.core.simulate import clay, shapes


def distances_to(mesh, points):
    """Exact point-to-mesh distances (open3d's closest-point queries work in this build; float32).
    Its signed distance does not: it needs the ray casting that returns no hits here."""
    import open3d as o3d

    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(mesh.points.astype(np.float32)),
                        o3d.core.Tensor(mesh.triangles.astype(np.uint32)))
    query = o3d.core.Tensor(np.asarray(points, dtype=np.float32))
    return scene.compute_distance(query).numpy()


def edge_lengths(mesh):
    t = mesh.triangles
    edges = np.unique(np.sort(np.vstack([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1), axis=0)
    return np.linalg.norm(mesh.points[edges[:, 0]] - mesh.points[edges[:, 1]], axis=1)


# name -> (mesh, expected extents x, y, z in its own frame, mm)
SHAPES = {
    "car": (lambda: shapes.car_body(), (250.0, 104.0, 80.0)),
    "figurine": (lambda: shapes.figurine_body(), (10.5, 14.4, 20.8)),
    "l_block": (lambda: shapes.l_block(), (120.0, 80.0, 60.0)),
    "platform": (lambda: shapes.platform(), (600.0, 600.0, 20.0)),
    "cylinder": (lambda: shapes.cylinder(), (60.0, 60.0, 80.0)),
    "sphere": (lambda: shapes.sphere(), (80.0, 80.0, 80.0)),
    "vase": (lambda: shapes.vase(), (76.7, 76.7, 120.0)),
    "ellipsoid": (lambda: shapes.ellipsoid(), (120.0, 80.0, 50.0)),
}


@pytest.fixture(scope="module")
def meshes():
    return {name: make() for name, (make, _) in SHAPES.items()}


@pytest.mark.parametrize("name", list(SHAPES))
def test_closed_outward_and_sized(meshes, name):
    mesh = meshes[name]
    t = mesh.triangles
    directed = np.vstack([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    _, per_edge = np.unique(np.sort(directed, axis=1), axis=0, return_counts=True)
    assert (per_edge == 2).all(), "every edge must be shared by exactly two faces"
    assert len(np.unique(directed, axis=0)) == len(directed), "each edge must run once each way (consistent winding)"
    assert signed_volume(mesh.points, t) > 0, "faces must be wound outward"
    _, areas = triangle_normals_and_areas(mesh.points, t)
    assert areas.min() > 0
    extents = mesh.points.max(axis=0) - mesh.points.min(axis=0)
    assert extents == pytest.approx(SHAPES[name][1], abs=0.6)


def test_volumes_of_known_solids(meshes):
    assert signed_volume(meshes["l_block"].points, meshes["l_block"].triangles) == pytest.approx((120 * 80 - 90 * 50) * 60)
    assert signed_volume(meshes["platform"].points, meshes["platform"].triangles) == pytest.approx(600 * 600 * 20)
    assert signed_volume(meshes["cylinder"].points, meshes["cylinder"].triangles) == pytest.approx(np.pi * 30**2 * 80, rel=0.01)
    assert signed_volume(meshes["sphere"].points, meshes["sphere"].triangles) == pytest.approx(4 / 3 * np.pi * 40**3, rel=0.01)
    assert signed_volume(meshes["ellipsoid"].points, meshes["ellipsoid"].triangles) == pytest.approx(
        4 / 3 * np.pi * 60 * 40 * 25, rel=0.01)


def test_platform_top_face_is_at_zero(meshes):
    assert meshes["platform"].points[:, 2].max() == 0.0
    assert meshes["platform"].points[:, 2].min() == -20.0


def test_l_block_has_eight_exactly_planar_rectangular_faces(meshes):
    mesh = meshes["l_block"]
    normals, areas = triangle_normals_and_areas(mesh.points, mesh.triangles)
    assert np.allclose(np.abs(normals).max(axis=1), 1.0), "every face is axis-aligned"
    axis = np.abs(normals).argmax(axis=1)
    sign = np.sign(normals[np.arange(len(normals)), axis])
    corners = mesh.points[mesh.triangles]
    offset = corners[np.arange(len(corners)), 0, axis]
    assert np.allclose(corners[np.arange(len(corners)), :, axis], offset[:, None], atol=0), "faces exactly planar"
    planes = {}
    for a, s, o, area in zip(axis, sign, offset, areas):
        planes[(a, s, o)] = planes.get((a, s, o), 0.0) + area
    assert len(planes) == 8  # top, bottom and six walls of the L
    assert planes[(2, 1.0, 60.0)] == pytest.approx(120 * 80 - 90 * 50)
    assert planes[(0, -1.0, 0.0)] == pytest.approx(80 * 60)
    assert planes[(1, 1.0, 30.0)] == pytest.approx(90 * 60)


def test_cylinder_caps_are_planar_with_sharp_rims(meshes):
    mesh = meshes["cylinder"]
    normals, _ = triangle_normals_and_areas(mesh.points, mesh.triangles)
    caps = np.abs(normals[:, 2]) > 0.999
    assert np.isin(mesh.points[mesh.triangles[caps]][..., 2], [0.0, 80.0]).all()
    assert (np.abs(normals[~caps, 2]) < 1e-9).all(), "side faces are vertical: the rim is a sharp edge"


def test_car_is_mirror_symmetric_left_right_only(meshes):
    car = meshes["car"]
    mirrored = {axis: car.points * np.where(np.arange(3) == axis, -1.0, 1.0) for axis in range(3)}
    left_right = distances_to(car, mirrored[1])
    front_back = distances_to(car, mirrored[0])
    assert left_right.max() < 0.1  # the chord error of the mesh: vertices are not mirror images of each other
    assert np.mean(front_back) > 3.0, "front and back must differ"
    top_bottom = distances_to(car, mirrored[2] + [0, 0, car.points[:, 2].max()])
    assert np.mean(top_bottom) > 3.0
    # No turn about the vertical maps it onto itself (it is longer than wide, so 180 deg is the candidate).
    turned = frames.apply(frames.rigid(frames.rot_z(180)), car.points)
    assert np.mean(distances_to(car, turned)) > 3.0


def test_figurine_has_no_mirror_symmetry(meshes):
    figurine = meshes["figurine"]
    centre = 0.5 * (figurine.points.min(axis=0) + figurine.points.max(axis=0))
    for axis in range(3):
        mirrored = centre + (figurine.points - centre) * np.where(np.arange(3) == axis, -1.0, 1.0)
        assert np.mean(distances_to(figurine, mirrored)) > 0.2


def test_symmetric_shapes_map_onto_themselves(meshes):
    for name in ("vase", "cylinder", "sphere"):
        turned = frames.apply(frames.rigid(frames.rot_z(37.0)), meshes[name].points)
        assert distances_to(meshes[name], turned).max() < 0.05, name
    ellipsoid = meshes["ellipsoid"]
    for R in (frames.rot_x(180), frames.rot_y(180), frames.rot_z(180)):
        assert distances_to(ellipsoid, ellipsoid.points @ R.T).max() < 0.05
    assert np.mean(distances_to(ellipsoid, ellipsoid.points @ frames.rot_z(90).T)) > 2.0


def test_edge_length_follows_the_resolution_parameter():
    for edge in (1.75, 3.0):
        assert np.median(edge_lengths(shapes.car_body(edge))) == pytest.approx(edge, rel=0.2)
    assert np.median(edge_lengths(shapes.l_block(edge_mm=5.0))) == pytest.approx(5.0)


def test_workpieces_are_deterministic_and_in_an_arbitrary_frame():
    a, b = shapes.car(), shapes.car()
    assert np.array_equal(a.points, b.points) and np.array_equal(a.triangles, b.triangles)
    body = shapes.car_body()
    assert np.allclose(frames.apply(shapes.CAR_BODY_IN_X, body.points), a.points)
    for upright in (shapes.CAR_BODY_IN_X, shapes.FIGURINE_BODY_IN_X):
        assert frames.omega(upright) > 30 and np.linalg.norm(upright[:3, 3]) > 20


# ---------------------------------------------------------------------------------------------
# Clay
# ---------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def sphere_mesh():
    return shapes.sphere(40.0, edge_mm=1.0)


def test_lump_raises_the_intended_area_by_the_intended_height(sphere_mesh):
    centre = np.array([0.0, 0.0, 40.0])
    result = clay.add_lump(sphere_mesh, centre, radius=10.0, height=2.0)
    within = np.linalg.norm(sphere_mesh.points - centre, axis=1) < 10.0
    assert np.array_equal(result.changed, within)
    assert np.array_equal(result.mesh.points[~within], sphere_mesh.points[~within])
    assert np.array_equal(result.mesh.triangles, sphere_mesh.triangles)
    top = np.argmax(sphere_mesh.points[:, 2])
    assert result.mesh.points[top, 2] == pytest.approx(42.0, abs=1e-9)
    assert result.displacement_mm.max() == pytest.approx(2.0)
    outward = np.linalg.norm(result.mesh.points[within], axis=1) - 40.0  # the sphere's normals are radial
    assert outward == pytest.approx(result.displacement_mm[within], abs=0.01)
    assert (result.displacement_mm[within] > 0).all()


def test_carve_lowers_the_intended_area(sphere_mesh):
    centre = np.array([40.0, 0.0, 0.0])
    result = clay.carve_patch(sphere_mesh, centre, radius=8.0, depth=1.5)
    inward = np.linalg.norm(result.mesh.points[result.changed], axis=1) - 40.0
    assert inward.min() == pytest.approx(-1.5, abs=0.01)
    assert (result.displacement_mm[result.changed] < 0).all()
    assert np.linalg.norm(sphere_mesh.points[result.changed] - centre, axis=1).max() < 8.0
    assert signed_volume(result.mesh.points, result.mesh.triangles) < signed_volume(sphere_mesh.points,
                                                                                     sphere_mesh.triangles)


def test_edit_on_top_sits_on_the_upper_surface():
    car = shapes.car()
    edit = clay.on_top("lump", car, shapes.CAR_BODY_IN_X, at=(60.0, 10.0), radius=15.0, height=4.0)
    local = frames.apply(frames.invert(shapes.CAR_BODY_IN_X), np.array([edit.centre]))[0]
    assert local[:2] == pytest.approx([60.0, 10.0])
    body = shapes.car_body()
    assert distances_to(body, [local])[0] < 1e-3, "on the surface"
    above = local + np.outer(np.linspace(0.5, 100.0, 200), [0, 0, 1])
    assert distances_to(body, above).min() > 0.4, "nothing of the car above it: it is on the top"
    with pytest.raises(InputError):
        clay.on_top("lump", car, shapes.CAR_BODY_IN_X, at=(500.0, 0.0))
    with pytest.raises(InputError):
        clay.ClayEdit("melt", (0, 0, 0), 1.0, 1.0)
