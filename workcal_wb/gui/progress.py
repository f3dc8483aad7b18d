"""Run a long pure-Python/numpy job (file reading, region finding) without freezing the window.

``run_in_background(job, label)`` runs ``job()`` in a worker thread and keeps the event loop going;
after ``SHOW_AFTER_S`` a busy progress dialog with a Cancel button appears.  Cancel raises
``Cancelled`` at once (the worker's result is then dropped; Python threads cannot be killed, so the
worker finishes in the background).  ``job`` must not touch FreeCAD documents or widgets.
"""
from __future__ import annotations

import threading
import time

import FreeCAD

from workcal_wb.core.errors import Cancelled

SHOW_AFTER_S = 0.4
POLL_S = 0.02

translate = FreeCAD.Qt.translate


def run_in_background(job, label: str, title: str | None = None):
    """``job()``'s result, or its exception re-raised here; Cancelled when the user cancels."""
    from PySide import QtCore, QtGui

    try:
        from PySide import QtWidgets
    except ImportError:
        QtWidgets = QtGui

    outcome = {}

    def work():
        try:
            outcome["result"] = job()
        except BaseException as exc:  # handed to the main thread as is
            outcome["error"] = exc

    worker = threading.Thread(target=work, name="WorkCal background job", daemon=True)
    started = time.monotonic()
    worker.start()
    dialog = None
    app = QtWidgets.QApplication.instance()
    try:
        while worker.is_alive():
            if dialog is None and time.monotonic() - started > SHOW_AFTER_S and FreeCAD.GuiUp:
                import FreeCADGui

                dialog = QtWidgets.QProgressDialog(label, translate("WorkCal", "Cancel"), 0, 0,
                                                   FreeCADGui.getMainWindow())
                dialog.setWindowTitle(title or translate("WorkCal", "WorkCal"))
                dialog.setWindowModality(QtCore.Qt.WindowModal)
                dialog.setMinimumDuration(0)
                dialog.setObjectName("WorkCalProgress")
                dialog.show()
            if dialog is not None and dialog.wasCanceled():
                raise Cancelled(translate("WorkCal", "{} cancelled").format(label))
            if app is not None:
                app.processEvents(QtCore.QEventLoop.AllEvents, 30)
            worker.join(POLL_S)
    finally:
        if dialog is not None:
            dialog.close()
            dialog.deleteLater()
    if "error" in outcome:
        raise outcome["error"]
    return outcome.get("result")
