"""Large binary PLY point clouds thinned while they are read, so they are never in memory whole."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..files import checked_input
from .common import _MAX_HEADER_BYTES, _Parsed, _trailing, _truncated
from .ply import _ply_header

# A scan with more points than this is thinned on reading by the commands (a few million points fix a
# pose as well as tens of millions, and memory stays bounded); thinning keeps at most half of it.
LARGE_SCAN_POINTS = 6_000_000
THIN_CHUNK = 1 << 20  # records read at a time
GRID_SAMPLE = 1 << 16  # the first finite points, whose spacing sizes the thinning grid
_KEY_BITS = 21  # voxel index bits per axis


def _thinned_ply(path: Path, label: str, max_points: int) -> _Parsed | None:
    """A binary PLY holding only vertices, more than ``max_points`` of them, read in chunks of
    THIN_CHUNK records and thinned as it is read: one point per voxel (the first in the file, a real
    measurement with its normal), the voxel doubled whenever more than max_points / 2 are kept, so
    memory stays bounded whatever the file holds.  Doubled voxels nest, so the points kept are those
    of the final grid over the whole file, whatever the chunk size.  None for any other file (read
    whole as usual).  The counts are checked both ways as for any PLY."""
    if checked_input(path).stat().st_size < max_points * 12:  # under max_points vertices of 3 floats
        return None
    with open(path, "rb") as fh:
        header = _ply_header(fh.read(_MAX_HEADER_BYTES), label)
        (vertex, *others) = header.elements
        names = [p.name for p in vertex.properties]
        if (header.byte_order is None or others or vertex.name != "vertex" or vertex.count <= max_points
                or any(p.length_type for p in vertex.properties) or not {"x", "y", "z"} <= set(names)):
            return None  # (the whole-file reader names what is missing or wrong)
        record = np.dtype([(p.name, header.byte_order + p.type) for p in vertex.properties])
        size = os.fstat(fh.fileno()).st_size
        end = header.body_start + vertex.count * record.itemsize
        if size < end:
            raise _truncated(label, vertex.count, "vertices", (size - header.body_start) // record.itemsize)
        fh.seek(end)
        if fh.read(3) not in (b"", b"\n", b"\r\n"):
            raise _trailing(label, f"byte {end} ({size - end} bytes more)", vertex.count, "vertices")
        fh.seek(header.body_start)
        columns = ["x", "y", "z"] + (["nx", "ny", "nz"] if {"nx", "ny", "nz"} <= set(names) else [])
        thinning = _Thinning(vertex.count, max_points // 2, len(columns))
        for start in range(0, vertex.count, THIN_CHUNK):
            chunk = np.fromfile(fh, record, min(THIN_CHUNK, vertex.count - start))
            values = np.empty((len(chunk), len(columns)))
            for k, name in enumerate(columns):  # one column at a time: no second copy of the chunk
                values[:, k] = chunk[name]
            del chunk
            thinning.add(values, start)
    values, kept = thinning.result()
    grid = thinning.grid
    warnings = [f"{label}: {vertex.count:,} points, more than the {max_points:,} read whole: thinned while "
                f"reading to {kept:,}, one point kept per voxel of "
                f"{grid.voxel if grid is not None else 0:.3g} (the file's units)"]
    if thinning.dropped:
        warnings.append(f"{label}: ignored {thinning.dropped} points with NaN or infinite coordinates")
    return _Parsed(values[:, :3], values[:, 3:] if values.shape[1] == 6 else None, None, header.units,
                   tuple(warnings), None if header.viewpoint is None else header.viewpoint[None])


class _Thinning:
    """The points kept so far (file order) and the sorted keys of their voxels: a chunk adds the first
    point of each voxel no earlier point reached; past ``target`` points the voxel doubles."""

    def __init__(self, total: int, target: int, width: int):
        self.total, self.target = total, target
        self.grid: _ThinningGrid | None = None
        self.parts = [(np.zeros((0, width)), np.zeros(0, np.int64))]  # (values, file index)
        self.count = 0  # points in parts
        self.seen = np.zeros(0, np.int64)  # sorted keys of the voxels kept
        self.dropped = 0  # non-finite points

    def add(self, values: np.ndarray, start: int) -> None:
        finite = np.isfinite(values[:, :3]).all(axis=1)  # a bad normal is for checked() to judge
        self.dropped += len(values) - int(finite.sum())
        values, index = values[finite], start + np.flatnonzero(finite)
        if self.grid is None:  # kept whole until GRID_SAMPLE finite points (or the file's end) size the grid
            self.parts.append((values, index))
            self.count += len(index)
            if self.count and self.count >= min(GRID_SAMPLE, self.total - self.dropped):
                values, index = self._joined()
                self.grid, self.count = _ThinningGrid(values[:GRID_SAMPLE, :3], self.total, self.target), 0
            else:
                return
        keys, first = np.unique(self.grid.keys(values[:, :3], index), return_index=True)
        new = ~_sorted_holds(self.seen, keys)
        first = np.sort(first[new])
        self.seen = np.insert(self.seen, np.searchsorted(self.seen, keys[new]), keys[new])
        self.parts.append((values[first], index[first]))
        self.count += len(first)
        if self.count > self.target:
            values, index = self._joined()
            while len(index) > self.target:  # a doubled voxel holds whole voxels of the last grid
                self.grid.voxel *= 2.0
                self.seen, first = np.unique(self.grid.keys(values[:, :3], index), return_index=True)
                first = np.sort(first)
                values, index = values[first], index[first]
            self.parts, self.count = [(values, index)], len(index)

    def _joined(self):
        values, index = (np.concatenate(column) for column in zip(*self.parts))
        self.parts = []
        return values, index

    def result(self) -> tuple[np.ndarray, int]:
        """The values kept (file order) and how many."""
        values, index = self._joined()
        return values, len(index)


def _sorted_holds(sorted_keys: np.ndarray, keys: np.ndarray) -> np.ndarray:
    """Which of ``keys`` are in ``sorted_keys`` (ascending)."""
    at = np.minimum(np.searchsorted(sorted_keys, keys), max(len(sorted_keys) - 1, 0))
    return sorted_keys[at] == keys if len(sorted_keys) else np.zeros(len(keys), bool)


class _ThinningGrid:
    """Voxels fixed to the sample's corner, sized so that a surface sampled like it keeps about
    ``target`` points of ``total`` (points on a surface thin as the square of the voxel)."""

    def __init__(self, points: np.ndarray, total: int, target: int):
        from ..pointops import median_spacing

        self.corner = points.min(axis=0)
        self.voxel = max(median_spacing(points) * np.sqrt(total / target), 1e-9)

    def keys(self, points: np.ndarray, index: np.ndarray) -> np.ndarray:
        """Each point's voxel as one int64; a point beyond the grid's reach (a stray point far away)
        gets a key of its own (-1 - its file index), so it is always kept."""
        cells = np.floor((points - self.corner) / self.voxel) + (1 << (_KEY_BITS - 1))
        inside = ((cells >= 0) & (cells < 1 << _KEY_BITS)).all(axis=1)
        cells = np.where(inside[:, None], cells, 0).astype(np.int64)
        return np.where(inside, (cells[:, 0] << 2 * _KEY_BITS) | (cells[:, 1] << _KEY_BITS) | cells[:, 2], -1 - index)
