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
LABEL_FONT, LABEL_SIZE = "Sans", 15
LABEL_COLOUR = (0.1, 0.1, 0.12)


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

    group = coin.SoGroup()
    for obj in objects:
        vobj = getattr(obj, "ViewObject", None)
        if vobj is not None and vobj.Visibility:
            group.addChild(vobj.RootNode)
    if group.getNumChildren() == 0:
        return look(view, orientation)
    with without_animation(view):
        if orientation is not None:
            view.setCameraOrientation(orientation)
        camera = view.getCameraNode()
        camera.viewAll(group, view.getViewer().getSoRenderManager().getViewportRegion(), FIT_MARGIN)


def bounding_box(objects) -> np.ndarray | None:
    """(2, 3) lower and upper corners of the objects' geometry in document coordinates (None if empty)."""
    from pivy import coin

    group = coin.SoGroup()
    for obj in objects:
        vobj = getattr(obj, "ViewObject", None)
        if vobj is not None:
            group.addChild(vobj.RootNode)
    action = coin.SoGetBoundingBoxAction(coin.SbViewportRegion())
    action.apply(group)
    box = action.getBoundingBox()
    if box.isEmpty():
        return None
    return np.array([box.getMin().getValue(), box.getMax().getValue()], dtype=float)


def screen_box(view, points) -> tuple:
    """(x0, y0, x1, y1) in view pixels (Coin: origin bottom-left) of points projected by the camera."""
    from workcal_wb.gui.picking import project

    xy, valid = project(view, np.asarray(points, dtype=float).reshape(-1, 3))
    xy = xy[valid]
    return tuple(np.concatenate([xy.min(axis=0), xy.max(axis=0)]).tolist())


def box_corners(box: np.ndarray) -> np.ndarray:
    """The 8 corners of a (2, 3) box."""
    return np.array([[box[i][0], box[j][1], box[k][2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)])


class Labels:
    """Plain-word labels in a 3D view: each a text at a point of the document, drawn over the scene
    (never hidden by it) in a proportional font."""

    def __init__(self, view):
        from pivy import coin

        self.view = view
        self.root = coin.SoAnnotation()
        self.root.setName(LABEL_NODE)
        self.texts = []
        view.getSceneGraph().addChild(self.root)

    def show(self, labels) -> None:
        """Replace the labels by ``labels``: (text, (x, y, z)) pairs."""
        from pivy import coin

        self.root.removeAllChildren()
        self.texts = [text for text, _ in labels]
        if not labels:
            return
        colour = coin.SoBaseColor()
        colour.rgb = LABEL_COLOUR
        font = coin.SoFont()
        font.name, font.size = LABEL_FONT, LABEL_SIZE
        for node in (colour, font):
            self.root.addChild(node)
        for text, point in labels:
            sep = coin.SoSeparator()
            move = coin.SoTranslation()
            move.translation = tuple(float(v) for v in point)
            label = coin.SoText2()
            label.string = text
            label.justification = coin.SoText2.CENTER
            for node in (move, label):
                sep.addChild(node)
            self.root.addChild(sep)

    def remove(self) -> None:
        try:
            self.view.getSceneGraph().removeChild(self.root)
        except (RuntimeError, AttributeError):  # the view was closed with its document
            pass


def label_point(view, box: np.ndarray) -> tuple:
    """Where a label of the object in ``box`` goes: above its top edge as the camera sees it."""
    from pivy import coin

    up = np.array(view.getCameraNode().orientation.getValue().multVec(coin.SbVec3f(0, 1, 0)).getValue())
    centre = box.mean(axis=0)
    half = box_corners(box) - centre
    reach = float(np.max(half @ up))
    return tuple(centre + up * reach * 1.08)


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
