"""Task panel of WorkCal_Calibrate: choose inputs and options, run the calibration in a worker thread.

The inputs are read from the document in the main thread (FreeCAD objects are not thread-safe), the
core calibration runs in a Python thread, and its progress comes back through queued Qt signals to
the panel and the status bar.  Cancel stops the worker at its next progress report (the progress
callback raises Cancelled).  Only when the worker has finished is the result object added, in one
undo step; an error or a cancel leaves the document as it was.
"""
from __future__ import annotations

import threading
import time
import traceback

import FreeCAD

from workcal_wb.core.errors import Cancelled, WorkCalError
from workcal_wb.core.match import METHODS
from workcal_wb.fc import prefs
from workcal_wb.fc import calibration_object as co

from . import OK_CANCEL, QtCore, QtWidgets
from .common import error, message, warning

translate = FreeCAD.Qt.translate

NONE_ITEM = "(none)"


class CalibrationRunner(QtCore.QObject):
    """Runs ``calibration_object.run(inputs)`` in a Python thread; reports through queued signals."""

    progressed = QtCore.Signal(float, str)
    succeeded = QtCore.Signal(object)  # CalibrationResult
    failed = QtCore.Signal(str)
    cancelled = QtCore.Signal()

    def __init__(self, inputs: co.Inputs, parent=None):
        super().__init__(parent)
        self.inputs = inputs
        self._stop = threading.Event()
        self._thread = None
        self.state = "idle"  # idle, running, done, failed, cancelled
        self.result = None
        self.error = ""
        self.started_at = None

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def start(self) -> None:
        self.state = "running"
        self.started_at = time.monotonic()
        self._thread = threading.Thread(target=self._work, name="WorkCal calibration", daemon=True)
        self._thread.start()

    def cancel(self) -> None:
        self._stop.set()

    def _progress(self, fraction: float, text: str) -> None:
        if self._stop.is_set():
            raise Cancelled(translate("WorkCal", "calibration cancelled"))
        self.progressed.emit(float(fraction), str(text))

    def _work(self) -> None:
        try:
            result = co.run(self.inputs, self._progress)
            if self._stop.is_set():  # cancelled after the last progress report: still discard
                raise Cancelled(translate("WorkCal", "calibration cancelled"))
        except Cancelled:
            self.state = "cancelled"
            self.cancelled.emit()
        except WorkCalError as exc:
            self.error, self.state = str(exc), "failed"
            self.failed.emit(self.error)
        except Exception as exc:  # a bug in the calibration: report it, never take FreeCAD down
            self.error, self.state = f"unexpected error: {exc}\n{traceback.format_exc()}", "failed"
            self.failed.emit(self.error)
        else:
            self.result, self.state = result, "done"
            self.succeeded.emit(result)


class StatusProgress:
    """A progress bar in FreeCAD's status bar for as long as a job runs."""

    def __init__(self, title: str):
        self.bar = None
        if not FreeCAD.GuiUp:
            return
        import FreeCADGui

        self.status = FreeCADGui.getMainWindow().statusBar()
        self.bar = QtWidgets.QProgressBar()
        self.bar.setRange(0, 100)
        self.bar.setMaximumWidth(220)
        self.bar.setFormat(f"{title} %p%")
        self.status.addPermanentWidget(self.bar)
        self.bar.show()

    def update(self, fraction: float, text: str) -> None:
        if self.bar is not None:
            self.bar.setValue(int(round(100 * fraction)))
            self.status.showMessage(f"WorkCal: {text}")

    def close(self) -> None:
        if self.bar is not None:
            self.status.removeWidget(self.bar)
            self.bar.deleteLater()
            self.status.clearMessage()
            self.bar = None


def _objects_for(doc, kind: str) -> list:
    """Candidate objects for a role ("scan", "model" or "toolpath"), in document order."""
    from workcal_wb.fc import models as fcmodels
    from workcal_wb.fc import scan as fcscan
    from workcal_wb.fc.toolpath import is_job

    if kind == "toolpath":
        from workcal_wb.gui.commands.toolpath import toolpath_sources

        return toolpath_sources(doc)
    out = []
    for obj in doc.Objects:
        if getattr(obj, "WorkCalRole", "") or is_job(obj) or obj.TypeId.startswith(
                ("Path::", "App::Origin", "App::Line", "App::Plane")):
            continue
        if kind == "scan" and fcscan.can_be_scan(obj):
            out.append(obj)
        elif kind == "model" and not fcscan.is_scan(obj) and fcmodels.is_model_object(obj):
            out.append(obj)
    return out


def default_setup(doc) -> dict:
    """Scan and models as recorded by WorkCal's import commands (fc.setup), when available."""
    try:
        from workcal_wb.fc.setup import get_setup
    except ImportError:
        return {}
    try:
        return dict(get_setup(doc) or {})
    except Exception as exc:  # a broken setup record must not stop the panel from opening
        warning(f"cannot read the scan/model setup of {doc.Label}: {exc}")
        return {}


class CalibratePanel:
    """The task panel; ``start()`` and ``cancel()`` drive it without clicking (tests, scripts)."""

    current = None  # the panel last opened (FreeCAD's activeDialog() does not give the Python object)

    def __init__(self, doc, calibration=None):
        CalibratePanel.current = self
        self.doc = doc
        self.calibration = calibration  # editing an existing calibration object
        self.runner = None
        self.progress = None
        self.created = None  # the calibration object made or updated on success
        self.state = "idle"  # idle, running, cancelling, done, failed, cancelled
        self.last_error = ""
        self.closed = False
        self.form = self._build()
        self._fill()

    # ------------------------------------------------------------------ widgets
    def _build(self):
        form = QtWidgets.QWidget()
        form.setWindowTitle(translate("WorkCal", "Calibrate workpiece"))
        layout = QtWidgets.QVBoxLayout(form)

        inputs = QtWidgets.QGroupBox(translate("WorkCal", "Inputs"))
        grid = QtWidgets.QFormLayout(inputs)
        self.scan_box = QtWidgets.QComboBox()
        self.workpiece_box = QtWidgets.QComboBox()
        self.reference_box = QtWidgets.QComboBox()
        self.toolpath_box = QtWidgets.QComboBox()
        self.scan_box.setToolTip(translate("WorkCal", "The scene scan: workpiece and reference seen from one position"))
        self.workpiece_box.setToolTip(translate("WorkCal", "The workpiece model X-A, in its own frame X"))
        self.reference_box.setToolTip(translate("WorkCal", "The reference model B-P, in the robot base frame B"))
        self.toolpath_box.setToolTip(translate("WorkCal", "Optional: the uncertainty is reported at this "
                                                          "toolpath's cutting points"))
        grid.addRow(translate("WorkCal", "Scan"), self.scan_box)
        grid.addRow(translate("WorkCal", "Workpiece model"), self.workpiece_box)
        grid.addRow(translate("WorkCal", "Reference model"), self.reference_box)
        grid.addRow(translate("WorkCal", "Toolpath"), self.toolpath_box)
        layout.addWidget(inputs)

        options = QtWidgets.QGroupBox(translate("WorkCal", "Options"))
        grid = QtWidgets.QFormLayout(options)
        self.method_box = QtWidgets.QComboBox()
        self.method_box.addItems(list(METHODS))
        self.method_box.setToolTip(translate("WorkCal", "robust: trimmed point-to-plane ICP (default); icp and "
                                                        "hausdorff: the paper's least-squares and Hausdorff measures"))
        self.tolerance_box = QtWidgets.QDoubleSpinBox()
        self.tolerance_box.setDecimals(3)
        self.tolerance_box.setRange(0.001, 100.0)
        self.tolerance_box.setSingleStep(0.05)
        self.tolerance_box.setSuffix(" mm")
        self.tolerance_box.setToolTip(translate("WorkCal", "Residuals and the uncertainty must stay within it"))
        self.auto_regions = QtWidgets.QRadioButton(translate("WorkCal", "Automatic"))
        self.picked_regions = QtWidgets.QRadioButton(translate("WorkCal", "Use picked regions"))
        regions = QtWidgets.QHBoxLayout()
        regions.addWidget(self.auto_regions)
        regions.addWidget(self.picked_regions)
        self.seed_box = QtWidgets.QSpinBox()
        self.seed_box.setRange(0, 2 ** 31 - 1)
        self.resamples_box = QtWidgets.QSpinBox()
        self.resamples_box.setRange(1, 100)
        self.resamples_box.setToolTip(translate("WorkCal", "Bootstrap refits for the uncertainty bound"))
        self.placed_box = QtWidgets.QCheckBox(translate("WorkCal", "Show the workpiece model in the robot frame"))
        grid.addRow(translate("WorkCal", "Method"), self.method_box)
        grid.addRow(translate("WorkCal", "Tolerance"), self.tolerance_box)
        grid.addRow(translate("WorkCal", "Regions"), regions)
        grid.addRow(translate("WorkCal", "Seed"), self.seed_box)
        grid.addRow(translate("WorkCal", "Resamples"), self.resamples_box)
        grid.addRow(self.placed_box)
        layout.addWidget(options)

        self.progress_bar = QtWidgets.QProgressBar()
        self.progress_bar.setRange(0, 100)
        self.progress_bar.setValue(0)
        self.status_label = QtWidgets.QLabel(translate("WorkCal", "Press OK to calibrate."))
        self.status_label.setWordWrap(True)
        layout.addWidget(self.progress_bar)
        layout.addWidget(self.status_label)
        layout.addStretch(1)
        self.option_widgets = [inputs, options]
        return form

    def _fill(self):
        doc = self.doc
        setup = default_setup(doc)
        cal = self.calibration
        chosen = {
            "scan": cal.Scan if cal else setup.get("scan"),
            "workpiece": cal.Workpiece if cal else setup.get("workpiece"),
            "reference": cal.Reference if cal else setup.get("reference"),
            "toolpath": cal.Toolpath if cal else None,
        }
        self._objects = {}
        roles = (("scan", self.scan_box, "scan"), ("workpiece", self.workpiece_box, "model"),
                 ("reference", self.reference_box, "model"), ("toolpath", self.toolpath_box, "toolpath"))
        for role, box, kind in roles:
            candidates = _objects_for(doc, kind)
            if chosen[role] is not None and chosen[role] not in candidates:
                candidates.insert(0, chosen[role])
            if role == "toolpath":
                candidates.insert(0, None)
            self._objects[role] = candidates
            box.clear()
            box.addItems([NONE_ITEM if o is None else f"{o.Label} ({o.Name})" for o in candidates])
            if chosen[role] in candidates:
                box.setCurrentIndex(candidates.index(chosen[role]))
        if not chosen["reference"] and len(self._objects["reference"]) > 1 and chosen["workpiece"] is None:
            self.reference_box.setCurrentIndex(1)
        method = cal.Method if cal else prefs.get("Method")
        self.method_box.setCurrentIndex(list(METHODS).index(method))
        self.tolerance_box.setValue(cal.Tolerance.Value if cal else prefs.get("ToleranceMm"))
        picked = (cal.Regions if cal else prefs.get("Regions")) == "Picked"
        (self.picked_regions if picked else self.auto_regions).setChecked(True)
        self.seed_box.setValue(cal.Seed if cal else prefs.get("Seed"))
        self.resamples_box.setValue(cal.Resamples if cal else prefs.get("Resamples"))

    # ------------------------------------------------------------------ values
    def _chosen(self, role: str):
        box = {"scan": self.scan_box, "workpiece": self.workpiece_box, "reference": self.reference_box,
               "toolpath": self.toolpath_box}[role]
        objects = self._objects.get(role, [])
        i = box.currentIndex()
        return objects[i] if 0 <= i < len(objects) else None

    def set_inputs(self, scan=None, workpiece=None, reference=None, toolpath=None):
        """Choose input objects programmatically (they are added to the lists if missing)."""
        for role, obj in (("scan", scan), ("workpiece", workpiece), ("reference", reference),
                          ("toolpath", toolpath)):
            if obj is None:
                continue
            box = {"scan": self.scan_box, "workpiece": self.workpiece_box, "reference": self.reference_box,
                   "toolpath": self.toolpath_box}[role]
            if obj not in self._objects[role]:
                self._objects[role].append(obj)
                box.addItem(f"{obj.Label} ({obj.Name})")
            box.setCurrentIndex(self._objects[role].index(obj))

    def set_options(self, method=None, tolerance_mm=None, regions=None, seed=None, resamples=None,
                    placed_model=None):
        if method is not None:
            self.method_box.setCurrentIndex(list(METHODS).index(method))
        if tolerance_mm is not None:
            self.tolerance_box.setValue(float(tolerance_mm))
        if regions is not None:
            (self.picked_regions if regions == "Picked" else self.auto_regions).setChecked(True)
        if seed is not None:
            self.seed_box.setValue(int(seed))
        if resamples is not None:
            self.resamples_box.setValue(int(resamples))
        if placed_model is not None:
            self.placed_box.setChecked(bool(placed_model))

    def regions_mode(self) -> str:
        return "Picked" if self.picked_regions.isChecked() else "Auto"

    # ------------------------------------------------------------------ task dialog protocol
    def getStandardButtons(self):
        return OK_CANCEL

    def accept(self):
        """OK: start the calibration (the dialog stays open until it finishes)."""
        self.start()
        return False

    def reject(self):
        """Cancel: stop a running calibration (the dialog closes once the worker has stopped)."""
        if self.state in ("running", "cancelling"):
            self.cancel()
            return False
        self._close()
        return True

    # ------------------------------------------------------------------ work
    def start(self) -> bool:
        """Read the inputs and start the worker; False (message in the panel and the Report view) when
        the inputs are not usable or a calibration is already running."""
        if self.state in ("running", "cancelling"):
            return False
        try:
            options = co.options_from(self.tolerance_box.value(), self.method_box.currentText(),
                                      self.seed_box.value(), self.resamples_box.value())
            inputs = co.gather_inputs(self._chosen("scan"), self._chosen("workpiece"), self._chosen("reference"),
                                      options=options, regions=self.regions_mode(), toolpath=self._chosen("toolpath"))
        except WorkCalError as exc:
            self._failed(str(exc))
            return False
        self.inputs = inputs
        self.runner = CalibrationRunner(inputs)
        self.runner.progressed.connect(self._on_progress)
        self.runner.succeeded.connect(self._on_success)
        self.runner.failed.connect(self._failed)
        self.runner.cancelled.connect(self._on_cancelled)
        self.state = "running"
        self.last_error = ""
        self._busy(True)
        self.progress = StatusProgress(translate("WorkCal", "Calibrating"))
        self._on_progress(0.0, translate("WorkCal", "starting"))
        message(translate("WorkCal", "calibrating {} against {} and {} ...").format(
            inputs.labels["scan"], inputs.labels["workpiece"], inputs.labels["reference"]))
        self.runner.start()
        return True

    def cancel(self) -> None:
        if self.runner is not None and self.state == "running":
            self.state = "cancelling"
            self.runner.cancel()
            self._show(None, translate("WorkCal", "Cancelling..."))

    @property
    def finished(self) -> bool:
        return self.state in ("done", "failed", "cancelled", "idle")

    def _alive(self) -> bool:
        """Whether the panel's widgets still exist (the dialog may have been closed under us)."""
        try:
            self.form.objectName()
        except RuntimeError:
            return False
        return True

    def _show(self, fraction: float | None = None, text: str | None = None) -> None:
        if not self._alive():
            return
        if fraction is not None:
            self.progress_bar.setValue(int(round(100 * fraction)))
        if text is not None:
            self.status_label.setText(text)

    def _busy(self, busy: bool) -> None:
        if not self._alive():
            return
        for widget in self.option_widgets:
            widget.setEnabled(not busy)

    def _end_progress(self) -> None:
        if self.progress is not None:
            self.progress.close()
            self.progress = None

    def _on_progress(self, fraction: float, text: str) -> None:
        self._show(fraction, text)
        if self.progress is not None:
            self.progress.update(fraction, text)

    def _on_success(self, result) -> None:
        self._end_progress()
        self._busy(False)
        if self.doc.Name not in FreeCAD.listDocuments():  # closed while the worker ran
            self.state = "cancelled"
            message(translate("WorkCal", "calibration finished after its document was closed; result dropped"))
            self._close()
            return
        try:
            if self.calibration is not None and self.doc.getObject(self.calibration.Name) is not None:
                co.update_calibration(self.calibration, result, self.inputs, self.regions_mode(),
                                      placed_model=self.placed_box.isChecked())
                self.created = self.calibration
            else:
                self.created = co.make_calibration(
                    self.doc, self._chosen("scan"), self._chosen("workpiece"), self._chosen("reference"),
                    toolpath=self._chosen("toolpath"), regions=self.regions_mode(), result=result,
                    inputs=self.inputs, placed_model=self.placed_box.isChecked())
        except WorkCalError as exc:
            self._failed(str(exc))
            return
        except Exception as exc:
            self._failed(f"unexpected error while adding the result: {exc}\n{traceback.format_exc()}")
            return
        self.state = "done"
        self._show(1.0, translate("WorkCal", "Calibration {}").format(result.status))
        self._close()

    def _failed(self, text: str) -> None:
        self._end_progress()
        self._busy(False)
        self.state = "failed"
        self.last_error = text
        error(translate("WorkCal", "calibration not done: {}").format(text))
        self._show(0.0, translate("WorkCal", "Error: {}").format(text.splitlines()[0] if text else ""))

    def _on_cancelled(self) -> None:
        self._end_progress()
        self._busy(False)
        self.state = "cancelled"
        message(translate("WorkCal", "calibration cancelled; the document is unchanged"))
        self._close()

    def _close(self) -> None:
        if self.closed:
            return
        self.closed = True
        if FreeCAD.GuiUp:
            import FreeCADGui

            if FreeCADGui.Control.activeDialog():
                FreeCADGui.Control.closeDialog()
            if self.calibration is not None and FreeCADGui.ActiveDocument is not None:
                try:
                    FreeCADGui.ActiveDocument.resetEdit()
                except Exception:
                    pass

    def wait(self, timeout_s: float = 120.0) -> str:
        """Keep the event loop running until the worker is finished and its result handled."""
        from .common import process_events

        end = time.monotonic() + timeout_s
        while self.state in ("running", "cancelling") and time.monotonic() < end:
            process_events(0.05)
        process_events(0.05)
        return self.state
