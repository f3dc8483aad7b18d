"""Task panels of the WorkCal commands, and the Qt names they share (FreeCAD 0.20 and 1.x)."""
from PySide import QtCore, QtGui

try:  # FreeCAD 1.x (PySide6 wrapper) has QtWidgets; 0.20's QtGui re-exports the widgets
    from PySide import QtWidgets
except ImportError:  # pragma: no cover - depends on the FreeCAD version
    QtWidgets = QtGui

__all__ = ["QtCore", "QtGui", "QtWidgets"]
