"""Run at FreeCAD start-up by Init.py (with and without GUI): register WorkCal's scan import type.

Kept light on purpose: it imports only FreeCAD; numpy and the readers load when a file is imported.
FreeCAD's File > Import calls ``insert``/``open`` below for the "WorkCal scan" filter.

``VIEW_PROVIDERS`` lets the GUI attach view providers to objects the FreeCAD layer creates without
``workcal_wb.fc`` importing any GUI module: ``workcal_wb.gui.workbench`` fills it in at GUI start-up.
"""
import importlib

import FreeCAD

SCAN_FILE_FILTER = "WorkCal scan (*.ply *.pcd *.xyz *.asc *.pts *.e57)"
FreeCAD.addImportType(SCAN_FILE_FILTER, "workcal_wb.fc.init")

# kind ("Scan", "Setup", ...) -> "module:Class" of the view provider proxy; filled in by the GUI.
VIEW_PROVIDERS = {}


def attach_view_provider(obj, kind: str) -> None:
    """Give ``obj`` the registered view provider of ``kind`` when FreeCAD runs with its GUI."""
    target = VIEW_PROVIDERS.get(kind)
    if not FreeCAD.GuiUp or target is None or getattr(obj, "ViewObject", None) is None:
        return
    module, cls = target.split(":")
    getattr(importlib.import_module(module), cls)(obj.ViewObject)


def insert(filename, docname):
    """File > Import of a scan into document ``docname`` (units: the ScanUnits preference, else mm)."""
    from workcal_wb.core.errors import WorkCalError
    from workcal_wb.fc import scan

    doc = FreeCAD.getDocument(docname)
    units = scan.preferred_units() or "mm"
    try:
        obj = scan.import_scan(doc, filename, units)
    except WorkCalError as exc:  # a clear message instead of a traceback from FreeCAD's import code
        FreeCAD.Console.PrintError(f"WorkCal: {exc}\n")
        return None
    FreeCAD.Console.PrintMessage(f"WorkCal: imported {obj.Label} ({obj.Points.CountPoints} points, "
                                 f"read as {obj.Units})\n")
    return obj


def open(filename):  # noqa: A001  (the name FreeCAD's importer protocol requires)
    """File > Open of a scan: a new document holding it."""
    import os

    doc = FreeCAD.newDocument(os.path.splitext(os.path.basename(filename))[0] or "Scan")
    insert(filename, doc.Name)
    return doc
