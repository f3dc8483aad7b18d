"""A model placed by a calibration: drawn like the model (a Python feature without a view provider
proxy gets no display mode and is not drawn at all), in its region's colour; over the scan it is
half transparent so the scan points show through."""
from workcal_wb.gui.view_providers.base import ViewProvider

COLOURS = {"workpiece": (1.0, 0.55, 0.1), "reference": (0.2, 0.5, 0.95)}  # as the scan's regions
TRANSPARENCY_ON_SCAN = 35


class ViewProviderPlacedModel(ViewProvider):
    ICON = "WorkCal_ShowInRobotFrame"
    DEFAULT_MODES = ("Shaded", "Flat Lines", "Points")  # mesh, shape, point cloud: the first one offered

    def attach(self, vobj):
        super().attach(vobj)
        self.paint(vobj.Object)

    def updateData(self, obj, prop):
        if prop in ("Role", "Frame"):
            self.paint(obj)

    def paint(self, obj) -> None:
        vobj = getattr(obj, "ViewObject", None)
        if vobj is None or "Role" not in obj.PropertiesList:
            return
        for name in ("ShapeColor", "PointColor"):
            if hasattr(vobj, name):
                setattr(vobj, name, COLOURS.get(obj.Role, COLOURS["workpiece"]))
        if hasattr(vobj, "Transparency"):
            vobj.Transparency = TRANSPARENCY_ON_SCAN if obj.Frame == "Scan" else 0

    def getDefaultDisplayMode(self):
        modes = self.ViewObject.listDisplayModes() if hasattr(self, "ViewObject") else []
        return next((m for m in self.DEFAULT_MODES if m in modes), modes[0] if modes else "Shaded")
