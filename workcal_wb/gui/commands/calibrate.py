"""WorkCal_Calibrate: the guide at its calibrate step (at the result step for a selected calibration)."""
from __future__ import annotations

import FreeCAD

from workcal_wb.gui.task_panels.common import Command, active_document, selected_objects

QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP


class CalibrateCommand(Command):
    NAME, TITLE = "WorkCal_Calibrate", "Calibrate"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_Calibrate", "Calibrate")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_Calibrate", "Find where the workpiece is in the robot's base frame: match "
                                                      "the workpiece and the reference object in the scan (W = V^-1 U)")

    def run(self):
        from workcal_wb.fc.lookups import is_calibration
        from workcal_wb.gui.commands.guide import open_guide

        selected = any(is_calibration(o) for o in selected_objects())
        open_guide(active_document(), "result" if selected else "calibrate")


COMMANDS = {"WorkCal_Calibrate": CalibrateCommand()}
