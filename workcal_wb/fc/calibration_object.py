"""The calibration as a FreeCAD document object: W = ^B X = V^-1 U and everything it rests on.

``make_calibration(doc, ...)`` checks the inputs, calibrates (``fc.inputs.run``) and adds one
``Part::FeaturePython`` in one undo step; ``update_calibration`` runs it again with other options.
The object:

* links its inputs (Scan, Workpiece, Reference, optional Toolpath), so FreeCAD recomputes it when one
  of them changes; ``execute`` calibrates again only when the input data or the options differ from
  what the stored result was computed from (a fingerprint), so reopening a file costs nothing;
* shows the frames as a triad shape (X at its origin, B and S where they are) with ``Placement = W``,
  i.e. in the robot base frame B: the triad of X sits where the workpiece frame is;
* holds W, U and V as placements, W's Z-Y-Z Euler angles and Omega, the residuals, the uncertainty
  bounds, the status and its reasons, and the whole CalibrationResult as JSON (hidden ``ResultJson``)
  for the exporters: ``result_of(obj)`` gives it back.

Its view provider (labels of the triads, double-click, context menu) is in the GUI layer.
"""
from __future__ import annotations

import json
import os

import numpy as np

import FreeCAD

from workcal_wb.core import frames
from workcal_wb.core.calibration import CalibrationOptions
from workcal_wb.core.errors import InputError, WorkCalError
from workcal_wb.core.match import METHODS
from workcal_wb.core import choice
from workcal_wb.core.result import (AMBIGUOUS, CHOSEN, ERROR, FAILED, OK, USABLE, CalibrationResult, Reason,
                                    choice_words)
from workcal_wb.fc import inputs as fc_inputs
from workcal_wb.fc import placed_model, prefs
from workcal_wb.fc.lookups import CALIBRATION_TYPE, is_calibration, label, result_of
from workcal_wb.fc.models import model_cloud
from workcal_wb.fc.placements import placement
from workcal_wb.fc.proxies import Feature, add_properties
from workcal_wb.fc.scan import scan_cloud
from workcal_wb.fc.setup import get_setup, toolpath_of
from workcal_wb.fc.undo import transaction

translate = FreeCAD.Qt.translate
QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP

TYPE = CALIBRATION_TYPE
# error: the inputs could not be calibrated at all; "ok (chosen)": a person chose among the poses an ambiguous
# result left (result.CHOSEN), last so that files saved before it keep their values' places.
STATUSES = ["new", OK, AMBIGUOUS, FAILED, "error", CHOSEN]
FRAME_FRACTION = 0.35  # triad axis length as a fraction of the workpiece model's diagonal
DEFAULT_FRAME_MM = 50.0

INPUT_PROPERTIES = [
    ("App::PropertyLink", "Scan", "Inputs", QT_TRANSLATE_NOOP(
        "App::Property", "The scene scan: the workpiece and the reference object seen at once (scanner frame S)")),
    ("App::PropertyLink", "Workpiece", "Inputs", QT_TRANSLATE_NOOP(
        "App::Property", "The workpiece model in its own frame, the toolpath's (X-A in frame X); a Part, Mesh or "
                         "Points object")),
    ("App::PropertyLink", "Reference", "Inputs", QT_TRANSLATE_NOOP(
        "App::Property", "The fixed reference object's model, where it stands in the robot base frame (B-P in B)")),
    ("App::PropertyLink", "Toolpath", "Inputs", QT_TRANSLATE_NOOP(
        "App::Property", "Optional Path/CAM Job or operation: the uncertainty is reported at its cutting points")),
    ("App::PropertyFile", "GcodeFile", "Inputs", QT_TRANSLATE_NOOP(
        "App::Property", "Optional G-code file (used when Toolpath is empty): the uncertainty is reported at its "
                         "cutting points")),
]
OPTION_PROPERTIES = [
    ("App::PropertyEnumeration", "Method", "Options", QT_TRANSLATE_NOOP(
        "App::Property", "How the models are fitted to the scan: robust (default), icp or hausdorff (the paper's "
                         "two measures)")),
    ("App::PropertyLength", "Tolerance", "Options", QT_TRANSLATE_NOOP(
        "App::Property", "Milling tolerance: residuals and the uncertainty at the toolpath must stay within it")),
    ("App::PropertyEnumeration", "Regions", "Options", QT_TRANSLATE_NOOP(
        "App::Property", "Auto: find the workpiece and the reference in the scan; Picked: use the regions picked "
                         "on the scan")),
    ("App::PropertyInteger", "Seed", "Options", QT_TRANSLATE_NOOP(
        "App::Property", "Random seed of the search and the uncertainty estimate: the same seed gives the same W")),
    ("App::PropertyInteger", "Refits", "Options", QT_TRANSLATE_NOOP(
        "App::Property", "Refits of both matches the uncertainty is estimated from (bootstrap)")),
    ("App::PropertyBool", "ScannerOn", "Options", QT_TRANSLATE_NOOP(
        "App::Property", "Use Scanner as where the scanner stood (else the scan file's position, or none: the "
                         "views are judged without it)")),
    ("App::PropertyVectorDistance", "Scanner", "Options", QT_TRANSLATE_NOOP(
        "App::Property", "Where the scanner stood, the origin of the scanner frame S, in the scan's coordinates "
                         "(used when ScannerOn is true)")),
    ("App::PropertyVector", "Up", "Options", QT_TRANSLATE_NOOP(
        "App::Property", "The platform's up direction in the scan's coordinates, the side the objects stand on "
                         "(0, 0, 0: from the data)")),
    ("App::PropertyBool", "Frames", "Display", QT_TRANSLATE_NOOP(
        "App::Property", "Show the axes of the robot base frame (B), the scanner frame (S) and the workpiece "
                         "frame (X)")),
    ("App::PropertyLength", "FrameSize", "Display", QT_TRANSLATE_NOOP(
        "App::Property", "Length of the frame axes")),
]
# Short names: they must fit the property editor's first column at FreeCAD's default panel width
# (about ten characters: tests/gui/test_calibrate_flow.py measures them).
RESULT_PROPERTIES = [
    ("App::PropertyEnumeration", "Status", "Result", QT_TRANSLATE_NOOP(
        "App::Property", "ok: W can be used; ambiguous: another pose fits almost as well; ok (chosen): a person "
                         "chose one of those poses; failed: W must not be used (see Reasons); error: the inputs "
                         "could not be calibrated")),
    ("App::PropertyPlacement", "W", "Result", QT_TRANSLATE_NOOP(
        "App::Property", "Where the workpiece is in the robot base frame: W = ^B X = V^-1 U, the workpiece frame X "
                         "in the robot base frame B")),
    ("App::PropertyString", "EulerZYZ", "Result", QT_TRANSLATE_NOOP(
        "App::Property", "W's rotation as the paper's Z-Y-Z Euler angles phi, theta, psi (degrees)")),
    ("App::PropertyAngle", "Omega", "Result", QT_TRANSLATE_NOOP(
        "App::Property", "W's rotation angle about its principal axis: Omega = acos((trace(R) - 1) / 2)")),
    ("App::PropertyPlacement", "U", "Result", QT_TRANSLATE_NOOP(
        "App::Property", "Where the workpiece is in the scan: U = ^S X, the workpiece frame X in the scanner frame S")),
    ("App::PropertyPlacement", "V", "Result", QT_TRANSLATE_NOOP(
        "App::Property", "Where the robot base is in the scan: V = ^S B, the robot base frame B in the scanner "
                         "frame S (from the reference object)")),
    ("App::PropertyLength", "PartRMS", "Fit", QT_TRANSLATE_NOOP(
        "App::Property", "RMS distance of the workpiece's scan points to its model")),
    ("App::PropertyLength", "RefRMS", "Fit", QT_TRANSLATE_NOOP(
        "App::Property", "RMS distance of the reference object's scan points to its model")),
    ("App::PropertyLength", "AtToolpath", "Uncertainty", QT_TRANSLATE_NOOP(
        "App::Property", "How far a toolpath point may be off because of the calibration (0 without a toolpath)")),
    ("App::PropertyLength", "AtSurface", "Uncertainty", QT_TRANSLATE_NOOP(
        "App::Property", "How far a point of the workpiece surface may be off because of the calibration")),
    ("App::PropertyAngle", "Rotation", "Uncertainty", QT_TRANSLATE_NOOP(
        "App::Property", "How far W's rotation may be off")),
    ("App::PropertyStringList", "Reasons", "Result", QT_TRANSLATE_NOOP(
        "App::Property", "Why the calibration is not ok (failed checks, another pose that fits)")),
    ("App::PropertyStringList", "Warnings", "Result", QT_TRANSLATE_NOOP("App::Property", "Warnings of the calibration")),
    ("App::PropertyFloat", "Seconds", "Result", QT_TRANSLATE_NOOP(
        "App::Property", "Seconds the calibration took")),
    ("App::PropertyBool", "Accepted", "Result", QT_TRANSLATE_NOOP(
        "App::Property", "Someone checked this result and accepted W (cleared when it is calibrated again)")),
]
HIDDEN_PROPERTIES = [
    ("App::PropertyString", "ResultJson", "Result", QT_TRANSLATE_NOOP(
        "App::Property", "The complete CalibrationResult as JSON (for exporters and reports)")),
    ("App::PropertyString", "InputsKey", "Result", QT_TRANSLATE_NOOP(
        "App::Property", "Fingerprint of the inputs the result was computed from")),
]


def toolpath_source(obj):
    """The toolpath a calibration reports its uncertainty at: its Job/Path object, file, or None."""
    return obj.Toolpath if obj.Toolpath is not None else (obj.GcodeFile or None)


def scanner_of(obj):
    """The scanner position stored on the calibration (x, y, z in mm), or None: from the file or unknown."""
    return tuple(obj.Scanner) if obj.ScannerOn else None


def up_of(obj):
    """The up direction stored on the calibration, or None: from the data."""
    return tuple(obj.Up) if obj.Up.Length > 0 else None


def options_of(obj) -> CalibrationOptions:
    """The calibration options the object's properties say."""
    return fc_inputs.options_from(obj.Tolerance.Value, obj.Method, obj.Seed, obj.Refits, scanner_of(obj), up_of(obj))


def inputs_of(obj) -> fc_inputs.Inputs:
    """The inputs as the object's links and options say."""
    return fc_inputs.gather_inputs(obj.Scan, obj.Workpiece, obj.Reference, options=options_of(obj), regions=obj.Regions,
                                   toolpath=toolpath_source(obj))


def workpiece_region(obj) -> tuple:
    """(the workpiece's scan points in S, its model X-A as a Cloud, the result) of a calibration: what
    a deviation map and a report compare.  InputError when there is no U to place the model with, no
    recorded region, or the scan no longer has the points the region names."""
    result = result_of(obj)
    if result.U is None:
        raise InputError(f"{obj.Label}: the workpiece match failed, there is no U to place the model with")
    idx = (result.regions or {}).get("workpiece")
    if idx is None or len(idx) == 0:
        raise InputError(f"{obj.Label}: the calibration records no workpiece region")
    scan = scan_cloud(obj.Scan)
    idx = np.asarray(idx, dtype=np.int64)
    if idx.max() >= len(scan):
        raise InputError(f"{obj.Label}: the scan {obj.Scan.Label} changed since the calibration (recompute it first)")
    return scan.points[idx], model_cloud(obj.Workpiece, role="workpiece"), result


def _finite(value, default=0.0) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError):
        return default
    return value if np.isfinite(value) else default


def euler_text(T) -> str:
    phi, theta, psi = frames.euler_zyz(T)
    return f"phi {phi:.4f}, theta {theta:.4f}, psi {psi:.4f} deg"


def store_result(obj, result: CalibrationResult, key: str = "") -> None:
    """Write a CalibrationResult into the object's properties and shape."""
    obj.ResultJson = json.dumps(result.to_dict(), allow_nan=True)
    obj.InputsKey = key
    obj.Status = result.status
    for name in ("W", "U", "V"):
        T = getattr(result, name)
        setattr(obj, name, placement(np.eye(4) if T is None else T))
    obj.EulerZYZ = "" if result.W is None else euler_text(result.W)
    obj.Omega = 0.0 if result.W is None else frames.omega(result.W)
    obj.PartRMS = _finite(getattr(result.workpiece, "rms_mm", None))
    obj.RefRMS = _finite(getattr(result.reference, "rms_mm", None))
    u = result.uncertainty or {}
    obj.AtToolpath = _finite(u.get("toolpath_bound_mm"))
    obj.AtSurface = _finite(u.get("surface_bound_mm"))
    obj.Rotation = _finite(u.get("rotation_bound_deg"))
    obj.Warnings = [str(w) for w in result.warnings]
    obj.Reasons = [str(r) for r in result.reasons]
    obj.Seconds = _finite(result.time_s)
    obj.Accepted = False
    _update_shape(obj, result)


def report(result: CalibrationResult, label: str = "Calibration") -> None:
    """The summary in the Report view (worded for people: no command-line flags): a message when ok, a
    warning otherwise."""
    from workcal_wb.core.wording import for_people

    (FreeCAD.Console.PrintMessage if result.ok else FreeCAD.Console.PrintWarning)(
        f"WorkCal: {label}: {for_people(result.summary())}\n")


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


def _update_shape(obj, result: CalibrationResult) -> None:
    """Triads of the frames (three edges each: x, y, z), placed by W."""
    import Part

    size = obj.FrameSize.Value or DEFAULT_FRAME_MM
    edges = []
    if obj.Frames:
        for T in frame_poses(result).values():
            origin = FreeCAD.Vector(*T[:3, 3])
            edges += [Part.LineSegment(origin, FreeCAD.Vector(*(T[:3, 3] + size * T[:3, axis]))).toShape()
                      for axis in range(3)]
    shape = Part.makeCompound(edges or [Part.Vertex(FreeCAD.Vector(0, 0, 0))])  # an empty compound keeps the placement
    pl = placement(result.W) if result.W is not None else FreeCAD.Placement()
    shape.Placement = pl
    obj.Shape = shape
    obj.Placement = pl


# Files saved by WorkCal 0.1: properties renamed since (old -> new) and properties no longer kept.
RENAMED = {"ShowFrames": "Frames", "ToolpathFile": "GcodeFile", "Resamples": "Refits", "ComputeTime": "Seconds",
           "WorkpieceRMS": "PartRMS", "ReferenceRMS": "RefRMS", "ToolpathBound": "AtToolpath",
           "SurfaceBound": "AtSurface", "RotationBound": "Rotation", "ScannerOrigin": "Scanner",
           "ScannerOriginGiven": "ScannerOn"}
DROPPED = [f"{n}{p}" for n in "WUV" for p in ("Matrix", "EulerZYZ", "Omega", "Translation")] + [
    "WorkpieceHausdorff", "WorkpieceWithinTolerance", "ReferenceHausdorff", "ReferenceWithinTolerance",
    "ModelDiagonal"]


def _migrate(obj) -> None:
    """Bring a calibration saved by WorkCal 0.1 to today's properties, values kept (its status was text)."""
    values = {new: obj.getPropertyByName(old) for old, new in RENAMED.items() if old in obj.PropertiesList}
    status = obj.Status if obj.getTypeIdOfProperty("Status") == "App::PropertyString" else None
    for name in list(RENAMED) + DROPPED + (["Status"] if status is not None else []):
        if name in obj.PropertiesList:
            obj.removeProperty(name)
    add_properties(obj, INPUT_PROPERTIES + OPTION_PROPERTIES + RESULT_PROPERTIES + HIDDEN_PROPERTIES)
    for name, value in values.items():
        setattr(obj, name, value)
    if status is not None:
        obj.Status = STATUSES
        obj.Status = status if status in STATUSES else "error"


class CalibrationFeature(Feature):
    """Proxy of the calibration object (``Part::FeaturePython``)."""

    TYPE = TYPE

    def onDocumentRestored(self, obj):
        _migrate(obj)
        super().onDocumentRestored(obj)

    def setup(self, obj) -> None:
        add_properties(obj, INPUT_PROPERTIES + OPTION_PROPERTIES + RESULT_PROPERTIES + HIDDEN_PROPERTIES,
                       read_only=[p[1] for p in RESULT_PROPERTIES] + ["Placement"],
                       hidden=[p[1] for p in HIDDEN_PROPERTIES])
        if not obj.getEnumerationsOfProperty("Method"):
            obj.Method = list(METHODS)
            obj.Method = prefs.get("Method")
        if not obj.getEnumerationsOfProperty("Regions"):
            obj.Regions = fc_inputs.REGION_MODES
            obj.Regions = prefs.get("Regions")
        if not obj.getEnumerationsOfProperty("Status"):
            obj.Status = STATUSES
            obj.Status = "new"
        elif obj.getEnumerationsOfProperty("Status") != STATUSES:  # saved before a status was added
            status = obj.Status
            obj.Status = STATUSES
            obj.Status = status
        if obj.Tolerance.Value == 0:
            obj.Tolerance = prefs.get("ToleranceMm")
        if obj.Refits == 0:
            obj.Refits = prefs.get("Resamples")

    def execute(self, obj):
        prepared = self.__dict__.pop("_prepared", None)  # (key, result) just computed by make/update
        if prepared is not None:
            store_result(obj, prepared[1], prepared[0])
            report(prepared[1], obj.Label)
            return
        try:
            inputs = inputs_of(obj)
            key = inputs.key()
            if obj.FrameSize.Value == 0:
                obj.FrameSize = FRAME_FRACTION * inputs.workpiece.diagonal() or DEFAULT_FRAME_MM
            if key != obj.InputsKey or not obj.ResultJson:
                result = fc_inputs.run(inputs)
                store_result(obj, result, key)
                report(result, obj.Label)
            else:
                _update_shape(obj, result_of(obj))
        except WorkCalError as exc:
            store_result(obj, CalibrationResult(FAILED, W=None, reasons=[Reason(ERROR, str(exc))],
                                                tolerance_mm=obj.Tolerance.Value))
            obj.Status = "error"
            FreeCAD.Console.PrintError(f"WorkCal: {obj.Label}: {exc}\n")
            raise


def _set_options(obj, options, regions: str, toolpath) -> None:
    obj.Method = options.method
    obj.Tolerance = options.tolerance_mm
    obj.Seed = options.seed
    obj.Refits = options.resamples
    obj.ScannerOn = options.scanner_origin is not None
    obj.Scanner = FreeCAD.Vector(*(options.scanner_origin or (0.0, 0.0, 0.0)))
    obj.Up = FreeCAD.Vector(*(options.up or (0.0, 0.0, 0.0)))
    obj.Regions = regions
    is_file = isinstance(toolpath, (str, os.PathLike))
    obj.Toolpath = None if (toolpath is None or is_file) else toolpath
    obj.GcodeFile = os.fspath(toolpath) if is_file else ""


UNSET = object()


def make_calibration(doc, scan=None, workpiece=None, reference=None, *, tolerance_mm=None, method=None, seed=None,
                     resamples=None, scanner_origin=None, up=None, regions: str | None = None, toolpath=UNSET,
                     overlays: bool = False, progress=None, name: str = "Calibration"):
    """Calibrate and add the calibration object to ``doc`` in one undo step; return it.

    Inputs not given come from the document's WorkCal setup (``fc.setup``), options not given from
    the preferences; ``scanner_origin`` (mm) and ``up``, in the scan's coordinates, are stored on the
    object (None: from the scan's file or the data); ``toolpath`` (Job, Path object, G-code path or None) defaults to the setup's.
    ``overlays``: also show both models placed on the scan (``fc.placed_model``), in the same step.
    ``progress`` as in core.calibrate.  Bad inputs raise InputError, cancelling raises Cancelled: in
    both cases the document is left as it was.  A calibration whose status is "failed" is still added
    (its reasons tell why; exporters refuse it unless forced)."""
    setup = get_setup(doc)
    scan = scan if scan is not None else setup["scan"]
    workpiece = workpiece if workpiece is not None else setup["workpiece"]
    reference = reference if reference is not None else setup["reference"]
    toolpath = toolpath_of(doc) if toolpath is UNSET else toolpath
    regions = regions or prefs.get("Regions")
    options = fc_inputs.options_from(tolerance_mm, method, seed, resamples, scanner_origin, up)
    inputs = fc_inputs.gather_inputs(scan, workpiece, reference, options=options, regions=regions, toolpath=toolpath)
    result = fc_inputs.run(inputs, progress)  # before the document changes: a failure leaves it as it was
    with transaction(doc, translate("WorkCal", "WorkCal calibration")):
        obj = doc.addObject("Part::FeaturePython", name)
        CalibrationFeature(obj)
        obj.Label = translate("WorkCal", "Calibration") if name == "Calibration" else name
        obj.Scan, obj.Workpiece, obj.Reference = scan, workpiece, reference
        _set_options(obj, options, regions, toolpath)
        obj.FrameSize = FRAME_FRACTION * inputs.workpiece.diagonal() or DEFAULT_FRAME_MM
        obj.Frames = True
        obj.Proxy._prepared = (inputs.key(), result)
        obj.recompute()
        if overlays:
            placed_model.add_on_scan(obj)
        doc.recompute()
    return obj


def update_calibration(obj, *, tolerance_mm=None, method=None, seed=None, resamples=None, scanner_origin=UNSET,
                       up=UNSET, regions: str | None = None, overlays: bool = False,
                       progress=None) -> CalibrationResult:
    """Calibrate ``obj`` again with other options (those not given stay; ``scanner_origin`` or ``up``
    None: from the scan's file or the data), in one undo step; returns the new result.  Bad options
    or inputs raise InputError and leave the object as it was."""
    doc = obj.Document
    options = fc_inputs.options_from(obj.Tolerance.Value if tolerance_mm is None else tolerance_mm,
                                     method or obj.Method, obj.Seed if seed is None else seed,
                                     obj.Refits if resamples is None else resamples,
                                     scanner_of(obj) if scanner_origin is UNSET else scanner_origin,
                                     up_of(obj) if up is UNSET else up)
    regions = regions or obj.Regions
    inputs = fc_inputs.gather_inputs(obj.Scan, obj.Workpiece, obj.Reference, options=options, regions=regions,
                                     toolpath=toolpath_source(obj))
    result = fc_inputs.run(inputs, progress)
    with transaction(doc, translate("WorkCal", "WorkCal calibration")):
        _set_options(obj, options, regions, toolpath_source(obj))
        obj.Proxy._prepared = (inputs.key(), result)
        obj.recompute()
        if overlays:
            placed_model.add_on_scan(obj)
        doc.recompute()
    return result


def choose_pose(obj, index: int, who: str | None = None) -> CalibrationResult:
    """Record that ``who`` (default: the OS user) chose pose ``index`` (0: the best) of an ambiguous
    calibration's match in doubt, as its poses are listed (``placed_model.candidate_poses``): W from that
    pose, the status "ok (chosen)", the models on the scan shown at it; one undo step.  Returns the
    result.  InputError (the object unchanged) when its inputs changed since its result (recompute first),
    when it is not ambiguous only by a tie between poses (``core.choice.why_not``) or has no such pose."""
    if not is_calibration(obj):
        raise InputError(f"{label(obj)}: not a WorkCal calibration")
    if obj.InputsKey != inputs_of(obj).key():
        raise InputError(f"{obj.Label}: its inputs changed since it was calibrated: recompute first, then choose "
                         "among the poses of that result")
    result = result_of(obj)
    try:
        role = choice.role_to_choose(result)
    except InputError as why:
        raise InputError(f"{obj.Label}: {why}") from None
    source = obj.Workpiece if role == "workpiece" else obj.Reference
    axes = choice.part_axes(model_cloud(source, role=role).points)
    chosen = choice.choose(result, role, int(index), axes, who or choice.user_name())
    with transaction(obj.Document, translate("WorkCal", "Choose the pose")):
        store_result(obj, chosen, obj.InputsKey)
        placed_model.show_chosen(obj)
        obj.Document.recompute()
    FreeCAD.Console.PrintMessage(f"WorkCal: {obj.Label}: {choice_words(chosen.choice)}\n")
    return chosen


def accept(obj) -> None:
    """Record that someone checked the result and accepts W (one undo step).  Only an "ok" calibration
    (or "ok (chosen)") can be accepted: an ambiguous or failed one is calibrated again or forced at export."""
    if not is_calibration(obj):
        raise InputError(f"{label(obj)}: not a WorkCal calibration")
    if obj.Status not in USABLE:
        raise InputError(f"{obj.Label}: its status is {obj.Status!r}; only an ok calibration can be accepted "
                         "(calibrate again, or force the export)")
    with transaction(obj.Document, translate("WorkCal", "Accept the calibration")):
        obj.Accepted = True
    FreeCAD.Console.PrintMessage(f"WorkCal: {obj.Label}: W accepted\n")
