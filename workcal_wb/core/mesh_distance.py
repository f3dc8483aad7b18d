"""Exact point-to-mesh distances with numpy and scipy alone, for points near the mesh.

open3d's BVH answers any query fast, but importing open3d costs a whole process ~0.5 s of CPU and
~20 MB, about what a calibration's queries cost here (its verdict and its report weigh points within
a few mm of the workpiece).  Each face is bounded by a sphere about its centroid (radius: its
farthest corner, so every point of the face, a segment or a point too, lies within it), the faces
in tiers of similar radius.  A query point's K nearest centroids of a tier name candidate faces;
the nearest one's exact distance is a first bound, and a face whose sphere lies beyond the best so
far cannot hold a nearer point.  A face of the tier not among the K has its centroid at least the
K-th distance away, so it lies at least that minus the tier's largest radius away: when the best is
within that, it is the exact answer; otherwise every face of the tier whose centroid lies within the
best plus that radius is weighed.  Far from the mesh that is many faces a point: past a budget the
caller's ``beyond`` (open3d) answers for the farthest points.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

# Centroids of each tier asked for first: near a mesh of even faces they nearly always settle a point.
NEAREST_K = 16
# Queries of fewer points go to open3d (SurfaceModel.exact_distance).  Per point numpy costs 2-4x
# open3d's BVH once that is imported (0.5 s): worth it for the few queries of a verdict's poses and a
# report's region (thousands of points each), not for the hundreds of smaller ones with which a pose is
# centred between edges (up to ~3000 points each).
MIN_POINTS = 4096
# Faces weighed at most (about) by the points of a chunk whose K nearest faces leave them in doubt,
# before the farthest of those are handed to the caller's ``beyond`` (~0.05 s of pairs).
BALL_PAIRS = 150_000
# The first tier of faces holds radii up to this many times the median; each next one twice as large.
TIER_SPAN = 1.6
# Points searched at once: their candidate pairs' temporaries stay within ~20 MB.
CHUNK_POINTS = 8192
# Queries of more points than this search the KD-tree on every core (fewer: one is faster).
PARALLEL_POINTS = 4096


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", a, b)


def _workers(points) -> int:
    return -1 if len(points) > PARALLEL_POINTS else 1


class _Tier:
    """Faces of similar size: their indices, centroids (in a KD-tree) and radii."""

    def __init__(self, faces: np.ndarray, centroids: np.ndarray, radius: np.ndarray):
        self.faces, self.centroids, self.radius = faces, centroids, radius
        self.max_radius = float(radius.max())
        self.tree = cKDTree(centroids, balanced_tree=False, compact_nodes=False)


class MeshDistance:
    """Exact unsigned distances from points to a triangle mesh (vertices N x 3, triangles M x 3, M > 0).

    Coordinates are taken from the vertices' centre in float64, so results are exact to rounding.
    Faces of zero area count by their edges.
    """

    def __init__(self, vertices: np.ndarray, triangles: np.ndarray):
        vertices = np.asarray(vertices, dtype=float)
        triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
        self.origin = vertices.mean(axis=0)
        a, b, c = (vertices[triangles[:, i]] - self.origin for i in range(3))
        ab, ac, bc = b - a, c - a, c - b
        normal = np.cross(ab, ac)
        length = np.linalg.norm(normal, axis=1)
        d00, d01, d11 = _dot(ab, ab), _dot(ab, ac), _dot(ac, ac)
        denominator = d00 * d11 - d01**2
        flat = (length <= 0) | (denominator <= 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            # A face without an area gets no plane and NaN barycentric scale: its foot is never inside.
            unit = np.where(flat[:, None], 0.0, normal / length[:, None])
            scale = np.where(flat, np.nan, 1.0 / denominator)
            # 1 / |edge|^2, 0 for an edge of no length (its nearest point is its start).
            inverse = [np.where(n2 > 0, 1.0 / n2, 0.0) for n2 in (d00, d11, _dot(bc, bc))]
        # Everything a point-to-face distance reads, one row per face, so a pair gathers one row.
        self._faces = np.column_stack([a, ab, ac, unit, d00, d01, d11, scale, _dot(ab, bc), _dot(bc, bc), *inverse])
        centroid = (a + b + c) / 3
        radius = np.sqrt(np.max([_dot(v - centroid, v - centroid) for v in (a, b, c)], axis=0))
        # Rounding slack of a bound's comparison (mm): far below any distance the callers weigh.
        self._slack = 1e-9 * (1.0 + float(np.abs(a).max(initial=0.0)) + float(radius.max(initial=0.0)))
        # Faces in tiers by radius: a tier's bound for the faces a point's K nearest leave out is its own
        # largest radius, so a few large faces do not put every point in doubt.
        first = TIER_SPAN * max(float(np.median(radius)), self._slack)
        tier = np.maximum(np.ceil(np.log2(np.maximum(radius, first) / first)), 0).astype(np.int64)
        self._tiers = []
        for t in np.unique(tier):
            faces = np.flatnonzero(tier == t)
            self._tiers.append(_Tier(faces, centroid[faces], radius[faces]))

    def distance(self, points: np.ndarray, beyond=None) -> np.ndarray:
        """Exact unsigned distance of each point (finite, K x 3) to the mesh.  ``beyond(points)``, when
        given, answers instead for points that would weigh more faces than the search's budget (far from
        the mesh, where the faces within reach grow with the square of the distance)."""
        p = np.asarray(points, dtype=float).reshape(-1, 3) - self.origin
        out = np.empty(len(p))
        for start in range(0, len(p), CHUNK_POINTS):  # bounded temporaries (pairs gather a row each)
            out[start:start + CHUNK_POINTS] = self._distance(p[start:start + CHUNK_POINTS], beyond)
        return out

    def _distance(self, p: np.ndarray, beyond) -> np.ndarray:
        best, handed = None, np.zeros(len(p), dtype=bool)
        for tier in self._tiers:
            k = min(NEAREST_K, len(tier.faces))
            if best is None:  # the first tier's nearest face bounds the rest
                reach, near = tier.tree.query(p, k=k, workers=_workers(p))
                reach, near = reach.reshape(len(p), k), near.reshape(len(p), k)
                best = self.face_distance(p, tier.faces[near[:, 0]])
            else:  # one bound for all (scipy 1.10 takes no array of them)
                bound = float(best.max(initial=0.0)) + tier.max_radius + 2 * self._slack
                reach, near = tier.tree.query(p, k=k, distance_upper_bound=bound, workers=_workers(p))
                reach, near = reach.reshape(len(p), k), near.reshape(len(p), k)
                near = np.where(np.isfinite(reach), near, 0)
            row, col = np.nonzero(reach - tier.radius[near] < best[:, None] + self._slack)
            self._keep_nearest(p, best, row, tier.faces[near[row, col]])
            # A face of the tier not among the k has its centroid at least the k-th distance away.
            doubt = np.flatnonzero((reach[:, -1] - tier.max_radius < best + self._slack) & ~handed)
            if len(doubt) and k < len(tier.faces):
                # The faces within a ball grow with its area: k within the k-th distance.
                cost = k * ((best[doubt] + tier.max_radius) / np.maximum(reach[doubt, -1], self._slack))**2
                if beyond is not None and cost.sum() > BALL_PAIRS:
                    order = np.argsort(cost, kind="stable")
                    within = np.cumsum(cost[order]) <= BALL_PAIRS
                    handed[doubt[order[~within]]] = True
                    doubt = np.sort(doubt[order[within]])
                if len(doubt):
                    self._within(p, best, doubt, tier)
        if handed.any():
            best[handed] = beyond(p[handed] + self.origin)
        return best

    def _within(self, p: np.ndarray, best: np.ndarray, rows: np.ndarray, tier: "_Tier") -> None:
        """Lower ``best`` at ``rows`` to the nearest of every face of the tier whose sphere reaches within it."""
        near = tier.tree.query_ball_point(p[rows], best[rows] + tier.max_radius + self._slack)
        count = np.fromiter(map(len, near), dtype=np.int64, count=len(near))
        index = np.fromiter((i for found in near for i in found), dtype=np.int64, count=int(count.sum()))
        row = np.repeat(rows, count)
        offset = p[row] - tier.centroids[index]
        keep = np.sqrt(_dot(offset, offset)) - tier.radius[index] < best[row] + self._slack
        self._keep_nearest(p, best, row[keep], tier.faces[index[keep]])

    def _keep_nearest(self, p: np.ndarray, best: np.ndarray, row: np.ndarray, face: np.ndarray) -> None:
        """Lower ``best`` (in place) to each point's nearest face of the pairs (``row``, ``face``), given
        grouped by row."""
        if len(row):
            start = np.flatnonzero(np.r_[True, row[1:] != row[:-1]])
            nearest = np.minimum.reduceat(self.face_distance(p[row], face), start)
            best[row[start]] = np.minimum(best[row[start]], nearest)

    def face_distance(self, p: np.ndarray, face: np.ndarray) -> np.ndarray:
        """Exact distance of each point ``p[i]`` (relative to ``origin``) to the face ``face[i]``: to its
        plane when the foot falls inside the face, else to the nearest of its edges (each from dot
        products with the face's edges: one gathered row a pair)."""
        f = self._faces[face]
        ap = p - f[:, 0:3]
        along_ab, along_ac, height = (_dot(ap, f[:, i:i + 3]) for i in (3, 6, 9))
        d00, d01, d11, scale, ab_bc, d22, inv00, inv11, inv22 = f[:, 12:21].T
        v = (d11 * along_ab - d01 * along_ac) * scale
        w = (d00 * along_ac - d01 * along_ab) * scale
        out = np.abs(height)
        edge = np.flatnonzero(~((v >= 0) & (w >= 0) & (v + w <= 1)))
        if len(edge):
            ap2 = _dot(ap[edge], ap[edge])
            s1, s2 = along_ab[edge], along_ac[edge]
            d00, d11, ab_bc, d22 = d00[edge], d11[edge], ab_bc[edge], d22[edge]
            bp2 = ap2 - 2 * s1 + d00  # |p - b|^2, b = a + ab
            along_bc = (s2 - s1) - ab_bc  # (p - b) . bc, bc = ac - ab
            squared = np.minimum(np.minimum(_to_segment(ap2, s1, d00, inv00[edge]), _to_segment(ap2, s2, d11, inv11[edge])),
                                 _to_segment(bp2, along_bc, d22, inv22[edge]))
            out[edge] = np.sqrt(np.maximum(squared, 0.0))
        return out


def _to_segment(q2: np.ndarray, along: np.ndarray, length2: np.ndarray, inverse: np.ndarray) -> np.ndarray:
    """Squared distance of points to segments from their start, given |q|^2, q . edge, |edge|^2 and
    1 / |edge|^2 (0 for an edge of no length: its nearest point is its start)."""
    t = np.clip(along * inverse, 0.0, 1.0)
    return q2 - 2 * t * along + t * t * length2
