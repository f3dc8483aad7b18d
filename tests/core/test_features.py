"""FPFH in numpy (core/features.py): the same features as open3d's, also where rounding puts a cosine
a hair past 1 (a normal along the line to a neighbour, as on a thin cylinder's end cap)."""
import numpy as np
import pytest

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


def test_a_cosine_rounded_past_one_is_no_error():
    features = fpfh(PAIR, ALONG, radius=1.0)
    assert features.shape == (2, 33) and np.isfinite(features).all()
    assert np.allclose(features, _open3d_fpfh(PAIR, ALONG, 1.0), atol=1e-10)


def test_fpfh_equals_open3ds_on_a_curved_surface():
    rng = np.random.default_rng(4)
    u, v = rng.random((2, 800)) * 20
    points = np.column_stack([u, v, np.sin(u / 3) * 2])
    normals = np.column_stack([-np.cos(u / 3) * 2 / 3, np.zeros_like(u), np.ones_like(u)])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    assert np.allclose(fpfh(points, normals, 3.0), _open3d_fpfh(points, normals, 3.0), atol=1e-9)
