"""A WorkCal scan: FreeCAD's point display drawn shaded (gui/scan_shading) plus the region overlay
(gui/region_display)."""
from workcal_wb.fc import scan as fc_scan
from workcal_wb.gui.view_providers.base import ViewProvider

REGION_PROPERTIES = {fc_scan.WORKPIECE_PROP, fc_scan.REFERENCE_PROP, fc_scan.SOURCE_PROP, "Points", "Placement"}
SHADING_PROPERTIES = {"Points", "Placement"}
_pending_shading = set()  # (document name, object name) waiting for a deferred shading update


def schedule_shading(obj) -> None:
    """Shade the scan once the event loop runs again (after the property changes of one edit)."""
    key = (obj.Document.Name, obj.Name)
    if key in _pending_shading:
        return
    _pending_shading.add(key)
    from PySide import QtCore

    QtCore.QTimer.singleShot(0, lambda: _shade(key))


def _shade(key) -> None:
    import FreeCAD

    from workcal_wb.gui import scan_shading

    _pending_shading.discard(key)
    doc = FreeCAD.listDocuments().get(key[0])
    obj = doc.getObject(key[1]) if doc is not None else None
    if obj is not None:
        scan_shading.update(obj)


class ViewProviderScan(ViewProvider):
    ICON = "WorkCal_Scan"
    COLOR = (0.33, 0.34, 0.36)  # dark grey: visible on FreeCAD's light background, under the region colours

    def __init__(self, vobj):
        super().__init__(vobj)
        if hasattr(vobj, "ShapeColor"):  # only for a new scan: a reopened one keeps the user's colour
            vobj.ShapeColor = self.COLOR

    def updateData(self, obj, prop):
        if prop in SHADING_PROPERTIES:
            schedule_shading(obj)
        if prop in REGION_PROPERTIES:
            from workcal_wb.gui import region_display

            region_display.schedule(obj)

    def onChanged(self, vobj, prop):
        if prop == "Visibility" and getattr(vobj, "Object", None) is not None:
            from workcal_wb.gui import region_display, scan_shading

            region_display.set_visible(vobj.Object, bool(vobj.Visibility))
            scan_shading.set_visible(vobj.Object, bool(vobj.Visibility))
        elif prop == "PointSize" and getattr(vobj, "Object", None) is not None:
            schedule_shading(vobj.Object)

    def doubleClicked(self, vobj):
        from workcal_wb.gui.commands.guide import open_guide

        open_guide(vobj.Object.Document, "regions")
        return True
