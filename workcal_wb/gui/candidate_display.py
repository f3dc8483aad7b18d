"""The poses an ambiguous calibration left, drawn in the 3D view so that a person sees what changes
between them: for each pose the workpiece frame's axes (X, Y, Z at their tips) and the toolpath where
the robot would run it were that pose chosen, each pose in its own colour, the pose shown drawn
thicker and labelled.

One ``SoSeparator`` named OVERLAY_NAME in the view's scene graph, in document coordinates (each pose
is the workpiece frame X placed in the scan, ``core.choice.workpiece_placements``: for a reference
pose not the reference's own transform but where the workpiece would be), drawn over the scan (no
depth test) so that a toolpath inside the scan's points still shows.  ``drawn(view)`` reads it back.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from workcal_wb.core import frames

OVERLAY_NAME = "WorkCalCandidatePoses"
# One colour per pose, in order (cycled past the last): apart from each other, from the regions'
# orange and blue and from the deviation map's red-green.
COLOURS = ((0.10, 0.45, 1.00), (1.00, 0.30, 0.85), (0.00, 0.75, 0.75), (0.95, 0.80, 0.00), (0.55, 0.25, 1.00),
           (0.60, 0.40, 0.20))
SHOWN_WIDTH, OTHER_WIDTH = 4.0, 1.5  # line widths (px) of the pose shown and of the others
# The toolpath drawn with at most this many points per pose (evenly thinned): a view, not the program.
MAX_PATH_POINTS = 5000


def colour(index: int) -> tuple:
    """The colour of pose ``index`` (0: the best)."""
    return COLOURS[index % len(COLOURS)]


def hex_colour(index: int) -> str:
    return "#" + "".join(f"{round(255 * c):02x}" for c in colour(index))


@dataclass
class Poses:
    """What to draw: the workpiece frame X placed in the scan for each pose (4x4s, best first), which
    is shown, the length of the frame's axes (mm) and the toolpath's points in X (None: no toolpath)."""

    matrices: list
    shown: int
    frame_mm: float
    toolpath: np.ndarray | None = None


def _coin():
    from pivy import coin

    return coin


def _root(view):
    return view.getSceneGraph()


def _find(view):
    root = _root(view)
    for i in range(root.getNumChildren()):
        if root.getChild(i).getName().getString() == OVERLAY_NAME:
            return root.getChild(i)
    return None


def clear(view) -> None:
    found = _find(view)
    if found is not None:
        _root(view).removeChild(found)


def draw(view, poses: Poses | None) -> None:
    """Draw ``poses`` in ``view`` in place of what was drawn (None: only clear)."""
    clear(view)
    if poses is None or view is None:
        return
    coin = _coin()
    overlay = coin.SoSeparator()
    overlay.setName(OVERLAY_NAME)
    light = coin.SoLightModel()
    light.model = coin.SoLightModel.BASE_COLOR
    overlay.addChild(light)
    if hasattr(coin, "SoDepthBuffer"):
        depth = coin.SoDepthBuffer()
        depth.test = False
        overlay.addChild(depth)
    path = None if poses.toolpath is None or len(poses.toolpath) < 2 else _thinned(np.asarray(poses.toolpath))
    order = [i for i in range(len(poses.matrices)) if i != poses.shown] + [poses.shown]  # the shown one on top
    for index in order:
        overlay.addChild(_pose(index, poses.matrices[index], index == poses.shown, poses.frame_mm, path))
    _root(view).addChild(overlay)


def _thinned(points: np.ndarray) -> np.ndarray:
    if len(points) <= MAX_PATH_POINTS:
        return points
    return points[np.linspace(0, len(points) - 1, MAX_PATH_POINTS).astype(np.int64)]


def _pose(index: int, T: np.ndarray, shown: bool, size: float, path):
    coin = _coin()
    part = coin.SoSeparator()
    part.setName(f"WorkCalPose_{index}")
    base = coin.SoBaseColor()
    base.rgb = colour(index)
    part.addChild(base)
    style = coin.SoDrawStyle()
    style.lineWidth = SHOWN_WIDTH if shown else OTHER_WIDTH
    part.addChild(style)
    origin = T[:3, 3]
    tips = [origin + size * T[:3, axis] for axis in range(3)]
    _lines(part, [[origin, tip] for tip in tips], "WorkCalAxes")
    if path is not None:
        _lines(part, [frames.apply(T, path)], "WorkCalToolpath")
    words = [(tip, name) for tip, name in zip(tips, "XYZ")] if shown else []
    words.append((origin, f"pose {index + 1}"))
    for where, text in words:
        place = coin.SoSeparator()
        move = coin.SoTranslation()
        move.translation = [float(v) for v in where]
        note = coin.SoText2()
        note.string = text
        place.addChild(move)
        place.addChild(note)
        part.addChild(place)
    return part


def _lines(parent, polylines, name: str) -> None:
    coin = _coin()
    group = coin.SoSeparator()
    group.setName(name)
    points = np.vstack(polylines).astype(np.float32)
    coords = coin.SoCoordinate3()
    coords.point.setValues(0, len(points), points.tolist())
    lines = coin.SoLineSet()
    lines.numVertices.setValues(0, len(polylines), [len(p) for p in polylines])
    group.addChild(coords)
    group.addChild(lines)
    parent.addChild(group)


def drawn(view) -> dict:
    """What the overlay shows: {pose index: {"colour", "width", "axes": (3, 2, 3) from-to points,
    "toolpath": (N, 3) points or None}} (tests read it back)."""
    overlay = _find(view)
    out = {}
    if overlay is None:
        return out
    for i in range(overlay.getNumChildren()):
        part = overlay.getChild(i)
        name = part.getName().getString()
        if not name.startswith("WorkCalPose_"):
            continue
        entry = {"colour": tuple(round(c, 3) for c in part.getChild(0).rgb.getValues()[0].getValue()),
                 "width": part.getChild(1).lineWidth.getValue(), "toolpath": None}
        for j in range(part.getNumChildren()):
            child = part.getChild(j)
            kind = child.getName().getString()
            if kind in ("WorkCalAxes", "WorkCalToolpath"):
                points = np.array([tuple(p.getValue()) for p in child.getChild(0).point.getValues()])
                entry["axes" if kind == "WorkCalAxes" else "toolpath"] = \
                    points.reshape(3, 2, 3) if kind == "WorkCalAxes" else points
        out[int(name.split("_")[1])] = entry
    return out
