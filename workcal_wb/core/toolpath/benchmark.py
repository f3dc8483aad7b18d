"""The G-code throughput row of ``make bench``: a 2-million-move file read, transformed and exported.

Run in a fresh process (``benchmark.run`` does that) so its peak memory is its own: the figure is
the peak resident set after the export minus the resident set before reading, over the moves.
"""
from __future__ import annotations

import resource
import time
from pathlib import Path

import numpy as np

from .. import frames
from ..result import CalibrationResult
from . import export, read_gcode

MOVES = 2_000_000
ARC_EVERY = 50  # one move in 50 is an R arc (the reader's general path)
TARGET_S, TARGET_BYTES_PER_MOVE = 20.0, 200.0


def write_sample(path: Path, moves: int = MOVES) -> None:
    """A raster finishing pass over a wavy surface: G1 XYZ lines, every ARC_EVERY-th a G2 with R."""
    with open(path, "w", encoding="ascii") as fh:
        fh.write("(WorkCal benchmark raster)\nG21 G90 G17\nG0 X0 Y0 Z10\nG1 Z0 F1200\n")
        for first in range(0, moves, 100_000):
            k = np.arange(first, min(first + 100_000, moves))
            x, y = (k % 1000) * 0.1, (k // 1000) * 0.1
            z = np.sin(x * 0.05) + np.cos(y * 0.05)
            fh.write("".join(f"G2 X{a:.3f} Y{b:.3f} Z{c:.3f} R1000\n" if (i + ARC_EVERY // 2) % ARC_EVERY == 0
                             else f"G1 X{a:.3f} Y{b:.3f} Z{c:.3f}\n" for i, a, b, c in zip(k, x, y, z)))


def measure(source: Path, out: Path) -> dict:
    """Read ``source``, export it as G-code through a turned-and-moved W; times and memory."""
    before = _rss_mb()
    t0 = time.perf_counter()
    path = read_gcode(source)
    t1 = time.perf_counter()
    W = frames.rigid(frames.rot_z(30.0), (500.0, 100.0, 50.0))
    export(path, CalibrationResult("ok", W), "gcode", out)
    t2 = time.perf_counter()
    peak = _peak_mb()
    return {"moves": len(path), "read_s": t1 - t0, "export_s": t2 - t1, "total_s": t2 - t0,
            "bytes_per_move": (peak - before) * 2 ** 20 / len(path), "file_mb": source.stat().st_size / 2 ** 20}


def _rss_mb() -> float:
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * resource.getpagesize() / 2 ** 20


def _peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def table(row: dict) -> list[str]:
    """The Markdown section of the report."""
    met = row["total_s"] < TARGET_S and row["bytes_per_move"] < TARGET_BYTES_PER_MOVE
    return ["## G-code throughput", "",
            f"One G-code file of {row['moves']:,} moves ({row['file_mb']:.0f} MB: G1 XYZ lines, one in {ARC_EVERY} "
            "a G2 with R) read line by line into columns, transformed by a turned and moved W (arcs kept) and "
            "written as 3-axis G-code, in a fresh process. Memory: peak resident set after the export minus the "
            "resident set before reading, per move (Python and libraries excluded).", "",
            "| moves | read (s) | transform + checks + export (s) | total (s) | memory per move (bytes) | target |",
            "|---|---|---|---|---|---|",
            f"| {row['moves']:,} | {row['read_s']:.2f} | {row['export_s']:.2f} | {row['total_s']:.2f} | "
            f"{row['bytes_per_move']:.0f} | under {TARGET_S:g} s and {TARGET_BYTES_PER_MOVE:g} bytes: "
            f"{'met' if met else 'MISSED'} |", ""]
