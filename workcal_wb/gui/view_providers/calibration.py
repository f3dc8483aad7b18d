"""The calibration: coloured triads of the frames with their names, double-click opens its result in
the guide, and the right-click menu offers the workpiece model in the robot frame and the deviation
map (both through their recorded commands).  A new result redraws its scan's region overlay, which
shows the points off the placed models."""
import FreeCAD

from workcal_wb.core.errors import WorkCalError
from workcal_wb.fc.calibration_object import frame_poses
from workcal_wb.fc.lookups import result_of
from workcal_wb.gui.view_providers.base import ViewProvider

translate = FreeCAD.Qt.translate

AXIS_COLOURS = ((0.9, 0.1, 0.1), (0.1, 0.7, 0.1), (0.1, 0.2, 0.95))  # x red, y green, z blue
FRAME_WORDS = {"B": "B (robot base)", "S": "S (scanner)", "X": "X (workpiece)"}


class ViewProviderCalibration(ViewProvider):
    ICON = "WorkCal_Calibration"

    def attach(self, vobj):
        from pivy import coin

        super().attach(vobj)
        # Frame names, outside the display-mode switch: shown and hidden with the object by hand.
        self.switch = coin.SoSwitch()
        self.labels = coin.SoSeparator()
        self.switch.addChild(self.labels)
        self.switch.whichChild = 0 if vobj.Visibility else -1
        vobj.RootNode.addChild(self.switch)
        for name, value in (("LineWidth", 3.0), ("PointSize", 1.0)):
            if hasattr(vobj, name):
                setattr(vobj, name, value)
        self._update_labels(vobj.Object)

    def updateData(self, obj, prop):
        if prop in ("Shape", "ResultJson", "Frames"):
            self._update_labels(obj)
            self._colour_edges(obj)
        if prop in ("ResultJson", "Scan"):  # the scan shows the points off the placed models in red
            self._update_scan_overlay(obj)

    @staticmethod
    def _update_scan_overlay(obj):
        from workcal_wb.gui import region_display

        scan = getattr(obj, "Scan", None)
        if scan is not None and getattr(scan, "ViewObject", None) is not None:
            region_display.schedule(scan)

    def onDelete(self, vobj, subelements):
        self._update_scan_overlay(vobj.Object)  # once it is gone: its off-model points go with it
        return True

    def _colour_edges(self, obj):
        vobj = getattr(obj, "ViewObject", None)
        if vobj is None or not hasattr(vobj, "LineColorArray"):
            return
        n = len(obj.Shape.Edges)
        if n and n % 3 == 0:
            vobj.LineColorArray = [AXIS_COLOURS[i % 3] for i in range(n)]

    def _update_labels(self, obj):
        from pivy import coin

        if not hasattr(self, "labels"):
            return
        vobj = getattr(obj, "ViewObject", None)
        if vobj is not None:
            self.switch.whichChild = 0 if vobj.Visibility else -1
        self.labels.removeAllChildren()
        if not getattr(obj, "Frames", False) or not getattr(obj, "ResultJson", ""):
            return
        try:
            result = result_of(obj)
        except WorkCalError:
            return
        size = obj.FrameSize.Value
        colour = coin.SoBaseColor()
        colour.rgb = (0.1, 0.1, 0.1)
        font = coin.SoFont()
        font.name, font.size = "Sans", 13
        self.labels.addChild(colour)
        self.labels.addChild(font)
        for name, T in frame_poses(result).items():
            sep = coin.SoSeparator()
            move = coin.SoTranslation()
            move.translation = tuple(float(v) for v in T[:3, 3] - 0.12 * size * (T[:3, 0] + T[:3, 1]))
            text = coin.SoText2()
            text.string = FRAME_WORDS.get(name, name)
            sep.addChild(move)
            sep.addChild(text)
            self.labels.addChild(sep)

    def onChanged(self, vobj, prop):
        if prop == "Visibility" and hasattr(self, "switch"):
            self.switch.whichChild = 0 if vobj.Visibility else -1

    def doubleClicked(self, vobj):
        from workcal_wb.gui.commands.guide import open_guide

        open_guide(vobj.Object.Document, "result")
        return True

    def setupContextMenu(self, vobj, menu):
        import FreeCADGui

        obj = vobj.Object  # QMenu.addAction(text): QAction moved from QtWidgets to QtGui in Qt6

        def run(command):
            FreeCADGui.Selection.clearSelection()
            FreeCADGui.Selection.addSelection(obj)
            FreeCADGui.runCommand(command)

        menu.addAction(translate("WorkCal", "Show the workpiece model in the robot frame")).triggered.connect(
            lambda: run("WorkCal_ShowInRobotFrame"))
        menu.addAction(translate("WorkCal", "Deviation map")).triggered.connect(lambda: run("WorkCal_DeviationMap"))

    def claimChildren(self):
        return []
