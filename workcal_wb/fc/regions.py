"""Scan regions as document use cases: find them automatically, set picked ones, clear them.

Each function is one undo step on the scan object (``fc.scan`` stores the index lists) and leaves the
document as it was when it refuses.  ``find_regions`` does the slow part (the search) without touching
the document, so the GUI runs it in a worker thread; it remembers its last answer, so the recorded
``auto_regions(...)`` that follows finds it instead of searching again.

Picked regions are recorded as index ranges (``ranges``/``indices``): a box picked on a scan taken
row by row is a few hundred runs, short enough for a macro line.

After a calibration, ``off_model(calibration)`` says of each region the points its placed model
leaves unexplained (how many, where, what to change) and ``off_model_points(scan)`` gives their
indices for the 3D view, while the scan's regions still hold them.
"""
from __future__ import annotations

import hashlib

import numpy as np

import FreeCAD

from workcal_wb.core.errors import InputError, WorkCalError
from workcal_wb.fc import prefs
from workcal_wb.fc import scan as fc_scan
from workcal_wb.fc.memo import LastResult
from workcal_wb.fc.models import model_cloud
from workcal_wb.fc.setup import get_setup
from workcal_wb.fc.undo import transaction

translate = FreeCAD.Qt.translate

_last = LastResult()


def regions_inputs(scan, workpiece=None, reference=None) -> tuple:
    """(scan cloud, workpiece cloud, reference cloud) for ``find_regions``, the models defaulting to the
    document's setup (main thread: reads document objects)."""
    setup = get_setup(scan.Document)
    workpiece = workpiece if workpiece is not None else setup["workpiece"]
    reference = reference if reference is not None else setup["reference"]
    missing = [name for name, obj in (("workpiece model", workpiece), ("reference model", reference)) if obj is None]
    if missing:
        raise InputError(f"automatic regions need the {' and the '.join(missing)}: choose it first "
                         "(WorkCal > Choose models)")
    return fc_scan.scan_cloud(scan), model_cloud(workpiece, role="workpiece"), model_cloud(reference, role="reference")


def _key(clouds, tolerance_mm: float, seed: int) -> str:
    h = hashlib.sha1(repr((tolerance_mm, seed)).encode())
    for cloud in clouds:
        h.update(np.ascontiguousarray(cloud.points, dtype=np.float64).tobytes())
        if cloud.triangles is not None:
            h.update(np.ascontiguousarray(cloud.triangles, dtype=np.int64).tobytes())
    return h.hexdigest()


def find_regions(clouds, blas_threads: int | None = 1) -> dict:
    """The workpiece and reference regions in a scan (``core.regions.find_regions`` with the preferred
    tolerance and seed) from ``regions_inputs``; touches no document, so any thread may call it."""
    from workcal_wb.core.regions import find_regions as core_find_regions

    tolerance_mm, seed = prefs.get("ToleranceMm"), prefs.get("Seed")
    key = _key(clouds, tolerance_mm, seed)
    found = _last.get(key)
    if found is None:
        found = core_find_regions(*clouds, tolerance_mm=tolerance_mm, seed=seed, blas_threads=blas_threads)
        _last.put(key, found)
    return found


def auto_regions(scan, workpiece=None, reference=None) -> dict:
    """Find the workpiece and the reference in ``scan`` with their models (default: the setup's) and
    store the regions (source "auto") in one undo step; returns what ``find_regions`` found.
    InputError says what is missing or which object was not found; the document is then unchanged."""
    found = find_regions(regions_inputs(scan, workpiece, reference))
    with transaction(scan.Document, translate("WorkCal", "Find regions automatically")):
        fc_scan.set_regions(scan, found["workpiece"], found["reference"], source="auto")
    for text in found.get("warnings", []):
        FreeCAD.Console.PrintWarning(f"WorkCal: {text}\n")
    FreeCAD.Console.PrintMessage(f"WorkCal: regions of {scan.Label} found: workpiece {len(found['workpiece'])} "
                                 f"points, reference {len(found['reference'])} points; check them and correct "
                                 "with the pick tools if needed\n")
    return found


def set_regions(scan, workpiece=None, reference=None) -> None:
    """Store regions picked by the user (index arrays, masks or ``indices(ranges)``) in one undo step."""
    with transaction(scan.Document, translate("WorkCal", "Pick scan regions")):
        fc_scan.set_regions(scan, workpiece, reference, source="user")


def clear_regions(scan) -> bool:
    """Remove both regions of the scan (one undo step); False (and a warning) when there were none."""
    if not fc_scan.has_regions(scan):
        FreeCAD.Console.PrintWarning(f"WorkCal: {scan.Label} has no regions to clear\n")
        return False
    with transaction(scan.Document, translate("WorkCal", "Clear regions")):
        fc_scan.set_regions(scan)
    FreeCAD.Console.PrintMessage(f"WorkCal: regions of {scan.Label} cleared\n")
    return True


def off_model(calibration) -> dict:
    """Per region ("workpiece", "reference"), what the calibration's result says of its points off its
    placed model: "indices" (scan indices), "count", "where" and "change" (sentences, empty when there
    are none); only the regions it says something of ({} for a calibration not computed, or one that
    matched nothing)."""
    from workcal_wb.fc.lookups import result_of

    if not getattr(calibration, "ResultJson", ""):
        return {}
    try:
        result = result_of(calibration)
    except WorkCalError:
        return {}
    notes = {role: result.off_model(role) for role in ("workpiece", "reference")}
    return {role: note for role, note in notes.items() if note is not None and note["indices"] is not None}


def off_model_points(scan) -> dict:
    """{role: scan indices} of the points off their placed models in the latest calibration of ``scan``,
    as the 3D view draws them; a region's are left out when the calibration used picked regions and the
    scan's region no longer holds them all (picked again since), and all when they no longer fit the scan."""
    from workcal_wb.fc.lookups import find_calibrations

    calibration = next((c for c in reversed(find_calibrations(scan.Document)) if c.Scan is scan and c.ResultJson),
                       None)
    if calibration is None:
        return {}
    try:
        count, regions = fc_scan.point_count(scan), fc_scan.get_regions(scan)
    except WorkCalError:
        return {}
    found = {}
    for role, note in off_model(calibration).items():
        idx = note["indices"]
        if len(idx) == 0 or idx.max() >= count:
            continue
        if calibration.Regions == "Picked" and (regions[role] is None or not np.isin(idx, regions[role]).all()):
            continue
        found[role] = idx
    return found


def ranges(idx) -> list:
    """Sorted unique indices as [start, stop) runs: [[0, 3], [7, 8]] for 0, 1, 2, 7."""
    idx = np.unique(np.asarray(idx, dtype=np.int64))
    if not len(idx):
        return []
    breaks = np.flatnonzero(np.diff(idx) != 1)
    starts = np.concatenate([[idx[0]], idx[breaks + 1]])
    stops = np.concatenate([idx[breaks] + 1, [idx[-1] + 1]])
    return [[int(a), int(b)] for a, b in zip(starts, stops)]


def indices(runs) -> np.ndarray:
    """The indices of [start, stop) runs (``ranges`` undone)."""
    parts = [np.arange(int(a), int(b), dtype=np.int64) for a, b in runs]
    return np.concatenate(parts) if parts else np.empty(0, dtype=np.int64)
