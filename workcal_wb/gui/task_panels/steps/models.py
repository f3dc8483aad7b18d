"""Step 2: the workpiece model (in its own frame) and the reference model (where it stands for the robot)."""
from __future__ import annotations

import FreeCAD

from .base import DONE, TODO, Scene, Step, UnitChooser, button, combo, label

translate = FreeCAD.Qt.translate

ROLES = ("workpiece", "reference")


class ModelsStep(Step):
    NAME = "models"
    TITLE = translate("WorkCal", "Models")
    HEADING = translate("WorkCal", "Models: the workpiece and the reference object")
    TIP = translate("WorkCal", "The workpiece model X-A in its own frame X (the toolpath's), and the reference "
                               "model B-P placed where the reference object stands in the robot base frame B")
    WORDS = {"workpiece": (translate("WorkCal", "Workpiece model"),
                           translate("WorkCal", "The workpiece as designed (X-A), in its own frame X: the frame the "
                                                "toolpath was computed in")),
             "reference": (translate("WorkCal", "Reference model"),
                           translate("WorkCal", "The fixed reference object (B-P), placed where it stands in the robot "
                                                "base frame B"))}

    def build(self, layout) -> None:
        self.combos = {}
        self.unit_choosers = {}
        self._unit_cache = {}  # role -> (the model's name, unit and box, its warning, the unit suggested)
        for role in ROLES:
            title, tip = self.WORDS[role]
            layout.addWidget(label(title, tip))
            chooser = combo(f"WorkCal_{role}", tip)
            chooser.activated.connect(lambda index, r=role: self.run_guarded(
                translate("WorkCal", "Choose models"), lambda: self.use_chosen(r)))
            layout.addWidget(chooser)
            layout.addWidget(button(translate("WorkCal", "From a file..."),
                                    translate("WorkCal", "STEP, IGES, BREP, STL, OBJ, OFF, PLY or a point file"),
                                    lambda r=role: self.ask_and_import(r), f"WorkCal_{role}_file"))
            self.combos[role] = chooser
            self.unit_choosers[role] = UnitChooser(f"WorkCal_{role}_unit", lambda units, r=role: self.read_in(r, units))
            layout.addWidget(self.unit_choosers[role])
        layout.addWidget(label(translate(
            "WorkCal", "The workpiece model is used in its own frame, the toolpath's. The reference model must "
                       "stand where the reference object stands for the robot.")))

    def state(self) -> tuple:
        chosen = self.setup()
        missing = [self.WORDS[r][0].lower() for r in ROLES if chosen[r] is None]
        if missing:
            return TODO, translate("WorkCal", "Choose the {}").format(translate("WorkCal", " and the ").join(missing))
        return DONE, translate("WorkCal", "workpiece: {}, reference: {}").format(chosen["workpiece"].Label,
                                                                                chosen["reference"].Label)

    def refresh(self) -> None:
        from workcal_wb.gui.actions import model_candidates

        chosen = self.setup()
        self.candidates = model_candidates(self.doc)
        for role, chooser in self.combos.items():
            chooser.blockSignals(True)
            chooser.clear()
            for obj in self.candidates:
                chooser.addItem(obj.Label, obj.Name)
            chooser.setCurrentIndex(self.candidates.index(chosen[role]) if chosen[role] in self.candidates else -1)
            chooser.blockSignals(False)
            self._show_units(role, chosen[role])

    def _show_units(self, role: str, obj) -> None:
        """The unit the model's file was read in, and a warning when the size it gives makes no sense."""
        from workcal_wb.fc import models as fc_models
        from workcal_wb.gui.task_panels.common import for_people

        units = fc_models.file_units(obj) if obj is not None else ""
        if not units:
            self.unit_choosers[role].show_units("")
            return
        kind, data = fc_models.kind_of(obj)
        key = (obj.Name, units, str(data.BoundBox) if data is not None else "")
        if self._unit_cache.get(role, (None,))[0] != key:
            text, suggestion = fc_models.model_unit_warning(obj)
            self._unit_cache[role] = (key, for_people(text), suggestion)
        self.unit_choosers[role].show_units(units, *self._unit_cache[role][1:])

    def read_in(self, role: str, units: str) -> None:
        """Read the file of the model of ``role`` again in ``units`` (recorded, one undo step)."""
        from workcal_wb.fc import models as fc_models
        from workcal_wb.gui import replay

        obj = self.setup()[role]
        if obj is None or not units or units == fc_models.file_units(obj):
            return
        self.run_guarded(translate("WorkCal", "Model unit"),
                         lambda: replay.run("workcal_wb.fc.models.change_units", obj, units, result="model"))
        self.guide.go(self.NAME)

    def select(self, role: str, obj) -> None:
        """Choose ``obj`` as the model of ``role`` (recorded), as picking it in the list does."""
        from workcal_wb.gui.actions import choose_models

        choose_models(self.doc, **{role: obj})
        self.guide.go(self.NAME)

    def use_chosen(self, role: str) -> None:
        index = self.combos[role].currentIndex()
        if 0 <= index < len(self.candidates):
            self.select(role, self.candidates[index])

    def ask_and_import(self, role: str) -> None:
        from workcal_wb.gui.actions import ask_for_model_file

        path = ask_for_model_file()
        if path:
            self.load_file(role, path)

    def load_file(self, role: str, path, units: str | None = None):
        """Read a model file (recorded) and choose it for ``role``."""
        from workcal_wb.gui.actions import import_model

        obj = self.run_guarded(translate("WorkCal", "Model file"), lambda: import_model(path, self.doc, units, role))
        self.guide.go(self.NAME)
        return obj

    def scene(self) -> Scene:
        chosen = self.setup()
        shown = [chosen[r] for r in ROLES if chosen[r] is not None]
        words = {"workpiece": translate("WorkCal", "Workpiece model (its own frame)"),
                 "reference": translate("WorkCal", "Reference model (robot frame)")}
        return Scene(show=shown, labels=[(words[r], chosen[r]) for r in ROLES if chosen[r] is not None],
                     orientation="isometric")
