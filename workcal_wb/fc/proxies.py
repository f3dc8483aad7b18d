"""Base classes of WorkCal's proxies: the Python side of its document objects and view providers.

FreeCAD saves a proxy with the document, 0.20 through ``__getstate__``/``__setstate__`` and 1.x
through ``dumps``/``loads``: ``Proxy`` defines both pairs once.  A WorkCal proxy saves nothing but
its ``STATE`` (JSON-able); caches and scene nodes are rebuilt after reopening.
"""
import workcal_wb


class Proxy:
    STATE = None  # what the document stores for the proxy: None or a small JSON-able dict

    def __getstate__(self):
        return self.STATE

    def __setstate__(self, state):
        return None

    def dumps(self):
        return self.__getstate__()

    def loads(self, state):
        return self.__setstate__(state)


class Feature(Proxy):
    """Proxy of a document object whose ``setup(obj)`` adds the properties it lacks.  It runs when the
    object is made and again when its document is reopened, so files saved by an older WorkCal gain
    the properties added since."""

    def __init__(self, obj):
        obj.Proxy = self
        self.setup(obj)

    def onDocumentRestored(self, obj):
        self.setup(obj)
        obj.purgeTouched()  # restoring dynamic properties touches the object; its stored result is still valid


class ViewProvider(Proxy):
    """View provider proxy whose tree icon is resources/icons/<ICON>.svg."""

    ICON = "WorkCal"

    def __init__(self, vobj):
        vobj.Proxy = self

    def attach(self, vobj):
        self.ViewObject = vobj
        self.Object = vobj.Object

    def getIcon(self):
        return workcal_wb.icon(self.ICON)
