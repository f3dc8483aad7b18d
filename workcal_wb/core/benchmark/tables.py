"""What every table of the benchmark shares: when a pose counts as found, numbers as the tables print
them, and a measurement run in a fresh process of its own."""
from __future__ import annotations

import multiprocessing

import numpy as np

from .. import frames

# A pose counts as found when it is within both of the truth: rotation (deg) and the largest
# displacement of a model point (mm).
SUCCESS_DEG, SUCCESS_MM = 1.0, 1.0
# WorkCal's match at most this fraction of stock Open3D's median time: per call in the match table (on
# the bunny scans and the depth camera's parts), as a whole process in every case family: a cell that
# matches scan after scan waits for it.
TIME_RATIO_TARGET = 0.5


def pose_errors(estimate, truth, model_points) -> tuple[float, float]:
    """Rotation between estimate and truth (deg) and the largest displacement of a model point (mm)."""
    if estimate is None:
        return float("inf"), float("inf")
    rotation = frames.rotation_between_deg(estimate, truth)
    displacement = np.linalg.norm(frames.apply(estimate, model_points) - frames.apply(truth, model_points), axis=1)
    return rotation, float(displacement.max())


def in_child(target, *args):
    """What ``target(*args, queue)`` puts on its queue, run in a fresh (spawned) process of its own: its
    memory and its imports are its own, and what it leaves behind goes with the process."""
    context = multiprocessing.get_context("spawn")
    queue = context.Queue()
    process = context.Process(target=target, args=(*args, queue))
    process.start()
    outcome = queue.get()
    process.join()
    return outcome


def fmt(x, digits=3):
    """A number as the tables print it: ``digits`` decimals, or "inf"."""
    return "inf" if not np.isfinite(x) else f"{x:.{digits}f}"
