"""WorkCal_ChooseModels: choose the scan, the workpiece model (X-A) and the reference model (B-P).

The command opens the guide at its models step.  ``actions.choose_models`` and ``actions.import_model`` are
what that step does, as recorded commands (``workcal_wb.fc.setup.choose_models``,
``workcal_wb.fc.models.import_model``): one undo step each, replayable in a macro.
"""
from __future__ import annotations

import FreeCAD

from workcal_wb.gui.task_panels.common import Command, active_document

QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP
translate = FreeCAD.Qt.translate

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
