"""Step 6: the toolpath, chosen once for the document and shown carried into the robot base frame."""
from __future__ import annotations

import os

import FreeCAD

from .base import DONE, TODO, Scene, Step, button, combo, label

translate = FreeCAD.Qt.translate


class ToolpathStep(Step):
    NAME = "toolpath"
    TITLE = translate("WorkCal", "Toolpath")
    HEADING = translate("WorkCal", "Toolpath: the CAM toolpath, carried to where the part is")
    TIP = translate("WorkCal", "The toolpath in the workpiece's own frame (X-m): a Path/CAM Job or a G-code file, "
                               "carried into the robot base frame by W (B-m = W X-m)")

    def build(self, layout) -> None:
        layout.addWidget(label(translate("WorkCal", "The toolpath as the CAM system wrote it, in the workpiece "
                                                    "model's frame. Chosen once; the export uses it too.")))
        self.choice = combo("WorkCal_toolpath", translate("WorkCal", "A Path/CAM Job or operation of this document, or "
                                                                     "the G-code file chosen"))
        self.choice.activated.connect(lambda index: self.run_guarded(translate("WorkCal", "Choose the toolpath"),
                                                                     self.use_chosen))
        layout.addWidget(self.choice)
        layout.addWidget(button(translate("WorkCal", "G-code file..."),
                                translate("WorkCal", "A G-code file (opens where the scan lies)"), self.ask_for_file,
                                "WorkCalToolpathFile"))
        self.show_button = button(translate("WorkCal", "Show it in the robot frame"),
                                  translate("WorkCal", "Carry the toolpath into the robot base frame with the "
                                                       "calibration's W and show it with the placed workpiece"),
                                  self.show_in_robot_frame, "WorkCalShowToolpath")
        layout.addWidget(self.show_button)
        self.info = label(name="WorkCalToolpathInfo")
        layout.addWidget(self.info)

    def chosen(self):
        from workcal_wb.fc.setup import toolpath_of

        return toolpath_of(self.doc)

    def calibrated_path(self):
        from workcal_wb.fc.toolpath import calibrated_paths

        calibration = self.guide.calibration()
        return (calibrated_paths(calibration) or [None])[-1] if calibration is not None else None

    def state(self) -> tuple:
        from workcal_wb.fc.toolpath_input import source_label

        source = self.chosen()
        if source is None:
            return TODO, translate("WorkCal", "Choose the toolpath (CAM Job or G-code file)")
        if self.calibrated_path() is None:
            return TODO, translate("WorkCal", "{}: show it in the robot frame").format(source_label(source))
        return DONE, translate("WorkCal", "{}, shown in the robot frame").format(source_label(source))

    def refresh(self) -> None:
        from workcal_wb.fc.toolpath import toolpath_sources
        from workcal_wb.fc.toolpath_input import source_label

        source = self.chosen()
        self.sources = list(toolpath_sources(self.doc))
        if isinstance(source, (str, os.PathLike)):
            self.sources.append(source)
        self.choice.blockSignals(True)
        self.choice.clear()
        for item in self.sources:
            self.choice.addItem(source_label(item))
        self.choice.setCurrentIndex(self.sources.index(source) if source in self.sources else -1)
        self.choice.blockSignals(False)
        calibration = self.guide.calibration()
        self.show_button.setEnabled(source is not None and calibration is not None and calibration.ResultJson != "")
        self.info.setText(self.state()[1])

    def use_chosen(self) -> None:
        from workcal_wb.gui.actions import choose_toolpath

        index = self.choice.currentIndex()
        if 0 <= index < len(self.sources):
            choose_toolpath(self.doc, self.sources[index])
            self.guide.go(self.NAME)

    def ask_for_file(self) -> None:
        from workcal_wb.gui.actions import ask_for_toolpath_file

        path = ask_for_toolpath_file(self.doc)
        if path:
            self.use_file(path)

    def use_file(self, path) -> None:
        from workcal_wb.gui.actions import choose_toolpath

        self.run_guarded(translate("WorkCal", "Choose the toolpath"), lambda: choose_toolpath(self.doc, path))
        self.guide.go(self.NAME)

    def show_in_robot_frame(self, confirm=None):
        """The calibrated toolpath (recorded; forcing asked for a calibration that is not ok) and the
        workpiece model placed by W beside the reference model."""
        from workcal_wb.gui.actions import transform_toolpath
        from workcal_wb.gui.task_panels.common import with_force

        calibration = self.guide.calibration()

        def make():
            from workcal_wb.gui import replay

            made = with_force(lambda force: transform_toolpath(calibration, force=force), confirm)
            if made is not None:
                replay.run("workcal_wb.fc.placed_model.show_in_robot_frame", calibration, result="placed_model")
            return made

        made = self.run_guarded(translate("WorkCal", "Calibrated toolpath"), make)
        self.guide.go(self.NAME)
        return made

    def scene(self) -> Scene:
        return robot_frame_scene(self)


def robot_frame_scene(step) -> Scene:
    """The calibrated toolpath, the workpiece placed by W and the reference model, in the robot base frame;
    before there is a calibrated toolpath, the workpiece model the toolpath was made on."""
    from workcal_wb.fc.placed_model import IN_ROBOT_FRAME, find

    calibration = step.guide.calibration()
    setup = step.setup()
    path = step.guide.steps["toolpath"].calibrated_path()
    placed = find(calibration, "workpiece", IN_ROBOT_FRAME) if calibration is not None else None
    if path is None or placed is None:
        model = setup["workpiece"]
        return Scene(show=[model] if model is not None else [],
                     labels=[(translate("WorkCal", "Workpiece model: the toolpath's frame"), model)] if model else [],
                     orientation="isometric")
    shown = [path, placed] + ([setup["reference"]] if setup["reference"] is not None else [])
    labels = [(translate("WorkCal", "Toolpath in the robot frame"), path),
              (translate("WorkCal", "Workpiece, placed"), placed)]
    if setup["reference"] is not None:
        labels.append((translate("WorkCal", "Reference object"), setup["reference"]))
    return Scene(show=shown, fit=[path, placed], labels=labels, orientation="isometric")
