"""Deviation map: the workpiece region of the scan coloured by its signed distance to the placed model.

Where the clay was changed (a lump added, a groove carved) the scan leaves the model surface.  The
colours are ``core.deviation.DeviationScale``'s, read against the calibration's tolerance (green
within it, yellow to red for material added, cyan to blue for material removed, full colour at
``Limit``, grey where no model surface is near) and the same as in the report.  The GUI draws
a legend of that scale while the map is shown.

The map is a ``Points::FeaturePython`` linked to its calibration: it recomputes when the calibration
does.  Its points are the scan points as ``fc.scan.scan_cloud`` gives them (the scan object's
Placement applied, i.e. where the scan is shown), so the map lies exactly on the scan.
"""
from __future__ import annotations

import FreeCAD

from workcal_wb.core.deviation import LIMIT_TOLERANCES, DeviationScale, deviation_stats, signed_deviations
from workcal_wb.core.errors import InputError, WorkCalError
from workcal_wb.fc import prefs
from workcal_wb.fc.calibration_object import workpiece_region
from workcal_wb.fc.lookups import is_calibration
from workcal_wb.fc.proxies import Feature, add_properties, objects_of, type_of
from workcal_wb.fc.undo import transaction

translate = FreeCAD.Qt.translate
QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP

TYPE = "WorkCal::DeviationMap"
PROPERTIES = [
    ("App::PropertyLink", "Calibration", "Deviation", QT_TRANSLATE_NOOP(
        "App::Property", "The calibration whose workpiece match is shown")),
    ("App::PropertyBool", "AutoLimit", "Deviation", QT_TRANSLATE_NOOP(
        "App::Property", "The colours reach full strength at 3 tolerances (set Limit to choose another limit)")),
    ("App::PropertyLength", "Limit", "Deviation", QT_TRANSLATE_NOOP(
        "App::Property", "Deviation at which the colours reach full red (added) and blue (removed)")),
    ("App::PropertyLength", "Tolerance", "Deviation", QT_TRANSLATE_NOOP(
        "App::Property", "Points within this distance of the model are green (the calibration's tolerance)")),
    ("App::PropertyDistance", "Mean", "Statistics", QT_TRANSLATE_NOOP("App::Property", "Mean signed deviation")),
    ("App::PropertyLength", "RMS", "Statistics", QT_TRANSLATE_NOOP("App::Property", "RMS deviation")),
    ("App::PropertyDistance", "Min", "Statistics", QT_TRANSLATE_NOOP(
        "App::Property", "Largest deviation into the model (material removed)")),
    ("App::PropertyDistance", "Max", "Statistics", QT_TRANSLATE_NOOP(
        "App::Property", "Largest deviation out of the model (material added)")),
    ("App::PropertyFloat", "Within", "Statistics", QT_TRANSLATE_NOOP(
        "App::Property", "% of points within the tolerance")),
    ("App::PropertyInteger", "FarPoints", "Statistics", QT_TRANSLATE_NOOP(
        "App::Property", "Points with no model surface near them (grey)")),
    ("App::PropertyBool", "Legend", "Display", QT_TRANSLATE_NOOP(
        "App::Property", "Show the colour scale in the 3D view")),
    ("App::PropertyFloatList", "Deviations", "Deviation", QT_TRANSLATE_NOOP(
        "App::Property", "Signed deviation per point, mm (NaN: no surface near)")),
    ("App::PropertyColorList", "Color", "Deviation", QT_TRANSLATE_NOOP("App::Property", "Colour per point")),
]
OUTPUTS = ("Mean", "RMS", "Min", "Max", "Within", "FarPoints", "Tolerance", "Calibration")
HIDDEN = ("Deviations", "Color")


def is_deviation_map(obj) -> bool:
    return type_of(obj) == TYPE


def deviation_maps(calibration) -> list:
    return [o for o in objects_of(calibration.Document, TYPE) if o.Calibration is calibration]


def scale_of(obj) -> DeviationScale:
    """The colour scale of a deviation map: the one its legend shows and its calibration's report uses."""
    return DeviationScale.for_tolerance(obj.Tolerance.Value, obj.Limit.Value)


def compute(calibration) -> dict:
    """Points (S), signed deviations and statistics of the workpiece region of a calibration's scan."""
    points, model, result = workpiece_region(calibration)
    deviations = signed_deviations(points, model, result.U)
    return {"points": points, "deviations": deviations, "tolerance_mm": result.tolerance_mm,
            "stats": deviation_stats(deviations, result.tolerance_mm)}


class DeviationFeature(Feature):
    """Proxy of the deviation map (``Points::FeaturePython``)."""

    TYPE = TYPE

    def setup(self, obj):
        fresh = "Legend" not in obj.PropertiesList
        add_properties(obj, PROPERTIES, read_only=OUTPUTS, hidden=HIDDEN)
        if fresh:
            obj.Legend = True
            obj.AutoLimit = True

    def onChanged(self, obj, prop):
        if prop == "Limit" and not getattr(self, "_setting_limit", False) and "AutoLimit" in obj.PropertiesList:
            obj.AutoLimit = False  # the user chose a limit: keep it when the tolerance changes

    def execute(self, obj):
        import Points

        if obj.Calibration is None or not is_calibration(obj.Calibration):
            raise InputError(f"{obj.Label}: link a WorkCal calibration")
        try:
            data = compute(obj.Calibration)
        except WorkCalError as exc:
            FreeCAD.Console.PrintError(f"WorkCal: {obj.Label}: {exc}\n")
            raise
        d, stats, tol = data["deviations"], data["stats"], data["tolerance_mm"]
        limit = LIMIT_TOLERANCES * tol if obj.AutoLimit else obj.Limit.Value
        scale = DeviationScale.for_tolerance(tol, limit)
        self._setting_limit = True
        try:
            obj.Limit = scale.limit_mm
        finally:
            self._setting_limit = False
        obj.Tolerance = tol
        obj.Points = Points.Points([tuple(p) for p in data["points"].tolist()])
        obj.Deviations = [float(v) for v in d]
        obj.Color = [tuple(c) for c in scale.colours(d).tolist()]
        obj.Mean = stats.get("mean_mm", 0.0)
        obj.RMS = stats.get("rms_mm", 0.0)
        obj.Min = stats.get("min_mm", 0.0)
        obj.Max = stats.get("max_mm", 0.0)
        obj.Within = stats.get("within_tolerance_pct", 0.0)
        obj.FarPoints = stats.get("n_far", 0)


def make_deviation_map(calibration, *, limit_mm: float | None = None):
    """Add a deviation map of ``calibration`` in one undo step and return it.  ``limit_mm``: where the
    colours reach full strength (default: the DeviationRangeMm preference, or 3 tolerances when it is
    automatic).  The document is left unchanged when the map cannot be made (InputError: no U, no
    region, the scan changed)."""
    if not is_calibration(calibration):
        raise InputError(f"{getattr(calibration, 'Label', calibration)}: not a WorkCal calibration")
    data = compute(calibration)  # fail before touching the document
    limit_mm = limit_mm or prefs.get("DeviationRangeMm") or None
    if limit_mm:
        DeviationScale.for_tolerance(data["tolerance_mm"], limit_mm)  # a limit inside the tolerance is refused
    doc = calibration.Document
    with transaction(doc, translate("WorkCal", "WorkCal deviation map")):
        obj = doc.addObject("Points::FeaturePython", "DeviationMap")
        DeviationFeature(obj)
        obj.Label = translate("WorkCal", "Deviation map of the workpiece")
        obj.Calibration = calibration
        if limit_mm:
            obj.Limit = float(limit_mm)  # AutoLimit goes off
        obj.recompute()
        if obj.isValid() is False or not obj.Deviations:
            raise InputError(f"{calibration.Label}: the deviation map could not be computed (see the Report view)")
        doc.recompute()
    FreeCAD.Console.PrintMessage(describe(obj) + "\n")
    return obj


def describe(obj) -> str:
    return (f"WorkCal: {obj.Label}: {len(obj.Deviations)} points, mean {obj.Mean.Value:+.3f} mm, "
            f"RMS {obj.RMS.Value:.3f} mm, min {obj.Min.Value:+.3f} mm, max {obj.Max.Value:+.3f} mm, "
            f"{obj.Within:.1f}% within {obj.Tolerance.Value:g} mm, {obj.FarPoints} far from the model; "
            f"full colour at +-{obj.Limit.Value:g} mm")
