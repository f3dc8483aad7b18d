"""The stock Open3D pipeline WorkCal is measured against, as Open3D's global-registration tutorial
builds it: voxel grid, FPFH, RANSAC on feature matches, then point-to-plane ICP at full resolution.

The tutorial's parameters are multiples of one voxel size; here the voxel is the model's diagonal
over VOXELS_PER_DIAGONAL, which gives the tutorial's proportions on its own demo data.  The model
side (its voxel grid, normals and FPFH, and the full cloud with normals) is prepared once and reused
across scans, exactly as WorkCal reuses its prepared SurfaceModel, so both are timed per scan.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import frames
from ..errors import require_open3d

VOXELS_PER_DIAGONAL = 50  # the tutorial's 5 cm voxel on its ~2.5 m demo scene


@dataclass
class StockModel:
    """The target side of the tutorial pipeline, computed once per model."""

    voxel: float
    full: object  # open3d PointCloud with normals
    down: object
    features: object


def _prepare(points: np.ndarray, voxel: float):
    o3d = require_open3d()
    reg = o3d.pipelines.registration
    full = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    down = full.voxel_down_sample(voxel)
    down.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=2 * voxel, max_nn=30))
    features = reg.compute_fpfh_feature(down, o3d.geometry.KDTreeSearchParamHybrid(radius=5 * voxel, max_nn=100))
    return full, down, features


def prepare_stock_model(model_points: np.ndarray, model_diagonal: float) -> StockModel:
    o3d = require_open3d()
    voxel = model_diagonal / VOXELS_PER_DIAGONAL
    full, down, features = _prepare(model_points, voxel)
    full.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=2 * voxel, max_nn=30))
    return StockModel(voxel, full, down, features)


def stock_open3d(scan: np.ndarray, model: StockModel) -> np.ndarray:
    """U (model -> scan) as the tutorial pipeline finds it (it registers scan onto model)."""
    o3d = require_open3d()
    reg = o3d.pipelines.registration
    voxel = model.voxel
    source, source_down, source_fpfh = _prepare(scan, voxel)
    distance = 1.5 * voxel
    coarse = reg.registration_ransac_based_on_feature_matching(
        source_down, model.down, source_fpfh, model.features, True, distance,
        reg.TransformationEstimationPointToPoint(False), 3,
        [reg.CorrespondenceCheckerBasedOnEdgeLength(0.9), reg.CorrespondenceCheckerBasedOnDistance(distance)],
        reg.RANSACConvergenceCriteria(100000, 0.999))
    source.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=2 * voxel, max_nn=30))
    fine = reg.registration_icp(source, model.full, 0.4 * voxel, coarse.transformation,
                                reg.TransformationEstimationPointToPlane())
    return frames.invert(np.asarray(fine.transformation))
