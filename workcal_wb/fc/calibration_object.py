"""The calibration as a FreeCAD document object: W = ^B X = V^-1 U and everything it rests on.

``make_calibration(doc, scan, workpiece, reference, ...)`` checks the inputs, runs the core
calibration (or takes a result computed elsewhere, e.g. by the GUI's worker thread) and adds one
``Part::FeaturePython`` object in one undo step.  The object:

* links its inputs (Scan, Workpiece, Reference, optional Toolpath), so FreeCAD recomputes it when one
  of them changes; ``execute`` re-runs the calibration only when the input data or the options differ
  from what the stored result was computed from (a fingerprint), so reopening a file costs nothing;
* shows the frames as a triad shape (X at its origin, B and S where they are) with ``Placement = W``,
  i.e. in the robot base frame B: the triad of X sits where the workpiece frame is;
* holds U, V, W as placements and matrices, their Z-Y-Z Euler angles, Omega and translation, the
  residuals, the uncertainty bounds, status, warnings and reasons, and the whole CalibrationResult
  as JSON (hidden ``ResultJson``) for the exporters: ``result_of(obj)`` gives it back.

The proxy keeps no state worth saving (see ``fc.proxies``), so documents reopen without WorkCal
having to rebuild anything.
"""
from __future__ import annotations

import hashlib
import json
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

import FreeCAD

from workcal_wb.core import frames
from workcal_wb.core.calibration import CalibrationOptions, calibrate
from workcal_wb.core.errors import InputError, WorkCalError
from workcal_wb.core.geometry import Cloud
from workcal_wb.core.match import METHODS
from workcal_wb.core.model_cache import ModelCache
from workcal_wb.core.result import FAILED, OK, CalibrationResult
from workcal_wb.fc import prefs
from workcal_wb.fc.placed_model import make_placed_model
from workcal_wb.fc.placements import freecad_matrix, placement
from workcal_wb.fc.proxies import Feature, ViewProvider
from workcal_wb.fc.undo import transaction

translate = FreeCAD.Qt.translate
QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP

ROLE = "WorkCalCalibration"  # value of the hidden WorkCalRole property, how commands find these objects
REGION_MODES = list(prefs.REGION_MODES)
FRAME_FRACTION = 0.35  # triad axis length as a fraction of the workpiece model's diagonal (FrameSize 0)
DEFAULT_FRAME_MM = 50.0
AXIS_COLOURS = ((0.9, 0.1, 0.1), (0.1, 0.7, 0.1), (0.1, 0.2, 0.95))  # x red, y green, z blue


def log(text: str) -> None:
    FreeCAD.Console.PrintMessage(text.rstrip("\n") + "\n")


def warn(text: str) -> None:
    FreeCAD.Console.PrintWarning(text.rstrip("\n") + "\n")


def error(text: str) -> None:
    FreeCAD.Console.PrintError(text.rstrip("\n") + "\n")


# ----------------------------------------------------------------------------------------- inputs

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

    def key(self) -> str:
        """Fingerprint of the data and options: equal keys give the same calibration."""
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
        h.update(repr(sorted(asdict(self.options).items())).encode())
        return h.hexdigest()


def _label(obj) -> str:
    return getattr(obj, "Label", None) or getattr(obj, "Name", None) or str(obj)


def _scan_cloud(obj) -> Cloud:
    if obj is None:
        raise InputError(translate("WorkCal", "no scan given: import a scan first (WorkCal > Import scan)"))
    from workcal_wb.fc import scan as fcscan

    try:
        cloud = fcscan.scan_cloud(obj)
    except WorkCalError:
        raise
    except Exception as exc:  # anything else means: this object is not a scan WorkCal can read
        raise InputError(f"{_label(obj)}: cannot be used as a scan ({exc})") from exc
    if len(cloud) == 0:
        raise InputError(f"{_label(obj)}: the scan has no points")
    return cloud


def _model_cloud(obj, role: str) -> Cloud:
    if obj is None:
        raise InputError(f"no {role} model given: choose the {role} model (a Part, Mesh or Points object)")
    from workcal_wb.fc import models as fcmodels

    try:
        cloud = fcmodels.model_cloud(obj)
    except WorkCalError:
        raise
    except Exception as exc:
        raise InputError(f"{_label(obj)}: cannot be used as the {role} model ({exc})") from exc
    if len(cloud) == 0:
        raise InputError(f"{_label(obj)}: the {role} model has no points or faces")
    return cloud


def _picked_regions(scan_obj) -> dict:
    from workcal_wb.fc import scan as fcscan

    picked = fcscan.get_regions(scan_obj) or {}
    missing = [role for role in ("workpiece", "reference") if picked.get(role) is None or len(picked[role]) == 0]
    if missing:
        raise InputError(f"{_label(scan_obj)}: no {' and no '.join(missing)} region picked; pick the regions "
                         "(WorkCal > Regions) or use automatic regions")
    return {role: np.asarray(picked[role], dtype=np.int64) for role in ("workpiece", "reference")}


def toolpath_points(obj) -> np.ndarray:
    """Cutting points (X, mm) of a Path/CAM Job or operation, or of a G-code file path."""
    from workcal_wb.core.toolpath import RAPID, linearised, read_gcode

    if isinstance(obj, (str, os.PathLike)):
        tp = read_gcode(os.fspath(obj))
    else:
        from workcal_wb.fc.toolpath import read_toolpath

        tp = read_toolpath(obj)
    tp = linearised(tp)
    cutting = [m.end for m in tp.moves if m.kind != RAPID]
    points = np.array(cutting) if cutting else tp.points()
    if len(points) == 0:
        raise InputError(f"{_label(obj)}: the toolpath has no moves")
    return points


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


def gather_inputs(scan, workpiece, reference, *, options: CalibrationOptions | None = None,
                  regions: str = "Auto", toolpath=None) -> Inputs:
    """Read the document objects into plain clouds (main thread only); bad inputs raise InputError.

    ``regions``: "Auto" (found by the calibration) or "Picked" (the regions stored on the scan object).
    ``toolpath``: None, a Path/CAM Job or operation, or a G-code file path: the uncertainty is
    reported at its cutting points."""
    if regions not in REGION_MODES:
        raise InputError(f"regions must be one of {REGION_MODES}, not {regions!r}")
    scan_cloud = _scan_cloud(scan)
    workpiece_cloud = _model_cloud(workpiece, "workpiece")
    reference_cloud = _model_cloud(reference, "reference")
    for obj, role in ((workpiece, "workpiece"), (reference, "reference")):
        if obj is scan:
            raise InputError(f"{_label(obj)}: the scan cannot also be the {role} model")
    picked = _picked_regions(scan) if regions == "Picked" else None
    points = None if toolpath is None else toolpath_points(toolpath)
    labels = {"scan": _label(scan), "workpiece": _label(workpiece), "reference": _label(reference),
              "toolpath": "" if toolpath is None else _label(toolpath)}
    return Inputs(scan_cloud, workpiece_cloud, reference_cloud, options or options_from(), picked, points, labels,
                  prefs.model_cache_folder())


def run(inputs: Inputs, progress=None) -> CalibrationResult:
    """The core calibration on gathered inputs; touches no FreeCAD object, so any thread may call it.

    ``progress(fraction, message)`` may raise errors.Cancelled to stop; the exception propagates.  The
    models are prepared once and kept in ``inputs.model_cache`` for later calibrations (also after a
    restart); a folder that cannot be written is a warning of the result."""
    cache = ModelCache(inputs.model_cache)
    workpiece, reference = (cache.model(m, inputs.options.seed) for m in (inputs.workpiece, inputs.reference))
    result = calibrate(inputs.scan, workpiece, reference, regions=inputs.regions,
                       toolpath_points=inputs.toolpath_points, options=inputs.options, progress=progress)
    cache.store()
    result.warnings += cache.notes
    return result


# ------------------------------------------------------------------------------------- the object

# (type, name, group, tooltip); outputs are read-only in the property editor.
INPUT_PROPERTIES = [
    ("App::PropertyLink", "Scan", "Inputs", "The scene scan (points in the scanner frame S)"),
    ("App::PropertyLink", "Workpiece", "Inputs", "The workpiece model X-A (Part, Mesh or Points, in its frame X)"),
    ("App::PropertyLink", "Reference", "Inputs", "The reference model B-P (in the robot base frame B)"),
    ("App::PropertyLink", "Toolpath", "Inputs", "Optional Path/CAM Job or operation: the uncertainty is "
                                                "reported at its cutting points"),
    ("App::PropertyFile", "ToolpathFile", "Inputs", "Optional G-code file (used when Toolpath is empty): the "
                                                    "uncertainty is reported at its cutting points"),
]
OPTION_PROPERTIES = [
    ("App::PropertyEnumeration", "Method", "Options", "Matching method: robust (default), icp or hausdorff "
                                                      "(the paper's two measures)"),
    ("App::PropertyLength", "Tolerance", "Options", "Milling tolerance: residuals and the uncertainty at the "
                                                    "toolpath must stay within it"),
    ("App::PropertyEnumeration", "Regions", "Options", "Auto: find workpiece and reference in the scan; "
                                                       "Picked: use the regions picked on the scan"),
    ("App::PropertyInteger", "Seed", "Options", "Random seed of the global search and the bootstrap"),
    ("App::PropertyInteger", "Resamples", "Options", "Bootstrap refits for the uncertainty"),
    ("App::PropertyBool", "ScannerOriginGiven", "Options", "Use ScannerOrigin as where the scanner stood (else the "
                                                           "scan file's, or estimated)"),
    ("App::PropertyVectorDistance", "ScannerOrigin", "Options", "Where the scanner stood, in the scan's coordinates"),
    ("App::PropertyVector", "Up", "Options", "The platform's up direction in the scan's coordinates (0, 0, 0: from "
                                             "the data)"),
    ("App::PropertyBool", "ShowFrames", "Display", "Show triads of the frames B, S and X"),
    ("App::PropertyLength", "FrameSize", "Display", "Length of the triad axes (0: from the workpiece size)"),
]
FRAME_NAMES = ("W", "U", "V")
FRAME_TIPS = {"W": "W = ^B X, the workpiece frame X in the robot base frame B (= V^-1 U)",
              "U": "U = ^S X, the workpiece frame X in the scanner frame S (workpiece match)",
              "V": "V = ^S B, the robot base frame B in the scanner frame S (reference match)"}
RESULT_PROPERTIES = [("App::PropertyString", "Status", "Result", "ok, ambiguous or failed (error: could not run)")]
for _n in FRAME_NAMES:
    RESULT_PROPERTIES += [
        ("App::PropertyPlacement", _n, "Result", FRAME_TIPS[_n]),
        ("App::PropertyMatrix", f"{_n}Matrix", "Result", f"{_n} as a 4x4 matrix (mm)"),
        ("App::PropertyVector", f"{_n}EulerZYZ", "Result", f"{_n}: Z-Y-Z Euler angles phi, theta, psi in degrees"),
        ("App::PropertyAngle", f"{_n}Omega", "Result", f"{_n}: rotation angle about the principal axis"),
        ("App::PropertyVectorDistance", f"{_n}Translation", "Result", f"{_n}: translation"),
    ]
RESULT_PROPERTIES += [
    ("App::PropertyLength", "WorkpieceRMS", "Residuals", "RMS point-to-surface distance of the workpiece match"),
    ("App::PropertyLength", "WorkpieceHausdorff", "Residuals", "Mean directed Hausdorff distance, workpiece"),
    ("App::PropertyFloat", "WorkpieceWithinTolerance", "Residuals", "% of workpiece inliers within the tolerance"),
    ("App::PropertyLength", "ReferenceRMS", "Residuals", "RMS point-to-surface distance of the reference match"),
    ("App::PropertyLength", "ReferenceHausdorff", "Residuals", "Mean directed Hausdorff distance, reference"),
    ("App::PropertyFloat", "ReferenceWithinTolerance", "Residuals", "% of reference inliers within the tolerance"),
    ("App::PropertyLength", "ToolpathBound", "Uncertainty", "Bound on the displacement of toolpath points "
                                                            "(0 without a toolpath)"),
    ("App::PropertyLength", "SurfaceBound", "Uncertainty", "Bound on the displacement of workpiece surface points"),
    ("App::PropertyAngle", "RotationBound", "Uncertainty", "Bound on the rotation error of W"),
    ("App::PropertyStringList", "Warnings", "Result", "Warnings of the calibration"),
    ("App::PropertyStringList", "Reasons", "Result", "Why the calibration is not ok (failed gates, ambiguity)"),
    ("App::PropertyFloat", "ComputeTime", "Result", "Seconds the calibration took"),
]
HIDDEN_PROPERTIES = [
    ("App::PropertyString", "ResultJson", "Result", "The complete CalibrationResult as JSON (for exporters)"),
    ("App::PropertyString", "InputsKey", "Result", "Fingerprint of the inputs the result was computed from"),
    ("App::PropertyString", "WorkCalRole", "Base", "What this object is to WorkCal"),
    ("App::PropertyFloat", "ModelDiagonal", "Display", "Workpiece model diagonal, mm (auto frame size)"),
]


def _add_properties(obj) -> None:
    for kind, name, group, tip in INPUT_PROPERTIES + OPTION_PROPERTIES + RESULT_PROPERTIES + HIDDEN_PROPERTIES:
        if name not in obj.PropertiesList:
            obj.addProperty(kind, name, group, QT_TRANSLATE_NOOP("App::Property", tip))
    for _, name, _, _ in RESULT_PROPERTIES:
        obj.setEditorMode(name, 1)  # read-only
    for _, name, _, _ in HIDDEN_PROPERTIES:
        obj.setEditorMode(name, 2)  # hidden
    obj.setEditorMode("Placement", 1)  # = W, set by the calibration


def options_of(obj) -> CalibrationOptions:
    origin = getattr(obj, "ScannerOrigin", None) if getattr(obj, "ScannerOriginGiven", False) else None
    up = getattr(obj, "Up", None)
    return options_from(obj.Tolerance.Value, obj.Method, obj.Seed, obj.Resamples,
                        scanner_origin=None if origin is None else (origin.x, origin.y, origin.z),
                        up=None if up is None or up.Length == 0 else (up.x, up.y, up.z))


def inputs_of(obj) -> Inputs:
    """The inputs as the object's links and options say."""
    toolpath = obj.Toolpath if obj.Toolpath is not None else (obj.ToolpathFile or None)
    return gather_inputs(obj.Scan, obj.Workpiece, obj.Reference, options=options_of(obj), regions=obj.Regions,
                         toolpath=toolpath)


def result_of(obj) -> CalibrationResult:
    """The CalibrationResult stored on a calibration object."""
    if not is_calibration(obj):
        raise InputError(f"{_label(obj)}: not a WorkCal calibration")
    if not obj.ResultJson:
        raise InputError(f"{_label(obj)}: the calibration has not been computed yet")
    return CalibrationResult.from_text(obj.ResultJson, f"calibration {obj.Label!r}")


def is_calibration(obj) -> bool:
    return getattr(obj, "WorkCalRole", None) == ROLE


def find_calibrations(doc) -> list:
    return [] if doc is None else [o for o in doc.Objects if is_calibration(o)]


def _set_frame(obj, name: str, T) -> None:
    M = np.eye(4) if T is None else np.asarray(T, dtype=float)
    setattr(obj, name, placement(M))
    setattr(obj, f"{name}Matrix", freecad_matrix(M))
    if T is None:
        setattr(obj, f"{name}EulerZYZ", FreeCAD.Vector(0, 0, 0))
        setattr(obj, f"{name}Omega", 0.0)
        setattr(obj, f"{name}Translation", FreeCAD.Vector(0, 0, 0))
        return
    setattr(obj, f"{name}EulerZYZ", FreeCAD.Vector(*frames.euler_zyz(M)))
    setattr(obj, f"{name}Omega", frames.omega(M))
    setattr(obj, f"{name}Translation", FreeCAD.Vector(*M[:3, 3]))


def _finite(value, default=0.0) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError):
        return default
    return value if np.isfinite(value) else default


def apply_result(obj, result: CalibrationResult, key: str = "") -> None:
    """Write a CalibrationResult into the object's properties (the shape follows in execute)."""
    obj.ResultJson = json.dumps(result.to_dict(), allow_nan=True)
    obj.InputsKey = key
    obj.Status = result.status
    for name in FRAME_NAMES:
        _set_frame(obj, name, getattr(result, name))
    for role, match in (("Workpiece", result.workpiece), ("Reference", result.reference)):
        setattr(obj, f"{role}RMS", _finite(getattr(match, "rms_mm", None)))
        setattr(obj, f"{role}Hausdorff", _finite(getattr(match, "mean_directed_hausdorff_mm", None)))
        setattr(obj, f"{role}WithinTolerance", _finite(getattr(match, "within_tolerance_pct", None)))
    u = result.uncertainty or {}
    obj.ToolpathBound = _finite(u.get("toolpath_bound_mm"))
    obj.SurfaceBound = _finite(u.get("surface_bound_mm"))
    obj.RotationBound = _finite(u.get("rotation_bound_deg"))
    obj.Warnings = [str(w) for w in result.warnings]
    obj.Reasons = [str(r) for r in result.reasons]
    obj.ComputeTime = _finite(result.time_s)


def _error_result(message: str, options: CalibrationOptions | None) -> CalibrationResult:
    return CalibrationResult(FAILED, W=None, reasons=[message],
                             tolerance_mm=options.tolerance_mm if options else prefs.get("ToleranceMm"))


def report(result: CalibrationResult, label: str = "Calibration") -> None:
    """The summary in the Report view: a message when ok, a warning otherwise."""
    (log if result.status == OK else warn)(f"WorkCal: {label}: {result.summary()}")


def _triad(T: np.ndarray, size: float):
    import Part

    origin = FreeCAD.Vector(*T[:3, 3])
    edges = []
    for axis in range(3):
        tip = FreeCAD.Vector(*(T[:3, 3] + size * T[:3, axis]))
        edges.append(Part.LineSegment(origin, tip).toShape())
    return edges


def frame_size(obj) -> float:
    """Triad axis length: FrameSize, or a fraction of the workpiece model's size."""
    if obj.FrameSize.Value > 0:
        return obj.FrameSize.Value
    return FRAME_FRACTION * obj.ModelDiagonal if obj.ModelDiagonal > 0 else DEFAULT_FRAME_MM


def frame_poses(result: CalibrationResult) -> dict:
    """The frames to draw, in the object's local frame (X when W is known, else B): name -> 4x4."""
    if result.W is not None:
        W_inv = frames.invert(result.W)
        out = {"X": np.eye(4), "B": W_inv}
        if result.V is not None:
            out["S"] = W_inv @ frames.invert(result.V)
        return out
    out = {"B": np.eye(4)}
    if result.V is not None:
        out["S"] = frames.invert(result.V)
    return out


class CalibrationFeature(Feature):
    """Proxy of the calibration object (``Part::FeaturePython``)."""

    STATE = {"type": "WorkCalCalibration", "version": 1}

    def setup(self, obj) -> None:
        _add_properties(obj)
        obj.WorkCalRole = ROLE
        if not obj.getEnumerationsOfProperty("Method"):
            obj.Method = list(METHODS)
            obj.Method = prefs.get("Method")
        if not obj.getEnumerationsOfProperty("Regions"):
            obj.Regions = REGION_MODES
            obj.Regions = prefs.get("Regions")
        if obj.Tolerance.Value == 0:
            obj.Tolerance = prefs.get("ToleranceMm")
        if obj.Resamples == 0:
            obj.Resamples = prefs.get("Resamples")
        if not obj.Status:
            obj.ShowFrames = True
            obj.Status = "new"

    def execute(self, obj):
        prepared, self._prepared = getattr(self, "_prepared", None), None
        result = None
        try:
            if prepared is not None:
                key, inputs, result = prepared
            else:
                inputs = inputs_of(obj)
                key = inputs.key()
                if key != obj.InputsKey or not obj.ResultJson:
                    log(f"WorkCal: {obj.Label}: inputs changed, calibrating again")
                    result = run(inputs)
                    report(result, obj.Label)
            if result is not None:
                apply_result(obj, result, key)
            obj.ModelDiagonal = inputs.workpiece.diagonal()
        except WorkCalError as exc:
            message = f"{obj.Label}: {exc}"
            apply_result(obj, _error_result(str(exc), None), "")
            obj.Status = "error"
            error(f"WorkCal: {message}")
            self._update_shape(obj)
            raise
        self._update_shape(obj)

    def _update_shape(self, obj) -> None:
        import Part

        try:
            result = result_of(obj)
        except WorkCalError:
            result = CalibrationResult(FAILED, W=None)
        size = frame_size(obj)
        edges = []
        if obj.ShowFrames:
            for name, T in frame_poses(result).items():
                edges += _triad(T, size)
        if not edges:  # an empty compound still carries the placement
            edges = [Part.Vertex(FreeCAD.Vector(0, 0, 0))]
        shape = Part.makeCompound(edges)
        pl = placement(result.W) if result.W is not None else FreeCAD.Placement()
        shape.Placement = pl
        obj.Shape = shape
        obj.Placement = pl

    def onChanged(self, obj, prop):
        pass


# --------------------------------------------------------------------------------- create / update

def make_calibration(doc, scan, workpiece, reference, *, tolerance_mm=None, method=None, seed=None,
                     resamples=None, scanner_origin=None, up=None, regions: str | None = None, toolpath=None,
                     result: CalibrationResult | None = None, inputs: Inputs | None = None, progress=None,
                     name: str = "Calibration", placed_model: bool = False):
    """Calibrate and add the result object to ``doc`` in one undo step; return the object.

    Options not given come from the preferences; ``scanner_origin`` and ``up`` (scan coordinates) are
    stored on the object as document inputs.  ``result`` (with the ``inputs`` it came from) is a
    calibration computed elsewhere, e.g. in a worker thread; otherwise it is computed here, with
    ``progress`` as in core.calibrate.  Bad inputs raise InputError, cancelling raises Cancelled: in
    both cases the document is left as it was.  A calibration whose status is "failed" is still
    added (its reasons tell why; exporters refuse it unless forced)."""
    if inputs is None:
        options = options_from(tolerance_mm, method, seed, resamples, scanner_origin, up)
        inputs = gather_inputs(scan, workpiece, reference, options=options,
                               regions=regions or prefs.get("Regions"), toolpath=toolpath)
    if result is None:
        result = run(inputs, progress)
    with transaction(doc, translate("WorkCal", "WorkCal calibration")):
        obj = doc.addObject("Part::FeaturePython", name)
        CalibrationFeature(obj)
        obj.Label = name
        _write_inputs(obj, scan, workpiece, reference, toolpath, inputs, regions)
        obj.Proxy._prepared = (inputs.key(), inputs, result)
        if FreeCAD.GuiUp:
            ViewProviderCalibration(obj.ViewObject)
        obj.recompute()
        if placed_model and result.W is not None:
            make_placed_model(obj)
        doc.recompute()
    report(result, obj.Label)
    return obj


def _write_inputs(obj, scan, workpiece, reference, toolpath, inputs: Inputs, regions) -> None:
    obj.Scan, obj.Workpiece, obj.Reference = scan, workpiece, reference
    is_file = isinstance(toolpath, (str, os.PathLike))
    obj.Toolpath = None if (toolpath is None or is_file) else toolpath
    obj.ToolpathFile = os.fspath(toolpath) if is_file else ""
    o = inputs.options
    obj.Method = o.method
    obj.Tolerance = o.tolerance_mm
    obj.Seed = o.seed
    obj.Resamples = o.resamples
    obj.ScannerOriginGiven = o.scanner_origin is not None
    obj.ScannerOrigin = FreeCAD.Vector(*(o.scanner_origin or (0.0, 0.0, 0.0)))
    obj.Up = FreeCAD.Vector(*(o.up or (0.0, 0.0, 0.0)))
    obj.Regions = regions or ("Picked" if inputs.regions is not None else "Auto")


def update_calibration(obj, result: CalibrationResult, inputs: Inputs, regions: str | None = None,
                       placed_model: bool = False) -> None:
    """Store a result computed elsewhere (e.g. re-run from the task panel) on an existing object,
    with the options it was computed with, in one undo step (with the placed model when asked for)."""
    doc = obj.Document
    with transaction(doc, translate("WorkCal", "WorkCal calibration")):
        toolpath = obj.Toolpath if obj.Toolpath is not None else (obj.ToolpathFile or None)
        _write_inputs(obj, obj.Scan, obj.Workpiece, obj.Reference, toolpath, inputs, regions or obj.Regions)
        obj.Proxy._prepared = (inputs.key(), inputs, result)
        obj.touch()
        if placed_model and result.W is not None:
            make_placed_model(obj)
        doc.recompute()
    report(result, obj.Label)


# ------------------------------------------------------------------------------------------- view

class ViewProviderCalibration(ViewProvider):
    """Icon, coloured triads with frame labels, double-click opens the calibrate task panel."""

    ICON = "WorkCal_Calibration"

    def attach(self, vobj):
        from pivy import coin

        super().attach(vobj)
        # Frame names, outside the display-mode switch: shown and hidden with the object by hand.
        self.switch = coin.SoSwitch()
        self.labels = coin.SoSeparator()
        self.switch.addChild(self.labels)
        self.switch.whichChild = 0 if vobj.Visibility else -1
        vobj.RootNode.addChild(self.switch)
        try:
            vobj.LineWidth = 3.0
            vobj.PointSize = 1.0
        except Exception:  # older/newer view providers without these
            pass
        self._update_labels(vobj.Object)

    def updateData(self, obj, prop):
        if prop in ("Shape", "ResultJson", "ShowFrames"):
            self._update_labels(obj)
            self._colour_edges(obj)

    def _colour_edges(self, obj):
        vobj = getattr(obj, "ViewObject", None)
        if vobj is None or not hasattr(vobj, "LineColorArray"):
            return
        n = len(obj.Shape.Edges)
        if n and n % 3 == 0:
            vobj.LineColorArray = [AXIS_COLOURS[i % 3] for i in range(n)]

    def _update_labels(self, obj):
        from pivy import coin

        if not hasattr(self, "labels"):
            return
        vobj = getattr(obj, "ViewObject", None)
        if vobj is not None:
            self.switch.whichChild = 0 if vobj.Visibility else -1
        self.labels.removeAllChildren()
        if not getattr(obj, "ShowFrames", False) or not getattr(obj, "ResultJson", ""):
            return
        try:
            result = result_of(obj)
        except WorkCalError:
            return
        size = frame_size(obj)
        colour = coin.SoBaseColor()
        colour.rgb = (0.1, 0.1, 0.1)
        self.labels.addChild(colour)
        for name, T in frame_poses(result).items():
            sep = coin.SoSeparator()
            move = coin.SoTranslation()
            move.translation = tuple(float(v) for v in T[:3, 3] - 0.12 * size * (T[:3, 0] + T[:3, 1]))
            text = coin.SoText2()
            text.string = name
            sep.addChild(move)
            sep.addChild(text)
            self.labels.addChild(sep)

    def onChanged(self, vobj, prop):
        if prop == "Visibility" and hasattr(self, "switch"):
            self.switch.whichChild = 0 if vobj.Visibility else -1

    def doubleClicked(self, vobj):
        import FreeCADGui

        if FreeCADGui.Control.activeDialog():
            return False
        from workcal_wb.gui.task_panels.calibrate_panel import CalibratePanel

        FreeCADGui.Control.showDialog(CalibratePanel(vobj.Object.Document, calibration=vobj.Object))
        return True

    def setupContextMenu(self, vobj, menu):
        obj = vobj.Object  # QMenu.addAction(text): QAction moved from QtWidgets to QtGui in Qt6
        menu.addAction(translate("WorkCal", "Show workpiece model in the robot frame")).triggered.connect(
            lambda: _placed_model_action(obj))
        menu.addAction(translate("WorkCal", "Deviation map")).triggered.connect(lambda: _deviation_action(obj))

    def claimChildren(self):
        return []


def _placed_model_action(obj):
    try:
        doc = obj.Document
        with transaction(doc, translate("WorkCal", "Show placed workpiece model")):
            make_placed_model(obj)
            doc.recompute()
    except WorkCalError as exc:
        error(f"WorkCal: {exc}")


def _deviation_action(obj):
    from workcal_wb.fc import deviation_view

    try:
        deviation_view.make_deviation_map(obj.Document, obj)
    except WorkCalError as exc:
        error(f"WorkCal: {exc}")
