"""The robot drawn at a pose: shaded in one colour that stands apart from the workpiece (orange), the
reference (blue) and the toolpath (a Python feature without a view provider proxy would not be drawn)."""
from workcal_wb.gui.view_providers.base import ViewProvider

# A light steel grey: the arm reads as a machine beside the coloured models, and the part stays in front.
ROBOT_COLOUR = (0.62, 0.66, 0.72)


class ViewProviderRobotPose(ViewProvider):
    ICON = "WorkCal_ExportToolpath"

    def attach(self, vobj):
        super().attach(vobj)
        if hasattr(vobj, "ShapeColor"):
            vobj.ShapeColor = ROBOT_COLOUR

    def getDefaultDisplayMode(self):
        return "Shaded"
