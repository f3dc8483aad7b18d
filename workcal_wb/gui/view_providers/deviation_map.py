"""The deviation map: points in their deviation colours, larger, and a legend of the colour scale while
the map is shown.

The legend is drawn by Qt (the application's font, anti-aliased) into an image that Coin shows in a
corner of the 3D view, pixel for pixel at any view size: the bottom-right corner, or the top-right
one when FreeCAD's navigation cube sits bottom-right, so the two never overlap.  Its colours come
from the map's ``DeviationScale``, the one the report uses.
"""
from __future__ import annotations

import numpy as np

import FreeCAD

from workcal_wb.gui.view import boxed_canvas, image_node, navigation_cube_rect, overlay_font
from workcal_wb.gui.view_providers.base import ViewProvider

translate = FreeCAD.Qt.translate

LEGEND_NODE = "WorkCalDeviationLegend"
BAR_WIDTH, BAR_HEIGHT, MARGIN, PADDING = 22, 170, 8, 10
FONT_PIXELS = 13
BEYOND_PIXELS = 12  # the boxes above and below the bar: past the colour limit


def legend_lines(scale) -> dict:
    """The legend's words: title, tick labels (top to bottom) and the notes under the bar."""
    return {
        "title": [translate("WorkCal", "Deviation from the model"),
                  translate("WorkCal", "green: within +/- {} mm").format(f"{scale.tolerance_mm:g}")],
        "ticks": [f"{v:+.2f} mm" if v else "0" for v in scale.ticks()],
        "notes": [translate("WorkCal", "red: material added"), translate("WorkCal", "blue: material removed"),
                  translate("WorkCal", "grey: no model near")],
    }


def legend_image(scale):
    """The legend as a QImage (RGBA, transparent margin) and the font it was written in."""
    from workcal_wb.gui.task_panels import QtCore, QtGui

    words = legend_lines(scale)
    font = overlay_font(FONT_PIXELS)
    metrics = QtGui.QFontMetrics(font)
    line = metrics.height()
    text_width = max(metrics.boundingRect(t).width() for t in words["title"] + words["notes"])
    tick_width = max(metrics.boundingRect(t).width() for t in words["ticks"])
    width = 2 * (MARGIN + PADDING) + max(text_width, BAR_WIDTH + 8 + tick_width)
    bar_top = MARGIN + PADDING + 2 * line + 6 + BEYOND_PIXELS
    height = bar_top + BAR_HEIGHT + BEYOND_PIXELS + 6 + 3 * line + PADDING + MARGIN
    image, painter = boxed_canvas(width, height, font, inset=MARGIN, radius=5, fill_alpha=235)
    x = MARGIN + PADDING
    for i, text in enumerate(words["title"]):
        painter.drawText(x, MARGIN + PADDING + metrics.ascent() + i * line, text)
    rows = np.linspace(scale.limit_mm, -scale.limit_mm, BAR_HEIGHT)  # top row: +limit
    for row, rgb in enumerate(scale.colours(rows)):
        painter.setPen(QtGui.QColor(*[int(round(255 * c)) for c in rgb]))
        painter.drawLine(x, bar_top + row, x + BAR_WIDTH - 1, bar_top + row)
    beyond = scale.colours([2 * scale.limit_mm, -2 * scale.limit_mm])
    for rgb, y in zip(beyond, (bar_top - BEYOND_PIXELS, bar_top + BAR_HEIGHT)):
        painter.fillRect(x, y, BAR_WIDTH, BEYOND_PIXELS, QtGui.QColor(*[int(round(255 * c)) for c in rgb]))
    painter.setPen(QtGui.QColor(60, 60, 60))
    painter.setBrush(QtCore.Qt.NoBrush)
    painter.drawRect(x, bar_top - BEYOND_PIXELS, BAR_WIDTH - 1, BAR_HEIGHT + 2 * BEYOND_PIXELS - 1)
    painter.setPen(QtGui.QColor(20, 20, 20))
    for value, text in zip(scale.ticks(), words["ticks"]):
        y = bar_top + (scale.limit_mm - value) / (2 * scale.limit_mm) * (BAR_HEIGHT - 1)
        painter.drawLine(x + BAR_WIDTH, int(round(y)), x + BAR_WIDTH + 4, int(round(y)))
        painter.drawText(x + BAR_WIDTH + 8, int(round(y + metrics.ascent() / 2 - 1)), text)
    notes_top = bar_top + BAR_HEIGHT + BEYOND_PIXELS + 6
    for i, text in enumerate(words["notes"]):
        painter.drawText(x, notes_top + metrics.ascent() + i * line, text)
    painter.end()
    return image, font


def legend_corner() -> str:
    """"bottom" unless FreeCAD's navigation cube sits in the bottom-right corner."""
    rect = navigation_cube_rect(1000, 1000)
    return "top" if rect is not None and rect[0] > 500 and rect[1] > 500 else "bottom"


def legend_rect(image_size, view_size) -> tuple:
    """(x0, y0, x1, y1) in view pixels (Qt: origin top-left) the legend covers in a view of ``view_size``."""
    (w, h), (width, height) = image_size, view_size
    return (width - w, height - h, width, height) if legend_corner() == "bottom" else (width - w, 0, width, h)


class ViewProviderDeviationMap(ViewProvider):
    ICON = "WorkCal_DeviationMap"
    POINT_SIZE = 3.0

    def __init__(self, vobj):
        super().__init__(vobj)
        vobj.PointSize = self.POINT_SIZE

    def getDefaultDisplayMode(self):
        return "Color"

    def attach(self, vobj):
        from pivy import coin

        super().attach(vobj)
        self.switch = coin.SoSwitch()
        self.switch.setName(LEGEND_NODE)
        self.legend = coin.SoAnnotation()  # drawn last, over the scene
        self.switch.addChild(self.legend)
        vobj.RootNode.addChild(self.switch)
        self.image_size = (0, 0)
        self._rebuild(vobj.Object)

    def updateData(self, obj, prop):
        if prop in ("Limit", "Tolerance", "Legend", "Color"):
            self._rebuild(obj)

    def onChanged(self, vobj, prop):
        if prop == "Visibility":
            self._show(vobj.Object)

    def _show(self, obj):
        if not hasattr(self, "switch"):
            return
        vobj = getattr(obj, "ViewObject", None)
        visible = bool(getattr(obj, "Legend", True)) and vobj is not None and vobj.Visibility
        self.switch.whichChild = 0 if visible and self.legend.getNumChildren() else -1

    def _rebuild(self, obj):
        from pivy import coin

        from workcal_wb.core.errors import WorkCalError
        from workcal_wb.fc.deviation_map import scale_of

        if not hasattr(self, "legend") or "Limit" not in obj.PropertiesList:
            return
        self.legend.removeAllChildren()
        try:
            scale = scale_of(obj)
        except WorkCalError:  # not computed yet
            self._show(obj)
            return
        image, _ = legend_image(scale)
        self.image_size = (image.width(), image.height())
        bottom = legend_corner() == "bottom"
        node = image_node(image, "RIGHT", "BOTTOM" if bottom else "TOP")
        camera = coin.SoOrthographicCamera()
        camera.viewportMapping = coin.SoCamera.LEAVE_ALONE  # x, y in -1..1 whatever the window shape
        camera.position = (0.0, 0.0, 5.0)
        camera.height = 2.0
        camera.nearDistance, camera.farDistance = 0.1, 10.0
        corner = coin.SoTranslation()
        corner.translation = (1.0, -1.0 if bottom else 1.0, 0.0)
        pick = coin.SoPickStyle()
        pick.style = coin.SoPickStyle.UNPICKABLE
        for child in (pick, camera, corner, node):
            self.legend.addChild(child)
        self._show(obj)
