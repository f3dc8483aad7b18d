"""Long jobs behind the WorkCal panels: the calibration in a worker thread, a progress bar in the status bar.

The inputs are read from the document in the main thread (FreeCAD objects are not thread-safe), the
core calibration runs in a Python thread and its progress comes back through queued Qt signals.
Cancel stops the worker at its next progress report (the progress callback raises Cancelled).  The
worker leaves OpenBLAS's process-wide thread setting alone (FreeCAD's own thread goes on using numpy).
"""
from __future__ import annotations

import threading
import time
import traceback

import FreeCAD

from workcal_wb.core.errors import Cancelled, WorkCalError
from workcal_wb.fc import inputs as fc_inputs

from . import QtCore, QtWidgets

translate = FreeCAD.Qt.translate


class CalibrationRunner(QtCore.QObject):
    """Runs ``fc.inputs.run(inputs)`` in a Python thread; reports through queued signals.  Made in the
    GUI thread (never in the worker), so its slots run there."""

    progressed = QtCore.Signal(float, str)
    succeeded = QtCore.Signal(object)  # CalibrationResult
    failed = QtCore.Signal(str)
    cancelled = QtCore.Signal()

    def __init__(self, inputs: fc_inputs.Inputs, parent=None):
        super().__init__(parent)
        self.inputs = inputs
        self._stop = threading.Event()
        self._thread = None
        self.state = "idle"  # idle, running, done, failed, cancelled
        self.result = None
        self.error = ""

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def start(self) -> None:
        self.state = "running"
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
            result = fc_inputs.run(self.inputs, self._progress, blas_threads=None)
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


def wait_until(predicate, timeout_s: float = 120.0) -> bool:
    """Keep the event loop running until ``predicate()`` holds (or the time is up); returns it."""
    from .common import process_events

    end = time.monotonic() + timeout_s
    while not predicate() and time.monotonic() < end:
        process_events(0.05)
    process_events(0.02)
    return bool(predicate())
