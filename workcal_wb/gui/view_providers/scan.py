"""A WorkCal scan: FreeCAD's point display plus the region overlay (see gui/region_display)."""
from workcal_wb.fc import scan as fc_scan
from workcal_wb.gui.view_providers.base import ViewProvider

REGION_PROPERTIES = {fc_scan.WORKPIECE_PROP, fc_scan.REFERENCE_PROP, fc_scan.SOURCE_PROP, "Points", "Placement"}


class ViewProviderScan(ViewProvider):
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
        from workcal_wb.gui.commands.guide import open_guide

        open_guide(vobj.Object.Document, "regions")
        return True
