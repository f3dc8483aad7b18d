"""Z-buffer rasterisation in numpy: for every pixel, the front-most triangle covering its centre.

Open3D's ray casting returns no hits in the Debian build, so the scanner and the top-view height
maps rasterise here instead.  Each triangle's pixel bounding box is expanded into candidate pixels
with ``np.repeat`` (in chunks, to bound memory), tested with barycentric coordinates, and the
candidates are resolved per pixel by sorting: occlusion is exact, with no per-pixel Python loop.
"""
from __future__ import annotations

import numpy as np

# Candidate (triangle, pixel) pairs handled at once: about 100 MB of temporaries.
_CHUNK_CANDIDATES = 1_500_000
# Pixel centres this close outside an edge (in barycentric units) still count, so that a centre on
# an edge shared by two triangles is never lost to rounding.
_EDGE_TOLERANCE = 1e-9


def front_triangles(corners: np.ndarray, key: np.ndarray, shape: tuple[int, int]):
    """Per covered pixel, the triangle with the largest ``key`` there.

    corners: (T, 3, 2) triangle corners in pixel units (column, row); pixel (r, c) has its centre
    at (c, r).  key: (T, 3) values at the corners of a quantity that is affine over each triangle in
    pixel space (1/depth for a perspective camera, height for a top view); the largest wins.
    Returns (flat pixel index r * cols + c, triangle index, interpolated key), sorted by pixel.
    """
    rows, cols = shape
    lo = np.ceil(corners.min(axis=1)).astype(np.int64)
    hi = np.floor(corners.max(axis=1)).astype(np.int64)
    lo = np.maximum(lo, 0)
    hi = np.minimum(hi, [cols - 1, rows - 1])
    span = hi - lo + 1
    count = np.where((span > 0).all(axis=1), span[:, 0] * span[:, 1], 0)
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    double_area = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    count[np.abs(double_area) < 1e-12] = 0  # seen edge-on: covers no pixel centre

    best_key = np.full(rows * cols, -np.inf)
    best_tri = np.full(rows * cols, -1, dtype=np.int64)
    live = np.flatnonzero(count)
    ends = np.cumsum(count[live])
    start = 0
    while start < len(live):
        stop = max(start + 1, int(np.searchsorted(ends, ends[start] - count[live[start]] + _CHUNK_CANDIDATES,
                                                  side="right")))
        tri = live[start:stop]
        n = count[tri]
        t = np.repeat(tri, n)
        offset = np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)
        width = span[t, 0]
        px = (lo[t, 0] + offset % width).astype(float)
        py = (lo[t, 1] + offset // width).astype(float)
        # Barycentric weights of corners b and c (the weight of a is what is left).
        wb = ((px - a[t, 0]) * (c[t, 1] - a[t, 1]) - (py - a[t, 1]) * (c[t, 0] - a[t, 0])) / double_area[t]
        wc = ((b[t, 0] - a[t, 0]) * (py - a[t, 1]) - (b[t, 1] - a[t, 1]) * (px - a[t, 0])) / double_area[t]
        wa = 1.0 - wb - wc
        inside = (wa >= -_EDGE_TOLERANCE) & (wb >= -_EDGE_TOLERANCE) & (wc >= -_EDGE_TOLERANCE)
        t, px, py = t[inside], px[inside], py[inside]
        k = wa[inside] * key[t, 0] + wb[inside] * key[t, 1] + wc[inside] * key[t, 2]
        pixel = py.astype(np.int64) * cols + px.astype(np.int64)
        order = np.lexsort((-k, pixel))
        first = order[np.r_[True, pixel[order][1:] != pixel[order][:-1]]] if len(order) else order
        pixel, k, t = pixel[first], k[first], t[first]
        better = k > best_key[pixel]
        best_key[pixel[better]], best_tri[pixel[better]] = k[better], t[better]
        start = stop
    hit = np.flatnonzero(best_tri >= 0)
    return hit, best_tri[hit], best_key[hit]


def heights_above(vertices: np.ndarray, triangles: np.ndarray, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """Height of the highest surface point over each (x, y) of an evenly spaced grid; NaN where none.

    The mesh is looked at straight down its z axis: a (len(ys), len(xs)) height map.
    """
    step_x = xs[1] - xs[0] if len(xs) > 1 else 1.0
    step_y = ys[1] - ys[0] if len(ys) > 1 else 1.0
    corners = np.stack([(vertices[:, 0] - xs[0]) / step_x, (vertices[:, 1] - ys[0]) / step_y], axis=-1)[triangles]
    pixel, _, height = front_triangles(corners, vertices[:, 2][triangles], (len(ys), len(xs)))
    out = np.full(len(ys) * len(xs), np.nan)
    out[pixel] = height
    return out.reshape(len(ys), len(xs))
