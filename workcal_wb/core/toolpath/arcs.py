"""Circular and helical arc geometry on stacks of arcs: sweep, points along them, linearisation.

Every function takes arrays with one row per arc: start (K, 3), end (K, 3), centre (K, 3), unit
normal (K, 3) and ``ccw`` (K,) bool; a single arc is a stack of one.
"""
from __future__ import annotations

import math

import numpy as np

# Start and end closer than this in the arc plane make a full circle (G-code's own convention).
FULL_CIRCLE_MM = 1e-6


def _rows(*arrays):
    return [np.asarray(a, dtype=float).reshape(-1, 3) for a in arrays]


def _in_plane(vectors: np.ndarray, normals: np.ndarray) -> np.ndarray:
    return vectors - np.sum(vectors * normals, axis=1, keepdims=True) * normals


def radius(point, centre, normal) -> float | np.ndarray:
    """Distance from ``centre`` to ``point`` in the arc plane (a float for one arc)."""
    p, c, n = _rows(point, centre, normal)
    r = np.linalg.norm(_in_plane(p - c, n), axis=1)
    return float(r[0]) if np.ndim(point) == 1 else r


def signed_sweep(start, end, centre, normal, ccw) -> np.ndarray:
    """(K,) angle turned about the normal in radians: positive counter-clockwise, in (0, 2 pi] in size."""
    s, e, c, n = _rows(start, end, centre, normal)
    ccw = np.asarray(ccw, dtype=bool).reshape(-1)
    u, v = _in_plane(s - c, n), _in_plane(e - c, n)
    ccw_turn = np.arctan2(np.sum(n * np.cross(u, v), axis=1), np.sum(u * v, axis=1)) % (2 * math.pi)
    turn = np.where(ccw, ccw_turn, 2 * math.pi - ccw_turn)
    turn = np.where(np.linalg.norm(u - v, axis=1) < FULL_CIRCLE_MM, 2 * math.pi, turn)
    return np.where(ccw, turn, -turn)


def points_at(start, end, centre, normal, ccw, owner, fractions) -> np.ndarray:
    """Points on arc ``owner[k]`` at ``fractions[k]`` (0 = start, 1 = end) of its sweep and rise."""
    s, e, c, n = _rows(start, end, centre, normal)
    sweep = signed_sweep(s, e, c, n, ccw)
    u = _in_plane(s - c, n)
    w = np.cross(n, u)
    rise = np.sum((e - s) * n, axis=1)
    f = np.asarray(fractions, dtype=float)
    angle = (f * sweep[owner])[:, None]
    return c[owner] + np.cos(angle) * u[owner] + np.sin(angle) * w[owner] + (f * rise[owner])[:, None] * n[owner]


def segment_counts(start, end, centre, normal, ccw, chord_tol_mm: float) -> np.ndarray:
    """(K,) fewest equal segments whose chords stay within ``chord_tol_mm`` of each arc."""
    s, e, c, n = _rows(start, end, centre, normal)
    r = np.linalg.norm(_in_plane(s - c, n), axis=1)
    sweep = np.abs(signed_sweep(s, e, c, n, ccw))
    step = np.where(r > chord_tol_mm, 2 * np.arccos(np.clip(1 - chord_tol_mm / np.maximum(r, 1e-300), -1, 1)),
                    math.pi / 2)
    return np.maximum(1, np.ceil(sweep / step - 1e-9)).astype(np.int64)


def linearise(start, end, centre, normal, ccw, chord_tol_mm: float) -> tuple[np.ndarray, np.ndarray]:
    """Chord end points of every arc, in order, each arc's last one exactly its end point;
    and the (K,) number of points per arc."""
    s, e, c, n = _rows(start, end, centre, normal)
    counts = segment_counts(s, e, c, n, ccw, chord_tol_mm)
    owner = np.repeat(np.arange(len(s)), counts)
    last = np.cumsum(counts) - 1
    step = np.arange(len(owner)) - np.repeat(last - counts + 1, counts) + 1
    points = points_at(s, e, c, n, ccw, owner, step / counts[owner])
    points[last] = e
    return points, counts
