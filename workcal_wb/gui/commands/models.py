"""WorkCal_ChooseModels: choose the scan, the workpiece model X-A and the reference model B-P.

A task panel lists the document's point clouds and meshes (scan) and its Part shapes, meshes and point
clouds (models); models can also be read from files (STEP/IGES/BREP, STL/OBJ/OFF/PLY, point files).
The choice is stored in the document (``workcal_wb.fc.setup``) for Calibrate and Auto regions.  The
panel is one undo step: Cancel also removes models read from files.  ``choose_models`` and
``import_model`` are the same without the panel.
"""
from __future__ import annotations

import os

import FreeCAD

import workcal_wb
from workcal_wb.core.errors import InputError, WorkCalError
from workcal_wb.fc.undo import transaction
from workcal_wb.gui.task_panels.common import Command, active_document, message, show_error, show_panel

QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP
translate = FreeCAD.Qt.translate

ROLES = ("scan", "workpiece", "reference")
LAST_DIR_KEY = "LastModelDir"


def _setup():
    from workcal_wb.fc import setup

    return setup


def choose_models(doc=None, **chosen):
    """Store the chosen objects (keywords scan/workpiece/reference; None clears, omitted stays) as one
    undo step.  InputError names a refused object; the document is then unchanged."""
    setup = _setup()
    unknown = set(chosen) - set(ROLES)
    if unknown:
        raise TypeError(f"unknown roles {sorted(unknown)}")
    doc = doc or active_document()
    with transaction(doc, translate("WorkCal", "Choose models")):
        obj = setup.set_setup(doc, **chosen)
    chosen_now = setup.get_setup(doc)
    message(translate("WorkCal", "setup: scan {}, workpiece model {}, reference model {}").format(
        *(_label(chosen_now[r]) for r in ROLES)))
    return obj


def _label(obj) -> str:
    return obj.Label if obj is not None else "-"


def import_model(path, doc=None, units: str | None = None):
    """Read a model file into the document (no undo step of its own: the panel's, or the caller's)."""
    from workcal_wb.fc import models as fc_models
    from workcal_wb.gui.commands.import_scan import ask_units

    doc = doc or active_document()
    ext = os.path.splitext(str(path))[1].lower()
    if units is None and ext not in fc_models.CAD_EXTENSIONS:
        units = ask_units()
    obj = fc_models.import_model_file(doc, path, units or "mm")
    doc.recompute()
    FreeCAD.ParamGet("User parameter:BaseApp/Preferences/Mod/WorkCal").SetString(
        LAST_DIR_KEY, os.path.dirname(os.path.abspath(str(path))))
    return obj


def scan_candidates(doc) -> list:
    from workcal_wb.fc import scan as fc_scan

    found = [o for o in doc.Objects if fc_scan.can_be_scan(o)]
    return sorted(found, key=lambda o: not fc_scan.is_scan(o))  # WorkCal scans first


def model_candidates(doc) -> list:
    from workcal_wb.fc import models as fc_models
    from workcal_wb.fc import scan as fc_scan

    out = []
    for obj in doc.Objects:
        if fc_scan.is_scan(obj) or obj.TypeId in ("App::Part", "App::DocumentObjectGroup", "App::Origin") \
                or obj.TypeId.startswith(("App::Line", "App::Plane")):
            continue
        if obj.TypeId.startswith("Path::") or obj.TypeId.startswith("Sketcher::"):
            continue
        kind = fc_models.kind_of(obj)[0]
        if kind is None:
            continue
        if kind == "shape" and not fc_models.kind_of(obj)[1].Faces:
            continue
        out.append(obj)
    return out


class ChooseModelsPanel:
    def __init__(self, doc):
        from workcal_wb.gui.task_panels import QtGui, QtWidgets

        self.doc = doc
        self.transaction = bool(getattr(doc, "UndoMode", 0))
        if self.transaction:
            doc.openTransaction(translate("WorkCal", "Choose models"))
        self.form = QtWidgets.QWidget()
        self.form.setObjectName("WorkCalChooseModels")
        self.form.setWindowTitle(translate("WorkCal", "Choose models"))
        self.form.setWindowIcon(QtGui.QIcon(workcal_wb.icon("WorkCal_ChooseModels")))
        layout = QtWidgets.QVBoxLayout(self.form)
        grid = QtWidgets.QGridLayout()
        self.combos, self.file_buttons = {}, {}
        titles = {"scan": translate("WorkCal", "Scan (frame S)"),
                  "workpiece": translate("WorkCal", "Workpiece model X-A"),
                  "reference": translate("WorkCal", "Reference model B-P")}
        for row, role in enumerate(ROLES):
            grid.addWidget(QtWidgets.QLabel(titles[role]), row, 0)
            combo = QtWidgets.QComboBox()
            combo.setObjectName(f"WorkCal_{role}")
            combo.setMinimumContentsLength(16)
            grid.addWidget(combo, row, 1)
            self.combos[role] = combo
            if role != "scan":
                button = QtWidgets.QPushButton(translate("WorkCal", "From file..."))
                button.setObjectName(f"WorkCal_{role}_file")
                button.clicked.connect(lambda checked=False, r=role: self._from_file_dialog(r))
                grid.addWidget(button, row, 2)
                self.file_buttons[role] = button
        layout.addLayout(grid)
        note = QtWidgets.QLabel(translate(
            "WorkCal", "The workpiece model is used in its own frame X (the toolpath's frame); the reference "
                       "model must be placed where the reference object stands in the robot base frame B."))
        note.setWordWrap(True)
        layout.addWidget(note)
        layout.addStretch(1)
        self._fill(_setup().get_setup(doc))

    def _fill(self, current: dict) -> None:
        lists = {"scan": scan_candidates(self.doc), "workpiece": model_candidates(self.doc),
                 "reference": model_candidates(self.doc)}
        for role, combo in self.combos.items():
            combo.blockSignals(True)
            combo.clear()
            combo.addItem(translate("WorkCal", "(none)"), "")
            for obj in lists[role]:
                combo.addItem(f"{obj.Label} ({obj.TypeId.split('::')[-1]})", obj.Name)
            chosen = current.get(role)
            index = combo.findData(chosen.Name) if chosen is not None else 0
            combo.setCurrentIndex(max(index, 0))
            combo.blockSignals(False)

    def selected(self) -> dict:
        return {role: (self.doc.getObject(combo.currentData()) if combo.currentData() else None)
                for role, combo in self.combos.items()}

    def select(self, role: str, obj) -> None:
        combo = self.combos[role]
        index = combo.findData(obj.Name if obj is not None else "")
        if index < 0:
            raise InputError(translate("WorkCal", "{} cannot be chosen as the {}").format(
                getattr(obj, "Label", obj), role))
        combo.setCurrentIndex(index)

    def load_file(self, role: str, path, units: str | None = None):
        """Read a model file (part of this panel's undo step) and choose it for ``role``."""
        obj = import_model(path, self.doc, units)
        current = self.selected()
        current[role] = obj
        self._fill(current)
        return obj

    def _from_file_dialog(self, role: str) -> None:
        import FreeCADGui

        from workcal_wb.fc import models as fc_models
        from workcal_wb.gui.task_panels import QtWidgets

        start = FreeCAD.ParamGet("User parameter:BaseApp/Preferences/Mod/WorkCal").GetString(LAST_DIR_KEY, "")
        patterns = " ".join("*" + e for e in fc_models.MODEL_EXTENSIONS)
        path, _ = QtWidgets.QFileDialog.getOpenFileName(
            FreeCADGui.getMainWindow(), translate("WorkCal", "Model file"), start or os.path.expanduser("~"),
            translate("WorkCal", "Models") + f" ({patterns});;" + translate("WorkCal", "All files") + " (*)")
        if not path:
            return
        try:
            self.load_file(role, path)
        except WorkCalError as exc:
            show_error(translate("WorkCal", "Model file"), str(exc))

    def getStandardButtons(self):
        from workcal_wb.gui.task_panels import OK_CANCEL

        return OK_CANCEL

    def accept(self):
        """Store the choice; on a refused object show why and keep the panel open (returns False)."""
        import FreeCADGui

        try:
            _setup().set_setup(self.doc, **self.selected())
        except WorkCalError as exc:
            show_error(translate("WorkCal", "Choose models"), str(exc))
            return False
        if self.transaction:
            self.doc.commitTransaction()
            self.transaction = False
        chosen = _setup().get_setup(self.doc)
        message(translate("WorkCal", "setup: scan {}, workpiece model {}, reference model {}").format(
            *(_label(chosen[r]) for r in ROLES)))
        FreeCADGui.Control.closeDialog()
        return True

    def reject(self):
        import FreeCADGui

        if self.transaction:
            self.doc.abortTransaction()
            self.transaction = False
        FreeCADGui.Control.closeDialog()
        return True


def open_panel(doc=None) -> ChooseModelsPanel:
    doc = doc or active_document()
    return show_panel(lambda: ChooseModelsPanel(doc))


class ChooseModelsCommand(Command):
    NAME, TITLE = "WorkCal_ChooseModels", "Choose models"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_ChooseModels", "Choose models...")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_ChooseModels", "Choose the scan, the workpiece model X-A and the reference "
                                                         "model B-P (Part shapes, meshes or point clouds from the "
                                                         "document or from files)")

    def run(self):
        open_panel()


COMMANDS = {"WorkCal_ChooseModels": ChooseModelsCommand()}
