"""The stock Open3D pipeline WorkCal is measured against, as Open3D's global-registration tutorial
builds it: voxel grid, FPFH, RANSAC on feature matches, then point-to-plane ICP at full resolution.

The tutorial's parameters are multiples of one voxel size; here the voxel is the model's diagonal
over VOXELS_PER_DIAGONAL, which gives the tutorial's proportions on its own demo data.
"""
from __future__ import annotations

import numpy as np

from .. import frames
from ..errors import require_open3d

VOXELS_PER_DIAGONAL = 50  # the same coarse grid WorkCal's global search uses


def stock_open3d(scan: np.ndarray, model_points: np.ndarray, model_diagonal: float) -> np.ndarray:
    """U (model -> scan) as the tutorial pipeline finds it (it registers scan onto model)."""
    o3d = require_open3d()
    reg = o3d.pipelines.registration
    voxel = model_diagonal / VOXELS_PER_DIAGONAL

    def prepare(points):
        full = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
        down = full.voxel_down_sample(voxel)
        down.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=2 * voxel, max_nn=30))
        feature = reg.compute_fpfh_feature(down, o3d.geometry.KDTreeSearchParamHybrid(radius=5 * voxel, max_nn=100))
        return full, down, feature

    source, source_down, source_fpfh = prepare(scan)
    target, target_down, target_fpfh = prepare(model_points)
    distance = 1.5 * voxel
    coarse = reg.registration_ransac_based_on_feature_matching(
        source_down, target_down, source_fpfh, target_fpfh, True, distance,
        reg.TransformationEstimationPointToPoint(False), 3,
        [reg.CorrespondenceCheckerBasedOnEdgeLength(0.9), reg.CorrespondenceCheckerBasedOnDistance(distance)],
        reg.RANSACConvergenceCriteria(100000, 0.999))
    for cloud in (source, target):
        cloud.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=2 * voxel, max_nn=30))
    fine = reg.registration_icp(source, target, 0.4 * voxel, coarse.transformation,
                                reg.TransformationEstimationPointToPlane())
    return frames.invert(np.asarray(fine.transformation))
