"""WorkCal_TransformToolpath and WorkCal_ExportToolpath: the document's toolpath carried into B by W.

The toolpath is chosen once per document (the guide's toolpath step: a Path/CAM Job or operation, or
a G-code file, remembered by ``fc.setup``) and used by both.  Both refuse a calibration whose status
is not "ok" unless the user confirms forcing it (the result is then marked FORCED).
``actions.transform_toolpath`` and ``actions.export_program`` are the recorded ``workcal_wb.fc.toolpath`` calls,
``actions.show_robot_at_worst_pose`` the recorded ``workcal_wb.fc.robot_pose`` call.
"""
from __future__ import annotations

import FreeCAD

from workcal_wb.gui.actions import transform_toolpath
from workcal_wb.gui.task_panels.common import Command, active_document, calibration_for, with_force

QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP
translate = FreeCAD.Qt.translate

class TransformToolpathCommand(Command):
    NAME, TITLE = "WorkCal_TransformToolpath", "Calibrated toolpath"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_TransformToolpath", "Calibrated toolpath")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_TransformToolpath", "Show the document's toolpath (its CAM Job or G-code "
                                                              "file) carried from the workpiece's frame into the "
                                                              "robot base frame by the calibration")

    def run(self):
        from workcal_wb.fc.setup import toolpath_of
        from workcal_wb.gui.commands.guide import open_guide

        doc = active_document()
        if toolpath_of(doc) is None:
            open_guide(doc, "toolpath")  # choose it there first
            return
        calibration = calibration_for(doc)
        obj = with_force(lambda force: transform_toolpath(calibration, force=force))
        if obj is not None:
            import FreeCADGui

            FreeCADGui.Selection.clearSelection()
            FreeCADGui.Selection.addSelection(obj)


class ExportToolpathCommand(Command):
    NAME, TITLE = "WorkCal_ExportToolpath", "Export robot program"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_ExportToolpath", "Export robot program")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_ExportToolpath", "Write the toolpath through the calibration as KUKA KRL, "
                                                           "ABB RAPID, URScript, Fanuc LS, G-code or CSV, for a robot "
                                                           "or a 3- or 5-axis machine")

    def run(self):
        from workcal_wb.gui.commands.guide import open_guide

        open_guide(active_document(), "export")


COMMANDS = {"WorkCal_TransformToolpath": TransformToolpathCommand(),
            "WorkCal_ExportToolpath": ExportToolpathCommand()}
