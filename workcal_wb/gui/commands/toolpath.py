"""WorkCal_TransformToolpath and WorkCal_ExportToolpath: the document's toolpath carried into B by W.

The toolpath is chosen once per document (the guide's toolpath step: a Path/CAM Job or operation, or
a G-code file, remembered by ``fc.setup``) and used by both.  Both refuse a calibration whose status
is not "ok" unless the user confirms forcing it (the result is then marked FORCED).
``transform_toolpath`` and ``export_program`` are the recorded ``workcal_wb.fc.toolpath`` calls,
``show_robot_at_worst_pose`` the recorded ``workcal_wb.fc.robot_pose`` call.
"""
from __future__ import annotations

import os

import FreeCAD

from workcal_wb.gui import replay
from workcal_wb.gui.task_panels.common import Command, active_document, calibration_for, with_force

QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP
translate = FreeCAD.Qt.translate

GCODE_FILTER = "G-code (*.nc *.ngc *.gcode *.tap *.cnc *.txt);;All files (*)"
LAST_DIR_KEY = "LastToolpathDir"
PARAMS = "User parameter:BaseApp/Preferences/Mod/WorkCal"


def choose_toolpath(doc, source):
    """Remember the document's toolpath (recorded ``fc.setup.choose_toolpath``, one undo step)."""
    from workcal_wb.fc.toolpath_input import read_source

    read_source(source)  # a file that is no toolpath is refused before anything is recorded
    if isinstance(source, (str, os.PathLike)):
        FreeCAD.ParamGet(PARAMS).SetString(LAST_DIR_KEY, os.path.dirname(os.path.abspath(os.fspath(source))))
    return replay.run("workcal_wb.fc.setup.choose_toolpath", doc, source, result="setup")


def start_folder(doc) -> str:
    """Where a toolpath file dialog opens: beside the scan's file (CAM output usually sits with the job's
    data), else where the last toolpath was, else beside the document."""
    from workcal_wb.fc.setup import get_setup

    scan = get_setup(doc)["scan"]
    source = getattr(scan, "SourceFile", "") if scan is not None else ""
    for folder in (os.path.dirname(source) if source else "", FreeCAD.ParamGet(PARAMS).GetString(LAST_DIR_KEY, ""),
                   os.path.dirname(doc.FileName) if doc.FileName else ""):
        if folder and os.path.isdir(folder):
            return folder
    return os.path.expanduser("~")


def ask_for_toolpath_file(doc) -> str:
    import FreeCADGui

    from workcal_wb.gui.task_panels import QtWidgets

    path, _ = QtWidgets.QFileDialog.getOpenFileName(FreeCADGui.getMainWindow(), translate("WorkCal", "Toolpath"),
                                                    start_folder(doc), GCODE_FILTER)
    return path


def transform_toolpath(calibration, force: bool = False):
    """The document's toolpath in the robot base frame (recorded ``fc.toolpath.make_calibrated_path``;
    a refusal is raised before anything is recorded, so a macro holds only what worked)."""
    from workcal_wb.fc.toolpath import check_calibrated_path

    check_calibrated_path(calibration, force=force)
    return replay.run("workcal_wb.fc.toolpath.make_calibrated_path", calibration, force=force,
                      result="calibrated_toolpath")


def export_program(calibration, path, fmt=None, force: bool = False, **options):
    """The document's toolpath as a robot/CNC program (recorded ``fc.toolpath.export_program``; a refusal
    is raised before anything is recorded)."""
    from workcal_wb.fc.toolpath import check_export

    check_export(calibration, os.fspath(path), fmt, force=force, **options)
    return replay.run("workcal_wb.fc.toolpath.export_program", calibration, os.fspath(path), fmt, force=force,
                      result="program", **options)


def show_robot_at_worst_pose(calibration, fmt=None, force: bool = False, **options):
    """The robot of a checked export drawn at the program's worst pose (recorded
    ``fc.robot_pose.show_robot_at_worst_pose``, with the export's format, force and options).  Offered only
    after a check that found a pose to show, so what it could refuse has been refused already."""
    return replay.run("workcal_wb.fc.robot_pose.show_robot_at_worst_pose", calibration, fmt, force=force,
                      result="robot_pose", **options)


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
