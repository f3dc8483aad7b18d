"""WorkCal_ImportScan: read scan files into WorkCal scan objects.

``actions.import_scan_files(paths, units)`` is what the command does after its file dialog (tests call it
directly).  The length unit of scan files is asked once and remembered (preference "ScanUnits"); a
PLY written by WorkCal declares its own unit.  Each file is read in a worker thread with a progress
dialog, then added by the recorded command ``workcal_wb.fc.scan.import_scan(...)`` (one undo step,
replayable in a macro), which makes it the document's scan.
"""
from __future__ import annotations

import FreeCAD

from workcal_wb.gui.actions import ask_for_scan_files, import_scan_files
from workcal_wb.gui.task_panels.common import Command

QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP
translate = FreeCAD.Qt.translate

class ImportScanCommand(Command):
    NAME, TITLE = "WorkCal_ImportScan", "Import scan"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_ImportScan", "Import scan...")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_ImportScan", "Read a 3D scan of the mounted workpiece and the reference "
                                                       "object (PLY, PCD, XYZ, ASC, PTS, CSV, E57, STL, OBJ, OFF); it "
                                                       "becomes the document's scan")
    NEEDS_DOCUMENT = False

    def run(self):
        from workcal_wb.gui.commands.guide import open_guide

        paths = ask_for_scan_files()
        if paths:
            import_scan_files(paths)
            open_guide(FreeCAD.ActiveDocument, "scan")


COMMANDS = {"WorkCal_ImportScan": ImportScanCommand()}
