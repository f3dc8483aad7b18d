"""View providers of WorkCal's scan, setup and placed-model objects (tree icons, region overlay, double-click).

``workcal_wb.gui.workbench`` registers them with ``workcal_wb.fc.init.VIEW_PROVIDERS`` at GUI start-up,
so objects made by the FreeCAD layer get them without that layer importing GUI code.  FreeCAD
re-creates them from the class path saved in the document.
"""
from __future__ import annotations

from workcal_wb.fc import scan as fc_scan
from workcal_wb.fc.proxies import ViewProvider

REGION_PROPERTIES = {fc_scan.WORKPIECE_PROP, fc_scan.REFERENCE_PROP, fc_scan.SOURCE_PROP, "Points", "Placement"}


class ViewProviderScan(ViewProvider):
    """A WorkCal scan: FreeCAD's point display plus the region overlay (see region_display)."""

    ICON = "WorkCal_Scan"
    COLOR = (0.33, 0.34, 0.36)  # dark grey: visible on FreeCAD's light background, under the region colours

    def __init__(self, vobj):
        super().__init__(vobj)
        if hasattr(vobj, "ShapeColor"):  # only for a new scan: a reopened one keeps the user's colour
            vobj.ShapeColor = self.COLOR

    def updateData(self, obj, prop):
        if prop in REGION_PROPERTIES:
            from workcal_wb.gui import region_display

            region_display.schedule(obj)

    def onChanged(self, vobj, prop):
        if prop == "Visibility" and getattr(vobj, "Object", None) is not None:
            from workcal_wb.gui import region_display

            region_display.set_visible(vobj.Object, bool(vobj.Visibility))

    def doubleClicked(self, vobj):
        from workcal_wb.gui.commands.regions import open_pick_panel
        from workcal_wb.gui.task_panels.common import guarded

        guarded("Pick region")(open_pick_panel)(vobj.Object)
        return True


class ViewProviderSetup(ViewProvider):
    """The document's WorkCal setup: double-click opens Choose models."""

    ICON = "WorkCal_Setup"

    def doubleClicked(self, vobj):
        from workcal_wb.gui.commands.models import open_panel
        from workcal_wb.gui.task_panels.common import guarded

        guarded("Choose models")(open_panel)(vobj.Object.Document)
        return True


class ViewProviderPlacedModel(ViewProvider):
    """The workpiece model at W: drawn like the model (a Python feature without a view provider proxy
    gets no display mode and is not drawn at all), in the workpiece region's orange."""

    ICON = "WorkCal_Calibration"
    COLOR = (1.0, 0.6, 0.2)
    DEFAULT_MODES = ("Shaded", "Flat Lines", "Points")  # mesh, shape, point cloud: the first one offered

    def __init__(self, vobj):
        super().__init__(vobj)
        for name in ("ShapeColor", "PointColor"):
            if hasattr(vobj, name):
                setattr(vobj, name, self.COLOR)

    def getDefaultDisplayMode(self):
        modes = self.ViewObject.listDisplayModes() if hasattr(self, "ViewObject") else []
        return next((m for m in self.DEFAULT_MODES if m in modes), modes[0] if modes else "Shaded")
