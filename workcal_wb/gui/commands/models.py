"""WorkCal_ChooseModels: choose the scan, the workpiece model (X-A) and the reference model (B-P).

The command opens the guide at its models step.  ``choose_models`` and ``import_model`` are what that
step does, as recorded commands (``workcal_wb.fc.setup.choose_models``,
``workcal_wb.fc.models.import_model``): one undo step each, replayable in a macro.
"""
from __future__ import annotations

import os

import FreeCAD

from workcal_wb.gui import replay
from workcal_wb.gui.task_panels.common import Command, active_document

QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP
translate = FreeCAD.Qt.translate

ROLES = ("scan", "workpiece", "reference")
LAST_DIR_KEY = "LastModelDir"
PARAMS = "User parameter:BaseApp/Preferences/Mod/WorkCal"


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
    from workcal_wb.gui.commands.import_scan import ask_units

    doc = doc or active_document()
    ext = os.path.splitext(str(path))[1].lower()
    if units is None and ext not in fc_models.CAD_EXTENSIONS:
        units = ask_units()
    fc_models.read_model_file(path, units or "mm")  # a file that cannot be read is refused before it is recorded
    obj = replay.run("workcal_wb.fc.models.import_model", doc, str(path), units or "mm", result="model")
    FreeCAD.ParamGet(PARAMS).SetString(LAST_DIR_KEY, os.path.dirname(os.path.abspath(str(path))))
    if role is not None:
        choose_models(doc, **{role: obj})
    return obj


def ask_for_model_file() -> str:
    """A model file chosen in a file dialog (opening where the last model, else the scan, was read)."""
    import FreeCADGui

    from workcal_wb.fc import models as fc_models
    from workcal_wb.gui.task_panels import QtWidgets

    start = FreeCAD.ParamGet(PARAMS).GetString(LAST_DIR_KEY, "") or FreeCAD.ParamGet(PARAMS).GetString(
        "LastScanDir", "") or os.path.expanduser("~")
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


class ChooseModelsCommand(Command):
    NAME, TITLE = "WorkCal_ChooseModels", "Choose models"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_ChooseModels", "Choose models...")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_ChooseModels", "Choose the workpiece model (X-A, in its own frame) and the "
                                                         "reference model (B-P, in the robot base frame): Part shapes, "
                                                         "meshes or point clouds from the document or from files")

    def run(self):
        from workcal_wb.gui.commands.guide import open_guide

        open_guide(active_document(), "models")


COMMANDS = {"WorkCal_ChooseModels": ChooseModelsCommand()}
