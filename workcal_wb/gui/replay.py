"""Document changes made by WorkCal's commands, as the Python lines that make them.

As Draft's and gears' commands do, every WorkCal command changes the document by running a call of
a public ``workcal_wb.fc`` function through ``FreeCADGui.doCommand``: the line shows in the Python
console, goes into a macro being recorded, and that macro runs again under freecadcmd (no GUI
module is ever named in it).  Slow work (reading a scan, finding regions, calibrating) runs in a
worker thread first; the ``fc`` functions remember its result, so the recorded call does not
compute it again.  Exceptions raised by the call come back here with their type (InputError...).
"""
from __future__ import annotations

import sys

import numpy as np

import FreeCAD

PREFIX = "workcal_wb.fc."


class Code(str):
    """Python text written into the call as it is (e.g. a call of another ``workcal_wb.fc`` function)."""


def literal(value) -> str:
    """Python text that gives ``value`` back in the macro: document objects by their document and name."""
    if isinstance(value, Code):
        return str(value)
    if hasattr(value, "TypeId") and hasattr(value, "Document") and hasattr(value, "Name"):
        return f"{document_text(value.Document)}.getObject({value.Name!r})"
    if hasattr(value, "Objects") and hasattr(value, "Name") and hasattr(value, "Label"):
        return document_text(value)
    if isinstance(value, np.ndarray):
        return repr(value.tolist())
    if isinstance(value, (np.integer, np.floating)):
        return repr(value.item())
    if isinstance(value, (list, tuple)):
        inner = ", ".join(literal(v) for v in value)
        return f"[{inner}]" if isinstance(value, list) else f"({inner}{',' if len(value) == 1 else ''})"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{literal(k)}: {literal(v)}" for k, v in value.items()) + "}"
    if value is None or isinstance(value, (bool, int, float, str)):
        return repr(value)
    raise TypeError(f"cannot write {value!r} into a macro")


def document_text(doc) -> str:
    """``App.ActiveDocument`` for the active document (a macro replays into whatever document is
    active, as FreeCAD's own recorded lines do), else the document by name."""
    return "App.ActiveDocument" if FreeCAD.ActiveDocument is doc else f"App.getDocument({doc.Name!r})"


def call_text(function: str, *args, **kwargs) -> str:
    parts = [literal(a) for a in args] + [f"{k}={literal(v)}" for k, v in kwargs.items()]
    return f"{function}({', '.join(parts)})"


def run(function: str, *args, result: str = "_", **kwargs):
    """Run ``function(*args, **kwargs)`` (the dotted name of a public ``workcal_wb.fc`` function) as a
    recorded command, its return value assigned to ``result`` in the console; returns that value."""
    import FreeCADGui

    if not function.startswith(PREFIX):
        raise ValueError(f"{function}: only workcal_wb.fc functions are recorded (a macro must replay headless)")
    # Not FreeCADGui.addModule: it writes the import only the first time in a session, so a macro recorded
    # later would lack it and fail when it replays in a fresh freecadcmd.
    FreeCADGui.doCommand(f"import {function.rsplit('.', 1)[0]}")
    FreeCADGui.doCommand(f"{result} = {call_text(function, *args, **kwargs)}")
    return vars(sys.modules["__main__"]).get(result)
