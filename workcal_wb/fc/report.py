"""The calibration report of a document's calibration: the data it needs and where it goes.

``write_report(calibration)`` writes report.html and report.json (``core.report``) with the deviation
map of the workpiece region in the same colour scale as the calibration's deviation map in the 3D view
(or the default scale when there is none), and both regions drawn in the scan with the points off
their models.  When the scan no longer has the region's points, the report is written without the
map and says so in the Report view.
"""
from __future__ import annotations

import os
import tempfile

import FreeCAD

from workcal_wb.core import report as core_report
from workcal_wb.core.deviation import DeviationScale
from workcal_wb.core.errors import WorkCalError
from workcal_wb.fc import prefs
from workcal_wb.fc.calibration_object import workpiece_region
from workcal_wb.fc.lookups import result_of
from workcal_wb.fc.scan import scan_cloud


def default_report_dir(calibration) -> str:
    """The ReportDir preference, else a folder beside the document (or in the temporary folder)."""
    base = prefs.get("ReportDir")
    doc = calibration.Document
    if not base:
        base = os.path.dirname(doc.FileName) if doc.FileName else os.path.join(tempfile.gettempdir(), "workcal")
    stem = os.path.splitext(os.path.basename(doc.FileName))[0] if doc.FileName else doc.Name
    return os.path.join(base, f"{stem}_{calibration.Name}_report")


def report_data(calibration) -> dict:
    """The keyword arguments of ``core.report.write_report`` for a calibration object."""
    from workcal_wb.fc.deviation_map import deviation_maps, scale_of

    result = result_of(calibration)
    maps = deviation_maps(calibration)
    data = {"deviation_scale": scale_of(maps[-1]) if maps else
            DeviationScale.for_tolerance(result.tolerance_mm, prefs.get("DeviationRangeMm") or None),
            "title": f"WorkCal calibration: {calibration.Document.Label} / {calibration.Label}"}
    try:
        points, model, _ = workpiece_region(calibration)
        data.update(workpiece_points=points, workpiece_model=model)
    except WorkCalError as exc:  # the report still shows every number
        FreeCAD.Console.PrintWarning(f"WorkCal: report without the deviation map: {exc}\n")
    try:  # both regions drawn in the scan, with the points off their models
        data["scan_points"] = scan_cloud(calibration.Scan).points
    except WorkCalError as exc:
        FreeCAD.Console.PrintWarning(f"WorkCal: report without the views of the regions: {exc}\n")
    return data


def write_report(calibration, out_dir: str | None = None) -> dict:
    """Write report.html and report.json of a calibration object; returns their paths ("html", "json")."""
    out_dir = out_dir or default_report_dir(calibration)
    paths = core_report.write_report(result_of(calibration), out_dir, **report_data(calibration))
    paths = {k: os.fspath(v) for k, v in paths.items()}
    FreeCAD.Console.PrintMessage(f"WorkCal: report written: {paths['html']}\n")
    return paths
