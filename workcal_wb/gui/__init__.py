"""The FreeCAD GUI layer: workbench, commands, task panels, 3D-view picking.  Calls only workcal_wb.fc.

pivy is loaded first: FreeCAD 1.x no longer imports it at start-up, and until it is loaded every
scene-graph access (``vobj.RootNode``, ``view.getSceneGraph()``) raises "No SWIG wrapped library loaded".
"""
from pivy import coin  # noqa: F401
