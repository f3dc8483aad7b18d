"""What a calibration reads from a document, as plain data: the use case before the calibration object.

``gather_inputs`` reads the scan, the two models, the regions and the toolpath into numpy (main
thread only: FreeCAD objects are not thread-safe) and refuses bad inputs with an InputError naming
the object.  ``run`` is the core calibration on them; it touches no document, so any thread may call
it, and it remembers its last result by the inputs' fingerprint: the GUI calibrates in a worker
thread, then records ``make_calibration(...)``, which finds the result instead of computing it again
(and computes it when a recorded macro replays headless).
"""
from __future__ import annotations

import hashlib
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from workcal_wb.core.calibration import CalibrationOptions, calibrate
from workcal_wb.core.errors import InputError
from workcal_wb.core.geometry import Cloud
from workcal_wb.core.result import CalibrationResult
from workcal_wb.fc import prefs
from workcal_wb.fc.lookups import label
from workcal_wb.fc.memo import LastResult
from workcal_wb.fc.models import model_cloud
from workcal_wb.fc.prepared_models import KEPT, source_of
from workcal_wb.fc.scan import get_regions, scan_cloud
from workcal_wb.fc.toolpath_input import source_label, toolpath_points

REGION_MODES = list(prefs.REGION_MODES)


@dataclass
class Inputs:
    """Everything a calibration needs, as plain data: safe to hand to a worker thread."""

    scan: Cloud
    workpiece: Cloud
    reference: Cloud
    options: CalibrationOptions
    regions: dict | None = None
    toolpath_points: np.ndarray | None = None
    labels: dict = field(default_factory=dict)
    model_cache: Path | None = None  # where prepared models are kept (prefs.model_cache_folder); None: nowhere
    sources: dict = field(default_factory=dict)  # role -> (document, object) the model came from (kept in memory)

    def key(self) -> str:
        """Fingerprint of the data and options: equal keys give the same calibration (the BLAS thread
        setting changes the speed, not the result)."""
        h = hashlib.sha1()
        for cloud in (self.scan, self.workpiece, self.reference):
            h.update(np.ascontiguousarray(cloud.points, dtype=np.float64).tobytes())
            if cloud.triangles is not None:
                h.update(np.ascontiguousarray(cloud.triangles, dtype=np.int64).tobytes())
        for role in ("workpiece", "reference"):
            idx = None if self.regions is None else self.regions.get(role)
            h.update(b"-" if idx is None else np.ascontiguousarray(idx, dtype=np.int64).tobytes())
        if self.toolpath_points is not None:
            h.update(np.ascontiguousarray(self.toolpath_points, dtype=np.float64).tobytes())
        options = asdict(replace(self.options, blas_threads=None))
        h.update(repr(sorted(options.items())).encode())
        return h.hexdigest()


def options_from(tolerance_mm=None, method=None, seed=None, resamples=None, scanner_origin=None,
                 up=None) -> CalibrationOptions:
    """CalibrationOptions with the preferences filling what is not given; bad values are InputErrors
    (CalibrationOptions checks them).  ``scanner_origin`` (mm) and ``up``, in the scan's coordinates,
    are the document's to give when the scan's file does not tell them (None: from the data)."""
    tolerance_mm = prefs.get("ToleranceMm") if tolerance_mm is None else float(tolerance_mm)
    method = prefs.get("Method") if method is None else str(method)
    seed = prefs.get("Seed") if seed is None else int(seed)
    resamples = prefs.get("Resamples") if resamples is None else int(resamples)
    return CalibrationOptions(tolerance_mm=tolerance_mm, method=method, seed=seed, resamples=resamples,
                              scanner_origin=None if scanner_origin is None else tuple(scanner_origin),
                              up=None if up is None else tuple(up))


def picked_regions(scan) -> dict:
    """The regions picked on the scan, both required; InputError says what to pick."""
    picked = get_regions(scan) or {}
    missing = [role for role in ("workpiece", "reference") if picked.get(role) is None or len(picked[role]) == 0]
    if missing:
        raise InputError(f"{label(scan)}: no {' and no '.join(missing)} region picked; pick the regions "
                         "(WorkCal > Regions) or use automatic regions")
    return {role: np.asarray(picked[role], dtype=np.int64) for role in ("workpiece", "reference")}


def gather_inputs(scan, workpiece, reference, *, options: CalibrationOptions | None = None,
                  regions: str = "Auto", toolpath=None) -> Inputs:
    """Read the document objects into plain clouds (main thread only); bad inputs raise InputError.

    ``regions``: "Auto" (found by the calibration) or "Picked" (the regions stored on the scan object).
    ``toolpath``: None, a Path/CAM Job or operation, or a G-code file path: the uncertainty is
    reported at its cutting points."""
    if regions not in REGION_MODES:
        raise InputError(f"regions must be one of {REGION_MODES}, not {regions!r}")
    for obj, role in ((workpiece, "workpiece"), (reference, "reference")):
        if obj is not None and obj is scan:
            raise InputError(f"{label(obj)}: the scan cannot also be the {role} model")
    scan_points = scan_cloud(scan)
    workpiece_cloud = model_cloud(workpiece, role="workpiece")
    reference_cloud = model_cloud(reference, role="reference")
    picked = picked_regions(scan) if regions == "Picked" else None
    points = None if toolpath is None else toolpath_points(toolpath)
    if prefs.get("KeepPreparedModels"):
        KEPT.watch()
    labels = {"scan": label(scan), "workpiece": label(workpiece), "reference": label(reference),
              "toolpath": "" if toolpath is None else source_label(toolpath)}
    return Inputs(scan_points, workpiece_cloud, reference_cloud, options or options_from(), picked, points, labels,
                  prefs.model_cache_folder(), {"workpiece": source_of(workpiece), "reference": source_of(reference)})


_last = LastResult()


def prepare_models(inputs: Inputs) -> list:
    """[(SurfaceModel, ModelCache to store after the run)] of the workpiece and the reference: kept in
    memory for their document objects, else from the cache folder, else prepared."""
    return [KEPT.model(inputs.sources.get(role), cloud, inputs.options.seed, inputs.model_cache)
            for role, cloud in (("workpiece", inputs.workpiece), ("reference", inputs.reference))]


def run(inputs: Inputs, progress=None, blas_threads: int | None = 1) -> CalibrationResult:
    """The core calibration on gathered inputs; touches no FreeCAD object, so any thread may call it.

    ``progress(fraction, message)`` may raise errors.Cancelled to stop; the exception propagates.
    ``blas_threads``: None from a worker thread inside FreeCAD (its GUI thread goes on using numpy).
    The last result is remembered by the inputs' fingerprint; the models are prepared once, kept in
    memory as long as their document objects (``fc.prepared_models``) and in ``inputs.model_cache`` for
    later sessions, and a folder that cannot be written is a warning of the result."""
    key = inputs.key()
    result = _last.get(key)
    if result is None:
        (workpiece, workpiece_cache), (reference, reference_cache) = prepare_models(inputs)
        result = calibrate(inputs.scan, workpiece, reference, regions=inputs.regions,
                           toolpath_points=inputs.toolpath_points,
                           options=replace(inputs.options, blas_threads=blas_threads), progress=progress)
        notes = []
        for cache in dict.fromkeys((workpiece_cache, reference_cache)):  # what this run added to the models
            cache.store()
            notes += cache.notes
            cache.notes.clear()
        result.warnings += list(dict.fromkeys(notes))
        _last.put(key, result)
    return result
