"""Draw a scan shaded by its surfaces instead of flat grey: each point's grey lit by its surface normal
(``core.pointops.shading``), with the light beside the scanner so that slopes, edges and the part's
relief show.  Display only: nothing is stored in the document.

The shaded copy is a ``SoSwitch`` named "WorkCalShading" in the scan's view-provider root, drawn over
FreeCAD's own points at the same depth (``SoDepthBuffer`` LEQUAL) and under the region overlay
(``region_display``), which comes after it in the root.  The brightness is worked out once per cloud
(on the main thread: normals of a million points take seconds) and kept on the view provider's proxy.
"""
from __future__ import annotations

import numpy as np

from workcal_wb.core.errors import WorkCalError

NODE_NAME = "WorkCalShading"
# The greys the brightness maps to: dark enough for the region colours to stand out, light enough that
# the darkest slopes still read on FreeCAD's background.
DARKEST, LIGHTEST = 0.2, 0.75
# The light stands beside the scanner, off its axis by this share of the distance to the scan (light
# from the scanner itself makes every surface it saw about equally bright).
LIGHT_OFFSET = 0.6


def _coin():
    from pivy import coin

    return coin


def _node(root, create: bool, before: str | None = None):
    """The shading switch of a view-provider root (made, when ``create``, before the child ``before``)."""
    coin = _coin()
    names = [root.getChild(i).getName().getString() for i in range(root.getNumChildren())]
    if NODE_NAME in names:
        return root.getChild(names.index(NODE_NAME))
    if not create:
        return None
    switch = coin.SoSwitch()
    switch.setName(NODE_NAME)
    if before in names:
        root.insertChild(switch, names.index(before))
    else:
        root.addChild(switch)
    return switch


def _cloud_key(obj) -> tuple:
    return (getattr(obj, "PointCount", 0), str(obj.Points.BoundBox), str(obj.Placement))


def brightness_of(points: np.ndarray, normals) -> np.ndarray:
    """The brightness of each point of a scan."""
    from workcal_wb.core.pointops import shading

    distance = float(np.linalg.norm(np.median(points, axis=0))) or 1.0
    light = np.array([LIGHT_OFFSET, -LIGHT_OFFSET, 0.0]) * distance  # the scanner stands at the scan's origin
    return shading(points, light, normals)


def update(obj) -> bool:
    """Draw the scan ``obj`` shaded, its brightness worked out once per cloud on the main thread (a
    worker's result could arrive for an object whose document has closed); whether it is drawn shaded."""
    from workcal_wb.fc import scan as fc_scan

    vobj = getattr(obj, "ViewObject", None)
    if vobj is None or getattr(vobj, "RootNode", None) is None:
        return False
    key = _cloud_key(obj)
    cached = getattr(vobj.Proxy, "_shading", None)
    if cached is None or cached[0] != key:
        try:
            cloud = fc_scan.scan_cloud(obj)
            cached = (key, brightness_of(cloud.points, cloud.normals))
        except WorkCalError:
            return False
        vobj.Proxy._shading = cached
    return _draw(obj, cached[1])


def wait(obj, timeout_s: float = 60.0) -> bool:
    """Let the event loop run until the scan ``obj`` is drawn shaded (for tests and scripts); whether it is."""
    import time

    from workcal_wb.gui.task_panels.common import process_events

    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if shown(obj):
            return True
        process_events(0.05)
    return shown(obj)


def _draw(obj, values: np.ndarray) -> bool:
    """Draw the scan ``obj`` with ``values`` as its points' brightness."""
    from workcal_wb.fc import scan as fc_scan
    from workcal_wb.gui.region_display import OVERLAY_NAME, _local_points

    vobj = obj.ViewObject
    try:
        points = _local_points(obj, fc_scan.scan_cloud(obj).points)
    except WorkCalError:
        return False
    if len(points) != len(values):
        return False
    coin = _coin()
    switch = _node(vobj.RootNode, create=True, before=OVERLAY_NAME)
    switch.removeAllChildren()
    group = coin.SoSeparator()
    pick = coin.SoPickStyle()  # FreeCAD's own points below stay the ones picked and preselected
    pick.style = coin.SoPickStyle.UNPICKABLE
    group.addChild(pick)
    light = coin.SoLightModel()
    light.model = coin.SoLightModel.BASE_COLOR
    group.addChild(light)
    if hasattr(coin, "SoDepthBuffer"):  # over the scan's own points, at the same depth
        depth = coin.SoDepthBuffer()
        depth.function = coin.SoDepthBuffer.LEQUAL
        group.addChild(depth)
    style = coin.SoDrawStyle()
    style.pointSize = float(getattr(vobj, "PointSize", 2.0))
    group.addChild(style)
    grey = (DARKEST + (LIGHTEST - DARKEST) * values).astype(np.float32)
    material = coin.SoMaterial()
    material.diffuseColor.setValues(0, len(grey), np.repeat(grey[:, None], 3, axis=1).tolist())
    group.addChild(material)
    binding = coin.SoMaterialBinding()
    binding.value = coin.SoMaterialBinding.PER_VERTEX
    group.addChild(binding)
    coords = coin.SoCoordinate3()
    coords.point.setValues(0, len(points), points.astype(np.float32).tolist())
    group.addChild(coords)
    group.addChild(coin.SoPointSet())
    switch.addChild(group)
    set_visible(obj, bool(getattr(vobj, "Visibility", True)))
    return True


def set_visible(obj, visible: bool) -> None:
    vobj = getattr(obj, "ViewObject", None)
    switch = _node(vobj.RootNode, create=False) if vobj is not None else None
    if switch is not None:
        coin = _coin()
        switch.whichChild = coin.SO_SWITCH_ALL if visible else coin.SO_SWITCH_NONE


def shown(obj) -> bool:
    """Whether the shaded scan is drawn now."""
    vobj = getattr(obj, "ViewObject", None)
    switch = _node(vobj.RootNode, create=False) if vobj is not None else None
    return switch is not None and switch.getNumChildren() > 0 and \
        switch.whichChild.getValue() == _coin().SO_SWITCH_ALL


def shown_colours(obj):
    """The (N, 3) colours the shaded scan is drawn with, read from the scene graph (None when not shaded)."""
    vobj = getattr(obj, "ViewObject", None)
    switch = _node(vobj.RootNode, create=False) if vobj is not None else None
    if switch is None or switch.getNumChildren() == 0:
        return None
    coin = _coin()
    group = switch.getChild(0)
    for i in range(group.getNumChildren()):
        node = group.getChild(i)
        if node.isOfType(coin.SoMaterial.getClassTypeId()):
            return np.array([c.getValue() for c in node.diffuseColor.getValues()], dtype=np.float64).reshape(-1, 3)
    return None
