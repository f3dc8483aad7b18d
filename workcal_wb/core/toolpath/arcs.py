"""Circular and helical arc geometry: sweep, points along the arc, linearisation by chordal tolerance."""
from __future__ import annotations

import math

import numpy as np

from .model import ARC_CCW, Move

# Start and end closer than this in the arc plane make a full circle (G-code's own convention).
FULL_CIRCLE_MM = 1e-6


def _in_plane(vector: np.ndarray, normal: np.ndarray) -> np.ndarray:
    return vector - np.dot(vector, normal) * normal


def radius(start: np.ndarray, move: Move) -> float:
    return float(np.linalg.norm(_in_plane(start - move.centre, move.normal)))


def signed_sweep(start: np.ndarray, move: Move) -> float:
    """Angle turned about ``move.normal`` in radians: positive counter-clockwise, in (0, 2 pi] in size."""
    n = move.normal
    u = _in_plane(start - move.centre, n)
    v = _in_plane(move.end - move.centre, n)
    if np.linalg.norm(u - v) < FULL_CIRCLE_MM:
        turn = 2 * math.pi
    else:
        ccw = math.atan2(float(np.dot(n, np.cross(u, v))), float(np.dot(u, v))) % (2 * math.pi)
        turn = ccw if move.kind == ARC_CCW else 2 * math.pi - ccw
    return turn if move.kind == ARC_CCW else -turn


def points_at(start: np.ndarray, move: Move, fractions) -> np.ndarray:
    """Points on the arc at the given fractions (0 = start, 1 = end) of its sweep and rise."""
    n = move.normal
    u = _in_plane(start - move.centre, n)
    w = np.cross(n, u)
    rise = float(np.dot(move.end - start, n))
    angles = np.asarray(fractions, dtype=float)[:, None] * signed_sweep(start, move)
    f = np.asarray(fractions, dtype=float)[:, None]
    return move.centre + np.cos(angles) * u + np.sin(angles) * w + f * rise * n


def segment_count(start: np.ndarray, move: Move, chord_tol_mm: float) -> int:
    """Fewest equal segments whose chords stay within ``chord_tol_mm`` of the arc."""
    r = radius(start, move)
    if r <= chord_tol_mm:
        return max(1, math.ceil(abs(signed_sweep(start, move)) / (math.pi / 2)))
    step = 2 * math.acos(1 - chord_tol_mm / r)
    return max(1, math.ceil(abs(signed_sweep(start, move)) / step - 1e-9))


def linearise(start: np.ndarray, move: Move, chord_tol_mm: float) -> np.ndarray:
    """(K, 3) points after ``start`` up to and including the arc's exact end point."""
    n = segment_count(start, move, chord_tol_mm)
    pts = points_at(start, move, np.arange(1, n + 1) / n)
    pts[-1] = move.end
    return pts
