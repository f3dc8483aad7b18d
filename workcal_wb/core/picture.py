"""Pictures of points drawn with numpy alone and written as PNG: the report's deviation views cost
milliseconds instead of matplotlib's import and rendering (about a second per report), and the
text around them (titles, axes, legend) is the report's HTML, where it stays sharp and searchable.
"""
from __future__ import annotations

import struct
import zlib

import numpy as np

WHITE = (255, 255, 255)


def canvas(width: int, height: int, colour=WHITE) -> np.ndarray:
    """An (height, width, 3) uint8 image filled with ``colour``."""
    image = np.empty((height, width, 3), np.uint8)
    image[:] = colour
    return image


def to_bytes(colours) -> np.ndarray:
    """RGB in 0..1 (one colour or N x 3) as uint8."""
    return np.clip(np.rint(255 * np.asarray(colours, dtype=float)), 0, 255).astype(np.uint8)


class View:
    """A 2D window onto the plane (horizontal, vertical) mapped onto an image of at most ``size``
    pixels per side with ``margin`` pixels around, the same scale along both axes (a drawing, not a
    stretched plot); vertical values grow upwards."""

    def __init__(self, points: np.ndarray, size: int = 520, margin: int = 8):
        lo, hi = points.min(axis=0), points.max(axis=0)
        span = np.maximum(hi - lo, 1e-9)
        self.mm_per_pixel = float(max(span) / (size - 2 * margin))
        self.lo, self.margin = lo, margin
        self.width, self.height = (np.ceil(span / self.mm_per_pixel).astype(int) + 2 * margin + 1)

    def pixels(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(column, row) of each point; rows counted from the top."""
        c = np.floor((points - self.lo) / self.mm_per_pixel).astype(np.int64) + self.margin
        return c[:, 0], self.height - 1 - c[:, 1]

    def draw(self, image: np.ndarray, points: np.ndarray, colours: np.ndarray, dot: int = 1) -> None:
        """Paint each point as a ``dot`` x ``dot`` square in its colour (uint8, one or N x 3); where
        dots overlap the later point wins, so callers pass points far to near (painter's order)."""
        column, row = self.pixels(points)
        colours = np.broadcast_to(np.asarray(colours, np.uint8), (len(points), 3))
        offsets = np.arange(dot) - dot // 2
        shape = (len(points), dot, dot)  # point, dot row, dot column
        column = np.broadcast_to(column[:, None, None] + offsets[None, None, :], shape).reshape(-1)
        row = np.broadcast_to(row[:, None, None] + offsets[None, :, None], shape).reshape(-1)
        inside = (column >= 0) & (column < image.shape[1]) & (row >= 0) & (row < image.shape[0])
        order = np.flatnonzero(inside)  # paint order: a dot's pixels in turn, the points in the order given
        last = last_painted(row[inside] * image.shape[1] + column[inside], order, image.shape[0] * image.shape[1])
        painted = np.flatnonzero(last >= 0)
        image.reshape(-1, 3)[painted] = colours[last[painted] // (dot * dot)]

    def scale_bar(self, image: np.ndarray, colour=(0, 0, 0)) -> float:
        """Draw a bar of a round length (1, 2 or 5 x 10^n mm, about a fifth of the width) at the lower
        left; its length in mm."""
        target = 0.2 * (image.shape[1] - 2 * self.margin) * self.mm_per_pixel
        exponent = 10.0 ** np.floor(np.log10(target))
        # default: log10 rounds a target just under a power of ten up to it, leaving no multiple at or under it
        length = max((m for m in (1, 2, 5) if m * exponent <= target), default=0.5) * exponent
        pixels = int(round(length / self.mm_per_pixel))
        row = image.shape[0] - self.margin // 2 - 2
        image[row - 1:row + 1, self.margin:self.margin + pixels] = colour
        image[row - 4:row + 1, self.margin] = colour
        image[row - 4:row + 1, self.margin + pixels - 1] = colour
        return float(length)


def last_painted(pixel: np.ndarray, order: np.ndarray, size: int) -> np.ndarray:
    """For each of ``size`` pixels, the largest ``order`` painted on it (-1: none), ``order`` rising.

    One scatter, which numpy fills in order (15 ms less than a sort of a view's 240k dots), checked,
    since numpy does not promise that order; if it did not hold, one sort of (pixel, order) keys."""
    last = np.full(size, -1, np.int64)
    last[pixel] = order
    if (last[pixel] >= order).all():
        return last
    return sorted_last_painted(pixel, order, size)


def sorted_last_painted(pixel: np.ndarray, order: np.ndarray, size: int) -> np.ndarray:
    """``last_painted`` by one sort of (pixel, order) keys: the last key of each pixel is the last painted."""
    last = np.full(size, -1, np.int64)
    if len(order):
        span = int(order.max()) + 1
        keys = np.sort(pixel * span + order)
        ends = np.append(keys[1:] // span != keys[:-1] // span, True)
        last[keys[ends] // span] = keys[ends] % span
    return last


def frame(image: np.ndarray, colour=(200, 200, 200)) -> None:
    """A one-pixel border around the image."""
    image[[0, -1], :] = colour
    image[:, [0, -1]] = colour


def png(image: np.ndarray) -> bytes:
    """An (height, width, 3) uint8 image as PNG bytes (8-bit RGB, no interlace, no metadata)."""
    height, width, _ = image.shape
    rows = np.concatenate([np.zeros((height, 1), np.uint8), image.reshape(height, width * 3)], axis=1)

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(rows.tobytes(), 6)) + chunk(b"IEND", b""))
