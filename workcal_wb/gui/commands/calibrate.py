"""WorkCal_Calibrate: the calibrate task panel; ``calibrate()`` does the same without a dialog."""
from __future__ import annotations

import FreeCAD

from workcal_wb.gui.task_panels.common import Command, active_document, show_panel

QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP
translate = FreeCAD.Qt.translate


def calibrate(doc=None, scan=None, workpiece=None, reference=None, **options):
    """Calibrate without a dialog (in the calling thread) and return the new calibration object.

    Inputs not given come from the document's WorkCal setup (the import commands record it);
    ``options``: tolerance_mm, method, seed, resamples, regions ("Auto"/"Picked"), toolpath,
    placed_model, name, progress.  Raises InputError with the reason; the document is then unchanged."""
    from workcal_wb.core.errors import InputError
    from workcal_wb.fc.calibration_object import make_calibration
    from workcal_wb.gui.task_panels.calibrate_panel import default_setup

    doc = doc or active_document()
    setup = default_setup(doc)
    scan = scan or setup.get("scan")
    workpiece = workpiece or setup.get("workpiece")
    reference = reference or setup.get("reference")
    if scan is None or workpiece is None or reference is None:
        missing = [n for n, o in (("scan", scan), ("workpiece model", workpiece), ("reference model", reference))
                   if o is None]
        raise InputError(translate("WorkCal", "calibration needs a {}: import or choose it first").format(
            " and a ".join(missing)))
    return make_calibration(doc, scan, workpiece, reference, **options)


def open_panel(doc=None, calibration=None):
    """Show the calibrate task panel (closing nothing else); returns the panel."""
    from workcal_wb.gui.task_panels.calibrate_panel import CalibratePanel

    doc = doc or active_document()
    return show_panel(lambda: CalibratePanel(doc, calibration=calibration))


class CalibrateCommand(Command):
    NAME, TITLE = "WorkCal_Calibrate", "Calibrate"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_Calibrate", "Calibrate")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_Calibrate", "Match the workpiece and the reference block in the scan and "
                                                      "compute W = V^-1 U, the workpiece frame in the robot base frame")

    def run(self):
        from workcal_wb.fc.calibration_object import is_calibration
        from workcal_wb.gui.task_panels.common import selected_objects

        selected = [o for o in selected_objects() if is_calibration(o)]
        open_panel(calibration=selected[0] if selected else None)  # a selected calibration: run it again


COMMANDS = {"WorkCal_Calibrate": CalibrateCommand()}
