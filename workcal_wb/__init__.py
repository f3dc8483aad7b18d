"""WorkCal: place a freeform workpiece in a robot's frame by matching one 3D scan to its model.

``workcal_wb.core`` is plain numpy/scipy/open3d and works without FreeCAD; ``workcal_wb.fc`` adapts it
to FreeCAD documents and ``workcal_wb.gui`` is the workbench.
"""
import os

__version__ = "0.1.0"

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RESOURCES = os.path.join(ROOT, "resources")
ICONS = os.path.join(RESOURCES, "icons")
TRANSLATIONS = os.path.join(RESOURCES, "translations")


def icon(name: str) -> str:
    """Absolute path of an SVG icon in resources/icons (name without extension)."""
    return os.path.join(ICONS, name + ".svg")
