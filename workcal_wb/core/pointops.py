"""Point-set operations the matcher builds on: spacing, voxel grids, normals, surface sampling."""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .errors import require_open3d


def median_spacing(points: np.ndarray, sample: int = 20000, seed: int = 0) -> float:
    """Median distance from a point to its nearest neighbour (the scan's resolution).

    Large clouds are estimated from a random subset: on a surface the spacing grows with the
    square root of the thinning, so the subset's spacing is scaled back by sqrt(m / n).
    """
    n = len(points)
    if n < 2:
        return 0.0
    subset = points
    if n > sample:
        subset = points[np.random.default_rng(seed).choice(n, sample, replace=False)]
    d, _ = cKDTree(subset).query(subset, k=2)
    return float(np.median(d[:, 1]) * np.sqrt(len(subset) / n))


def voxel_keys(points: np.ndarray, voxel: float) -> np.ndarray:
    """One int64 key per point naming its voxel (21 bits per axis, about 2 million voxels across)."""
    cells = np.floor((points - points.min(axis=0)) / voxel).astype(np.int64)
    return (cells[:, 0] << 42) | (cells[:, 1] << 21) | cells[:, 2]


def voxel_downsample(points: np.ndarray, voxel: float) -> tuple[np.ndarray, np.ndarray]:
    """Centroid of the points in each occupied voxel, and the index of one real point in it.

    Centroids average the noise for feature computation; the representative index lets callers
    keep per-point data (normals, labels) of a real point.
    """
    keys = voxel_keys(points, voxel)
    order = np.argsort(keys, kind="stable")
    sorted_keys = keys[order]
    starts = np.flatnonzero(np.r_[True, sorted_keys[1:] != sorted_keys[:-1]])
    counts = np.diff(np.r_[starts, len(order)])
    centroids = np.add.reduceat(points[order], starts, axis=0) / counts[:, None]
    return centroids, order[starts]


def estimate_normals(points: np.ndarray, radius: float, max_nn: int = 30) -> np.ndarray:
    """Unoriented unit normals by local PCA (open3d, multi-threaded)."""
    o3d = require_open3d()
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    pcd.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=radius, max_nn=max_nn))
    return np.asarray(pcd.normals).copy()


def orient_consistently(points: np.ndarray, normals: np.ndarray, k: int = 10) -> np.ndarray:
    """Give PCA normals one consistent side, then make that side the outside.

    The side is propagated along a minimum spanning tree of neighbours (open3d), which survives
    scans whose normals span more than a hemisphere; the global sign is then chosen so normals point
    away from the centroid on balance, true for the convex-ish parts that workpieces mostly are.
    """
    o3d = require_open3d()
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    pcd.normals = o3d.utility.Vector3dVector(normals)
    pcd.orient_normals_consistent_tangent_plane(k)
    oriented = np.asarray(pcd.normals).copy()
    if np.einsum("ij,ij->i", oriented, points - points.mean(axis=0)).sum() < 0:
        oriented = -oriented
    return oriented


def orient_outward(points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Flip normals of a closed-ish model to point away from its centroid."""
    away = points - points.mean(axis=0)
    return np.where(np.einsum("ij,ij->i", normals, away)[:, None] < 0, -normals, normals)


def triangle_normals_and_areas(vertices: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    a, b, c = (vertices[triangles[:, i]] for i in range(3))
    cross = np.cross(b - a, c - a)
    double_area = np.linalg.norm(cross, axis=1)
    normals = cross / np.maximum(double_area, 1e-300)[:, None]
    return normals, 0.5 * double_area


def signed_volume(vertices: np.ndarray, triangles: np.ndarray) -> float:
    """Volume enclosed by a closed mesh; negative when its faces are wound inward."""
    a, b, c = (vertices[triangles[:, i]] for i in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def vertex_normals(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Area-weighted vertex normals of a mesh (zero-area faces contribute nothing)."""
    fn, area = triangle_normals_and_areas(vertices, triangles)
    acc = np.zeros_like(vertices)
    for i in range(3):
        np.add.at(acc, triangles[:, i], fn * area[:, None])
    norm = np.linalg.norm(acc, axis=1, keepdims=True)
    return np.divide(acc, norm, out=np.zeros_like(acc), where=norm > 0)


def sample_triangles(vertices: np.ndarray, triangles: np.ndarray, spacing: float, seed: int = 0):
    """Points on a mesh surface about ``spacing`` apart: every face's centroid, plus uniform
    samples on faces larger than a spacing-sized square.  Returns (points, face normals, face ids).

    Each sample carries the normal and id of the face it lies on, so a point-to-plane residual
    against it is the exact distance to that face's plane, i.e. to the surface itself.
    """
    fn, area = triangle_normals_and_areas(vertices, triangles)
    valid = np.flatnonzero(area > 0)
    extra = np.maximum(np.round(area[valid] / spacing**2).astype(np.int64) - 1, 0)
    face_ids = np.concatenate([valid, np.repeat(valid, extra)])
    rng = np.random.default_rng(seed)
    n_extra = int(extra.sum())
    u, v = rng.random(n_extra), rng.random(n_extra)
    flip = u + v > 1
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    bary = np.concatenate([np.full((len(valid), 2), 1 / 3), np.column_stack([u, v])])
    a, b, c = (vertices[triangles[face_ids, i]] for i in range(3))
    points = a + bary[:, :1] * (b - a) + bary[:, 1:] * (c - a)
    return points, fn[face_ids], face_ids
