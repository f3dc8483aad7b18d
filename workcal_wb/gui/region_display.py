"""Show a scan's regions in the 3D view: the region points drawn again, larger and coloured, and after
a calibration each region's points off its placed model over them, larger still, in red.

The overlay is a ``SoSwitch`` named "WorkCalRegions" appended to the scan's view-provider root, so it
moves with the object's Placement and is hidden with it.  Coordinates are the kernel's own (the root
applies the Placement).  Regions above ``MAX_SHOWN`` points are thinned evenly for display only.
``shown_points(obj)`` reads the overlay back (tests use it to check what the user sees).  The
off-model points come from the scan's latest calibration (``fc.regions.off_model_points``).
"""
from __future__ import annotations

import numpy as np

import FreeCAD

from workcal_wb.core import frames
from workcal_wb.core.errors import WorkCalError
from workcal_wb.fc import scan as fc_scan
from workcal_wb.fc.placements import matrix_of
from workcal_wb.fc.regions import off_model_points

OVERLAY_NAME = "WorkCalRegions"
ROLES = ("workpiece", "reference")
COLORS = {"workpiece": (1.0, 0.45, 0.0), "reference": (0.0, 0.55, 1.0)}
MAX_SHOWN = 300_000
EXTRA_POINT_SIZE = 2.0
# A region's points off its placed model: red (neither region's colour), larger than the region's
# points so that they show over them (what the calibration asks the user to leave out).
OFF_MODEL_COLOR = (1.0, 0.0, 0.0)
OFF_MODEL_EXTRA_SIZE = 3.0
REGION_PART, OFF_MODEL_PART = "WorkCalRegion_", "WorkCalOffModel_"  # the overlay's parts, by role

_pending = set()  # (document name, object name) waiting for a deferred update


def _coin():
    from pivy import coin

    return coin


def _overlay(root, create: bool):
    coin = _coin()
    for i in range(root.getNumChildren()):
        child = root.getChild(i)
        if child.getName().getString() == OVERLAY_NAME:
            return child
    if not create:
        return None
    switch = coin.SoSwitch()
    switch.setName(OVERLAY_NAME)
    root.addChild(switch)
    return switch


def _local_points(obj, cloud_points: np.ndarray) -> np.ndarray:
    """Scan points (Placement applied) back in the kernel's own coordinates, as the root node expects."""
    placement = getattr(obj, "Placement", None)
    if placement is None or placement.isIdentity():
        return cloud_points
    return frames.apply(matrix_of(placement.inverse()), cloud_points)


def update(obj) -> dict:
    """Rebuild the overlay of ``obj`` from its stored regions and its latest calibration's off-model
    points; returns the number of points shown per role (and per "<role>_off_model")."""
    _pending.discard(_key(obj))
    vobj = getattr(obj, "ViewObject", None)
    if vobj is None or getattr(vobj, "RootNode", None) is None:
        return {}
    coin = _coin()
    try:
        regions = fc_scan.get_regions(obj)
    except WorkCalError as exc:
        FreeCAD.Console.PrintWarning(f"WorkCal: {exc}\n")
        regions = {"workpiece": None, "reference": None}
    wanted = {role: regions.get(role) for role in ROLES if regions.get(role) is not None}
    off_model = off_model_points(obj)
    switch = _overlay(vobj.RootNode, create=bool(wanted or off_model))
    if switch is None:
        return {}
    switch.removeAllChildren()
    shown = {}
    if wanted or off_model:
        points = _local_points(obj, fc_scan.scan_cloud(obj).points)
        size = float(getattr(vobj, "PointSize", 2.0)) + EXTRA_POINT_SIZE
        group = coin.SoSeparator()
        light = coin.SoLightModel()
        light.model = coin.SoLightModel.BASE_COLOR
        group.addChild(light)
        if hasattr(coin, "SoDepthBuffer"):  # draw over the scan's own points at the same depth
            depth = coin.SoDepthBuffer()
            depth.function = coin.SoDepthBuffer.LEQUAL
            group.addChild(depth)
        style = coin.SoDrawStyle()
        style.pointSize = size
        group.addChild(style)
        for role, idx in wanted.items():
            group.addChild(_part(REGION_PART + role, COLORS[role], points[_thinned(idx)]))
            shown[role] = len(_thinned(idx))
        for role, idx in off_model.items():  # after the regions: drawn over them
            group.addChild(_part(OFF_MODEL_PART + role, OFF_MODEL_COLOR, points[_thinned(idx)],
                                 size + OFF_MODEL_EXTRA_SIZE))
            shown[f"{role}_off_model"] = len(_thinned(idx))
        switch.addChild(group)
    set_visible(obj, bool(getattr(vobj, "Visibility", True)))
    return shown


def _thinned(idx: np.ndarray) -> np.ndarray:
    """At most MAX_SHOWN of the indices, evenly spread."""
    return idx if len(idx) <= MAX_SHOWN else idx[np.linspace(0, len(idx) - 1, MAX_SHOWN).astype(np.int64)]


def _part(name: str, colour, points: np.ndarray, size: float | None = None):
    """A named separator drawing ``points`` in ``colour`` (at ``size`` pixels, else the group's)."""
    coin = _coin()
    part = coin.SoSeparator()
    part.setName(name)
    base = coin.SoBaseColor()
    base.rgb = colour
    part.addChild(base)
    if size is not None:
        style = coin.SoDrawStyle()
        style.pointSize = size
        part.addChild(style)
    coords = coin.SoCoordinate3()
    coords.point.setValues(0, len(points), points.astype(np.float32).tolist())
    part.addChild(coords)
    part.addChild(coin.SoPointSet())
    return part


def set_visible(obj, visible: bool) -> None:
    vobj = getattr(obj, "ViewObject", None)
    switch = _overlay(vobj.RootNode, create=False) if vobj is not None else None
    if switch is not None:
        coin = _coin()
        switch.whichChild = coin.SO_SWITCH_ALL if visible else coin.SO_SWITCH_NONE


def shown_points(obj) -> dict:
    """{role: (N, 3) array of the overlay's points in kernel coordinates} as the scene graph holds them,
    and {"<role>_off_model": ...} for the points off the role's placed model drawn over them."""
    vobj = getattr(obj, "ViewObject", None)
    switch = _overlay(vobj.RootNode, create=False) if vobj is not None else None
    found = {}
    if switch is None or switch.getNumChildren() == 0:
        return found
    coin = _coin()
    group = switch.getChild(0)
    for i in range(group.getNumChildren()):
        part = group.getChild(i)
        name = part.getName().getString()
        for prefix, suffix in ((REGION_PART, ""), (OFF_MODEL_PART, "_off_model")):
            if name.startswith(prefix):
                coords = next(part.getChild(k) for k in range(part.getNumChildren())
                              if part.getChild(k).isOfType(coin.SoCoordinate3.getClassTypeId()))
                found[name[len(prefix):] + suffix] = np.array([v.getValue() for v in coords.point.getValues()],
                                                              dtype=np.float64).reshape(-1, 3)
    return found


def shown_sizes(obj) -> dict:
    """{part name: point size in pixels} of the overlay's parts that set their own (the off-model points)."""
    vobj = getattr(obj, "ViewObject", None)
    switch = _overlay(vobj.RootNode, create=False) if vobj is not None else None
    if switch is None or switch.getNumChildren() == 0:
        return {}
    coin = _coin()
    group, sizes = switch.getChild(0), {}
    for i in range(group.getNumChildren()):
        part = group.getChild(i)
        for k in range(part.getNumChildren()) if part.isOfType(coin.SoSeparator.getClassTypeId()) else ():
            if part.getChild(k).isOfType(coin.SoDrawStyle.getClassTypeId()):
                sizes[part.getName().getString()] = float(part.getChild(k).pointSize.getValue())
    return sizes


def overlay_visible(obj) -> bool:
    vobj = getattr(obj, "ViewObject", None)
    switch = _overlay(vobj.RootNode, create=False) if vobj is not None else None
    return switch is not None and switch.whichChild.getValue() == _coin().SO_SWITCH_ALL


def _key(obj):
    return (obj.Document.Name, obj.Name)


def schedule(obj) -> None:
    """Update the overlay once the event loop runs again (property changes come one at a time)."""
    key = _key(obj)
    if key in _pending:
        return
    _pending.add(key)
    from PySide import QtCore

    QtCore.QTimer.singleShot(0, lambda: _deferred(key))


def _deferred(key) -> None:
    if key not in _pending:  # updated synchronously in the meantime
        return
    _pending.discard(key)
    doc = FreeCAD.listDocuments().get(key[0])
    obj = doc.getObject(key[1]) if doc is not None else None
    if obj is not None:
        update(obj)
