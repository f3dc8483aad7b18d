"""A model prepared once for matching: dense surface samples with normals in a KD-tree.

A mesh is matched as a surface: every sample carries its face's plane, so the point-to-plane
residual against the nearest sample is the distance to the model surface itself, not to a vertex.
A point-cloud model (no faces) uses its points with their normals, or PCA normals turned outward.
What a match needs again and again is kept here, per model: the model's own symmetries and the
near-symmetric turns a match tries (symmetry.py), the samples a view is rendered from
(visibility.py), the coarse points and FPFH features of the global search, and the cell grids (the
paper's space binning) that make a nearest-sample lookup one array access.  What the constructor
computes is plain numpy arrays and numbers, so a cache of prepared models can store them.
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
# A cell grid never has more cells than this (4 bytes each); its cell grows instead.
MAX_GRID_CELLS = 16_000_000
_UNKNOWN, _FAR = -2, -1
# The finest grid (cell = one sample spacing) serves gates up to this many spacings; each coarser
# level doubles both, so a loose gate does not fill a fine grid far from the surface.
GATE_CELLS = 16
# A turn maps the model onto itself (a symmetry) when it moves its surface by less than this
# fraction of the model diagonal (0.1 mm on a 100 mm part), plus three times the model's own noise.
SYMMETRY_TOLERANCE_FRACTION = 1e-3


class NearestGrid:
    """The paper's 3D space binning: a grid around the model whose cells store the model sample
    nearest to their centre, so finding a point's closest model point is one array lookup.

    A grid answers for points within ``bound`` mm of the model; farther cells hold "none".  Cells
    are filled ahead of time (``precompute``) or on first use (``lookup``), each by one KD-tree
    query that is never repeated: an iterative fit keeps its points in nearly the same cells, so
    after the first iteration almost every lookup is a hit.  The cell's sample is at most half a
    cell diagonal from the point's own nearest sample, which at a cell of the sample spacing changes
    a point-to-plane residual by a second-order amount (curvature x offset^2).
    """

    def __init__(self, points: np.ndarray, tree: cKDTree, cell: float, bound: float):
        lo, hi = points.min(axis=0) - bound - cell, points.max(axis=0) + bound + cell
        cell = max(cell, float(np.prod(hi - lo) / MAX_GRID_CELLS) ** (1 / 3))
        self.lo, self.cell, self.bound, self.tree = lo, cell, bound, tree
        self.dims = np.ceil((hi - lo) / cell).astype(np.int64) + 1
        self.index = np.full(int(np.prod(self.dims)), _UNKNOWN, np.int32)
        self.complete = False  # every cell filled (precompute)

    def _cells(self, points: np.ndarray):
        c = np.floor((points - self.lo) / self.cell).astype(np.int64)
        inside = np.all((c >= 0) & (c < self.dims), axis=1)
        return (c[:, 0] * self.dims[1] + c[:, 1]) * self.dims[2] + c[:, 2], inside

    def _fill(self, cells: np.ndarray) -> None:
        cells = np.unique(cells)
        ijk = np.column_stack(np.unravel_index(cells, tuple(self.dims)))
        d, j = self.tree.query(self.lo + (ijk + 0.5) * self.cell, distance_upper_bound=self.bound,
                               workers=-1 if len(cells) > 10000 else 1)
        self.index[cells] = np.where(np.isfinite(d), j, _FAR)

    def lookup(self, points: np.ndarray) -> np.ndarray:
        """Sample index per point, -1 where no sample lies within the bound of its cell."""
        cells, inside = self._cells(points)
        cells = np.where(inside, cells, 0)
        idx = self.index[cells]
        unknown = (idx == _UNKNOWN) & inside
        if unknown.any():
            self._fill(cells[unknown])
            idx = self.index[cells]
        return np.where(inside, idx, _FAR)

    def precompute(self) -> None:
        """Fill every cell now: those within the bound of a sample by query, the rest as "none"."""
        if self.complete:
            return
        occupied = np.zeros(tuple(self.dims), bool)
        c = np.floor((self.tree.data - self.lo) / self.cell).astype(np.int64)
        occupied[c[:, 0], c[:, 1], c[:, 2]] = True
        from scipy.ndimage import binary_dilation

        near = binary_dilation(occupied, iterations=int(np.ceil(self.bound / self.cell)) + 1).ravel()
        self._fill(np.flatnonzero(near & (self.index == _UNKNOWN)))
        self.index[~near] = _FAR
        self.complete = True


class SurfaceModel:
    """Samples (mm) with unit outward normals and a KD-tree, the model's symmetries; coarse features
    cached per voxel size.

    ``symmetry_tolerance_mm`` (default: SYMMETRY_TOLERANCE_FRACTION of the diagonal plus three times
    the model's own noise) is how far a turn may move the surface and still count as a symmetry.
    """

    def __init__(self, model: Cloud, seed: int = 0, symmetry_tolerance_mm: float | None = None):
        if len(model) < 3 or shape_kind(model.points) != "solid":
            kind = "too small" if len(model) < 3 else shape_kind(model.points)
            raise InputError(f"{model.name}: the model is {kind}; a pose cannot be fitted to it")
        self.name = model.name
        self.diagonal = model.diagonal()
        self.is_mesh = model.is_mesh
        self.face_normals = None
        if model.is_mesh:
            spacing = self.diagonal / SAMPLES_PER_DIAGONAL
            points, face_ids = pointops.sample_triangles(model.points, model.triangles, spacing, seed)
            self.face_normals = pointops.triangle_normals_and_areas(model.points, model.triangles)[0]
            if pointops.signed_volume(model.points, model.triangles) < 0:
                self.face_normals = -self.face_normals  # wound inward (e.g. the Stanford bunny): make them outward
            normals = self.face_normals[face_ids]
            # Each sample stands for its share of its face (small faces get one sample each).
            area = pointops.triangle_normals_and_areas(model.points, model.triangles)[1]
            weights = area[face_ids] / np.bincount(face_ids, minlength=len(area))[face_ids]
        else:
            points = model.points
            spacing = pointops.median_spacing(points)
            if model.normals is not None:  # a file's normals say which side is out: keep them
                normals = model.normals / np.maximum(np.linalg.norm(model.normals, axis=1), 1e-12)[:, None]
            else:
                normals = pointops.orient_outward(points, pointops.estimate_normals(points, 3 * spacing))
            weights = np.ones(len(points))
        self.points, self.normals, self.spacing = points, normals, spacing
        self.tree = cKDTree(points)
        self.vertices = model.points
        self.triangles = model.triangles
        rng = np.random.default_rng(seed)
        # A mesh is exact; a point model scatters about its surface like a scan.
        self.noise_mm = 0.0 if model.is_mesh else pointops.surface_noise(points, rng)[0]
        self.view_order = rng.permutation(len(points))  # views are rendered from its first samples
        if symmetry_tolerance_mm is None:
            symmetry_tolerance_mm = float(np.hypot(SYMMETRY_TOLERANCE_FRACTION * self.diagonal, 3 * self.noise_mm))
        self.symmetry_tolerance_mm = symmetry_tolerance_mm
        from . import symmetry

        found = symmetry.find(points, normals, weights, self.tree, spacing, self.diagonal, symmetry_tolerance_mm, seed)
        self.symmetry_axes, self.symmetry_points = found["axes"], found["points"]
        self.symmetry_orders, self.symmetry_deviations_mm = found["orders"], found["deviations_mm"]
        self.flips = found["flips"]
        self._coarse = {}
        self._grids: dict[int, NearestGrid] = {}

    def symmetries(self) -> list[str]:
        """The model's symmetries in words (model frame), e.g. "turning the part 90 degrees about its
        axis ... gives the same surface"; empty when it has none."""
        from .symmetry import describe

        return describe(self.symmetry_axes, self.symmetry_points, self.symmetry_orders)

    def maps_onto_itself(self, T: np.ndarray) -> bool:
        """Whether the rigid motion T (model frame) moves the surface onto itself within the
        symmetry tolerance: two poses differing by such a T cannot be told apart by any scan."""
        return self._self_match.maps(T)[0]

    @cached_property
    def _self_match(self):
        from .symmetry import SelfMatch

        return SelfMatch(self.points, self.normals, self.tree, self.spacing, self.diagonal, self.symmetry_tolerance_mm)

    def nearest(self, points: np.ndarray, gate: float):
        """(distance, sample index, found) for each point, searching only within ``gate`` mm."""
        # Threads pay off only for large queries (measured: 2k points are faster on one).
        d, idx = self.tree.query(points, distance_upper_bound=gate, workers=-1 if len(points) > 10000 else 1)
        found = np.isfinite(d)
        return d, np.where(found, idx, 0), found

    def nearest_cell(self, points: np.ndarray, gate: float):
        """Like ``nearest``, through the cell grid of the gate's level: each point gets its cell's
        nearest sample."""
        level = max(0, int(np.ceil(np.log2(gate / (GATE_CELLS * self.spacing)))))
        idx = self.grid_level(level).lookup(points)
        found = idx >= 0
        idx = np.where(found, idx, 0)
        d = np.linalg.norm(points - self.points[idx], axis=1)
        found &= d <= gate
        return d, idx, found

    def grid_level(self, level: int) -> NearestGrid:
        """The cell grid for gates up to GATE_CELLS x 2^level sample spacings (cached)."""
        if level not in self._grids:
            cell = self.spacing * 2**level
            self._grids[level] = NearestGrid(self.points, self.tree, cell, GATE_CELLS * cell)
        return self._grids[level]

    def grid(self, cell: float, bound: float) -> NearestGrid:
        """A cell grid of its own cell size and bound (cached), e.g. for a method that fills it
        ahead of time."""
        key = ("grid", round(cell, 9), round(bound, 9))
        if key not in self._coarse:
            self._coarse[key] = NearestGrid(self.points, self.tree, cell, bound)
        return self._coarse[key]

    def plane_residuals(self, points: np.ndarray, idx: np.ndarray) -> np.ndarray:
        """Signed distance of each point to the tangent plane of its sample (positive outside)."""
        return np.einsum("ij,ij->i", points - self.points[idx], self.normals[idx])

    def cell_keys(self, points: np.ndarray, cell: float) -> np.ndarray:
        """One int64 key per point naming its cell of a ``cell`` mm grid fixed to the model, so keys
        of scan and model points compare (21 bits per axis, centred, clipped far outside)."""
        cells = np.floor((points - self.points.min(axis=0)) / cell).astype(np.int64) + (1 << 20)
        cells = np.clip(cells, 0, (1 << 21) - 1)
        return (cells[:, 0] << 42) | (cells[:, 1] << 21) | cells[:, 2]

    def occupied_cells(self, cell: float) -> np.ndarray:
        """Sorted keys of the grid cells the model surface passes through (cached per cell size)."""
        key = ("cells", round(cell, 9))
        if key not in self._coarse:
            self._coarse[key] = np.unique(self.cell_keys(self.points, cell))
        return self._coarse[key]

    def coarse(self, voxel: float):
        """(points, normals, FPFH features) of the model on a ``voxel`` grid, for global search."""
        key = round(voxel, 9)
        if key not in self._coarse:
            from .features import fpfh

            from .global_search import FEATURE_RADIUS, NORMAL_NEIGHBOURS

            centroids, rep = pointops.voxel_downsample(self.points, voxel)
            normals = pointops.pca_normals(centroids, NORMAL_NEIGHBOURS)  # as the scan's are estimated
            # Orient like the surface: PCA gives the plane, the samples' normals give the side.
            normals[np.einsum("ij,ij->i", normals, self.normals[rep]) < 0] *= -1
            self._coarse[key] = (centroids, normals, fpfh(centroids, normals, FEATURE_RADIUS * voxel))
        return self._coarse[key]

    @cached_property
    def _bvh(self):
        """open3d's BVH of the mesh and the origin its vertices are given from (the model's centre,
        so its float32 coordinates keep ~1e-4 mm)."""
        from .errors import require_open3d

        o3d = require_open3d()
        origin = self.vertices.mean(axis=0)
        scene = o3d.t.geometry.RaycastingScene()
        scene.add_triangles(o3d.core.Tensor((self.vertices - origin).astype(np.float32)),
                            o3d.core.Tensor(self.triangles.astype(np.uint32)))
        return scene, lambda points: o3d.core.Tensor((points - origin).astype(np.float32)), origin

    def closest_points(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(exact closest point on the mesh, outward normal of its face) for each point; meshes only."""
        scene, query, origin = self._bvh
        answer = scene.compute_closest_points(query(points))
        closest = answer["points"].numpy().astype(float) + origin
        return closest, self.face_normals[answer["primitive_ids"].numpy().astype(np.int64)]

    @cached_property
    def exact_distance(self):
        """Exact unsigned point-to-mesh distance function (open3d BVH), or None for point models."""
        if not self.is_mesh:
            return None
        scene, query, _ = self._bvh
        return lambda points: scene.compute_distance(query(points)).numpy().astype(float)
