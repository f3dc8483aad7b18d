"""What the WorkCal commands share: the Command base class, error guard, Report view messages, choosing
objects, force confirmation.

Every command's ``Activated`` runs through ``guarded`` so that nothing raised inside a command reaches
FreeCAD's event loop: a WorkCalError is a message for the user, anything else is logged as a bug.
Interactive choices (which calibration, whether to force) go through functions that tests replace
or bypass with the non-interactive entry points of each command module.
"""
from __future__ import annotations

import functools
import traceback

import FreeCAD

import workcal_wb
from workcal_wb.core.errors import Cancelled, WorkCalError
from workcal_wb.core.wording import for_people

from . import QtCore, QtWidgets, run_modal

translate = FreeCAD.Qt.translate


def message(text: str) -> None:
    FreeCAD.Console.PrintMessage(f"WorkCal: {text}\n")


def warning(text: str) -> None:
    FreeCAD.Console.PrintWarning(f"WorkCal: {text}\n")


def error(text: str) -> None:
    FreeCAD.Console.PrintError(f"WorkCal: {text}\n")


def main_window():
    if not FreeCAD.GuiUp:
        return None
    import FreeCADGui

    return FreeCADGui.getMainWindow()


# Tests set this to False so that no modal box blocks the event loop; messages still reach the Report view.
INTERACTIVE = True


def show_error(title: str, text: str) -> None:
    """The error in the Report view and, interactively, in a message box."""
    error(text)
    if INTERACTIVE and FreeCAD.GuiUp:
        QtWidgets.QMessageBox.critical(main_window(), title, for_people(text))


def guarded(title: str):
    """Decorator for Command.Activated: report errors instead of letting them escape into FreeCAD."""

    def wrap(func):
        @functools.wraps(func)
        def run(*args, **kwargs):
            try:
                return func(*args, **kwargs)
            except Cancelled:
                message(translate("WorkCal", "{} cancelled").format(title))
            except WorkCalError as exc:
                show_error(title, str(exc))
            except Exception as exc:  # a bug: full traceback in the Report view, FreeCAD keeps running
                error(f"{title}: unexpected error: {exc}\n{traceback.format_exc()}")
                if INTERACTIVE and FreeCAD.GuiUp:
                    QtWidgets.QMessageBox.critical(main_window(), title, f"{exc}\n\n(see the Report view)")
            return None

        return run

    return wrap


class Command:
    """A WorkCal command as FreeCAD calls it.  A subclass sets NAME (the command's name, also its icon's
    and the translation context of MENU_TEXT and TOOL_TIP), TITLE (heads its error messages) and
    defines ``run``, which ``Activated`` calls through ``guarded``."""

    NAME = MENU_TEXT = TOOL_TIP = TITLE = ""
    NEEDS_DOCUMENT = True  # greyed out while no document is open

    def GetResources(self):
        return {"Pixmap": workcal_wb.icon(self.NAME), "MenuText": self.MENU_TEXT, "ToolTip": self.TOOL_TIP}

    def IsActive(self):
        return not self.NEEDS_DOCUMENT or FreeCAD.ActiveDocument is not None

    def Activated(self):
        guarded(translate("WorkCal", self.TITLE))(self.run)()


def refuse_second_panel() -> None:
    """FreeCAD shows one task panel at a time: WorkCalError while another one is open."""
    import FreeCADGui

    if FreeCADGui.Control.activeDialog():
        raise WorkCalError(translate("WorkCal", "another task panel is open; close it first"))


def show_panel(make_panel):
    """Show the task panel ``make_panel()`` returns and return it; it is made only when no other is open."""
    import FreeCADGui

    refuse_second_panel()
    panel = make_panel()
    FreeCADGui.Control.showDialog(panel)
    return panel


def close_dialog() -> None:
    """Close the open task dialog, then bring the Model tab (tree and properties) to the front again
    once FreeCAD has closed it: FreeCAD 1.x leaves the empty Tasks tab in front."""
    import FreeCADGui

    if FreeCADGui.Control.activeDialog():
        FreeCADGui.Control.closeDialog()
    QtCore.QTimer.singleShot(0, show_model_tab)


def dock(name: str):
    """FreeCAD's dock widget of that object name ("Combo View" on 0.20; "Model", "Tasks" on 1.x), or None."""
    import FreeCADGui

    docks = [d for d in FreeCADGui.getMainWindow().findChildren(QtWidgets.QDockWidget) if d.objectName() == name]
    return docks[0] if docks else None


def show_model_tab() -> None:
    """The Model tab in front, unless a task dialog is open (the Tasks tab belongs in front then).  FreeCAD
    0.20 has them as the combo view's tabs; 1.x as two docks tabbed together."""
    import FreeCADGui

    if FreeCADGui.Control.activeDialog():
        return
    combo = dock("Combo View")
    tabs = combo.findChild(QtWidgets.QTabWidget) if combo is not None else None
    if tabs is not None:
        tabs.setCurrentIndex(0)
    elif dock("Model") is not None:
        dock("Model").raise_()


def active_document():
    doc = FreeCAD.ActiveDocument
    if doc is None:
        raise WorkCalError(translate("WorkCal", "no document open"))
    return doc


def selected_objects() -> list:
    if not FreeCAD.GuiUp:
        return []
    import FreeCADGui

    return list(FreeCADGui.Selection.getSelection())


def calibration_for(doc):
    """The calibration the user means: the selected one, or the only/most recent one in the document."""
    from workcal_wb.fc.lookups import find_calibrations, is_calibration

    for obj in selected_objects():
        if is_calibration(obj):
            return obj
        for linked in getattr(obj, "OutList", []):  # e.g. a deviation map selected
            if is_calibration(linked):
                return linked
    found = find_calibrations(doc)
    if not found:
        raise WorkCalError(translate("WorkCal", "no calibration in the document: run WorkCal > Calibrate first"))
    return found[-1]


def confirm_force(reason: str, reach: bool = False) -> bool:
    """Ask whether to go on with a calibration that did not pass its gates, or (``reach``) with a program
    the robot cannot follow (False when not interactive)."""
    if not (INTERACTIVE and FreeCAD.GuiUp):
        return False
    box = QtWidgets.QMessageBox(main_window())
    box.setIcon(QtWidgets.QMessageBox.Warning)
    if reach:
        box.setWindowTitle(translate("WorkCal", "Robot cannot follow the program"))
        box.setText(translate("WorkCal", "The robot cannot follow this program where the part is."))
        question = translate("WorkCal", "Write it anyway? The program is marked FORCED; check it in simulation, or "
                                        "by hand at low speed, before running it.")
    else:
        box.setWindowTitle(translate("WorkCal", "Calibration not ok"))
        box.setText(translate("WorkCal", "The calibration did not pass its quality gates."))
        question = translate("WorkCal", "Use it anyway? The result is marked FORCED; check the workpiece position by "
                                        "hand before running the program.")
    box.setInformativeText(for_people(reason) + "\n\n" + question)
    box.setStandardButtons(QtWidgets.QMessageBox.Yes | QtWidgets.QMessageBox.No)
    box.setDefaultButton(QtWidgets.QMessageBox.No)
    return run_modal(box) == QtWidgets.QMessageBox.Yes


def with_force(action, confirm=None):
    """Run ``action(force=False)``; when it is refused for the calibration's status or for the robot's
    reach, ask ``confirm(reason)`` (default: a message box) and, if confirmed, run ``action(force=True)``.
    Returns the action's result or None.  Other refusals (envelope, tilt, non-finite numbers) propagate:
    forcing does not help there."""
    from workcal_wb.core.toolpath import CalibrationNotOk, ReachRefused

    try:
        return action(force=False)
    except (CalibrationNotOk, ReachRefused) as exc:
        reach = isinstance(exc, ReachRefused)
        if not (confirm or (lambda reason: confirm_force(reason, reach)))(for_people(str(exc))):
            warning(for_people(str(exc)))
            return None
    warning(translate("WorkCal", "writing a program the robot cannot follow (FORCED)") if reach else
            translate("WorkCal", "using a calibration that did not pass its gates (FORCED)"))
    return action(force=True)


def scroll_area_around(widget):
    """The innermost QScrollArea holding ``widget`` (FreeCAD's task view, or a panel's own), or None.
    Found among the main window's scroll areas (whose Python wrapper keeps the wrappers it found), not by
    walking up ``parentWidget()`` nor through a scroll area's ``widget()``: PySide links the wrappers those
    return to the one asked, and collected with a closed panel they deleted FreeCAD's own task panel
    (FreeCAD 1.0 then crashed on its next layout pass)."""
    window = main_window()
    try:
        areas = [a for a in window.findChildren(QtWidgets.QScrollArea)
                 if a is not widget and a.isAncestorOf(widget)] if window else []
    except RuntimeError:  # the widget is gone
        return None
    inner = [a for a in areas if not any(b is not a and a.isAncestorOf(b) for b in areas)]
    return inner[0] if inner else None


def process_events(seconds: float = 0.0) -> None:
    """Let the event loop run (for waiting in tests and scripts without blocking the window)."""
    import time

    from . import QtCore

    app = QtWidgets.QApplication.instance()
    end = time.monotonic() + seconds
    while True:
        app.processEvents(QtCore.QEventLoop.AllEvents, 50)
        if time.monotonic() >= end:
            break
        time.sleep(0.01)
