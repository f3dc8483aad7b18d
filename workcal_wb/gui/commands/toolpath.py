"""WorkCal_TransformToolpath and WorkCal_ExportToolpath: a toolpath in X carried into B by W.

Sources: a Path/CAM Job, an operation or any Path object in the document, or a G-code file.  Both
commands refuse a calibration whose status is not "ok" unless the user confirms forcing it (the
result is then marked FORCED).  ``transform_toolpath`` and ``export_toolpath`` are the
non-interactive entry points; the commands call them after asking.
"""
from __future__ import annotations

import os

import FreeCAD

from workcal_wb.fc.undo import transaction
from workcal_wb.gui.task_panels.common import (Command, active_document, calibration_for, message, selected_objects,
                                              warning, with_force)

QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP
translate = FreeCAD.Qt.translate

GCODE_FILTER = "G-code (*.nc *.ngc *.gcode *.tap *.cnc *.txt);;All files (*)"
FILE_ITEM = "G-code file..."
MOTION = ("G0", "G1", "G2", "G3", "G00", "G01", "G02", "G03")


def read_source(source):
    """A Toolpath (workpiece frame X) from a document object or a G-code file path."""
    from workcal_wb.core.toolpath import read_gcode

    if isinstance(source, (str, os.PathLike)):
        return read_gcode(os.fspath(source))
    from workcal_wb.fc.toolpath import read_toolpath

    return read_toolpath(source)


def _label(source) -> str:
    return os.path.basename(os.fspath(source)) if isinstance(source, (str, os.PathLike)) else source.Label


def transform_toolpath(doc, calibration, source, *, force: bool = False, name: str | None = None):
    """A Path object in the robot base frame B from ``source`` moved by the calibration's W, in one undo
    step.  Raises ExportRefused for a calibration that is not ok (unless ``force``), InputError for a
    source that cannot be read; the document is unchanged then."""
    from workcal_wb.fc.calibration_object import result_of
    from workcal_wb.fc.toolpath import make_path_object

    result = result_of(calibration)
    toolpath = read_source(source)
    name = name or "CalibratedPath"
    with transaction(doc, translate("WorkCal", "WorkCal calibrated toolpath")):
        obj = make_path_object(doc, toolpath, result, force=force, name=name)
        obj.Label = f"{_label(source)} in B" + (" (FORCED)" if force and result.status != "ok" else "")
        obj.addProperty("App::PropertyString", "WorkCalSource", "WorkCal", "Toolpath the object was made from")
        obj.addProperty("App::PropertyString", "WorkCalCalibration", "WorkCal", "Calibration used (W)")
        obj.WorkCalSource = os.fspath(source) if isinstance(source, (str, os.PathLike)) else source.Name
        obj.WorkCalCalibration = calibration.Name
        doc.recompute()
    _start_display_at_first_point(obj)
    message(translate("WorkCal", "{}: {} moves carried into the robot base frame with {} ({})").format(
        obj.Label, len(toolpath), calibration.Label, result.status))
    return obj


def _start_display_at_first_point(obj) -> None:
    """FreeCAD draws a Path from its StartPosition (default: the origin of B); start at the first point."""
    vobj = getattr(obj, "ViewObject", None)
    if vobj is None or not hasattr(vobj, "StartPosition"):
        return
    for command in obj.Path.Commands:
        p = command.Parameters
        if all(axis in p for axis in "XYZ"):
            vobj.StartPosition = FreeCAD.Vector(p["X"], p["Y"], p["Z"])
            return


def export_toolpath(calibration, source, path, fmt: str | None = None, *, force: bool = False, **options):
    """Write ``source`` as a robot/CNC program through the calibration's W; returns the export job.

    ``fmt``: krl, rapid, urscript, fanuc, gcode or csv (default: from the file extension); ``options``
    go to core.toolpath.export (envelope, krl_mode, rapid_feed_mm_min, chord_tol_mm).  Nothing is
    written when the export is refused."""
    from workcal_wb.core.toolpath import FORMATS, export, format_for
    from workcal_wb.fc.calibration_object import result_of

    result = result_of(calibration)
    toolpath = read_source(source)
    fmt = fmt or format_for(path)
    job = export(toolpath, result, fmt, path, force=force, calibration_source=f"calibration {calibration.Label!r}",
                 **options)
    text = translate("WorkCal", "wrote {}: {}, {} moves from {}, calibration {}{}")
    (warning if job.forced else message)(text.format(path, FORMATS[fmt].NAME, len(toolpath), _label(source),
                                                     result.status, " (FORCED)" if job.forced else ""))
    return job


# ------------------------------------------------------------------------------ interactive parts

def toolpath_sources(doc) -> list:
    """Jobs first, then operations and other Path objects (calibrated ones excluded)."""
    from workcal_wb.fc.toolpath import is_job

    jobs = [o for o in doc.Objects if is_job(o)]
    paths = [o for o in doc.Objects if not is_job(o) and hasattr(o, "Path") and hasattr(o.Path, "Commands")
             and not hasattr(o, "WorkCalCalibration")  # WorkCal's own output is in B already
             and not hasattr(o, "SpindleSpeed")  # tool controllers hold a tool change, not a path
             and any(c.Name in MOTION for c in o.Path.Commands)]
    return jobs + paths


def choose_source(doc):
    """The selected Job/Path object, or one chosen from a list (or a G-code file); None if cancelled."""
    from workcal_wb.gui.task_panels import QtWidgets
    from workcal_wb.gui.task_panels.common import main_window

    from workcal_wb.fc.toolpath import is_job

    for obj in selected_objects():
        if is_job(obj) or (hasattr(obj, "Path") and hasattr(obj.Path, "Commands")):
            return obj
    sources = toolpath_sources(doc)
    items = [f"{o.Label} ({o.TypeId})" for o in sources] + [translate("WorkCal", FILE_ITEM)]
    item, ok = QtWidgets.QInputDialog.getItem(main_window(), translate("WorkCal", "Toolpath"),
                                              translate("WorkCal", "Toolpath in the workpiece frame X:"),
                                              items, 0, False)
    if not ok:
        return None
    index = items.index(item)
    if index < len(sources):
        return sources[index]
    path, _ = QtWidgets.QFileDialog.getOpenFileName(main_window(), translate("WorkCal", "Open G-code"), "",
                                                    GCODE_FILTER)
    return path or None


def export_filters() -> tuple[list, dict]:
    from workcal_wb.core.toolpath import FORMATS

    filters, by_filter = [], {}
    for name, module in FORMATS.items():
        text = f"{module.NAME} (*{module.EXTENSION})"
        filters.append(text)
        by_filter[text] = name
    return filters, by_filter


class ToolpathCommand(Command):
    """Both toolpath commands: the calibration and the toolpath first, then ``use`` them."""

    def run(self):
        doc = active_document()
        calibration = calibration_for(doc)
        source = choose_source(doc)
        if source is not None:
            self.use(doc, calibration, source)


class TransformToolpathCommand(ToolpathCommand):
    NAME, TITLE = "WorkCal_TransformToolpath", "Calibrated toolpath"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_TransformToolpath", "Calibrated toolpath")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_TransformToolpath", "Carry a Path/CAM Job, an operation or a G-code file from "
                                                              "the workpiece frame into the robot base frame with the "
                                                              "calibration, shown as a Path object")

    def use(self, doc, calibration, source):
        obj = with_force(lambda force: transform_toolpath(doc, calibration, source, force=force))
        if obj is not None and FreeCAD.GuiUp:
            import FreeCADGui

            FreeCADGui.Selection.clearSelection()
            FreeCADGui.Selection.addSelection(obj)


class ExportToolpathCommand(ToolpathCommand):
    NAME, TITLE = "WorkCal_ExportToolpath", "Export robot program"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_ExportToolpath", "Export robot program")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_ExportToolpath", "Write the toolpath through the calibration as KUKA KRL, "
                                                           "ABB RAPID, URScript, Fanuc LS, G-code or CSV")

    def use(self, doc, calibration, source):
        from workcal_wb.core.toolpath import FORMATS
        from workcal_wb.fc import prefs
        from workcal_wb.gui.task_panels import QtWidgets
        from workcal_wb.gui.task_panels.common import main_window

        filters, by_filter = export_filters()
        default = prefs.get("ExportFormat")
        initial = next(f for f in filters if by_filter[f] == default)
        folder = os.path.dirname(doc.FileName) if doc.FileName else os.path.expanduser("~")
        suggested = os.path.join(folder, f"{_safe(_label(source))}{FORMATS[default].EXTENSION}")
        path, chosen = QtWidgets.QFileDialog.getSaveFileName(
            main_window(), translate("WorkCal", "Export robot program"), suggested, ";;".join(filters), initial)
        if not path:
            return
        fmt = by_filter.get(chosen) or default
        if not os.path.splitext(path)[1]:
            path += FORMATS[fmt].EXTENSION
        with_force(lambda force: export_toolpath(calibration, source, path, fmt, force=force))


def _safe(text: str) -> str:
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in os.path.splitext(text)[0]) or "toolpath"


COMMANDS = {"WorkCal_TransformToolpath": TransformToolpathCommand(),
            "WorkCal_ExportToolpath": ExportToolpathCommand()}
