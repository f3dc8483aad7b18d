"""The FreeCAD layer: document objects and conversions between FreeCAD and the core's numpy types."""
