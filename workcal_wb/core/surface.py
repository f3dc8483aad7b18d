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

import threading
from functools import cached_property

import numpy as np
from scipy.spatial import cKDTree

from . import pointops
from .errors import InputError
from .geometry import SHAPE_WORDS, Cloud, checked, shape_kind
from .visibility import FLAT_DEG, View, median_wall_thickness

# Mesh samples per model diagonal: fine enough that the nearest sample's face is the face under
# the query point (so residuals are exact), coarse enough to keep the tree ~100k samples.
SAMPLES_PER_DIAGONAL = 250
# At most about this many mesh samples: faces whose area is many times what a part of their size
# has (duplicated, or folded onto each other) would otherwise ask for billions; the spacing grows.
MAX_MESH_SAMPLES = 2_000_000
# A cell grid never has more cells than this (4 bytes each); its cell grows instead.
MAX_GRID_CELLS = 16_000_000
# A cell's stored value: 0 not yet looked up, -1 no sample within the bound, else sample index + 1.
# Zero for "unknown" lets a brick of cells start as zeros.
_UNKNOWN, _FAR = 0, -1
# A grid keeps its cells in bricks of BRICK = 2^BRICK_BITS cells a side (BRICK^3 x 4 bytes each).
BRICK_BITS = 2
BRICK = 1 << BRICK_BITS
# Cells filled by one KD-tree query at most (bounds the temporary memory of a fill: ~100 bytes a cell).
FILL_CHUNK = 1 << 15
# precompute scans the grid in slabs of about this many cells: a slab's near cells' keys and values
# live at once (~60 bytes a cell), so the slab bounds the peak memory.
NEAR_SLAB_CELLS = 1 << 16
FLAT_NEIGHBOURS, FLAT_BLOCK = 16, 1 << 12  # SurfaceModel.flat
# SurfaceModel.wall_across looks through this many view samples, on pixels this many (thinned)
# sample spacings wide: a surface covers its pixels, so the wall behind does not show through.
WALL_SAMPLES, WALL_PIXEL_SPACINGS = 6000, 2.0
# sample_cover weighs this many faces at a time (~300 bytes a face at once).
COVER_BLOCK = 1 << 13
# The finest grid (cell = one sample spacing) serves gates up to this many spacings; each coarser
# level doubles both, so a loose gate does not fill a fine grid far from the surface.
GATE_CELLS = 16
# A turn maps the model onto itself (a symmetry) when it moves its surface by less than this
# fraction of the model diagonal (0.1 mm on a 100 mm part), plus three times the model's own noise.
SYMMETRY_TOLERANCE_FRACTION = 1e-3


class _Arrays:
    """Arrays of a stored model, each taken once with its dtype and shape checked (None: any length)."""

    def __init__(self, arrays: dict):
        self.arrays, self.taken = arrays, set()

    def __call__(self, name: str, dtype: str, shape: tuple) -> np.ndarray:
        a = self.arrays[name]
        if a.dtype != np.dtype(dtype) or a.ndim != len(shape) or any(
                want is not None and have != want for have, want in zip(a.shape, shape)):
            raise ValueError(f"{name}: {a.dtype}{a.shape}, not {dtype}{shape}")
        self.taken.add(name)
        return a

    def unused(self) -> set:
        return set(self.arrays) - self.taken


# The parts of a stored grid: (name, dtype, shape).
_GRID_PARTS = (("lo", "f8", (3,)), ("dims", "i8", (3,)), ("size", "f8", (2,)), ("complete", "?", ()),
               ("cells", "i8", (None,)), ("values", "i4", (None,)))


class NearestGrid:
    """The paper's 3D space binning: a grid around the model whose cells store the model sample
    nearest to their centre, so finding a point's closest model point is one array lookup.

    A grid answers for points within ``bound`` mm of the model; farther cells hold "none".  Cells
    are filled ahead of time (``precompute``) or on first use (``lookup``), each by one KD-tree
    query that is never repeated: an iterative fit keeps its points in nearly the same cells, so
    after the first iteration almost every lookup is a hit.  The cell's sample is at most half a
    cell diagonal from the point's own nearest sample, which at a cell of the sample spacing changes
    a point-to-plane residual by a second-order amount (curvature x offset^2).  A cell holds the
    same sample however and whenever it was filled, so a grid kept from an earlier run (the model
    cache) gives the same answers as a fresh one.

    Cells are kept in bricks of BRICK^3, stored only once one of their cells is filled: the cells a
    match visits lie along the surface, a thin shell of a grid of millions of cells, so a dense
    array would hold pages of untouched cells (a brick of 4^3 cells wastes least of a shell).  A cell is
    named by its key: its brick's number times BRICK^3 plus its place in the brick.
    """

    def __init__(self, lo: np.ndarray, dims: np.ndarray, cell: float, bound: float, tree, complete: bool = False):
        self.lo, self.dims, self.cell, self.bound = lo, dims, cell, bound
        self._tree = tree  # a function that returns the samples' KD-tree (built when a cell is first filled)
        self.bricks = -(-np.asarray(dims, np.int64) // BRICK)  # bricks along each axis
        # Each brick's row of ``_rows``: row 0 is all "unknown" and row 1 all "none", shared by the
        # bricks not stored (0 until a cell is filled; 1 for bricks precompute found far from the model).
        self._brick_row = np.zeros(int(np.prod(self.bricks)), np.int32)
        self._rows = np.zeros((8, BRICK**3), np.int32)
        self._rows[1] = _FAR
        self._row_brick = np.full(len(self._rows), -1, np.int64)  # the brick each stored row holds
        self._used = 2
        self.complete = complete  # every cell filled (precompute)
        self.filled = 0  # cells filled by lookups and precompute since the grid was made or loaded
        # One model may serve two threads at once (in FreeCAD a task panel's worker and a recompute;
        # calibration's bootstrap refits): storing a brick moves rows and may reallocate ``_rows``, so
        # reads and writes take turns until the grid is complete.
        self._lock = threading.RLock()

    def __getstate__(self) -> dict:
        return {k: v for k, v in self.__dict__.items() if k != "_lock"}

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state, _lock=threading.RLock())

    @classmethod
    def around(cls, points: np.ndarray, tree, cell: float, bound: float) -> "NearestGrid":
        """A grid over ``points`` and ``bound`` mm around them (no cell filled yet)."""
        lo, hi = points.min(axis=0) - bound - cell, points.max(axis=0) + bound + cell
        cell = max(cell, float(np.prod(hi - lo) / MAX_GRID_CELLS) ** (1 / 3))
        return cls(lo, np.ceil((hi - lo) / cell).astype(np.int64) + 1, cell, bound, tree)

    def _keys(self, ijk: np.ndarray) -> np.ndarray:
        i, j, k = ijk[:, 0], ijk[:, 1], ijk[:, 2]
        brick = ((i >> BRICK_BITS) * self.bricks[1] + (j >> BRICK_BITS)) * self.bricks[2] + (k >> BRICK_BITS)
        inner = BRICK - 1
        return (brick << 3 * BRICK_BITS) | ((i & inner) << 2 * BRICK_BITS) | ((j & inner) << BRICK_BITS) | (k & inner)

    def _ijk(self, keys: np.ndarray) -> np.ndarray:
        brick, place = np.divmod(keys, BRICK**3)
        b = np.column_stack(np.unravel_index(brick, tuple(self.bricks)))
        return b * BRICK + np.column_stack(np.unravel_index(place, (BRICK,) * 3))

    def centres(self, keys: np.ndarray) -> np.ndarray:
        """The centre (mm) of each cell named by its key."""
        return self.lo + (self._ijk(keys) + 0.5) * self.cell

    def _cells(self, points: np.ndarray):
        c = np.floor((points - self.lo) / self.cell).astype(np.int64)
        unsigned = c.view(np.uint64)  # a negative index becomes huge: one comparison per axis tests both ends
        inside = (unsigned[:, 0] < self.dims[0]) & (unsigned[:, 1] < self.dims[1]) & (unsigned[:, 2] < self.dims[2])
        return self._keys(c), inside

    def stored(self, keys: np.ndarray) -> np.ndarray:
        """What each cell holds: 0 not yet looked up, -1 no sample within the bound, else sample index + 1."""
        return self._rows[self._brick_row[keys >> 3 * BRICK_BITS], keys & (BRICK**3 - 1)]

    def _store(self, keys: np.ndarray, values: np.ndarray) -> None:
        brick, place = np.divmod(keys, BRICK**3)
        new = np.unique(brick[self._brick_row[brick] < 2])
        if len(new):
            if self._used + len(new) > len(self._rows):  # grow by half again (at least what is needed)
                size = max(self._used + len(new), len(self._rows) * 3 // 2)
                # In place (new rows zeroed): a large block is remapped, not copied beside the old one.
                # Only the grid holds these arrays (``stored`` hands out copies), hence no refcheck.
                self._rows.resize((size, BRICK**3), refcheck=False)
                self._row_brick.resize(size, refcheck=False)
            rows = np.arange(self._used, self._used + len(new))
            self._rows[rows] = self._rows[self._brick_row[new]]  # what the shared row said of its cells
            self._brick_row[new], self._row_brick[rows] = rows, new
            self._used += len(new)
        self._rows[self._brick_row[brick], place] = values

    def _fill(self, keys: np.ndarray) -> None:
        keys = np.unique(keys)
        self._store(keys, self._queried(keys))
        self.filled += len(keys)

    def _queried(self, keys: np.ndarray) -> np.ndarray:
        """What each cell holds once filled: its centre's nearest sample within the bound (index + 1), else "none"."""
        tree, values = self._tree(), np.empty(len(keys), np.int32)
        for start in range(0, len(keys), FILL_CHUNK):
            part = keys[start:start + FILL_CHUNK]
            d, j = tree.query(self.centres(part), distance_upper_bound=self.bound,
                              workers=-1 if len(part) > 10000 else 1)
            values[start:start + FILL_CHUNK] = np.where(np.isfinite(d), j + 1, _FAR)
        return values

    def lookup(self, points: np.ndarray) -> np.ndarray:
        """Sample index per point, -1 where no sample lies within the bound of its cell."""
        if self.complete:  # every cell filled (precompute): nothing is stored any more, so reads need no turn
            return self._looked_up(points)
        with self._lock:
            return self._looked_up(points)

    def _looked_up(self, points: np.ndarray) -> np.ndarray:
        keys, inside = self._cells(points)
        keys = np.where(inside, keys, 0)
        stored = self.stored(keys)
        unknown = (stored == _UNKNOWN) & inside
        if unknown.any():
            with self._lock:
                self._fill(keys[unknown])
                stored = self.stored(keys)
        return np.where(inside & (stored > 0), stored - 1, -1)

    def known(self) -> int:
        """How many cells are stored filled."""
        with self._lock:
            return int(np.count_nonzero(self._rows[2:self._used]))

    def precompute(self) -> None:
        """Fill every cell now: those within the bound of a sample by query, the rest as "none".

        The grid is scanned twice a slab at a time (a slab's near mask lives at once, not a mask of the
        whole grid).  The first pass counts the bricks that may hold a sample: their rows are allocated
        once and left untouched, so not resident, until used (grown on demand, up to half again too
        many rows were zeroed, and a reallocation may copy them).  The second queries each slab's near
        cells and stores only the bricks where some cell has a sample: about a third of the near
        cube's bricks hold "none" throughout, as the bricks never stored do; what stays unused of the
        rows is handed back."""
        with self._lock:
            if self.complete:
                return
            near_bricks = np.zeros(tuple(self.bricks), bool)
            for start, near in self._near_slabs():
                padded = np.pad(near, [(0, -n % BRICK) for n in near.shape])
                b0, b1, b2 = (n // BRICK for n in padded.shape)
                near_bricks[start // BRICK:start // BRICK + b0] = padded.reshape(
                    b0, BRICK, b1, BRICK, b2, BRICK).any(axis=(1, 3, 5))
            room = self._used + int(np.count_nonzero(self._brick_row[near_bricks.ravel()] == 0))
            del near_bricks
            if room > len(self._rows):
                rows, row_brick = np.empty((room, BRICK**3), np.int32), np.full(room, -1, np.int64)
                rows[:self._used], row_brick[:self._used] = self._rows[:self._used], self._row_brick[:self._used]
                self._rows, self._row_brick = rows, row_brick
            for start, near in self._near_slabs():
                ijk = np.column_stack(np.unravel_index(np.flatnonzero(near), near.shape))
                ijk[:, 0] += start
                keys = self._keys(ijk)
                del ijk
                keys = keys[self.stored(keys) == _UNKNOWN]
                values = self._queried(keys)
                brick = keys >> 3 * BRICK_BITS
                kept = np.isin(brick, brick[values > 0])  # a slab holds whole bricks
                self._store(keys[kept], values[kept])
                self.filled += len(keys)
            # Every near cell is filled now: what is still unknown is far from the model.
            rows = self._rows[2:self._used]
            rows[rows == _UNKNOWN] = _FAR
            self._brick_row[self._brick_row == 0] = 1
            self._rows.resize((self._used, BRICK**3), refcheck=False)
            self._row_brick.resize(self._used, refcheck=False)
            self.complete = True

    def _near_slabs(self):
        """(first x index, near mask) for the grid's slabs of BRICK-aligned x layers in turn.  A cell is
        near when a sample's cell lies within ``reach`` cells of it along every axis: the cube that
        repeated 3x3x3 dilation reaches (diagonal steps too), as three separable 1D maximum filters,
        each slab filtered with ``reach`` layers of halo so it sees the samples beside it."""
        from scipy.ndimage import maximum_filter1d

        reach = int(np.ceil(self.bound / self.cell)) + 1
        cells = np.floor((self._tree().data - self.lo) / self.cell).astype(np.int64)
        cells = cells[np.argsort(cells[:, 0], kind="stable")]
        layers, plane = int(self.dims[0]), (int(self.dims[1]), int(self.dims[2]))
        step = BRICK * max(1, NEAR_SLAB_CELLS // (BRICK * plane[0] * plane[1]))
        for start in range(0, layers, step):
            stop = min(start + step, layers)
            lo, hi = max(start - reach, 0), min(stop + reach, layers)
            first, last = np.searchsorted(cells[:, 0], [lo, hi])
            slab = np.zeros((hi - lo,) + plane, np.uint8)
            slab[cells[first:last, 0] - lo, cells[first:last, 1], cells[first:last, 2]] = 1
            for axis in (1, 2, 0):
                slab = maximum_filter1d(slab, 2 * reach + 1, axis=axis, mode="constant", cval=0)
            yield start, slab[start - lo:stop - lo].view(bool)

    def state(self) -> dict:
        """The grid as plain arrays (its geometry and the cells filled so far in the stored bricks), for
        the model cache."""
        with self._lock:
            rows = self._rows[2:self._used]
            row, place = np.nonzero(rows)
            return {"lo": self.lo, "dims": self.dims, "size": np.array([self.cell, self.bound]),
                    "complete": np.array(self.complete), "cells": self._row_brick[row + 2] * BRICK**3 + place,
                    "values": rows[row, place]}

    @classmethod
    def from_state(cls, state: dict, tree, samples: int) -> "NearestGrid":
        """The grid ``state`` gave for a model of ``samples`` samples; ValueError when it cannot be one."""
        dims, cells, values = state["dims"], state["cells"], state["values"]
        count = int(np.prod(dims)) if dims.shape == (3,) and (dims > 0).all() else 0
        total = int(np.prod(-(-dims // BRICK))) * BRICK**3 if count else 0
        if not (0 < count <= 2 * MAX_GRID_CELLS and state["lo"].shape == (3,) and state["size"].shape == (2,)
                and cells.shape == values.shape and cells.ndim == 1
                and (len(cells) == 0 or (cells.min() >= 0 and cells.max() < total
                                         and values.min() >= _FAR and values.max() <= samples))):
            raise ValueError("a nearest-sample grid that does not fit the model")
        grid = cls(state["lo"], dims, float(state["size"][0]), float(state["size"][1]), tree, bool(state["complete"]))
        if grid.complete:  # the bricks not stored are far from the model
            grid._brick_row[:] = 1
        grid._store(cells, values)
        return grid


class _SampleTree:
    """The samples' KD-tree, built on first call, shared by a model and its grids.  It holds the
    samples, not the model: a bound method would tie the model and its grids in a reference cycle
    (a model let go would keep its memory until the garbage collector's next full pass), and a weak
    reference to the model would leave a grid that outlives it (a copied model's, one kept alone)
    without its samples."""

    def __init__(self, points: np.ndarray):
        self.points, self._built = points, None

    def __call__(self) -> cKDTree:
        if self._built is None:
            self._built = cKDTree(self.points)
        return self._built

    def __getstate__(self) -> dict:
        return {"points": self.points, "_built": None}  # a copy builds its own tree when it needs one


def _faces_vertices_only(mesh: Cloud) -> Cloud:
    """``mesh`` without the vertices no face uses, with a warning: a stray vertex would set the model's
    size (its sample spacing), its shape and the origin its float32 distances are taken about."""
    used = np.zeros(len(mesh.points), bool)
    used[mesh.triangles.ravel()] = True
    unused = len(used) - int(used.sum())
    if not unused:
        return mesh
    warning = f"{mesh.name}: ignored {unused} {'vertex' if unused == 1 else 'vertices'} that no face uses"
    return checked(Cloud(mesh.points[used], None if mesh.normals is None else mesh.normals[used],
                         (np.cumsum(used) - 1)[mesh.triangles], mesh.name, [*mesh.warnings, warning]))


class SurfaceModel:
    """Samples (mm) with unit outward normals and a KD-tree, the model's symmetries; coarse features
    cached per voxel size.

    ``symmetry_tolerance_mm`` (default: SYMMETRY_TOLERANCE_FRACTION of the diagonal plus three times
    the model's own noise) is how far a turn may move the surface and still count as a symmetry.
    """

    def __init__(self, model: Cloud, seed: int = 0, symmetry_tolerance_mm: float | None = None):
        model = checked(model, 3)  # the readers' promises, also for a cloud made in code
        if model.is_mesh:
            model = _faces_vertices_only(model)
        if len(model) < 3 or shape_kind(model.points) != "solid":
            where = ("has fewer than 3 points" if len(model) < 3 else
                     f"has its points {SHAPE_WORDS[shape_kind(model.points)]}")
            raise InputError(f"{model.name}: the model {where}; a pose cannot be fitted to it")
        self.name = model.name
        self.diagonal = model.diagonal()
        self.is_mesh = model.is_mesh
        self.face_normals = None
        warnings = list(model.warnings)
        if model.is_mesh:
            spacing = self.diagonal / SAMPLES_PER_DIAGONAL
            self.face_normals, area = pointops.triangle_normals_and_areas(model.points, model.triangles)
            if area.sum() > MAX_MESH_SAMPLES * spacing**2:
                warnings.append(f"{model.name}: its faces cover {area.sum() / self.diagonal**2:.0f} times the area "
                                "of a square as wide as the part (duplicate or folded faces?); sampled more coarsely")
                spacing = float(np.sqrt(area.sum() / MAX_MESH_SAMPLES))
            points, face_ids = pointops.sample_triangles(model.points, model.triangles, spacing, seed)
            if pointops.signed_volume(model.points, model.triangles) < 0:
                self.face_normals = -self.face_normals  # wound inward (e.g. the Stanford bunny): make them outward
            normals = self.face_normals[face_ids]
            # Each sample stands for its share of its face (small faces get one sample each).
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
        self._tree = _SampleTree(points)
        self.warnings = warnings
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
        self.sample_cover = self._sample_cover() if self.is_mesh else 0.0
        self._features: dict[float, tuple] = {}  # voxel -> coarse points, normals, FPFH
        from .global_search import COARSE_VOXELS_PER_DIAGONAL

        voxel = self.diagonal / COARSE_VOXELS_PER_DIAGONAL  # the features a match at the default voxel uses
        self.flips = np.concatenate([found["flips"], symmetry.near_self_maps(
            *self.coarse(voxel), voxel, self._self_match, found["flips"],
            symmetry.principal_axes(points, weights)[0], spacing, self.diagonal, seed)])
        self._occupied: dict[float, np.ndarray] = {}  # cell size -> keys of the cells the surface passes through
        self._grids: dict[int, NearestGrid] = {}  # level -> the nearest-sample grid for its gates
        self._custom_grids: dict[tuple, NearestGrid] = {}  # (cell, bound) -> a grid of its own

    @property
    def tree(self) -> cKDTree:
        """KD-tree of the samples (built when first needed: a model from the cache may never need it)."""
        return self._tree()

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
        # Threads pay off only for large queries.
        d, idx = self.tree.query(points, distance_upper_bound=gate, workers=-1 if len(points) > 10000 else 1)
        found = np.isfinite(d)
        return d, np.where(found, idx, 0), found

    def nearest_cell(self, points: np.ndarray, gate: float):
        """Like ``nearest``, through the cell grid of the gate's level: each point gets its cell's
        nearest sample."""
        d, idx, found, _ = self._cell_offsets(points, gate)
        return d, idx, found

    def tangent_planes(self, points: np.ndarray, gate: float):
        """(found, residuals, normals): which points ``nearest_cell`` finds, and for those, their
        ``plane_residuals`` and their samples' normals, each sample array gathered once (a
        refinement step asks for all three)."""
        _, idx, found, offset = self._cell_offsets(points, gate)
        normals = self.normals[idx[found]]
        return found, np.einsum("ij,ij->i", offset[found], normals), normals

    def _cell_offsets(self, points: np.ndarray, gate: float):
        """(distance, sample index, found, offset from the sample) through the gate's cell grid."""
        idx = self.grid_level(self.grid_level_for(gate)).lookup(points)
        found = idx >= 0
        idx = np.where(found, idx, 0)
        offset = points - self.points[idx]
        d = pointops.lengths(offset)
        found &= d <= gate
        return d, idx, found, offset

    def grid_level_for(self, gate: float) -> int:
        """The level of the cell grid that serves ``gate`` (mm): the finest whose bound holds it."""
        return max(0, int(np.ceil(np.log2(gate / (GATE_CELLS * self.spacing)))))

    def grid_level(self, level: int) -> NearestGrid:
        """The cell grid for gates up to GATE_CELLS x 2^level sample spacings (cached)."""
        if level not in self._grids:
            cell = self.spacing * 2**level
            self._grids[level] = NearestGrid.around(self.points, self._tree, cell, GATE_CELLS * cell)
        return self._grids[level]

    def grid_filled(self, level: int) -> bool:
        """Whether the cell grid of ``level`` has every cell filled (match.prepare): its lookups fill nothing."""
        return level in self._grids and self._grids[level].complete

    def grid(self, cell: float, bound: float) -> NearestGrid:
        """A cell grid of its own cell size and bound (cached), e.g. for a method that fills it
        ahead of time."""
        key = (round(cell, 9), round(bound, 9))
        if key not in self._custom_grids:
            self._custom_grids[key] = NearestGrid.around(self.points, self._tree, cell, bound)
        return self._custom_grids[key]

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
        key = round(cell, 9)
        if key not in self._occupied:
            self._occupied[key] = np.unique(self.cell_keys(self.points, cell))
        return self._occupied[key]

    def coarse(self, voxel: float):
        """(points, normals, FPFH features) of the model on a ``voxel`` grid, for global search."""
        key = round(voxel, 9)
        if key not in self._features:
            from .features import fpfh

            from .global_search import FEATURE_RADIUS, NORMAL_NEIGHBOURS

            centroids, rep = pointops.voxel_downsample(self.points, voxel)
            normals = pointops.pca_normals(centroids, NORMAL_NEIGHBOURS)  # as the scan's are estimated
            # Orient like the surface: PCA gives the plane, the samples' normals give the side.
            normals[np.einsum("ij,ij->i", normals, self.normals[rep]) < 0] *= -1
            # In float32, as features are matched (global_search.nearest_both_ways): half the memory.
            features = fpfh(centroids, normals, FEATURE_RADIUS * voxel).astype(np.float32)
            self._features[key] = (centroids, normals, features)
        return self._features[key]


    # -- as plain data, for the model cache (model_cache.py) ---------------------------------------

    def state(self) -> tuple[dict, dict]:
        """(numbers and words, arrays): the model as built so far, everything a match reuses: samples,
        normals, mesh, view order, symmetries, and the features, occupied cells and nearest-sample
        grids computed until now.  ``from_state`` makes the same model from it."""
        meta = {"name": self.name, "warnings": list(self.warnings), "diagonal": self.diagonal,
                "is_mesh": self.is_mesh, "spacing": self.spacing, "noise_mm": self.noise_mm,
                "symmetry_tolerance_mm": self.symmetry_tolerance_mm, "sample_cover": self.sample_cover,
                "features": list(self._features),
                "occupied": list(self._occupied), "grids": list(self._grids),
                "custom_grids": [list(key) for key in self._custom_grids]}
        arrays = {"points": self.points, "normals": self.normals, "vertices": self.vertices,
                  "view_order": self.view_order, "symmetry_axes": self.symmetry_axes,
                  "symmetry_points": self.symmetry_points, "symmetry_orders": self.symmetry_orders,
                  "symmetry_deviations_mm": self.symmetry_deviations_mm, "flips": self.flips}
        if self.is_mesh:
            arrays.update(triangles=self.triangles, face_normals=self.face_normals)
        for i, value in enumerate(self._features.values()):
            arrays.update({f"features.{i}.{part}": a for part, a in zip(("points", "normals", "fpfh"), value)})
        arrays.update({f"occupied.{i}": keys for i, keys in enumerate(self._occupied.values())})
        for prefix, grids in (("grid", self._grids), ("custom", self._custom_grids)):
            for i, grid in enumerate(grids.values()):
                arrays.update({f"{prefix}.{i}.{part}": a for part, a in grid.state().items()})
        return meta, arrays

    @classmethod
    def from_state(cls, meta: dict, arrays: dict) -> "SurfaceModel":
        """The model ``state`` gave; ValueError (or KeyError, TypeError) when the data cannot be one."""
        self = cls.__new__(cls)
        for key, kind in (("name", str), ("diagonal", float), ("is_mesh", bool), ("spacing", float),
                          ("noise_mm", float), ("symmetry_tolerance_mm", float), ("sample_cover", float)):
            if not isinstance(meta[key], kind) and not (kind is float and isinstance(meta[key], int)):
                raise ValueError(f"{key} is not a {kind.__name__}")
            setattr(self, key, kind(meta[key]))
        self.warnings = [str(w) for w in meta["warnings"]]
        n = len(arrays["points"])
        take = _Arrays(arrays)
        self.points, self.normals = take("points", "f8", (n, 3)), take("normals", "f8", (n, 3))
        self._tree = _SampleTree(self.points)
        self.view_order = take("view_order", "i8", (n,))
        self.vertices = take("vertices", "f8", (None, 3))
        self.triangles = self.face_normals = None
        if self.is_mesh:
            self.triangles = take("triangles", "i8", (None, 3))
            self.face_normals = take("face_normals", "f8", (len(self.triangles), 3))
            if len(self.triangles) and not (0 <= self.triangles.min() and self.triangles.max() < len(self.vertices)):
                raise ValueError("faces refer to vertices that do not exist")
        k = len(arrays["symmetry_orders"])
        self.symmetry_axes, self.symmetry_points = take("symmetry_axes", "f8", (k, 3)), take("symmetry_points", "f8", (k, 3))
        self.symmetry_orders = take("symmetry_orders", "i8", (k,))
        self.symmetry_deviations_mm = take("symmetry_deviations_mm", "f8", (k,))
        self.flips = take("flips", "f8", (None, 4, 4))
        if n < 3 or not (np.isfinite(self.points).all() and (0 <= self.view_order).all() and (self.view_order < n).all()):
            raise ValueError("samples that are not finite, or a view order outside them")
        self._features = {}
        for i, voxel in enumerate(meta["features"]):
            m = len(arrays[f"features.{i}.points"])
            self._features[float(voxel)] = (take(f"features.{i}.points", "f8", (m, 3)),
                                            take(f"features.{i}.normals", "f8", (m, 3)),
                                            take(f"features.{i}.fpfh", "f4", (m, 33)))
        self._occupied = {float(cell): take(f"occupied.{i}", "i8", (None,)) for i, cell in enumerate(meta["occupied"])}
        self._grids, self._custom_grids = {}, {}
        for prefix, keys, grids in (("grid", [int(level) for level in meta["grids"]], self._grids),
                                    ("custom", [tuple(float(v) for v in key) for key in meta["custom_grids"]],
                                     self._custom_grids)):
            for i, key in enumerate(keys):
                part = {name: take(f"{prefix}.{i}.{name}", dtype, shape) for name, dtype, shape in _GRID_PARTS}
                grids[key] = NearestGrid.from_state(part, self._tree, n)
        if take.unused():
            raise ValueError(f"unknown data {sorted(take.unused())[:3]}")
        return self

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
        return scene, o3d, origin

    def _query(self, points: np.ndarray, ask):
        """``ask(scene, query tensor)`` for the points that are finite in float32, as a dict of
        numpy arrays with NaN rows for the others: open3d aborts the whole process on a NaN or
        infinite query point (an Eigen assertion), and 1e300 is infinite in float32."""
        scene, o3d, origin = self._bvh
        with np.errstate(over="ignore", invalid="ignore"):
            held = (np.asarray(points, float).reshape(-1, 3) - origin).astype(np.float32)
        finite = np.isfinite(held).all(axis=1)
        every = bool(finite.all())
        asked = ask(scene, o3d.core.Tensor(held if every else held[finite]))  # all finite: no copy
        answer = {key: value.numpy() for key, value in asked.items()}
        if every:
            return answer
        full = {}
        for key, value in answer.items():
            full[key] = np.full((len(held),) + value.shape[1:], np.nan)
            full[key][finite] = value
        return full

    def closest_points(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(exact closest point on the mesh, outward normal of its face) for each point (NaN for a
        point that is not finite); meshes only."""
        answer = self._query(points, lambda scene, q: scene.compute_closest_points(q))
        face = answer["primitive_ids"]
        known = np.isfinite(face)
        normals = np.full((len(face), 3), np.nan)
        normals[known] = self.face_normals[face[known].astype(np.int64)]
        return answer["points"].astype(float) + self._bvh[2], normals

    def flat(self, samples: np.ndarray, radius: float) -> np.ndarray:
        """Mask of the ``samples`` (indices) on a flat face: the normals of their FLAT_NEIGHBOURS nearest
        samples within ``radius`` mm agree with theirs within FLAT_DEG (near a face's edge they do not;
        a smooth surface sampled finely may pass, see Judge.continued_faces).  A block of samples at a
        time: their neighbours' normals are 400 bytes a sample."""
        flat, cos = np.empty(len(samples), bool), np.cos(np.radians(FLAT_DEG))
        for start in range(0, len(samples), FLAT_BLOCK):
            part = samples[start:start + FLAT_BLOCK]
            near = self.tree.query(self.points[part], FLAT_NEIGHBOURS, distance_upper_bound=radius)[1]
            found = near < len(self.points)
            agree = np.einsum("ikj,ij->ik", self.normals[np.where(found, near, 0)], self.normals[part]) >= cos
            flat[start:start + FLAT_BLOCK] = (agree | ~found).all(axis=1)
        return flat

    @cached_property
    def wall_across(self) -> float:
        """How thick (mm) the part's wall is, looked through along the axis its surface spreads least
        along (median over WALL_SAMPLES samples on pixels WALL_PIXEL_SPACINGS spacings wide; inf when
        it shows no wall): a plate's or a shell's thickness however far the shell bends (its spread
        across that axis grows with its bend), a body's depth."""
        from .symmetry import principal_axes

        samples = self.view_order[:WALL_SAMPLES]
        points, normals = self.points[samples], self.normals[samples]
        pixel = WALL_PIXEL_SPACINGS * self.spacing * np.sqrt(len(self.points) / len(samples))
        centre, axes, _ = principal_axes(points, np.ones(len(points)))
        view = View(centre + self.diagonal * axes[:, 0], centre, pixel).framed(points, margin=0)
        return median_wall_thickness(view, points, normals)

    @cached_property
    def centre(self) -> np.ndarray:
        """The samples' mean (mm, model frame): what a pose is turned about, and whose shift tells two
        poses apart."""
        return self.points.mean(axis=0)

    def _sample_cover(self) -> float:
        """How far (mm) a point of the mesh can lie from its nearest sample, at most: every face with an
        area has a sample at its centroid (pointops.sample_triangles), so its points lie within its
        farthest corner's distance of that; a face without one is a segment, each point of which lies
        within half its length of an end, and that end within its own nearest sample's distance of one.
        Computed when the model is made and kept in the model cache (every verdict asks for it: ~25 ms
        of a warm bunny match), a block of faces at a time (the corners of a whole large mesh, and
        their copies, set a match's peak memory)."""
        return max((self._cover(self.triangles[start:start + COVER_BLOCK])
                    for start in range(0, len(self.triangles), COVER_BLOCK)), default=0.0)

    def _cover(self, triangles: np.ndarray) -> float:
        corners = self.vertices[triangles]  # faces x 3 corners x 3
        flat = pointops.triangle_normals_and_areas(self.vertices, triangles)[1] <= 0
        cover = np.linalg.norm(corners - corners.mean(axis=1, keepdims=True), axis=2).max(axis=1)
        if flat.any():
            ends = self.tree.query(corners[flat].reshape(-1, 3))[0].reshape(-1, 3).max(axis=1)
            lengths = np.linalg.norm(corners[flat] - np.roll(corners[flat], 1, axis=1), axis=2).max(axis=1)
            cover[flat] = lengths / 2 + ends
        return float(cover.max(initial=0.0))

    def build_exact(self) -> None:
        """Build a mesh's BVH for the exact distances now (open3d imported with it), not in the first
        match that asks for them."""
        if self.is_mesh:
            self._bvh

    @cached_property
    def exact_distance(self):
        """Exact unsigned point-to-mesh distance function (open3d BVH), or None for point models."""
        if not self.is_mesh:
            return None
        return lambda points: self._query(points, lambda scene, q: {"d": scene.compute_distance(q)})["d"].astype(float)
