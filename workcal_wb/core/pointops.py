"""Point-set operations the matcher builds on: spacing, voxel grids, normals, surface sampling."""
from __future__ import annotations

import threading
from contextlib import contextmanager
from functools import lru_cache

import numpy as np
from scipy.spatial import cKDTree

from .errors import require_open3d


_blas_lock = threading.Lock()
_blas_users = 0  # blocks inside blas_threads, in any thread
_blas_before = None  # OpenBLAS's thread count before the first of them


@contextmanager
def blas_threads(count: int | None):
    """Run the block with OpenBLAS on ``count`` threads; ``None`` leaves it as it is.  A no-op with any
    other BLAS.

    The matcher's matrix products are small or few: OpenBLAS's threads would only spin after each
    one and take the cores that open3d's OpenMP threads need for the features, so headless runs ask
    for 1 (``MatchOptions.blas_threads``).
    OpenBLAS has one setting for the whole process: blocks that overlap (matches in several
    threads) share it; the first one sets it and the last one to leave puts back what was there
    before, so no order of entering and leaving leaves it changed.  This is what threadpoolctl does,
    without the dependency.
    """
    global _blas_users, _blas_before
    blas = _openblas() if count is not None else None
    if blas is None:
        yield
        return
    with _blas_lock:
        if _blas_users == 0:
            _blas_before = blas.openblas_get_num_threads()
            blas.openblas_set_num_threads(int(count))
        _blas_users += 1
    try:
        yield
    finally:
        with _blas_lock:
            _blas_users -= 1
            if _blas_users == 0:
                blas.openblas_set_num_threads(_blas_before)


@lru_cache(maxsize=1)
def _openblas():
    """The OpenBLAS library numpy is using, found among the loaded libraries (Linux), or None."""
    import ctypes

    try:
        with open("/proc/self/maps", encoding="utf-8") as maps:
            paths = {line.split()[-1] for line in maps if line.rstrip().endswith(".so") or ".so." in line}
    except OSError:
        return None
    names = {p: p.rsplit("/", 1)[-1].lower() for p in paths if p.startswith("/")}
    for path in sorted(p for p, name in names.items() if name.startswith("lib") and "blas" in name):
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        if hasattr(lib, "openblas_set_num_threads") and hasattr(lib, "openblas_get_num_threads"):
            return lib
    return None


def hand_back_freed_heap() -> None:
    """Return the free pages glibc's malloc keeps to the system.  A large temporary array freed below
    glibc's mmap threshold (which grows to the largest array freed so far) stays in the heap, and a
    process that prepares a model and then matches scan after scan would otherwise carry each step's
    high-water mark into the next; costs about a millisecond.  A no-op without glibc."""
    libc = _glibc()
    if libc is not None:
        libc.malloc_trim(0)


@lru_cache(maxsize=1)
def _glibc():
    import ctypes

    try:
        libc = ctypes.CDLL("libc.so.6")
    except OSError:  # not glibc
        return None
    return libc if hasattr(libc, "malloc_trim") else None


def lengths(vectors: np.ndarray) -> np.ndarray:
    """Length of each row of an (N, 3) array: np.linalg.norm(vectors, axis=1) to the bit (the same
    sums in the same order), computed a column at a time, which numpy does 2-3x faster."""
    x, y, z = vectors[:, 0], vectors[:, 1], vectors[:, 2]
    return np.sqrt(x * x + y * y + z * z)


def median(values: np.ndarray) -> float:
    """np.median of a non-empty 1-D array of finite numbers, to the bit (the same middle values, the same
    mean of two), without its general machinery: every refinement step asks for one, and on a few
    thousand residuals np.median's overhead is several times the partition's."""
    half = len(values) // 2
    if len(values) % 2:
        return float(np.partition(values, half)[half])
    middle = np.partition(values, (half - 1, half))
    return float((middle[half - 1] + middle[half]) / 2)


def random_subset(points: np.ndarray, limit: int, rng: np.random.Generator) -> np.ndarray:
    """At most ``limit`` of the rows (points, or indices to draw from), drawn without replacement (all
    of them, as they are, when no more)."""
    return points if len(points) <= limit else points[rng.choice(len(points), limit, replace=False)]


def median_spacing(points: np.ndarray, sample: int = 20000, seed: int = 0) -> float:
    """Median distance from a point to its nearest neighbour (the scan's resolution).

    Large clouds are estimated from a random subset: on a surface the spacing grows with the
    square root of the thinning, so the subset's spacing is scaled back by sqrt(m / n).
    """
    n = len(points)
    if n < 2:
        return 0.0
    subset = random_subset(points, sample, np.random.default_rng(seed))
    d, _ = cKDTree(subset).query(subset, k=2)
    return float(np.median(d[:, 1]) * np.sqrt(len(subset) / n))


KEY_BLOCK = 1 << 14  # points given their voxel keys at a time


def voxel_keys(points: np.ndarray, voxel: float) -> np.ndarray:
    """One int64 key per point naming its voxel: 21 bits per axis, or, for a cloud more than 2**21
    voxels across (a stray point far away), the voxel's rank among the occupied ones, so that two
    distant voxels never share a key."""
    low = points.min(axis=0)
    keys = np.empty(len(points), dtype=np.int64)
    # A block at a time: the cells of a whole large scan, as floats and as integers, were two copies of it.
    for start in range(0, len(points), KEY_BLOCK):
        cells = _cells(points[start:start + KEY_BLOCK], low, voxel)
        if cells.max() >= 1 << 21:
            return np.unique(_cells(points, low, voxel), axis=0, return_inverse=True)[1].reshape(-1).astype(np.int64)
        keys[start:start + KEY_BLOCK] = (cells[:, 0] << 42) | (cells[:, 1] << 21) | cells[:, 2]
    return keys


def _cells(points: np.ndarray, low: np.ndarray, voxel: float) -> np.ndarray:
    return np.floor((points - low) / voxel).astype(np.int64)


def voxel_downsample(points: np.ndarray, voxel: float, counts: bool = False):
    """Centroid of the points in each occupied voxel, the index of one real point in it and, if
    asked, how many points it holds.

    Centroids average the noise for feature computation; the representative index lets callers
    keep per-point data (normals, labels) of a real point.
    """
    keys = voxel_keys(points, voxel)
    order = np.argsort(keys)
    sorted_keys, keys = keys[order], None  # a large scan's keys go before its columns are gathered
    starts = np.flatnonzero(np.r_[True, sorted_keys[1:] != sorted_keys[:-1]])
    sizes = np.diff(np.r_[starts, len(order)])
    # An axis at a time (the same sums, bit for bit): points[order] whole was a copy of the scan.
    sums = np.stack([np.add.reduceat(points[order, axis], starts) for axis in range(3)], axis=1)
    centroids = sums / sizes[:, None]
    return (centroids, order[starts], sizes) if counts else (centroids, order[starts])


def estimate_normals(points: np.ndarray, radius: float, max_nn: int = 30) -> np.ndarray:
    """Unoriented unit normals by local PCA (open3d, multi-threaded)."""
    o3d = require_open3d()
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    pcd.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=radius, max_nn=max_nn))
    return np.asarray(pcd.normals).copy()


def pca_normals(points: np.ndarray, k: int = 12) -> np.ndarray:
    """Unoriented unit normals from the ``k`` nearest neighbours (for small clouds, where open3d's
    thread start-up costs more than the work)."""
    k = min(k, len(points))
    _, nb = cKDTree(points).query(points, k)
    nb = nb.reshape(len(points), k)  # k = 1 (a single point) gives a flat array
    local = points[nb] - points[nb].mean(axis=1, keepdims=True)
    _, vecs = np.linalg.eigh(np.einsum("nki,nkj->nij", local, local))
    return vecs[:, :, 0]


def orient_along_tree(points: np.ndarray, normals: np.ndarray, k: int = 10) -> np.ndarray:
    """Give PCA normals one side per connected piece by propagating it along a minimum spanning
    tree of the k-neighbour graph, weighted so that the tree follows nearly parallel normals
    (Hoppe et al. 1992).  Which side comes out is arbitrary: callers that care choose it."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import breadth_first_order, connected_components, minimum_spanning_tree

    n = len(points)
    k = min(k, n - 1)
    if k < 1:
        return normals.copy()
    _, nb = cKDTree(points).query(points, k + 1)
    rows, cols = np.repeat(np.arange(n), k), nb[:, 1:].ravel()
    weight = 1.0 + 1e-6 - np.abs(np.einsum("ij,ij->i", normals[rows], normals[cols]))
    # A virtual root joined to one point of each piece makes one tree for the whole forest.
    _, piece = connected_components(coo_matrix((weight, (rows, cols)), shape=(n, n)), directed=False)
    firsts = np.unique(piece, return_index=True)[1]
    rows = np.concatenate([rows, np.full(len(firsts), n)])
    cols = np.concatenate([cols, firsts])
    weight = np.concatenate([weight, np.full(len(firsts), 1e-9)])
    tree = minimum_spanning_tree(coo_matrix((weight, (rows, cols)), shape=(n + 1, n + 1)))
    order, parent = breadth_first_order(tree, n, directed=False)
    up = parent[:n]
    real = (up >= 0) & (up < n)  # not a child of the virtual root
    agrees = np.einsum("ij,ij->i", normals, normals[np.where(real, up, 0)]) >= 0
    sign = np.ones(n + 1)
    for node in order[1:]:
        if real[node]:
            sign[node] = sign[up[node]] if agrees[node] else -sign[up[node]]
    return normals * sign[:n, None]


def surface_noise(points: np.ndarray, rng: np.random.Generator, probes: int = 1000,
                  k: int = 12) -> tuple[float, float]:
    """The scan's own noise and the size of the patches it was measured on (mm): medians over random
    patches of ``k`` neighbours (see ``local_noise``)."""
    _, noise, radius = local_noise(points, rng, probes, k)
    return (float(np.median(noise)), float(np.median(radius))) if len(noise) else (float("inf"), 0.0)


def local_noise(points: np.ndarray, rng: np.random.Generator, probes: int = 1000, k: int = 12):
    """(indices of random probe points, the noise about each, the radius of its patch): the RMS
    residual of a quadric fitted to the probe's ``k`` nearest neighbours (so curvature does not count
    as noise; degrees of freedom corrected), per probe, so a caller can keep the probes on one object."""
    k = min(k, len(points))
    if k < 8:
        return np.empty(0, np.int64), np.empty(0), np.empty(0)
    chosen = rng.choice(len(points), min(probes, len(points)), replace=False)
    radius, nb = cKDTree(points).query(points[chosen], k)
    patch = points[nb] - points[nb].mean(axis=1, keepdims=True)
    _, axes = np.linalg.eigh(np.einsum("nki,nkj->nij", patch, patch))
    h, u, v = np.moveaxis(np.einsum("nki,nij->nkj", patch, axes), 2, 0)  # height along the normal first
    A = np.stack([u * u, u * v, v * v, u, v, np.ones_like(u)], axis=2)
    AtA = np.einsum("nki,nkj->nij", A, A) + 1e-9 * np.eye(6)
    coef = np.linalg.solve(AtA, np.einsum("nki,nk->ni", A, h)[..., None])[..., 0]
    residual = h - np.einsum("nki,ni->nk", A, coef)
    return chosen, np.sqrt((residual**2).sum(axis=1) / (k - 6)), radius[:, -1]


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
    samples on faces larger than a spacing-sized square.  Returns (points, face ids).

    Each sample carries the id of the face it lies on, so a point-to-plane residual against it
    (with that face's normal) is the exact distance to that face's plane, i.e. to the surface.
    """
    _, area = triangle_normals_and_areas(vertices, triangles)
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
    return points, face_ids


# Shading for display: the share of light every point gets whatever its slope (so no point goes black),
# and the neighbours each normal is fitted to (enough to smooth scanner noise, few enough to stay fast).
SHADING_AMBIENT = 0.3
SHADING_NEIGHBOURS = 12


def shading(points: np.ndarray, light_at, normals: np.ndarray | None = None) -> np.ndarray:
    """A brightness in [0, 1] per point, lit from ``light_at`` (the scanner: every point it saw faces it
    more or less) by the point's surface normal: surfaces square to the scanner bright, oblique ones
    darker.  Normals are estimated from the neighbours when not given."""
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if len(points) < 3:
        return np.ones(len(points))
    if normals is None or len(normals) != len(points):
        normals = _display_normals(points)
    towards = np.asarray(light_at, dtype=np.float64) - points
    towards /= np.maximum(lengths(towards), 1e-12)[:, None]
    facing = np.abs(np.einsum("ij,ij->i", normals, towards))
    return SHADING_AMBIENT + (1.0 - SHADING_AMBIENT) * np.nan_to_num(facing)


# Above this many points open3d's threads estimate normals faster than scipy in one thread.
OPEN3D_NORMALS_FROM = 20000


def _display_normals(points: np.ndarray) -> np.ndarray:
    """Normals good enough to shade by: open3d's for big clouds, scipy's where open3d is missing."""
    from .errors import MissingDependency

    if len(points) > OPEN3D_NORMALS_FROM:
        try:
            return estimate_normals_knn(points, SHADING_NEIGHBOURS)
        except MissingDependency:  # the display goes on without open3d, only slower
            pass
    return pca_normals(points, SHADING_NEIGHBOURS)


def estimate_normals_knn(points: np.ndarray, k: int) -> np.ndarray:
    """Unoriented unit normals from the ``k`` nearest neighbours (open3d, multi-threaded)."""
    o3d = require_open3d()
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(knn=k))
    return np.asarray(pcd.normals).copy()
