"""Looking at a calibration and at the method: WorkCal_DeviationMap, WorkCal_ShowInRobotFrame,
WorkCal_Report and WorkCal_Studies.

Document changes are recorded ``workcal_wb.fc`` calls (replayable in a macro); ``open_report`` shows
a written report in FreeCAD's web view (or the system browser where FreeCAD has none).
"""
from __future__ import annotations

import os
import tempfile
import threading
import traceback

import FreeCAD

from workcal_wb.core.errors import Cancelled, InputError, WorkCalError
from workcal_wb.gui import replay
from workcal_wb.gui.task_panels import QtCore
from workcal_wb.gui.task_panels.common import Command, active_document, calibration_for, message, warning

QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP
translate = FreeCAD.Qt.translate


# ------------------------------------------------------------------------------ deviation map

def deviation_map(calibration, limit_mm: float | None = None):
    """The deviation map of a calibration's workpiece region (recorded ``fc.deviation_map.make_deviation_map``),
    shown instead of the scan."""
    from workcal_wb.fc.calibration_object import workpiece_region

    workpiece_region(calibration)  # no U, no region, a changed scan: refused before it is recorded
    kwargs = {"limit_mm": limit_mm} if limit_mm else {}
    obj = replay.run("workcal_wb.fc.deviation_map.make_deviation_map", calibration, result="deviation_map", **kwargs)
    if calibration.Scan is not None and getattr(calibration.Scan, "ViewObject", None) is not None:
        calibration.Scan.ViewObject.Visibility = False  # the map lies exactly on the scan
    return obj


class DeviationMapCommand(Command):
    NAME, TITLE = "WorkCal_DeviationMap", "Deviation map"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_DeviationMap", "Deviation map")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_DeviationMap", "Colour the workpiece's scan points by their distance to its "
                                                         "placed model: green within the tolerance, red where clay was "
                                                         "added, blue where it was removed")

    def run(self):
        deviation_map(calibration_for(active_document()))


class ShowInRobotFrameCommand(Command):
    NAME, TITLE = "WorkCal_ShowInRobotFrame", "Workpiece in the robot frame"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_ShowInRobotFrame", "Show the workpiece model in the robot frame")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_ShowInRobotFrame", "Show the workpiece model where the calibration puts it "
                                                             "in the robot base frame (placed by W), beside the "
                                                             "reference model")

    def run(self):
        replay.run("workcal_wb.fc.placed_model.show_in_robot_frame", calibration_for(active_document()),
                   result="placed_model")


# ------------------------------------------------------------------------------------- report

def write_report(calibration, out_dir: str | None = None) -> dict:
    """report.html and report.json of a calibration (recorded ``fc.report.write_report``); their paths."""
    kwargs = {"out_dir": out_dir} if out_dir else {}
    return replay.run("workcal_wb.fc.report.write_report", calibration, result="report", **kwargs)


def report_title(calibration) -> str:
    """The name of a calibration's report tab."""
    return translate("WorkCal", "Report: {}").format(calibration.Label)


def open_report(path: str, title: str | None = None) -> str:
    """Show a report in front: in a tab of FreeCAD's web view named ``title`` (default: the file's name)
    when FreeCAD has one, the tab of an earlier report of that name replaced, else in the system browser.
    Returns where it went ("freecad" or "browser")."""
    from workcal_wb.gui.task_panels import QtGui

    url = QtCore.QUrl.fromLocalFile(os.path.abspath(path)).toString()
    title = title or os.path.basename(path)
    try:
        import WebGui

        with open(path, encoding="utf-8") as stream:
            html = stream.read()
        folder = QtCore.QUrl.fromLocalFile(os.path.dirname(os.path.abspath(path)) + os.sep).toString()
        for window in report_windows(title):
            window.close()
        WebGui.openBrowserHTML(html, folder, title)
    except Exception:  # no web view in this FreeCAD (WebGui missing or without QtWebEngine)
        QtGui.QDesktopServices.openUrl(QtCore.QUrl(url))
        return "browser"
    shown = report_windows(title)
    if shown:
        shown[-1].mdiArea().setActiveSubWindow(shown[-1])
    return "freecad"


def report_windows(title: str) -> list:
    """The main window's tabs (MDI windows) showing the report named ``title``."""
    from workcal_wb.gui.task_panels import QtWidgets
    from workcal_wb.gui.task_panels.common import main_window

    area = main_window().findChild(QtWidgets.QMdiArea)
    if area is None:
        return []
    return [w for w in area.subWindowList() if w.windowTitle().split("[*]")[0].strip() == title]


class ReportCommand(Command):
    NAME, TITLE = "WorkCal_Report", "Calibration report"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_Report", "Calibration report")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_Report", "Write the report of the calibration (where the workpiece is, "
                                                   "residuals, uncertainty, checks, deviation map) and open it")

    def run(self):
        calibration = calibration_for(active_document())
        open_report(write_report(calibration)["html"], report_title(calibration))


# -------------------------------------------------------------------------------------- studies

def available_studies() -> dict:
    """name -> title of the studies in workcal_wb.core.studies."""
    from workcal_wb.core import studies

    return {name: getattr(module, "TITLE", name) for name, module in studies.STUDIES.items()}


def run_study(name: str, out_dir: str, *, quick: bool = True, n: int | None = None, positions: int | None = None,
              seed: int = 0, progress=None, announce: bool = True):
    """Run one study on simulated scenes, writing <name>.png/.csv/.json into ``out_dir``; returns the
    StudyResult (its plot: ``result.files["figure"]``).  ``progress(message)`` may raise Cancelled.
    ``announce``: print the outcome to the Report view (main thread only)."""
    from workcal_wb.core import studies
    from workcal_wb.fc import prefs

    settings = studies.StudySettings(quick=quick, seed=seed, tolerance_mm=prefs.get("ToleranceMm"),
                                     method=prefs.get("Method"))
    result = studies.run_study(name, out_dir, settings=settings, n=n, positions=positions, progress=progress)
    png = os.fspath(result.files.get("figure", ""))
    if not png or not os.path.exists(png):
        raise InputError(f"study {name} wrote no plot in {out_dir}")
    if announce:
        announce_study(result)
    return result


def announce_study(result) -> None:
    (message if result.passed else warning)(
        translate("WorkCal", "study {}: {} (targets {}); plot {}").format(
            result.name, result.title, "met" if result.passed else "NOT met", os.fspath(result.files["figure"])))


class StudyRunner(QtCore.QObject):
    """A study in a Python thread; its messages go to the status bar through a queued signal."""

    said = QtCore.Signal(str)
    done = QtCore.Signal(object, str)  # StudyResult or None, error text

    def __init__(self, name: str, out_dir: str, **kwargs):
        super().__init__()
        self.name, self.out_dir, self.kwargs = name, out_dir, kwargs
        self._stop = threading.Event()
        self.result, self.error, self.state = None, "", "idle"

    def _say(self, text: str) -> None:
        if self._stop.is_set():
            raise Cancelled(f"study {self.name} cancelled")
        self.said.emit(str(text))

    def start(self) -> None:
        self.state = "running"
        threading.Thread(target=self._work, name=f"WorkCal study {self.name}", daemon=True).start()

    def cancel(self) -> None:
        self._stop.set()

    def _work(self) -> None:
        try:
            self.result = run_study(self.name, self.out_dir, progress=self._say, announce=False, **self.kwargs)
            self.state = "done"
        except Cancelled as exc:
            self.error, self.state = str(exc), "cancelled"
        except WorkCalError as exc:
            self.error, self.state = str(exc), "failed"
        except Exception as exc:  # a bug in a study must not take FreeCAD down
            self.error, self.state = f"unexpected error: {exc}\n{traceback.format_exc()}", "failed"
        self.done.emit(self.result, self.error)


def start_study(name: str, out_dir: str | None = None, *, show: bool = True, **kwargs) -> StudyRunner:
    """Run a study without blocking the window; on success its plot opens in a window (``show``)."""
    from workcal_wb.gui.task_panels.runner import StatusProgress

    out_dir = out_dir or os.path.join(tempfile.gettempdir(), "workcal-studies", name)
    runner = StudyRunner(name, out_dir, **kwargs)
    status = StatusProgress(translate("WorkCal", "Study"))
    if status.bar is not None:
        status.bar.setRange(0, 0)  # a busy indicator: studies report steps, not fractions
    runner.said.connect(lambda text: status.update(0.0, text))

    def finished(result, error_text):
        status.close()
        if result is None:
            (message if runner.state == "cancelled" else show_error_later)(error_text)
            return
        announce_study(result)
        if show:
            runner.window = ImageDialog(f"WorkCal study: {result.title}", os.fspath(result.files["figure"]))
            runner.window.show()

    runner.done.connect(finished)
    _running.append(runner)
    runner.done.connect(lambda *_: _running.remove(runner) if runner in _running else None)
    message(translate("WorkCal", "study {} started (results in {})").format(name, out_dir))
    runner.start()
    return runner


_running = []  # keeps runners alive until they finish


def show_error_later(text: str) -> None:
    from workcal_wb.gui.task_panels.common import show_error

    show_error("Studies", text)


class ImageDialog:
    """A non-modal window with a PNG plot."""

    def __init__(self, title: str, png: str):
        from workcal_wb.gui.task_panels import QtGui, QtWidgets
        from workcal_wb.gui.task_panels.common import main_window

        self.dialog = QtWidgets.QDialog(main_window())
        self.dialog.setWindowTitle(title)
        self.dialog.setAttribute(QtCore.Qt.WA_DeleteOnClose, True)
        layout = QtWidgets.QVBoxLayout(self.dialog)
        label = QtWidgets.QLabel()
        pixmap = QtGui.QPixmap(png)
        if pixmap.width() > 1100:
            pixmap = pixmap.scaledToWidth(1100, QtCore.Qt.SmoothTransformation)
        label.setPixmap(pixmap)
        scroll = QtWidgets.QScrollArea()
        scroll.setWidget(label)
        scroll.setWidgetResizable(True)
        layout.addWidget(scroll)
        path_label = QtWidgets.QLabel(png)
        path_label.setTextInteractionFlags(QtCore.Qt.TextSelectableByMouse)
        layout.addWidget(path_label)
        buttons = QtWidgets.QDialogButtonBox(QtWidgets.QDialogButtonBox.Close)
        buttons.rejected.connect(self.dialog.close)
        layout.addWidget(buttons)
        self.dialog.resize(min(pixmap.width() + 40, 1150), min(pixmap.height() + 100, 900))
        self.pixmap = pixmap

    def show(self):
        self.dialog.show()
        return self.dialog


class StudiesCommand(Command):
    NAME, TITLE = "WorkCal_Studies", "Studies"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_Studies", "Studies...")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_Studies", "Run one of the accuracy studies on a simulated scene and show "
                                                    "its plot")
    NEEDS_DOCUMENT = False

    def run(self):
        from workcal_wb.gui.task_panels import QtWidgets
        from workcal_wb.gui.task_panels.common import main_window

        studies = available_studies()
        items = [f"{title} [{name}]" for name, title in studies.items()]
        item, ok = QtWidgets.QInputDialog.getItem(
            main_window(), translate("WorkCal", "Studies"),
            translate("WorkCal", "Study to run on simulated scenes (quick settings, about a minute):"), items, 0, False)
        if not ok:
            return
        start_study(list(studies)[items.index(item)])


COMMANDS = {"WorkCal_DeviationMap": DeviationMapCommand(), "WorkCal_ShowInRobotFrame": ShowInRobotFrameCommand(),
            "WorkCal_Report": ReportCommand(), "WorkCal_Studies": StudiesCommand()}
TOOLBAR = ["WorkCal_DeviationMap", "WorkCal_Report", "WorkCal_Studies"]
