"""A model placed by a calibration: drawn like the model (a Python feature without a view provider
proxy gets no display mode and is not drawn at all), in its region's colour.  Over the scan its faces
are pulled a little towards the camera (a polygon offset), so where model and scan points coincide
the model shows, and only scan points that stand off the model (clay added, a wrong match) poke
through it."""
from workcal_wb.gui.view_providers.base import ViewProvider

COLOURS = {"workpiece": (1.0, 0.55, 0.1), "reference": (0.2, 0.5, 0.95)}  # as the scan's regions
OFFSET_NODE = "WorkCalOverScan"


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
        from pivy import coin

        vobj = getattr(obj, "ViewObject", None)
        if vobj is None or "Role" not in obj.PropertiesList:
            return
        for name in ("ShapeColor", "PointColor"):
            if hasattr(vobj, name):
                setattr(vobj, name, COLOURS.get(obj.Role, COLOURS["workpiece"]))
        root = vobj.RootNode
        existing = [root.getChild(i) for i in range(root.getNumChildren())
                    if root.getChild(i).getName().getString() == OFFSET_NODE]
        if obj.Frame == "Scan" and not existing:
            offset = coin.SoPolygonOffset()
            offset.setName(OFFSET_NODE)
            offset.factor, offset.units = -1.0, -5000.0  # towards the camera, past the scan noise
            root.insertChild(offset, 0)
        elif obj.Frame != "Scan":
            for node in existing:
                root.removeChild(node)

    def getDefaultDisplayMode(self):
        modes = self.ViewObject.listDisplayModes() if hasattr(self, "ViewObject") else []
        return next((m for m in self.DEFAULT_MODES if m in modes), modes[0] if modes else "Shaded")
