"""Task panels of the WorkCal commands, and the Qt names they share (FreeCAD 0.20, 1.0 and 1.1).

FreeCAD's ``PySide`` wraps PySide2 (0.20, 1.0) or PySide6 (1.1 builds on Qt6); what differs is kept here.
"""
from PySide import QtCore, QtGui

try:  # FreeCAD 1.x has QtWidgets; 0.20's QtGui re-exports the widgets
    from PySide import QtWidgets
except ImportError:  # pragma: no cover - depends on the FreeCAD version
    QtWidgets = QtGui

# What a task panel's getStandardButtons returns.  Not int(): PySide6 flags are not ints, and FreeCAD
# converts the flags itself on every version.
OK_CANCEL = QtWidgets.QDialogButtonBox.Ok | QtWidgets.QDialogButtonBox.Cancel
CLOSE = QtWidgets.QDialogButtonBox.Close


def run_modal(dialog):
    """``dialog.exec()``: PySide2 names it ``exec_``, PySide6 deprecates that name."""
    run = getattr(dialog, "exec", None) or dialog.exec_
    return run()


__all__ = ["QtCore", "QtGui", "QtWidgets", "OK_CANCEL", "CLOSE", "run_modal"]
