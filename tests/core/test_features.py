"""FPFH in numpy (core/features.py): the same features as open3d's, also where rounding puts a cosine
a hair past 1 (a normal along the line to a neighbour, as on a thin cylinder's end cap), and the
same for any block of points the work is split into."""
import numpy as np
import pytest

from workcal_wb.core import features
from workcal_wb.core.features import fpfh

# Two points whose unit normals point exactly along the line joining them: the cosine of that angle
# comes out 1.0000000000000002 in floating point.
PAIR = np.array([[0.1257302210933933, -0.1321048632913019, 0.6404226504432821],
                 [0.10490011715303971, -0.535669373161111, 0.36159505490948474]])
ALONG = np.tile([-0.04242717776475926, -0.8219883707168715, -0.5679216961810323], (2, 1))


def _open3d_fpfh(points, normals, radius, max_nn=100):
    o3d = pytest.importorskip("open3d")
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    cloud.normals = o3d.utility.Vector3dVector(normals)
    search = o3d.geometry.KDTreeSearchParamHybrid(radius=radius, max_nn=max_nn)
    return np.asarray(o3d.pipelines.registration.compute_fpfh_feature(cloud, search).data).T


def _curved_surface(count: int, seed: int):
    rng = np.random.default_rng(seed)
    u, v = rng.random((2, count)) * 20
    points = np.column_stack([u, v, np.sin(u / 3) * 2])
    normals = np.column_stack([-np.cos(u / 3) * 2 / 3, np.zeros_like(u), np.ones_like(u)])
    return points, normals / np.linalg.norm(normals, axis=1)[:, None]


def test_a_cosine_rounded_past_one_is_no_error():
    features = fpfh(PAIR, ALONG, radius=1.0)
    assert features.shape == (2, 33) and np.isfinite(features).all()
    assert np.allclose(features, _open3d_fpfh(PAIR, ALONG, 1.0), atol=1e-10)


def test_fpfh_equals_open3ds_on_a_curved_surface():
    points, normals = _curved_surface(800, 4)
    assert np.allclose(fpfh(points, normals, 3.0), _open3d_fpfh(points, normals, 3.0), atol=1e-9)


def _lattice_with_ties():
    """Points on a unit lattice (many neighbours at exactly equal distances) with scattered normals."""
    points = np.stack(np.meshgrid(np.arange(12.0), np.arange(12.0), np.arange(3.0)), -1).reshape(-1, 3)
    normals = np.random.default_rng(1).normal(size=points.shape)
    return points, normals / np.linalg.norm(normals, axis=1)[:, None]


@pytest.mark.parametrize("cloud, max_nn", [(_curved_surface(900, 5), 100), (_lattice_with_ties(), 10)])
def test_fpfh_is_the_same_bit_for_bit_for_any_block_of_points(monkeypatch, cloud, max_nn):
    """The neighbour search and the histograms go a block of points at a time (bounded memory); a
    point's features must not depend on where the blocks fall, also where equal distances make the
    nearest-first order and the max_nn cut a matter of tie-breaking."""
    points, normals = cloud
    whole = fpfh(points, normals, 2.5, max_nn)
    for block in (7, 64, 256):
        monkeypatch.setattr(features, "POINT_BLOCK", block)
        assert np.array_equal(fpfh(points, normals, 2.5, max_nn), whole)


def test_fpfh_searches_neighbours_a_bounded_block_at_a_time(monkeypatch):
    """All pairs at once set a prepared model's peak memory (tens of MB at the finest voxel): the
    search must go by blocks of at most POINT_BLOCK points, each point searched once."""
    points, normals = _curved_surface(900, 6)
    searched = []
    search = features._neighbours

    def counted(tree, points, block, *args):
        searched.append(block.stop - block.start)
        return search(tree, points, block, *args)

    monkeypatch.setattr(features, "POINT_BLOCK", 128)
    monkeypatch.setattr(features, "_neighbours", counted)
    fpfh(points, normals, 3.0)
    assert max(searched) <= 128 and sum(searched) == len(points)


def test_fpfh_of_a_model_is_the_same_bit_for_bit_in_blocks(monkeypatch, bunny):
    """The bunny model's prepared features at one of its voxels, whole and in blocks of the default
    size."""
    from workcal_wb.core import global_search, pointops
    from workcal_wb.core.readers import read_cloud

    voxel = 4.0  # mm: one of the voxels match.prepare describes the bunny at (diagonal / 50 / 1.25)
    points = pointops.voxel_downsample(read_cloud(bunny / "bun_zipper.ply", units="m").points, voxel)[0]
    normals = pointops.pca_normals(points, global_search.NORMAL_NEIGHBOURS)
    radius = global_search.FEATURE_RADIUS * voxel
    blocked = fpfh(points, normals, radius)
    assert len(points) > 2 * features.POINT_BLOCK
    monkeypatch.setattr(features, "POINT_BLOCK", len(points))
    assert np.array_equal(fpfh(points, normals, radius), blocked)
