"""Global search: pose hypotheses from feature correspondences, no initial guess needed.

RANSAC over FPFH correspondences, vectorised: thousands of 3-point samples are screened by the
rigidity of their triangles, solved in one batched SVD and voted on by all correspondences at once.
The best few distinct poses are returned, not just one, so the caller can refine them all and see
whether a clearly different pose fits almost as well (symmetry).
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .frames import rotation_between_deg


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


def feature_correspondences(scan_features: np.ndarray, model_features: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pairs (scan index, model index): each scan point's nearest model feature, and each model
    point's nearest scan feature; both directions, because clutter in the scan and the unseen part
    of the model each spoil one of them."""
    _, to_model = cKDTree(model_features).query(scan_features, workers=-1)
    _, to_scan = cKDTree(scan_features).query(model_features, workers=-1)
    pairs = np.unique(np.concatenate([
        np.column_stack([np.arange(len(scan_features)), to_model]),
        np.column_stack([to_scan, np.arange(len(model_features))]),
    ]), axis=0)
    return pairs[:, 0], pairs[:, 1]


def ransac_poses(src: np.ndarray, dst: np.ndarray, inlier_distance: float, rng: np.random.Generator,
                 samples: int = 30000, max_solved: int = 2000, keep: int = 100,
                 min_edge: float = 0.0, chunk: int = 128) -> tuple[np.ndarray, np.ndarray]:
    """Up to ``keep`` transforms taking src onto dst, best-voted first, and their vote counts.

    src[i] <-> dst[i] are putative correspondences, mostly wrong.  A sample survives when its two
    triangles have edges within 10 % of each other and longer than ``min_edge``; at most
    ``max_solved`` survivors are solved and voted on, which bounds the time.
    """
    n = len(src)
    if n < 3:
        return np.empty((0, 4, 4)), np.empty(0, int)
    triples = rng.integers(0, n, size=(samples, 3))
    s, d = src[triples], dst[triples]
    edges_s = np.linalg.norm(s - np.roll(s, 1, axis=1), axis=2)
    edges_d = np.linalg.norm(d - np.roll(d, 1, axis=1), axis=2)
    rigid = np.all(np.minimum(edges_s, edges_d) > 0.9 * np.maximum(edges_s, edges_d), axis=1)
    rigid &= np.all(edges_s > min_edge, axis=1)
    solved = np.flatnonzero(rigid)[:max_solved]
    if len(solved) == 0:
        return np.empty((0, 4, 4)), np.empty(0, int)
    T = kabsch_batch(s[solved], d[solved])
    # Preemptive scoring (Nister 2005): vote on a growing random subset of the correspondences and
    # keep the better part of the hypotheses at each round, so most time goes to the promising ones.
    order = rng.permutation(n)
    alive = np.arange(len(T))
    votes = np.zeros(len(T), int)
    counted = 0
    for size in (min(n, 256), min(n, 1024), n):
        batch = order[counted:size]
        votes[alive] += _count_inliers(T[alive], src[batch], dst[batch], inlier_distance, chunk)
        counted = size
        if size < n:
            alive = alive[np.argsort(-votes[alive], kind="stable")[:max(keep, len(alive) // 8)]]
    best = alive[np.argsort(-votes[alive], kind="stable")[:keep]]
    return T[best], votes[best]


def _count_inliers(T: np.ndarray, src: np.ndarray, dst: np.ndarray, distance: float, chunk: int) -> np.ndarray:
    """For each transform, how many src points it takes to within ``distance`` of their dst."""
    counts = np.empty(len(T), int)
    for start in range(0, len(T), chunk):
        Tc = T[start:start + chunk]
        diff = np.matmul(src[None], Tc[:, :3, :3].transpose(0, 2, 1)) + Tc[:, None, :3, 3] - dst
        counts[start:start + chunk] = (np.einsum("hni,hni->hn", diff, diff) < distance**2).sum(axis=1)
    return counts


def distinct(transforms: list, scores: list, centre: np.ndarray, min_angle_deg: float,
             min_shift: float) -> list[int]:
    """Indices of the best-scoring transforms that differ from every better one by more than
    ``min_angle_deg`` of rotation or ``min_shift`` mm of displacement at ``centre``."""
    order = np.argsort(-np.asarray(scores), kind="stable")
    chosen: list[int] = []
    for i in order:
        Ti = transforms[i]
        pi = Ti[:3, :3] @ centre + Ti[:3, 3]
        if all(rotation_between_deg(Ti, transforms[j]) > min_angle_deg
               or np.linalg.norm(pi - (transforms[j][:3, :3] @ centre + transforms[j][:3, 3])) > min_shift
               for j in chosen):
            chosen.append(int(i))
    return chosen
