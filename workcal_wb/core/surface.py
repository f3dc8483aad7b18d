"""A model prepared once for matching: dense surface samples with normals in a KD-tree.

A mesh is matched as a surface: every sample carries its face's plane, so the point-to-plane
residual against the nearest sample is the distance to the model surface itself, not to a vertex.
A point-cloud model (no faces) uses its points with PCA normals.
"""
from __future__ import annotations

from functools import cached_property

import numpy as np
from scipy.spatial import cKDTree

from . import pointops
from .errors import InputError
from .geometry import Cloud, shape_kind

# Mesh samples per model diagonal: fine enough that the nearest sample's face is the face under
# the query point (so residuals are exact), coarse enough to keep the tree ~100k samples.
SAMPLES_PER_DIAGONAL = 250


class SurfaceModel:
    """Samples (mm) with unit outward normals and a KD-tree; coarse features cached per voxel size."""

    def __init__(self, model: Cloud, seed: int = 0):
        if len(model) < 3 or shape_kind(model.points) != "solid":
            kind = "too small" if len(model) < 3 else shape_kind(model.points)
            raise InputError(f"{model.name}: the model is {kind}; a pose cannot be fitted to it")
        self.name = model.name
        self.diagonal = model.diagonal()
        self.is_mesh = model.is_mesh
        if model.is_mesh:
            spacing = self.diagonal / SAMPLES_PER_DIAGONAL
            points, normals, _ = pointops.sample_triangles(model.points, model.triangles, spacing, seed)
            if pointops.signed_volume(model.points, model.triangles) < 0:
                normals = -normals  # faces wound inward (e.g. the Stanford bunny): make normals outward
        else:
            points = model.points
            spacing = pointops.median_spacing(points)
            normals = model.normals if model.normals is not None else pointops.estimate_normals(points, 3 * spacing)
            normals = pointops.orient_outward(points, normals)
        self.points, self.normals, self.spacing = points, normals, spacing
        self.tree = cKDTree(points)
        self.vertices = model.points
        self.triangles = model.triangles
        self._coarse = {}

    def nearest(self, points: np.ndarray, gate: float):
        """(distance, sample index, found) for each point, searching only within ``gate`` mm."""
        # Threads pay off only for large queries (measured: 2k points are faster on one).
        d, idx = self.tree.query(points, distance_upper_bound=gate, workers=-1 if len(points) > 10000 else 1)
        found = np.isfinite(d)
        return d, np.where(found, idx, 0), found

    def plane_residuals(self, points: np.ndarray, idx: np.ndarray) -> np.ndarray:
        """Signed distance of each point to the tangent plane of its sample (positive outside)."""
        return np.einsum("ij,ij->i", points - self.points[idx], self.normals[idx])

    def coarse(self, voxel: float):
        """(points, normals, FPFH features) of the model on a ``voxel`` grid, for global search."""
        key = round(voxel, 9)
        if key not in self._coarse:
            from .features import fpfh

            centroids, rep = pointops.voxel_downsample(self.points, voxel)
            normals = pointops.estimate_normals(centroids, 2 * voxel)
            # Orient like the surface: PCA gives the plane, the samples' normals give the side.
            normals[np.einsum("ij,ij->i", normals, self.normals[rep]) < 0] *= -1
            self._coarse[key] = (centroids, normals, fpfh(centroids, normals, 5 * voxel))
        return self._coarse[key]

    @cached_property
    def exact_distance(self):
        """Exact unsigned point-to-mesh distance function (open3d BVH), or None for point models."""
        if not self.is_mesh:
            return None
        from .errors import require_open3d

        o3d = require_open3d()
        scene = o3d.t.geometry.RaycastingScene()
        scene.add_triangles(o3d.core.Tensor(self.vertices.astype(np.float32)),
                            o3d.core.Tensor(self.triangles.astype(np.uint32)))

        def distance(points: np.ndarray) -> np.ndarray:
            return scene.compute_distance(o3d.core.Tensor(points.astype(np.float32))).numpy().astype(float)

        return distance
