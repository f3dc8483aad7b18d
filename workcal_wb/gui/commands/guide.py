"""WorkCal_Guide: the steps of a calibration in one task panel (see task_panels/guide.py).

``open_guide(doc, step)`` shows the guide at a step (the open one switches to it); the other commands
open it at their step.
"""
from __future__ import annotations

import FreeCAD

from workcal_wb.gui.task_panels.common import Command, active_document

QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP


def open_guide(doc=None, step: str | None = None):
    """The guide of ``doc`` (default: the active document) at ``step`` (default: the next step to do);
    returns the panel."""
    from workcal_wb.gui.task_panels.guide import GuidePanel

    return GuidePanel.open(doc or active_document(), step)


class GuideCommand(Command):
    NAME, TITLE = "WorkCal_Guide", "WorkCal guide"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_Guide", "Guide...")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_Guide", "The steps of a calibration one after the other: scan, models, "
                                                  "regions, calibrate, result, toolpath, export; the next one to do "
                                                  "is highlighted")

    def run(self):
        open_guide()


COMMANDS = {"WorkCal_Guide": GuideCommand()}
