"""Exact point-to-mesh distances in numpy (mesh_distance.py) against brute force over every face."""
import numpy as np
import pytest

from workcal_wb.core import mesh_distance
from workcal_wb.core.geometry import Cloud
from workcal_wb.core.mesh_distance import MeshDistance
from workcal_wb.core.surface import SurfaceModel


def _closest_on_triangle(p, a, b, c):
    """Ericson's closest point on triangle abc to p (Real-Time Collision Detection 5.1.5), by Voronoi
    region; for a face of no area, the nearest of its three edges."""
    ab, ac, ap = b - a, c - a, p - a
    if np.linalg.norm(np.cross(ab, ac)) == 0:
        return min((_closest_on_segment(p, s, e) for s, e in ((a, b), (b, c), (c, a))), key=lambda q: np.linalg.norm(p - q))
    d1, d2 = ab @ ap, ac @ ap
    if d1 <= 0 and d2 <= 0:
        return a
    bp = p - b
    d3, d4 = ab @ bp, ac @ bp
    if d3 >= 0 and d4 <= d3:
        return b
    vc = d1 * d4 - d3 * d2
    if vc <= 0 and d1 >= 0 and d3 <= 0:
        return a + d1 / (d1 - d3) * ab
    cp = p - c
    d5, d6 = ab @ cp, ac @ cp
    if d6 >= 0 and d5 <= d6:
        return c
    vb = d5 * d2 - d1 * d6
    if vb <= 0 and d2 >= 0 and d6 <= 0:
        return a + d2 / (d2 - d6) * ac
    va = d3 * d6 - d5 * d4
    if va <= 0 and d4 - d3 >= 0 and d5 - d6 >= 0:
        return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b)
    denominator = 1 / (va + vb + vc)
    return a + ab * vb * denominator + ac * vc * denominator


def _closest_on_segment(p, s, e):
    length2 = (e - s) @ (e - s)
    t = 0.0 if length2 == 0 else np.clip((p - s) @ (e - s) / length2, 0.0, 1.0)
    return s + t * (e - s)


def _brute_force(points, vertices, triangles):
    return np.array([min(np.linalg.norm(p - _closest_on_triangle(p, *vertices[t])) for t in triangles) for p in points])


def _bumpy_mesh(n=9, seed=0):
    """A wavy grid of triangles of uneven sizes, with a sliver, a face folded to a segment, one shrunk to
    a point and a large face leaning over the rest (radius tiers, degenerate faces)."""
    rng = np.random.default_rng(seed)
    x, y = np.meshgrid(np.cumsum(rng.uniform(0.5, 2.0, n)), np.cumsum(rng.uniform(0.5, 2.0, n)))
    z = np.sin(x) * np.cos(0.7 * y)
    vertices = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    i = np.arange(n * n).reshape(n, n)
    quads = np.column_stack([i[:-1, :-1].ravel(), i[:-1, 1:].ravel(), i[1:, 1:].ravel(), i[1:, :-1].ravel()])
    triangles = np.vstack([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    extra = np.array([[3.0, 3.0, 2.0], [4.0, 3.0, 2.0], [5.0, 3.0, 2.0],  # a face folded to a segment
                      [6.0, 6.0, -1.0],  # a face shrunk to a point (three times one vertex)
                      [0.0, 0.0, 3.0], [14.0, 2.0, 4.0], [5.0, 15.0, 2.5]])  # a large face over the rest
    m = len(vertices)
    vertices = np.vstack([vertices, extra])
    triangles = np.vstack([triangles, [[m, m + 1, m + 2], [m + 3, m + 3, m + 3], [m + 4, m + 5, m + 6],
                                       [0, 1, m + 1]]])  # and a sliver from the grid's corner
    return vertices, triangles


def _queries(vertices, rng, count):
    """Points on, near and far from the mesh, and some exactly at its vertices."""
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    near = vertices[rng.integers(0, len(vertices), count)] + rng.normal(0, 0.3, (count, 3))
    far = rng.uniform(lo - 10, hi + 10, (count // 2, 3))
    return np.vstack([near, far, vertices[:5]])


@pytest.fixture(scope="module")
def bumpy():
    vertices, triangles = _bumpy_mesh()
    points = _queries(vertices, np.random.default_rng(1), 120)
    return vertices, triangles, points, _brute_force(points, vertices, triangles)


@pytest.mark.parametrize("nearest_k", [2, 16])
def test_distances_equal_brute_force_with_degenerate_and_large_faces(bumpy, nearest_k, monkeypatch):
    """With few candidates first (2), most points need the search of every face within reach."""
    vertices, triangles, points, exact = bumpy
    monkeypatch.setattr(mesh_distance, "NEAREST_K", nearest_k)
    assert np.allclose(MeshDistance(vertices, triangles).distance(points), exact, rtol=0, atol=1e-9)


def test_points_handed_beyond_the_budget_get_the_same_answer(monkeypatch):
    """Points that would weigh too many faces go to the caller's ``beyond`` (open3d in SurfaceModel);
    with no budget every point in doubt goes there, and the answers are the same."""
    vertices, triangles = _bumpy_mesh(seed=2)
    points = _queries(vertices, np.random.default_rng(3), 80)
    exact = _brute_force(points, vertices, triangles)
    handed = []

    def beyond(far):
        handed.append(len(far))
        return _brute_force(far, vertices, triangles)

    monkeypatch.setattr(mesh_distance, "BALL_PAIRS", 0)
    assert np.allclose(MeshDistance(vertices, triangles).distance(points, beyond=beyond), exact, rtol=0, atol=1e-9)
    assert handed and sum(handed) < len(points)  # the far ones only: those near are settled by their nearest faces


@pytest.mark.parametrize("offset", [0.0, 1e5])
def test_a_surface_model_answers_like_open3d_far_from_the_origin_too(offset):
    """SurfaceModel.exact_distance (numpy near the mesh) against open3d's BVH on a closed mesh, in
    coordinates far from the origin; a point that is not finite gets NaN, as from open3d."""
    pytest.importorskip("open3d")
    rng = np.random.default_rng(4)
    turns, rows = np.meshgrid(np.linspace(0, 2 * np.pi, 40, endpoint=False), np.linspace(0.2, np.pi - 0.2, 20))
    ring = np.column_stack([np.sin(rows.ravel()) * np.cos(turns.ravel()), np.sin(rows.ravel()) * np.sin(turns.ravel()),
                            np.cos(rows.ravel())]) * [40.0, 25.0, 15.0] + offset
    i = np.arange(800).reshape(20, 40)
    quads = np.column_stack([i[:-1].ravel(), np.roll(i, -1, axis=1)[:-1].ravel(), np.roll(i, -1, axis=1)[1:].ravel(),
                             i[1:].ravel()])
    triangles = np.vstack([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    model = SurfaceModel(Cloud(ring, triangles=triangles, name="ellipsoid band"))
    points = np.vstack([ring[rng.integers(0, 800, 6000)] + rng.normal(0, 0.5, (6000, 3)),
                        rng.uniform(-60, 60, (300, 3)) + offset, [[np.nan, 0, 0], [1e300, 0, 0]]])
    got, want = model.exact_distance(points), model._bvh_distance(points)
    assert np.isnan(got[-2:]).all() and np.isnan(want[-2:]).all()
    assert np.allclose(got[:-2], want[:-2], rtol=0, atol=1e-3 + 1e-7 * offset)  # open3d works in float32
