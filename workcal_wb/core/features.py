"""Local shape descriptors for global search (FPFH, Rusu et al. 2009, as open3d computes them)."""
from __future__ import annotations

import numpy as np

from .errors import require_open3d


def fpfh(points: np.ndarray, normals: np.ndarray, radius: float, max_nn: int = 100) -> np.ndarray:
    """(N, 33) Fast Point Feature Histograms; consistent normal orientation matters for matching."""
    o3d = require_open3d()
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    pcd.normals = o3d.utility.Vector3dVector(normals)
    feature = o3d.pipelines.registration.compute_fpfh_feature(
        pcd, o3d.geometry.KDTreeSearchParamHybrid(radius=radius, max_nn=max_nn))
    return np.asarray(feature.data).T.copy()
