"""The toolpath carried into the robot base frame: drawn by FreeCAD's Path view provider ("Waypoints": a
Python feature gets no display mode of its own) from its first point (FreeCAD starts the drawing at
StartPosition, by default the origin of B, far from the part)."""
import FreeCAD

from workcal_wb.gui.view_providers.base import ViewProvider


class ViewProviderCalibratedPath(ViewProvider):
    ICON = "WorkCal_TransformToolpath"

    def updateData(self, obj, prop):
        if prop != "Path":
            return
        vobj = getattr(obj, "ViewObject", None)
        if vobj is None or not hasattr(vobj, "StartPosition"):
            return
        for command in obj.Path.Commands:
            p = command.Parameters
            if all(axis in p for axis in "XYZ"):
                vobj.StartPosition = FreeCAD.Vector(p["X"], p["Y"], p["Z"])
                return

    def getDefaultDisplayMode(self):
        return "Waypoints"
