"""Run at FreeCAD start-up by Init.py (with and without GUI): register WorkCal's scan import type.

Kept light on purpose: it imports only FreeCAD; numpy and the readers load when a file is imported.
FreeCAD's File > Import calls ``insert``/``open`` below for the "WorkCal scan" filter.
"""
import FreeCAD

SCAN_FILE_FILTER = "WorkCal scan (*.ply *.pcd *.xyz *.asc *.pts *.e57)"
FreeCAD.addImportType(SCAN_FILE_FILTER, "workcal_wb.fc.init")


def insert(filename, docname):
    """File > Import of a scan into document ``docname`` (units: the ScanUnits preference, else mm)."""
    from workcal_wb.core.errors import WorkCalError
    from workcal_wb.fc import scan

    doc = FreeCAD.getDocument(docname)
    try:
        return scan.import_scan(doc, filename, scan.preferred_units() or "mm")
    except WorkCalError as exc:  # a clear message instead of a traceback from FreeCAD's import code
        FreeCAD.Console.PrintError(f"WorkCal: {exc}\n")
        return None


def open(filename):  # noqa: A001  (the name FreeCAD's importer protocol requires)
    """File > Open of a scan: a new document holding it."""
    import os

    doc = FreeCAD.newDocument(os.path.splitext(os.path.basename(filename))[0] or "Scan")
    insert(filename, doc.Name)
    return doc
