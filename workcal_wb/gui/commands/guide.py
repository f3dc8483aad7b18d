"""WorkCal_Guide: the steps of a calibration in one task panel (see task_panels/guide.py).

``open_guide(doc, step)`` shows the guide at a step (the open one switches to it); the other commands
open it at their step.
"""
from __future__ import annotations

import FreeCAD

from workcal_wb.gui.task_panels.common import Command, active_document, message

QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP
translate = FreeCAD.Qt.translate


def open_guide(doc=None, step: str | None = None):
    """The guide of ``doc`` (default: the active document; a new one when none is open) at ``step``
    (default: the next step to do); returns the panel."""
    import FreeCADGui

    from workcal_wb.gui.task_panels.guide import GuidePanel

    if doc is None and FreeCAD.ActiveDocument is None:
        FreeCADGui.runCommand("Std_New")  # recorded by FreeCAD itself: App.newDocument(...)
        message(translate("WorkCal", "no document was open: the guide works in a new one ({})").format(
            active_document().Label))
    return GuidePanel.open(doc or active_document(), step)


class GuideCommand(Command):
    NAME, TITLE = "WorkCal_Guide", "WorkCal guide"
    NEEDS_DOCUMENT = False  # without one, the guide starts a new document
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_Guide", "Guide...")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_Guide", "The steps of a calibration one after the other: scan, models, "
                                                  "regions, calibrate, result, toolpath, export; the next one to do "
                                                  "is highlighted")

    def run(self):
        open_guide()


COMMANDS = {"WorkCal_Guide": GuideCommand()}
