"""WorkCal_DeviationMap, WorkCal_Report and WorkCal_Studies: looking at a calibration and at the method.

Non-interactive entry points: ``deviation_map(doc, calibration)``, ``write_report(calibration, out_dir)``,
``run_study(name, out_dir)``; the commands call them and then show the result.
"""
from __future__ import annotations

import os
import tempfile
import threading
import traceback

import FreeCAD

from workcal_wb.core.errors import Cancelled, InputError, WorkCalError
from workcal_wb.gui.task_panels import QtCore
from workcal_wb.gui.task_panels.common import Command, active_document, calibration_for, message, warning

QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP
translate = FreeCAD.Qt.translate


# ------------------------------------------------------------------------------ deviation map

def deviation_map(doc, calibration, range_mm: float | None = None):
    """The deviation map of a calibration's workpiece region (see fc.deviation_view)."""
    from workcal_wb.fc.deviation_view import make_deviation_map

    return make_deviation_map(doc, calibration, range_mm=range_mm)


class DeviationMapCommand(Command):
    NAME, TITLE = "WorkCal_DeviationMap", "Deviation map"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_DeviationMap", "Deviation map")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_DeviationMap", "Colour the workpiece points of the scan by their signed "
                                                         "distance to the placed model: red where clay was added, blue "
                                                         "where it was removed")

    def run(self):
        doc = active_document()
        deviation_map(doc, calibration_for(doc))


# ------------------------------------------------------------------------------------- report

def default_report_dir(calibration) -> str:
    from workcal_wb.fc import prefs

    base = prefs.get("ReportDir")
    doc = calibration.Document
    if not base:
        base = os.path.dirname(doc.FileName) if doc.FileName else os.path.join(tempfile.gettempdir(), "workcal")
    stem = os.path.splitext(os.path.basename(doc.FileName))[0] if doc.FileName else doc.Name
    return os.path.join(base, f"{stem}_{calibration.Name}_report")


def _workpiece_data(calibration, result) -> dict:
    """The workpiece region of the scan (S) and X-A, for the report's deviation map; {} if unavailable."""
    from workcal_wb.fc.calibration_object import _model_cloud, _scan_cloud

    idx = (result.regions or {}).get("workpiece")
    if result.U is None or idx is None or len(idx) == 0:
        return {}
    try:
        scan = _scan_cloud(calibration.Scan)
        model = _model_cloud(calibration.Workpiece, "workpiece")
    except WorkCalError as exc:  # the report still shows the numbers
        warning(f"report without the deviation map: {exc}")
        return {}
    idx = [i for i in idx if i < len(scan)]
    return {"workpiece_points": scan.points[idx], "workpiece_model": model}


def write_report(calibration, out_dir: str | None = None, *, open_it: bool = False, studies=()) -> dict:
    """Write report.html and report.json of a calibration object; returns their paths ("html", "json")."""
    from workcal_wb.core import report as core_report
    from workcal_wb.fc.calibration_object import result_of

    result = result_of(calibration)
    out_dir = out_dir or default_report_dir(calibration)
    paths = core_report.write_report(result, out_dir, studies=studies,
                                     title=f"WorkCal calibration: {calibration.Document.Label} / {calibration.Label}",
                                     **_workpiece_data(calibration, result))
    paths = {k: os.fspath(v) for k, v in paths.items()}
    message(translate("WorkCal", "report written: {}").format(paths["html"]))
    if open_it:
        open_in_browser(paths["html"])
    return paths


def open_in_browser(path: str) -> None:
    """Open a local HTML file in the system browser (or FreeCAD's web view if none)."""
    from workcal_wb.gui.task_panels import QtCore, QtGui

    url = QtCore.QUrl.fromLocalFile(os.path.abspath(path))
    if QtGui.QDesktopServices.openUrl(url):
        return
    try:
        import WebGui

        WebGui.openBrowser(url.toString())
    except Exception as exc:
        message(f"open {path} in a browser ({exc})")


class ReportCommand(Command):
    NAME, TITLE = "WorkCal_Report", "Calibration report"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_Report", "Calibration report")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_Report", "Write the HTML report of the calibration (poses, residuals, "
                                                   "uncertainty, quality gates) and open it")

    def run(self):
        doc = active_document()
        write_report(calibration_for(doc), open_it=True)


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
    from workcal_wb.gui.task_panels.calibrate_panel import StatusProgress

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
        from workcal_wb.gui.task_panels import QtCore, QtGui, QtWidgets
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


COMMANDS = {"WorkCal_DeviationMap": DeviationMapCommand(), "WorkCal_Report": ReportCommand(),
            "WorkCal_Studies": StudiesCommand()}
