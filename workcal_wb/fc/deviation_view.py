"""Deviation map: the workpiece region of the scan coloured by its signed distance to the placed model.

Where the clay was changed (a lump added, a groove carved) the scan leaves the model surface: those
points turn red (outside the model, material added) or blue (inside, material removed); points within
the tolerance stay green; grey points have no model surface near them.  A colour bar with the scale
is drawn over the 3D view while the map is visible.

The map is a ``Points::FeaturePython`` linked to its calibration: it recomputes when the calibration
does.  Its points are the scan points as ``fc.scan.scan_cloud`` gives them (the scan object's
Placement applied, i.e. where the scan is shown), so the map lies exactly on the scan.
"""
from __future__ import annotations

import numpy as np

import FreeCAD

from workcal_wb.core.deviation import deviation_stats, signed_deviations
from workcal_wb.core.errors import InputError, WorkCalError
from workcal_wb.fc import prefs
from workcal_wb.fc.calibration_object import _model_cloud, _scan_cloud, error, is_calibration, log, result_of
from workcal_wb.fc.proxies import Feature, ViewProvider
from workcal_wb.fc.undo import transaction

translate = FreeCAD.Qt.translate
QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP

ROLE = "WorkCalDeviationMap"
NO_DATA_COLOUR = (0.55, 0.55, 0.55)
# Colour stops from -range to +range: blue, cyan, green (zero), yellow, red.
STOPS = np.array([[0.0, 0.0, 1.0], [0.0, 0.85, 1.0], [0.0, 0.8, 0.0], [1.0, 0.9, 0.0], [1.0, 0.0, 0.0]])
MIN_RANGE_TOLERANCES = 3.0  # the automatic range is at least this many tolerances
RANGE_PERCENTILE = 99.0


def nice_range(value: float) -> float:
    """The next of 1, 2, 2.5, 5 x 10^k at or above value."""
    if not value > 0:
        return 1.0
    exponent = np.floor(np.log10(value))
    for step in (1.0, 2.0, 2.5, 5.0, 10.0):
        candidate = step * 10 ** exponent
        if candidate >= value * (1 - 1e-9):
            return float(candidate)
    return float(10 ** (exponent + 1))


def auto_range(deviations: np.ndarray, tolerance_mm: float) -> float:
    finite = np.abs(deviations[np.isfinite(deviations)])
    spread = float(np.percentile(finite, RANGE_PERCENTILE)) if len(finite) else 0.0
    return nice_range(max(MIN_RANGE_TOLERANCES * tolerance_mm, spread))


def colours(deviations: np.ndarray, range_mm: float, tolerance_mm: float) -> np.ndarray:
    """(N, 3) RGB in 0..1: the colour scale over [-range, +range], green within the tolerance, grey for NaN."""
    d = np.asarray(deviations, dtype=float)
    out = np.tile(np.array(NO_DATA_COLOUR), (len(d), 1))
    ok = np.isfinite(d)
    t = (np.clip(d[ok] / range_mm, -1.0, 1.0) + 1.0) * 0.5 * (len(STOPS) - 1)  # 0 .. 4
    low = np.minimum(np.floor(t).astype(int), len(STOPS) - 2)
    frac = (t - low)[:, None]
    rgb = STOPS[low] * (1 - frac) + STOPS[low + 1] * frac
    rgb[np.abs(d[ok]) <= tolerance_mm] = STOPS[2]
    out[ok] = rgb
    return out


PROPERTIES = [
    ("App::PropertyLink", "Calibration", "Deviation", "The calibration whose workpiece match is shown"),
    ("App::PropertyLength", "Range", "Deviation", "Colour scale from -Range to +Range (0: from the data)"),
    ("App::PropertyLength", "RangeUsed", "Deviation", "The colour scale in use"),
    ("App::PropertyLength", "Tolerance", "Deviation", "Points within this distance are green"),
    ("App::PropertyDistance", "Mean", "Statistics", "Mean signed deviation"),
    ("App::PropertyLength", "RMS", "Statistics", "RMS deviation"),
    ("App::PropertyDistance", "Min", "Statistics", "Largest deviation into the model (material removed)"),
    ("App::PropertyDistance", "Max", "Statistics", "Largest deviation out of the model (material added)"),
    ("App::PropertyFloat", "WithinTolerance", "Statistics", "% of points within the tolerance"),
    ("App::PropertyInteger", "FarPoints", "Statistics", "Points with no model surface near them (grey)"),
    ("App::PropertyBool", "ShowLegend", "Display", "Show the colour bar in the 3D view"),
    ("App::PropertyFloatList", "Deviations", "Deviation", "Signed deviation per point, mm (NaN: no surface near)"),
    ("App::PropertyColorList", "Color", "Deviation", "Colour per point"),
    ("App::PropertyString", "WorkCalRole", "Base", "What this object is to WorkCal"),
]
OUTPUTS = ("RangeUsed", "Mean", "RMS", "Min", "Max", "WithinTolerance", "FarPoints", "Tolerance")
HIDDEN = ("Deviations", "Color", "WorkCalRole")


def is_deviation_map(obj) -> bool:
    return getattr(obj, "WorkCalRole", None) == ROLE


def compute(calibration) -> dict:
    """Points (S), signed deviations and statistics of the workpiece region of a calibration's scan."""
    result = result_of(calibration)
    if result.U is None:
        raise InputError(f"{calibration.Label}: the workpiece match failed, there is no U to place the model with")
    idx = (result.regions or {}).get("workpiece")
    if idx is None or len(idx) == 0:
        raise InputError(f"{calibration.Label}: the calibration records no workpiece region")
    scan = _scan_cloud(calibration.Scan)
    idx = np.asarray(idx, dtype=np.int64)
    if idx.max() >= len(scan):
        raise InputError(f"{calibration.Label}: the scan {calibration.Scan.Label} changed since the calibration "
                         "(recompute it first)")
    model = _model_cloud(calibration.Workpiece, "workpiece")
    points = scan.points[idx]
    deviations = signed_deviations(points, model, result.U)
    return {"points": points, "deviations": deviations, "tolerance_mm": result.tolerance_mm,
            "stats": deviation_stats(deviations, result.tolerance_mm)}


class DeviationFeature(Feature):
    """Proxy of the deviation map (``Points::FeaturePython``)."""

    STATE = {"type": ROLE, "version": 1}

    def setup(self, obj):
        for kind, name, group, tip in PROPERTIES:
            if name not in obj.PropertiesList:
                obj.addProperty(kind, name, group, QT_TRANSLATE_NOOP("App::Property", tip))
                if name == "ShowLegend":
                    obj.ShowLegend = True
        for name in OUTPUTS:
            obj.setEditorMode(name, 1)
        for name in HIDDEN:
            obj.setEditorMode(name, 2)
        obj.WorkCalRole = ROLE

    def execute(self, obj):
        import Points

        if obj.Calibration is None or not is_calibration(obj.Calibration):
            raise InputError(f"{obj.Label}: link a WorkCal calibration")
        try:
            data = compute(obj.Calibration)
        except WorkCalError as exc:
            error(f"WorkCal: {obj.Label}: {exc}")
            raise
        d, stats, tol = data["deviations"], data["stats"], data["tolerance_mm"]
        rng = obj.Range.Value or (prefs.get("DeviationRangeMm") or auto_range(d, tol))
        obj.Points = Points.Points([tuple(p) for p in data["points"].tolist()])
        obj.Deviations = [float(v) for v in d]
        obj.Color = [tuple(c) for c in colours(d, rng, tol).tolist()]
        obj.RangeUsed, obj.Tolerance = rng, tol
        obj.Mean = stats.get("mean_mm", 0.0)
        obj.RMS = stats.get("rms_mm", 0.0)
        obj.Min = stats.get("min_mm", 0.0)
        obj.Max = stats.get("max_mm", 0.0)
        obj.WithinTolerance = stats.get("within_tolerance_pct", 0.0)
        obj.FarPoints = stats.get("n_far", 0)


def make_deviation_map(doc, calibration, *, range_mm: float | None = None, name: str = "DeviationMap",
                       hide_scan: bool = True):
    """Add a deviation map of ``calibration`` in one undo step and return it; the document is left
    unchanged when it cannot be made (InputError: no U, no region, inputs gone)."""
    if not is_calibration(calibration):
        raise InputError(f"{getattr(calibration, 'Label', calibration)}: not a WorkCal calibration")
    compute(calibration)  # fail before touching the document
    with transaction(doc, translate("WorkCal", "WorkCal deviation map")):
        obj = doc.addObject("Points::FeaturePython", name)
        DeviationFeature(obj)
        obj.Label = f"{name} ({calibration.Label})"
        obj.Calibration = calibration
        if range_mm:
            obj.Range = float(range_mm)
        if FreeCAD.GuiUp:
            ViewProviderDeviation(obj.ViewObject)
        obj.recompute()
        if obj.isValid() is False or not obj.Deviations:
            raise InputError(f"{calibration.Label}: the deviation map could not be computed (see the Report view)")
        doc.recompute()
    if FreeCAD.GuiUp:
        obj.ViewObject.DisplayMode = "Color"
        if hide_scan and calibration.Scan is not None:
            calibration.Scan.ViewObject.Visibility = False
    log(describe(obj))
    return obj


def describe(obj) -> str:
    return (f"WorkCal: {obj.Label}: {len(obj.Deviations)} points, mean {obj.Mean.Value:+.3f} mm, "
            f"RMS {obj.RMS.Value:.3f} mm, min {obj.Min.Value:+.3f} mm, max {obj.Max.Value:+.3f} mm, "
            f"{obj.WithinTolerance:.1f}% within {obj.Tolerance.Value:g} mm, {obj.FarPoints} far from the model; "
            f"colour scale +-{obj.RangeUsed.Value:g} mm")


def legend_ticks(range_mm: float) -> list:
    return [range_mm, range_mm / 2, 0.0, -range_mm / 2, -range_mm]


class ViewProviderDeviation(ViewProvider):
    """Colour display mode, larger points, and a colour bar overlay while visible."""

    ICON = "WorkCal_DeviationMap"
    BAR_X = (0.74, 0.79)  # normalised device coordinates of the bar (-1..1)
    BAR_Y = (-0.7, 0.7)

    def __init__(self, vobj):
        super().__init__(vobj)
        vobj.PointSize = 3.0

    def getDefaultDisplayMode(self):
        return "Color"

    def attach(self, vobj):
        from pivy import coin

        super().attach(vobj)
        self.switch = coin.SoSwitch()
        self.legend = coin.SoAnnotation()  # drawn last, over the scene
        self.switch.addChild(self.legend)
        vobj.RootNode.addChild(self.switch)
        self._rebuild(vobj.Object)

    def updateData(self, obj, prop):
        if prop in ("RangeUsed", "Color", "Tolerance", "ShowLegend", "Mean", "Max", "Min"):
            self._rebuild(obj)

    def onChanged(self, vobj, prop):
        if prop == "Visibility":
            self._show(vobj.Object)

    def _show(self, obj):
        if not hasattr(self, "switch"):
            return
        visible = bool(getattr(obj, "ShowLegend", True)) and obj.ViewObject is not None and obj.ViewObject.Visibility
        self.switch.whichChild = 0 if visible and getattr(obj, "RangeUsed", None) and obj.RangeUsed.Value > 0 else -1

    def _rebuild(self, obj):
        from pivy import coin

        if not hasattr(self, "legend") or "RangeUsed" not in obj.PropertiesList:
            return
        node = self.legend
        node.removeAllChildren()
        rng, tol = obj.RangeUsed.Value, obj.Tolerance.Value
        if rng > 0:
            style = coin.SoDrawStyle()
            style.style = coin.SoDrawStyle.FILLED
            pick = coin.SoPickStyle()
            pick.style = coin.SoPickStyle.UNPICKABLE
            camera = coin.SoOrthographicCamera()
            camera.viewportMapping = coin.SoCamera.LEAVE_ALONE  # x, y in -1..1 whatever the window shape
            camera.position = (0.0, 0.0, 5.0)
            camera.height = 2.0
            camera.nearDistance, camera.farDistance = 0.1, 10.0
            light = coin.SoLightModel()
            light.model = coin.SoLightModel.BASE_COLOR
            for child in (style, pick, camera, light):
                node.addChild(child)
            node.addChild(self._bar(rng, tol))
            node.addChild(self._labels(obj, rng, tol))
        self._show(obj)

    def _bar(self, rng, tol):
        from pivy import coin

        x0, x1 = self.BAR_X
        y0, y1 = self.BAR_Y
        values = np.linspace(rng, -rng, 41)  # top to bottom, so the tolerance band shows crisp
        values = np.unique(np.concatenate([values, [tol, -tol, tol * (1 + 1e-6), -tol * (1 + 1e-6)]]))[::-1]
        values = values[np.abs(values) <= rng]
        ys = y0 + (values + rng) / (2 * rng) * (y1 - y0)
        rgb = colours(values, rng, tol)
        points, cols = [], []
        for i in range(len(values) - 1):
            quad_y = (ys[i + 1], ys[i + 1], ys[i], ys[i])
            quad_c = (rgb[i + 1], rgb[i + 1], rgb[i], rgb[i])
            points += [(x0, quad_y[0], 0.0), (x1, quad_y[1], 0.0), (x1, quad_y[2], 0.0), (x0, quad_y[3], 0.0)]
            cols += [tuple(float(c) for c in col) for col in quad_c]
        sep = coin.SoSeparator()
        binding = coin.SoMaterialBinding()
        binding.value = coin.SoMaterialBinding.PER_VERTEX
        material = coin.SoMaterial()
        material.diffuseColor.setValues(0, len(cols), cols)
        coords = coin.SoCoordinate3()
        coords.point.setValues(0, len(points), points)
        faces = coin.SoFaceSet()
        faces.numVertices.setValues(0, len(points) // 4, [4] * (len(points) // 4))
        for child in (binding, material, coords, faces):
            sep.addChild(child)
        # A frame around the bar.
        frame = coin.SoSeparator()
        colour = coin.SoBaseColor()
        colour.rgb = (0.15, 0.15, 0.15)
        line_coords = coin.SoCoordinate3()
        line_coords.point.setValues(0, 5, [(x0, y0, 0.0), (x1, y0, 0.0), (x1, y1, 0.0), (x0, y1, 0.0), (x0, y0, 0.0)])
        lines = coin.SoLineSet()
        lines.numVertices.setValue(5)
        for child in (colour, line_coords, lines):
            frame.addChild(child)
        sep.addChild(frame)
        return sep

    def _labels(self, obj, rng, tol):
        from pivy import coin

        x0, x1 = self.BAR_X
        y0, y1 = self.BAR_Y
        sep = coin.SoSeparator()
        colour = coin.SoBaseColor()
        colour.rgb = (0.1, 0.1, 0.1)
        font = coin.SoFont()
        font.size = 13
        sep.addChild(colour)
        sep.addChild(font)

        def text_at(x, y, lines):
            s = coin.SoSeparator()
            move = coin.SoTranslation()
            move.translation = (x, y, 0.0)
            text = coin.SoText2()
            text.string.setValues(0, len(lines), lines)
            s.addChild(move)
            s.addChild(text)
            sep.addChild(s)

        for value in legend_ticks(rng):
            y = y0 + (value + rng) / (2 * rng) * (y1 - y0)
            text_at(x1 + 0.015, y - 0.01, [f"{value:+.3g}"])
        title = [translate("WorkCal", "Deviation (mm)"), translate("WorkCal", "tolerance +-{} mm").format(f"{tol:g}")]
        text_at(x0 - 0.08, y1 + 0.14, title)
        notes = [translate("WorkCal", "red: material added"), translate("WorkCal", "blue: material removed"),
                 translate("WorkCal", "grey: no model near")]
        text_at(x0 - 0.08, y0 - 0.08, notes)
        return sep
