"""Global search: pose hypotheses from feature correspondences, no initial guess needed.

The scan is thinned to the coarse voxel grid, less the voxels that only stray points reach and
less a support plane wider than the model (table, platform), and described by FPFH on both sides
of its surface (a scene's normals cannot be oriented outward reliably: each object may come out
flipped), so every point keeps the side whose feature matches the model better.  RANSAC over those
correspondences is vectorised: thousands of samples of two oriented points are screened by their
rigidity, solved in one batched SVD and voted on by all correspondences at once.  The best
distinct poses are returned, not just one, so the caller can refine them all and see whether a
clearly different pose fits almost as well (symmetry).
"""
from __future__ import annotations

import numpy as np

from . import pointops
from .features import fpfh

# The coarse voxel of a search by default: this fraction of the model's diagonal.
COARSE_VOXELS_PER_DIAGONAL = 40
# A voxel reached by fewer scan points than this fraction of a typical point's voxel holds only
# stray points (dust, reflections): on a surface at the scan's density every voxel holds many.
STRAY_DENSITY = 0.2
# FPFH support radius in coarse voxels (Open3D's tutorial proportion), and the neighbours that
# fit a normal (a surface on the voxel grid has about 12 within the tutorial's 2-voxel radius).
FEATURE_RADIUS, NORMAL_NEIGHBOURS = 5.0, 12
_FLIPPED_BINS = np.r_[np.arange(10, -1, -1), np.arange(11, 22), np.arange(32, 21, -1)]
# Two correspondences agree when the cosines between their normals and the line joining them
# differ by less than this (coarse normals are good to a few degrees).
NORMAL_AGREEMENT = 0.15
# Hypotheses of a RANSAC round kept past each preemptive vote (at least; an eighth of them if more).
PREEMPTIVE_KEEP = 50
# A plane holding this fraction of the coarse points and wider than this many model diagonals
# is a support (table, platform), not part of the model.
PLANE_FRACTION, PLANE_WIDTH = 0.2, 1.2
PLANE_BLOCK = 512  # scan points weighed against every candidate plane at once


def coarse_points(points: np.ndarray, voxel: float) -> np.ndarray:
    """Voxel centroids of a scan, without the voxels that hold only stray points."""
    centroids, _, counts = pointops.voxel_downsample(points, voxel, counts=True)
    typical = np.median(np.repeat(counts, counts))  # the count of the voxel a typical point lies in
    return centroids[counts >= STRAY_DENSITY * typical]


def without_large_plane(points: np.ndarray, voxel: float, model_diagonal: float, rng: np.random.Generator,
                        trials: int = 200) -> np.ndarray:
    """The points less the largest plane, when that plane is wider than the model can be (a table or
    platform under the part): its points match every flat bit of the model and would swamp the
    correspondences.  Only the global search drops them; refinement sees every point."""
    plane = large_plane(points, voxel, model_diagonal, rng, trials)
    return points if plane is None else points[~plane[0]]


def large_plane(points: np.ndarray, voxel: float, model_diagonal: float, rng: np.random.Generator,
                trials: int = 200):
    """(mask of the points on it, a point on it, its unit normal) of the largest plane the points lie on
    within ``voxel``, when it holds PLANE_FRACTION of them and is wider than the model can be (a table
    or platform); None otherwise."""
    if len(points) < 50:
        return None
    triples = points[rng.integers(0, len(points), (trials, 3))]
    normals = np.cross(triples[:, 1] - triples[:, 0], triples[:, 2] - triples[:, 0])
    length = np.linalg.norm(normals, axis=1)
    ok = length > 1e-12
    normals, triples = normals[ok] / length[ok, None], triples[ok]
    offsets = np.einsum("tj,tj->t", triples[:, 0], normals)
    # A block of points against every plane at a time, kept as bits: all the (N, T) distances at once
    # were a match's largest transient (64 MB for 20k coarse points).  The same plane is found, save
    # for a point within a few ulps of the band (BLAS may sum a short block another way).
    votes, near = np.zeros(len(normals), dtype=np.int64), []
    for start in range(0, len(points), PLANE_BLOCK):
        block = np.abs(points[start:start + PLANE_BLOCK] @ normals.T - offsets) < voxel
        votes += block.sum(axis=0)
        near.append(np.packbits(block, axis=1))
    best, near = int(votes.argmax()), np.concatenate(near)
    on_plane = (near[:, best // 8] >> (7 - best % 8) & 1).astype(bool)
    flat = points[on_plane]
    if len(flat) < PLANE_FRACTION * len(points):
        return None
    centre = flat.mean(axis=0)
    _, _, axes = np.linalg.svd(flat - centre, full_matrices=False)
    spread = np.percentile(flat @ axes[:2].T, [1, 99], axis=0)
    if np.linalg.norm(spread[1] - spread[0]) <= PLANE_WIDTH * model_diagonal:
        return None
    return on_plane, centre, axes[2]


def describe_scan(points: np.ndarray, voxel: float) -> tuple[np.ndarray, np.ndarray]:
    """(N, 2, 33) FPFH of coarse scan points with their normals oriented one way and the other, in
    float32 as they are matched (nearest_both_ways), and those normals (the first way).

    Flipping every normal negates FPFH's first and third angle and keeps the second, so the
    flipped histogram is the same one with those two 11-bin blocks reversed: one computation.
    """
    normals = pointops.orient_along_tree(points, pointops.pca_normals(points, NORMAL_NEIGHBOURS))
    features = fpfh(points, normals, FEATURE_RADIUS * voxel).astype(np.float32)
    return np.stack([features, features[:, _FLIPPED_BINS]], axis=1), normals


def nearest_both_ways(a: np.ndarray, b: np.ndarray, chunk: int = 256):
    """For each row of ``a`` its nearest row of ``b`` and the squared distance, and the same for
    each row of ``b`` in ``a``: one matrix product serves both directions.

    Brute force: in 33 dimensions a KD-tree visits most of the points anyway, and BLAS does it
    faster.  ``chunk`` rows at a time: the block and the copy numpy's argmin down its columns makes
    stay a few MB (the same answers, bit for bit, for any chunk).
    """
    a, b = a.astype(np.float32, copy=False), b.astype(np.float32, copy=False)
    a_sq, b_sq = np.einsum("ij,ij->i", a, a), np.einsum("ij,ij->i", b, b)
    a_to_b, a_dist = np.empty(len(a), np.int64), np.empty(len(a), np.float32)
    b_to_a, b_dist = np.zeros(len(b), np.int64), np.full(len(b), np.inf, np.float32)
    for start in range(0, len(a), chunk):
        rows = slice(start, start + chunk)
        d = a[rows] @ b.T  # then |a|^2 - 2 a.b + |b|^2 in place: the matrix is the cost here
        d *= -2
        d += b_sq
        d += a_sq[rows, None]
        j = d.argmin(axis=1)
        a_to_b[rows], a_dist[rows] = j, d[np.arange(len(j)), j]
        i = d.argmin(axis=0)
        closer = d[i, np.arange(len(b))] < b_dist
        b_to_a[closer], b_dist[closer] = i[closer] + start, d[i[closer], np.flatnonzero(closer)]
    return a_to_b, a_dist, b_to_a, b_dist


def feature_correspondences(scan_features: np.ndarray, model_features: np.ndarray):
    """Pairs (scan index, model index) and the side (+1 or -1) of the scan normal that matched:
    each scan point's nearest model feature (over both of its sides), and each model point's nearest
    scan feature.  Both directions, because clutter in the scan and the unseen part of the model
    each spoil one."""
    n = len(scan_features)
    to_model, d_model, to_scan, _ = nearest_both_ways(scan_features.reshape(2 * n, -1), model_features)
    rows = 2 * np.arange(n) + d_model.reshape(n, 2).argmin(axis=1)
    pairs = np.concatenate([np.column_stack([np.arange(n), to_model[rows], rows % 2]),
                            np.column_stack([to_scan // 2, np.arange(len(model_features)), to_scan % 2])])
    _, first = np.unique(pairs[:, :2], axis=0, return_index=True)
    return pairs[first, 0], pairs[first, 1], 1 - 2 * pairs[first, 2]


def kabsch_batch(src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """Least-squares rigid transforms (h, 4, 4) taking src[h] onto dst[h], each (h, k, 3)."""
    cs, cd = src.mean(axis=1), dst.mean(axis=1)
    H = np.einsum("hki,hkj->hij", src - cs[:, None], dst - cd[:, None])
    U, _, Vt = np.linalg.svd(H)
    D = np.ones((len(H), 3))
    D[:, 2] = np.sign(np.linalg.det(np.einsum("hji,hkj->hik", Vt, U)))
    R = np.einsum("hji,hj,hkj->hik", Vt, D, U)
    T = np.tile(np.eye(4), (len(H), 1, 1))
    T[:, :3, :3] = R
    T[:, :3, 3] = cd - np.einsum("hij,hj->hi", R, cs)
    return T


def ransac_poses(src: np.ndarray, dst: np.ndarray, src_normals: np.ndarray, dst_normals: np.ndarray,
                 inlier_distance: float, rng: np.random.Generator, samples: int = 40000,
                 max_solved: int = 2000, keep: int = 100, min_edge: float = 0.0, rounds: int = 4,
                 enough: float = 0.1, chunk: int = 128) -> tuple[np.ndarray, np.ndarray]:
    """Up to ``keep`` transforms taking src onto dst, best-voted first, and their vote counts.

    src[i] <-> dst[i] are putative correspondences, mostly wrong, with unit normals.  A sample is
    two of them: two oriented points fix a pose, so a sample is right with
    the square of the inlier ratio, not its cube (blocky parts give ~1 % right correspondences:
    1e-4 instead of 1e-6).  It survives when the pairs agree in length (10 %, longer than
    ``min_edge``) and in the angles between the normals and the joining line (NORMAL_AGREEMENT);
    at most ``max_solved`` survivors are solved and voted on, which bounds the time.  The budget is
    spent in ``rounds``; the search stops early once a pose has the votes of ``enough`` of all
    correspondences (a clean view: the rest would only add copies of it).
    """
    n = len(src)
    found_T, found_votes = [np.empty((0, 4, 4))], [np.empty(0, int)]
    if n < 2:
        return found_T[0], found_votes[0]
    order = rng.permutation(n)
    arm = 2 * inlier_distance  # normals enter the fit as points this far along them
    for _ in range(rounds):
        a, b = rng.integers(0, n, size=(2, samples // rounds))
        ds, dd = src[b] - src[a], dst[b] - dst[a]
        ls, ld = np.linalg.norm(ds, axis=1), np.linalg.norm(dd, axis=1)
        ok = (np.minimum(ls, ld) > 0.9 * np.maximum(ls, ld)) & (ls > min_edge)
        us, ud = ds / np.maximum(ls, 1e-12)[:, None], dd / np.maximum(ld, 1e-12)[:, None]
        for s_val, d_val in ((np.einsum("ij,ij->i", src_normals[a], src_normals[b]),
                              np.einsum("ij,ij->i", dst_normals[a], dst_normals[b])),
                             (np.einsum("ij,ij->i", src_normals[a], us), np.einsum("ij,ij->i", dst_normals[a], ud)),
                             (np.einsum("ij,ij->i", src_normals[b], us), np.einsum("ij,ij->i", dst_normals[b], ud))):
            ok &= np.abs(s_val - d_val) < NORMAL_AGREEMENT
        solved = np.flatnonzero(ok)[:max_solved // rounds]
        if len(solved) == 0:
            continue
        a, b = a[solved], b[solved]
        T = kabsch_batch(np.stack([src[a], src[b], src[a] + arm * src_normals[a], src[b] + arm * src_normals[b]], 1),
                         np.stack([dst[a], dst[b], dst[a] + arm * dst_normals[a], dst[b] + arm * dst_normals[b]], 1))
        # Preemptive scoring (Nister 2005): vote on a growing subset of the correspondences and keep
        # the better part of the hypotheses at each step, so most time goes to the promising ones.
        alive = np.arange(len(T))
        votes = np.zeros(len(T), int)
        counted = 0
        for size in (min(n, 256), min(n, 1024), n):
            batch = order[counted:size]
            votes[alive] += _count_inliers(T[alive], src[batch], dst[batch], inlier_distance, chunk)
            counted = size
            if size < n:
                alive = alive[np.argsort(-votes[alive], kind="stable")[:max(PREEMPTIVE_KEEP, len(alive) // 8)]]
        found_T.append(T[alive])
        found_votes.append(votes[alive])
        if votes[alive].max() >= enough * n:
            break
    T, votes = np.concatenate(found_T), np.concatenate(found_votes)
    best = np.argsort(-votes, kind="stable")[:keep]
    return T[best], votes[best]


def _count_inliers(T: np.ndarray, src: np.ndarray, dst: np.ndarray, distance: float, chunk: int) -> np.ndarray:
    """For each transform, how many src points it takes to within ``distance`` of their dst."""
    counts = np.empty(len(T), int)
    for start in range(0, len(T), chunk):
        Tc = T[start:start + chunk]
        diff = np.matmul(src[None], Tc[:, :3, :3].transpose(0, 2, 1)) + Tc[:, None, :3, 3] - dst
        counts[start:start + chunk] = (np.einsum("hni,hni->hn", diff, diff) < distance**2).sum(axis=1)
    return counts


def distinct(transforms, scores, centre: np.ndarray, min_angle_deg: float, min_shift: float,
             limit: int | None = None) -> list[int]:
    """Indices of the best-scoring transforms (at most ``limit``) that differ from every better
    one by more than ``min_angle_deg`` of rotation or ``min_shift`` mm of displacement at ``centre``."""
    T = np.asarray(transforms).reshape(-1, 4, 4)
    at_centre = T[:, :3, :3] @ centre + T[:, :3, 3]
    # cos of the angle between two rotations is (trace(Ri^T Rj) - 1) / 2; all pairs at once
    cos = (np.einsum("aij,bij->ab", T[:, :3, :3], T[:, :3, :3]) - 1) / 2
    shift = np.linalg.norm(at_centre[:, None] - at_centre[None], axis=2)
    same = (cos >= np.cos(np.radians(min_angle_deg))) & (shift <= min_shift)
    chosen: list[int] = []
    for i in np.argsort(-np.asarray(scores), kind="stable"):
        if not same[i, chosen].any():
            chosen.append(int(i))
            if limit is not None and len(chosen) == limit:
                break
    return chosen
