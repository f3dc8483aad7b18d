"""What the toolbar commands and the guide's steps both do: ask for files, import scans and models,
choose the models and the toolpath, carry the toolpath into B and export it.

Each document change is a recorded ``workcal_wb.fc`` call (``replay.run``: one undo step, replayable in
a macro), checked first so that a refusal is raised before anything is recorded.  The commands
(``commands/``) and the steps (``task_panels/steps/``) both call these; neither imports the other.
"""
from __future__ import annotations

import os

import FreeCAD

from workcal_wb.core.errors import Cancelled, InputError
from workcal_wb.core.units import MM_PER_UNIT
from workcal_wb.gui import replay
from workcal_wb.gui.task_panels.common import active_document

translate = FreeCAD.Qt.translate

PARAMS = "User parameter:BaseApp/Preferences/Mod/WorkCal"
UNIT_CHOICES = ("mm", "cm", "m", "in", "um")
# Preferences: the folder each file dialog last read from (it opens there next time).
SCAN_DIR_KEY, MODEL_DIR_KEY, TOOLPATH_DIR_KEY = "LastScanDir", "LastModelDir", "LastToolpathDir"
GCODE_FILTER = "G-code (*.nc *.ngc *.gcode *.tap *.cnc *.txt);;All files (*)"


# --- scans -----------------------------------------------------------------------------------------

def file_filter() -> str:
    from workcal_wb.fc.scan import SCAN_EXTENSIONS

    patterns = " ".join("*" + ext for ext in SCAN_EXTENSIONS)
    return (translate("WorkCal", "Scans") + f" ({patterns});;" + translate("WorkCal", "All files") + " (*)")


def ask_units(ask_again: bool = False) -> str:
    """The unit of scan files: the remembered one, or asked now (once) and remembered."""
    from workcal_wb.fc import scan as fc_scan

    units = fc_scan.preferred_units()
    if units in MM_PER_UNIT and not ask_again:
        return units
    import FreeCADGui

    from workcal_wb.gui.task_panels import QtWidgets

    choice, ok = QtWidgets.QInputDialog.getItem(
        FreeCADGui.getMainWindow(), translate("WorkCal", "Scan units"),
        translate("WorkCal", "Length unit of the numbers in scan files\n(asked once; change it in the WorkCal "
                             "preferences):"),
        list(UNIT_CHOICES), 0, False)
    if not ok:
        raise Cancelled(translate("WorkCal", "import cancelled: no unit chosen"))
    fc_scan.set_preferred_units(choice)
    return choice


def import_scan_files(paths, units: str | None = None, doc=None) -> list:
    """Import each file as a WorkCal scan; returns the new objects.

    ``units``: the files' length unit (default: the remembered one, asked once).  A file that cannot
    be read raises InputError naming it; files before it stay imported (each is its own undo step)."""
    import FreeCADGui

    from workcal_wb.fc import scan as fc_scan
    from workcal_wb.gui.progress import run_in_background

    paths = [str(p) for p in ([paths] if isinstance(paths, (str, os.PathLike)) else paths)]
    if not paths:
        raise InputError(translate("WorkCal", "no scan file given"))
    units = units or ask_units()
    if units not in MM_PER_UNIT:
        raise InputError(translate("WorkCal", "unknown length unit {!r}; use one of {}").format(
            units, ", ".join(MM_PER_UNIT)))
    if doc is None and FreeCAD.ActiveDocument is None:
        FreeCADGui.runCommand("Std_New")  # recorded by FreeCAD itself: App.newDocument(...)
    doc = doc or FreeCAD.ActiveDocument
    created = []
    for path in paths:  # read first (remembered): a file that cannot be read is refused before it is recorded
        if os.path.splitext(path)[1].lower() in fc_scan.FREECAD_POINT_FORMATS:  # FreeCAD's reader: main thread
            fc_scan.read_scan_file(path, units)
        else:
            run_in_background(lambda p=path: fc_scan.read_scan_file(p, units),
                              translate("WorkCal", "Reading {}...").format(os.path.basename(path)),
                              translate("WorkCal", "Import scan"))
        created.append(replay.run("workcal_wb.fc.scan.import_scan", doc, path, units, result="scan"))
    FreeCAD.ParamGet(PARAMS).SetString(SCAN_DIR_KEY, os.path.dirname(os.path.abspath(paths[-1])))
    return created


def ask_for_scan_files() -> list:
    """The scan files chosen in a file dialog (opening where the last scan was read)."""
    import FreeCADGui

    from workcal_wb.gui.task_panels import QtWidgets

    start = FreeCAD.ParamGet(PARAMS).GetString(SCAN_DIR_KEY, "") or os.path.expanduser("~")
    paths, _ = QtWidgets.QFileDialog.getOpenFileNames(
        FreeCADGui.getMainWindow(), translate("WorkCal", "Import scan"), start, file_filter())
    return paths


# --- models ----------------------------------------------------------------------------------------

def choose_models(doc=None, **chosen):
    """Store the chosen objects (keywords scan/workpiece/reference; None clears, omitted stays) as one
    undo step.  InputError names a refused object, before anything is recorded; the document is then
    unchanged."""
    from workcal_wb.fc.setup import check_setup

    doc = doc or active_document()
    check_setup(doc, **chosen)
    return replay.run("workcal_wb.fc.setup.choose_models", doc, result="setup", **chosen)


def import_model(path, doc=None, units: str | None = None, role: str | None = None):
    """Read a model file into the document and, with ``role``, choose it as that model (one undo step each)."""
    from workcal_wb.fc import models as fc_models

    doc = doc or active_document()
    ext = os.path.splitext(str(path))[1].lower()
    if role is not None:
        refuse_model_file_twice(doc, path, role)
    if units is None and ext not in fc_models.CAD_EXTENSIONS:
        units = ask_units()
    fc_models.read_model_file(path, units or "mm")  # a file that cannot be read is refused before it is recorded
    obj = replay.run("workcal_wb.fc.models.import_model", doc, str(path), units or "mm", result="model")
    FreeCAD.ParamGet(PARAMS).SetString(MODEL_DIR_KEY, os.path.dirname(os.path.abspath(str(path))))
    if role is not None:
        choose_models(doc, **{role: obj})
    return obj


def refuse_model_file_twice(doc, path, role: str) -> None:
    """InputError, before anything is read, when ``path`` is the file the other model was read from."""
    from workcal_wb.fc import models as fc_models
    from workcal_wb.fc.setup import get_setup

    other = "reference" if role == "workpiece" else "workpiece"
    chosen = get_setup(doc)[other]
    source = fc_models.source_file(chosen) if chosen is not None else ""
    if source and os.path.exists(source) and os.path.exists(str(path)) and os.path.samefile(source, str(path)):
        raise InputError(translate("WorkCal", "{} is already loaded as the {} model ({!r}), so it cannot be the {} "
                                              "model too. Load the {}'s own file").format(
            os.path.basename(str(path)), other, chosen.Label, role,
            translate("WorkCal", "reference object") if role == "reference" else translate("WorkCal", "workpiece")))


def ask_for_model_file() -> str:
    """A model file chosen in a file dialog (opening where the last model, else the scan, was read)."""
    import FreeCADGui

    from workcal_wb.fc import models as fc_models
    from workcal_wb.gui.task_panels import QtWidgets

    start = FreeCAD.ParamGet(PARAMS).GetString(MODEL_DIR_KEY, "") or FreeCAD.ParamGet(PARAMS).GetString(
        SCAN_DIR_KEY, "") or os.path.expanduser("~")
    patterns = " ".join("*" + e for e in fc_models.MODEL_EXTENSIONS)
    path, _ = QtWidgets.QFileDialog.getOpenFileName(
        FreeCADGui.getMainWindow(), translate("WorkCal", "Model file"), start,
        translate("WorkCal", "Models") + f" ({patterns});;" + translate("WorkCal", "All files") + " (*)")
    return path


def scan_candidates(doc) -> list:
    from workcal_wb.fc import lookups
    from workcal_wb.fc.proxies import type_of

    found = [o for o in doc.Objects if lookups.can_be_scan(o) and (type_of(o) is None or lookups.is_scan(o))]
    return sorted(found, key=lambda o: not lookups.is_scan(o))  # WorkCal scans first


def model_candidates(doc) -> list:
    """Objects that can be a model: Part shapes with faces, meshes and point clouds that are not WorkCal's."""
    from workcal_wb.fc import models as fc_models
    from workcal_wb.fc.proxies import type_of

    out = []
    for obj in doc.Objects:
        if type_of(obj) is not None or obj.TypeId in ("App::Part", "App::DocumentObjectGroup", "App::Origin") \
                or obj.TypeId.startswith(("App::Line", "App::Plane", "Path::", "Sketcher::")):
            continue
        kind, data = fc_models.kind_of(obj)
        if kind is None or (kind == "shape" and not data.Faces):
            continue
        out.append(obj)
    return out


# --- the toolpath ----------------------------------------------------------------------------------

def choose_toolpath(doc, source):
    """Remember the document's toolpath (recorded ``fc.setup.choose_toolpath``, one undo step)."""
    from workcal_wb.fc.toolpath_input import read_source

    read_source(source)  # a file that is no toolpath is refused before anything is recorded
    if isinstance(source, (str, os.PathLike)):
        FreeCAD.ParamGet(PARAMS).SetString(TOOLPATH_DIR_KEY, os.path.dirname(os.path.abspath(os.fspath(source))))
    return replay.run("workcal_wb.fc.setup.choose_toolpath", doc, source, result="setup")


def start_folder(doc) -> str:
    """Where a toolpath file dialog opens: beside the scan's file (CAM output usually sits with the job's
    data), else where the last toolpath was, else beside the document."""
    from workcal_wb.fc.setup import get_setup

    scan = get_setup(doc)["scan"]
    source = getattr(scan, "SourceFile", "") if scan is not None else ""
    for folder in (os.path.dirname(source) if source else "", FreeCAD.ParamGet(PARAMS).GetString(TOOLPATH_DIR_KEY, ""),
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
