"""The 3D view brought to what a step is about, at once, with the objects named in plain words.

FreeCAD 1.x animates camera changes by default: ``setCameraOrientation`` then ``fitAll`` fits the
scene as seen from the old orientation while the turn is still under way, and the turn then ends
with the objects off screen.  Turning the animation off for the change makes it one step, as on
FreeCAD 0.20.

``look_at`` fits the view to some objects only (not to everything shown: far-away frame markers
or a reference model in another frame would shrink the scan to a speck).  ``Labels`` writes plain
words beside objects in the view.  ``navigation_cube_rect`` says where FreeCAD draws its navigation
cube, so overlays keep clear of it.
"""
from __future__ import annotations

from contextlib import contextmanager

import numpy as np

import FreeCAD

# Looking from the scanner: along +Z of the scan frame S, with -Y of S up (the usual camera convention
# of scanners; the camera looks along its own -Z).
FROM_SCANNER = FreeCAD.Rotation(FreeCAD.Vector(1, 0, 0), 180)
FIT_MARGIN = 1.1  # the fitted objects fill the view up to this factor (room for the labels)
LABEL_NODE = "WorkCalLabels"
LABEL_PIXELS, LABEL_PADDING = 14, 6
LABEL_COLOUR = (0.1, 0.1, 0.12)
LABEL_CLEARANCE_PX = 40  # labels whose anchors are closer than this on the screen would cover each other


@contextmanager
def without_animation(view):
    """Camera changes inside the block take effect immediately; the user's setting comes back after."""
    animated = bool(view.isAnimationEnabled())
    view.setAnimationEnabled(False)
    try:
        yield view
    finally:
        view.setAnimationEnabled(animated)


def look(view, orientation=None) -> None:
    """Turn the camera to ``orientation`` (a FreeCAD.Rotation; None keeps it) and fit everything shown."""
    with without_animation(view):
        if orientation is not None:
            view.setCameraOrientation(orientation)
        view.fitAll()


def look_at(view, objects, orientation=None) -> None:
    """Turn the camera to ``orientation`` (None keeps it) and fit the view to ``objects`` alone."""
    from pivy import coin

    box = bounding_box(o for o in objects if getattr(getattr(o, "ViewObject", None), "Visibility", False))
    if box is None:
        return look(view, orientation)
    stand_in = coin.SoSeparator()  # the box as geometry, for Coin's own fit
    move = coin.SoTranslation()
    move.translation = tuple(float(v) for v in box.mean(axis=0))
    cube = coin.SoCube()
    cube.width, cube.height, cube.depth = (float(max(v, 1e-6)) for v in box[1] - box[0])
    stand_in.addChild(move)
    stand_in.addChild(cube)
    with without_animation(view):
        if orientation is not None:
            view.setCameraOrientation(orientation)
        view.getCameraNode().viewAll(stand_in, view.getViewer().getSoRenderManager().getViewportRegion(),
                                     FIT_MARGIN)


def bounding_box(objects) -> np.ndarray | None:
    """(2, 3) lower and upper corners of the objects' geometry in document coordinates (None if none):
    what the objects are, not what their view providers draw around them (legends, labels)."""
    corners = []
    for obj in objects:
        commands = getattr(getattr(obj, "Path", None), "Commands", None)
        if commands is not None:  # a Path's own BoundBox always holds the origin, where its drawing starts
            ends = np.array([[c.Parameters[a] for a in "XYZ"] for c in commands
                             if all(a in c.Parameters for a in "XYZ")], dtype=float).reshape(-1, 3)
            if len(ends):
                corners.append([ends.min(axis=0), ends.max(axis=0)])
            continue
        for name in ("Shape", "Mesh", "Points"):
            box = getattr(getattr(obj, name, None), "BoundBox", None)
            if box is not None and box.isValid():
                corners.append([(box.XMin, box.YMin, box.ZMin), (box.XMax, box.YMax, box.ZMax)])
                break
    if not corners:
        return None
    corners = np.asarray(corners, dtype=float)
    return np.array([corners[:, 0].min(axis=0), corners[:, 1].max(axis=0)])


def screen_box(view, points) -> tuple:
    """(x0, y0, x1, y1) in view pixels (Coin: origin bottom-left) of points projected by the camera."""
    from workcal_wb.gui.picking import project

    xy, valid = project(view, np.asarray(points, dtype=float).reshape(-1, 3))
    xy = xy[valid]
    return tuple(np.concatenate([xy.min(axis=0), xy.max(axis=0)]).tolist())


def box_corners(box: np.ndarray) -> np.ndarray:
    """The 8 corners of a (2, 3) box."""
    return np.array([[box[i][0], box[j][1], box[k][2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)])


def boxed_canvas(width: int, height: int, font, inset: int = 0, radius: float = 4, fill_alpha: int = 225):
    """A transparent RGBA image with a light rounded box drawn in it (``inset`` pixels from its edges), and
    a painter on it in ``font`` (the caller draws on, then calls ``painter.end()``): what overlays of the
    3D view are drawn on, so they read over any scene."""
    from workcal_wb.gui.task_panels import QtCore, QtGui

    image = QtGui.QImage(width, height, QtGui.QImage.Format_RGBA8888)
    image.fill(QtGui.QColor(0, 0, 0, 0))
    painter = QtGui.QPainter(image)
    painter.setRenderHint(QtGui.QPainter.Antialiasing, True)
    painter.setFont(font)
    painter.setPen(QtGui.QColor(100, 100, 100))
    painter.setBrush(QtGui.QColor(255, 255, 255, fill_alpha))
    painter.drawRoundedRect(QtCore.QRectF(inset + 0.5, inset + 0.5, width - 2 * inset - 1, height - 2 * inset - 1),
                            radius, radius)
    painter.setPen(QtGui.QColor(*[int(255 * c) for c in LABEL_COLOUR]))
    return image, painter


def overlay_font(pixels: int):
    """The application's font at a size in pixels (crisp at any screen scale)."""
    from workcal_wb.gui.task_panels import QtGui, QtWidgets

    font = QtGui.QFont(QtWidgets.QApplication.font())
    font.setPixelSize(pixels)
    return font


def text_image(text: str, pixels: int = LABEL_PIXELS):
    """A label as a QImage: the text in the application's font on a light rounded box."""
    from workcal_wb.gui.task_panels import QtGui

    font = overlay_font(pixels)
    metrics = QtGui.QFontMetrics(font)
    width = metrics.boundingRect(text).width() + 2 * LABEL_PADDING + 2
    image, painter = boxed_canvas(width, metrics.height() + LABEL_PADDING + 2, font)
    painter.drawText(LABEL_PADDING + 1, LABEL_PADDING // 2 + 1 + metrics.ascent(), text)
    painter.end()
    return image


def image_node(image, horizontal: str = "CENTER", vertical: str = "BOTTOM"):
    """A Coin node drawing ``image`` (QImage, RGBA) pixel for pixel, anchored at the current position."""
    from pivy import coin

    flipped = image.mirrored(False, True)  # Coin's rows go bottom-up
    node = coin.SoImage()
    node.image.setValue(coin.SbVec2s(image.width(), image.height()), 4, bytes(flipped.constBits()))
    node.horAlignment = getattr(coin.SoImage, horizontal)
    node.vertAlignment = getattr(coin.SoImage, vertical)
    return node


class Labels:
    """Plain-word labels in a 3D view: each a text at a point of the document, drawn over the scene
    (never hidden by it) on a light box, in the application's font."""

    def __init__(self, view):
        from pivy import coin

        self.view = view
        self.root = coin.SoAnnotation()
        self.root.setName(LABEL_NODE)
        self.texts = []
        view.getSceneGraph().addChild(self.root)

    def show(self, labels) -> None:
        """Replace the labels by ``labels``: (text, (x, y, z)) pairs; the text's box sits above the point."""
        from pivy import coin

        self.root.removeAllChildren()
        self.texts = [text for text, _ in labels]
        pick = coin.SoPickStyle()
        pick.style = coin.SoPickStyle.UNPICKABLE
        self.root.addChild(pick)
        for text, point in labels:
            sep = coin.SoSeparator()
            move = coin.SoTranslation()
            move.translation = tuple(float(v) for v in point)
            sep.addChild(move)
            sep.addChild(image_node(text_image(text)))
            self.root.addChild(sep)

    def remove(self) -> None:
        try:
            self.view.getSceneGraph().removeChild(self.root)
        except (RuntimeError, AttributeError):  # the view was closed with its document
            pass


def label_points(view, boxes) -> list:
    """Where the labels of the objects in ``boxes`` go: above each object's top edge as the camera sees it,
    else below its bottom edge, else on its middle: the first place on the screen that covers no earlier
    label."""
    from pivy import coin

    from workcal_wb.gui.picking import project

    width, height = view.getSize()
    up = np.array(view.getCameraNode().orientation.getValue().multVec(coin.SbVec3f(0, 1, 0)).getValue())
    placed, taken = [], []
    for box in boxes:
        centre = box.mean(axis=0)
        reach = float(np.max((box_corners(box) - centre) @ up)) * 1.08
        candidates = [centre + side * up * reach for side in (1.0, -1.0, 0.0)]
        screen = project(view, np.array(candidates))[0]
        fits = [LABEL_CLEARANCE_PX <= x <= width - LABEL_CLEARANCE_PX and 0 <= y <= height - LABEL_CLEARANCE_PX
                and all(np.abs(np.array([x, y]) - other).max() > LABEL_CLEARANCE_PX for other in taken)
                for x, y in screen]
        choice = fits.index(True) if any(fits) else 2
        placed.append(tuple(candidates[choice]))
        taken.append(screen[choice])
    return placed


def navigation_cube_rect(width: int, height: int):
    """(x0, y0, x1, y1) in view pixels (Qt: origin top-left) that FreeCAD's navigation cube covers,
    from its preferences (FreeCAD 1.x keeps them under NaviCube, 0.20 the corner under View); None
    when the cube is hidden."""
    view = FreeCAD.ParamGet("User parameter:BaseApp/Preferences/View")
    cube = FreeCAD.ParamGet("User parameter:BaseApp/Preferences/NaviCube")
    if not view.GetBool("ShowNaviCube", True):
        return None
    corner = cube.GetInt("CornerNaviCube", view.GetInt("CornerNaviCube", 1))  # 0 TL, 1 TR, 2 BL, 3 BR
    size = cube.GetInt("CubeSize", 0) or view.GetInt("NaviWidgetSize", 0) or 132
    ox, oy = cube.GetInt("OffsetX", 0), cube.GetInt("OffsetY", 0)
    x0 = width - size - ox if corner in (1, 3) else ox
    y0 = oy if corner in (0, 1) else height - size - oy
    return (x0, y0, x0 + size, y0 + size)
