"""What every WorkCal document object shares: its proxy base class, its identity and its view provider.

* **Identity**: each proxy class names its object kind in ``TYPE`` ("WorkCal::Scan", ...);
  ``type_of(obj)`` reads it and ``objects_of(doc, TYPE)`` finds them.  It is the one way WorkCal
  recognises its objects (no hidden role properties, no label or name matching).
* **Saving**: FreeCAD saves a proxy with the document, 0.20 through ``__getstate__``/``__setstate__``
  and 1.x through ``dumps``/``loads``; ``Proxy`` defines both pairs once and saves ``{"Type": TYPE}``.
  Caches and scene nodes are rebuilt after reopening.
* **View providers**: the GUI fills ``VIEW_PROVIDERS`` (TYPE -> "module:Class", see
  ``workcal_wb.gui.view_providers``) at start-up; ``Feature`` attaches the registered one when it makes
  an object, so this layer never imports GUI code and headless documents get none.
"""
from __future__ import annotations

import importlib

import FreeCAD

# TYPE -> "module:Class" of its view provider proxy; filled by workcal_wb.gui.view_providers.register().
VIEW_PROVIDERS = {}
# Hidden properties older WorkCal versions used to recognise their objects; dropped on reopening.
LEGACY_PROPERTIES = ("WorkCalRole",)


class Proxy:
    TYPE = ""  # "WorkCal::<Kind>": what the object is to WorkCal

    def __getstate__(self):
        return {"Type": self.TYPE} if self.TYPE else None

    def __setstate__(self, state):
        return None

    def dumps(self):
        return self.__getstate__()

    def loads(self, state):
        return self.__setstate__(state)


class Feature(Proxy):
    """Proxy of a document object: ``setup(obj)`` adds the properties it lacks.  It runs when the object
    is made and again when its document is reopened, so files saved by an older WorkCal gain the
    properties added since."""

    def __init__(self, obj):
        obj.Proxy = self
        self.setup(obj)
        attach_view_provider(obj)

    def setup(self, obj) -> None:
        pass

    def execute(self, obj):
        pass

    def onDocumentRestored(self, obj):
        for name in LEGACY_PROPERTIES:
            if name in obj.PropertiesList:
                obj.removeProperty(name)
        self.setup(obj)
        obj.purgeTouched()  # restoring dynamic properties touches the object; its stored result is still valid


def type_of(obj) -> str | None:
    """The WorkCal kind of a document object ("WorkCal::Scan", ...), None for anything else."""
    return getattr(getattr(obj, "Proxy", None), "TYPE", None) or None


def objects_of(doc, kind: str) -> list:
    """The document's objects of one WorkCal kind, in document order."""
    return [] if doc is None else [o for o in doc.Objects if type_of(o) == kind]


def attach_view_provider(obj) -> None:
    """Give ``obj`` the view provider registered for its kind (only when FreeCAD runs with its GUI)."""
    target = VIEW_PROVIDERS.get(type_of(obj))
    if not FreeCAD.GuiUp or target is None or getattr(obj, "ViewObject", None) is None:
        return
    module, cls = target.split(":")
    getattr(importlib.import_module(module), cls)(obj.ViewObject)


def add_properties(obj, properties, read_only=(), hidden=()) -> None:
    """Add the (type, name, group, tooltip) properties ``obj`` lacks; set their editor modes."""
    for kind, name, group, tip in properties:
        if name not in obj.PropertiesList:
            obj.addProperty(kind, name, group, tip)
    for name in read_only:
        obj.setEditorMode(name, 1)
    for name in hidden:
        obj.setEditorMode(name, 2)
