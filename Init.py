import workcal_wb.fc.init  # noqa: F401  FreeCAD exec()s this file; the real module registers the scan import type
