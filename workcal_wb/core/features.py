"""Local shape descriptors for global search: Fast Point Feature Histograms (Rusu et al. 2009).

Computed with numpy and a KD-tree, the way open3d's ``compute_fpfh_feature`` defines them (its
neighbourhoods, angle conventions, 11 bins per angle and the inverse squared distance weights), so
the features are open3d's to rounding, without importing open3d: a match against a prepared model
then needs no library that takes a second to load.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.sparse import csr_matrix
from scipy.spatial import cKDTree

BINS = 11
# Pairs whose angles are computed at once (each pair's own arithmetic: the chunk changes no bit).
PAIR_CHUNK = 1 << 13
# Points whose neighbourhoods are searched and described at once: a block's candidate pairs (up to a
# few hundred per point) stay a few MB, where all points' pairs at once set a prepared model's peak.
POINT_BLOCK = 1 << 10


def fpfh(points: np.ndarray, normals: np.ndarray, radius: float, max_nn: int = 100) -> np.ndarray:
    """(N, 33) Fast Point Feature Histograms over the ``max_nn`` nearest neighbours within ``radius``;
    consistent normal orientation matters for matching.

    A block of points at a time (POINT_BLOCK): a point's histograms depend only on its own
    neighbours, and its sums are taken in the same order whatever the block, so the features are
    the same, bit for bit, for any block size."""
    points = np.ascontiguousarray(points, dtype=np.float64)
    normals = np.ascontiguousarray(normals, dtype=np.float64)
    n = len(points)
    if n < 2:
        return np.zeros((n, 3 * BINS))
    tree = cKDTree(points)
    blocks = [slice(start, min(start + POINT_BLOCK, n)) for start in range(0, n, POINT_BLOCK)]
    neighbours = []  # per block: the neighbours and their squared distances
    counts = np.empty(n, np.int64)  # neighbours per point
    spfh = np.empty((n, 3 * BINS))
    for block in blocks:
        counts[block], cols, squared = _neighbours(tree, points, block, radius, min(max_nn, n))
        spfh[block] = _simple_histograms(points, normals, block, counts[block], cols)
        neighbours.append((cols, squared))
    features = np.empty((n, 3 * BINS))
    for block in blocks:
        cols, squared = neighbours.pop(0)
        features[block] = _weighted_neighbours(spfh, counts[block], cols, squared)
    features += spfh
    features[counts == 0] = 0.0
    return features


def _weighted_neighbours(spfh, count, cols, squared) -> np.ndarray:
    """Each point's neighbours' SPFH weighted by their inverse squared distances, summed nearest
    first (a sparse product adds a row's entries in the order they are stored), and scaled so
    each of the three angles' histograms sums to 100."""
    rows = np.repeat(np.arange(len(count)), count)
    near = squared > 0
    starts = np.concatenate([[0], np.cumsum(np.bincount(rows[near], minlength=len(count)))])
    weights = csr_matrix((1.0 / squared[near], cols[near], starts), shape=(len(count), len(spfh)))
    features = (weights @ spfh).reshape(len(count), 3, BINS)
    sums = features.sum(axis=2)
    features *= np.divide(100.0, sums, out=np.ones_like(sums), where=sums != 0)[:, :, None]
    return features.reshape(len(count), 3 * BINS)


def _neighbours(tree: cKDTree, points: np.ndarray, block: slice, radius: float, max_nn: int):
    """(neighbours per point, neighbours, squared distances) of the points in ``block``: each one's
    nearest ``max_nn`` closer than ``radius``, itself excluded, nearest first (equal distances by
    index), point by point."""
    found = cKDTree(points[block]).sparse_distance_matrix(tree, radius, output_type="ndarray")
    index = np.int32 if len(points) < 2**31 else np.int64  # a model's features in less memory
    rows, cols = found["i"].astype(index), found["j"].astype(index)
    del found
    squared = np.zeros(len(rows))
    for axis in range(3):  # the same squared length either way round, bit for bit
        delta = points[cols, axis] - points[rows + block.start, axis]
        squared += delta * delta
    keep = (cols != rows + block.start) & (squared < radius * radius)
    rows, cols, squared = rows[keep], cols[keep], squared[keep]
    order = np.lexsort((cols, squared, rows))  # by point, nearest first, then by index
    rows, cols, squared = rows[order], cols[order], squared[order]
    del order
    rank = np.arange(len(rows)) - np.searchsorted(rows, rows)
    keep = rank < max_nn - 1  # max_nn counts the point itself
    count = np.bincount(rows[keep], minlength=block.stop - block.start)
    return count, cols[keep], squared[keep]


def _simple_histograms(points, normals, block: slice, count, cols) -> np.ndarray:
    """SPFH of the points in ``block``: per point, the histograms of the three Darboux-frame angles
    to each neighbour, each neighbour adding 100 / (neighbours) to one bin of each."""
    rows = np.repeat(np.arange(len(count)), count)
    bins = np.empty((3, len(rows)), np.int64)  # per angle, each pair's bin among the block's bins
    for start in range(0, len(rows), PAIR_CHUNK):  # a chunk of pairs at a time: their temporaries stay small
        part = slice(start, start + PAIR_CHUNK)
        i, j = rows[part] + block.start, cols[part]
        f1, f2, f3 = _pair_features(points[i], normals[i], points[j], normals[j])
        # floor, then clipped to the 11 bins (clipping first keeps the whole part of a non-negative value)
        bins[0, part] = np.clip(BINS * (f1 + np.pi) / (2.0 * np.pi), 0, BINS - 0.5)
        bins[1, part] = np.clip(BINS * (f2 + 1.0) * 0.5, 0, BINS - 0.5)
        bins[2, part] = np.clip(BINS * (f3 + 1.0) * 0.5, 0, BINS - 0.5)
        bins[:, part] += rows[part] * (3 * BINS) + BINS * np.arange(3)[:, None]
    increment = 100.0 / np.maximum(count[rows], 1)
    # One angle at a time: a bin only ever counts pairs of its own angle, each added in pair order,
    # so the sums are those of one count over all three (to the bit) in a third of the memory.
    histograms = np.zeros(len(count) * 3 * BINS)
    for angle in bins:
        histograms += np.bincount(angle, weights=increment, minlength=len(histograms))
    return histograms.reshape(-1, 3 * BINS)


def _pair_features(p1, n1, p2, n2):
    """The three angles of each pair (point 1 with its normal, point 2 with its): the source of the
    Darboux frame is the point whose normal makes the smaller angle with the line joining them."""
    d = p2 - p1
    length = np.sqrt(_dot(d, d))
    safe = np.where(length > 0, length, 1.0)
    angle1 = _dot(n1, d) / safe
    angle2 = _dot(n2, d) / safe
    swap = _smaller_angle_second(np.abs(angle1), np.abs(angle2))
    source = np.where(swap[:, None], n2, n1)
    target = np.where(swap[:, None], n1, n2)
    d[swap] *= -1
    f3 = np.where(swap, -angle2, angle1)
    v = _cross(d, source)
    v_norm = np.sqrt(_dot(v, v))
    v /= np.where(v_norm > 0, v_norm, 1.0)[:, None]
    f2 = _dot(v, target)
    f1 = np.arctan2(_dot(_cross(source, v), target), _dot(source, target))
    degenerate = (length == 0) | (v_norm == 0)  # a point on itself, or a normal along the joining line
    if degenerate.any():
        f1[degenerate] = f2[degenerate] = f3[degenerate] = 0.0
    return f1, f2, f3


def _smaller_angle_second(cos1: np.ndarray, cos2: np.ndarray) -> np.ndarray:
    """acos(cos1) > acos(cos2), decided as the C library decides it: numpy's vectorised arccos can
    differ from it in the last bit, which flips near ties (nearly parallel normals are common on a
    surface), so those are computed one by one with ``_acos``."""
    swap = cos1 < cos2
    close = np.flatnonzero(np.abs(cos1 - cos2) <= 1e-12 * np.maximum(cos1, cos2))
    swap[close] = [_acos(a) > _acos(b) for a, b in zip(cos1[close].tolist(), cos2[close].tolist())]
    return swap


def _acos(x: float) -> float:
    """The C library's acos: NaN (never greater) for a cosine rounded a hair past 1, where Python's
    raises."""
    return math.acos(x) if -1.0 <= x <= 1.0 else math.nan


def _dot(a, b):
    """Row-wise dot products of (N, 3) arrays, summed x, y, z in order (as open3d's C++ does)."""
    return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2]


def _cross(a, b):
    out = np.empty_like(a)
    out[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    out[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    out[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return out
