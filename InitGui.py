import workcal_wb.gui.workbench  # noqa: F401  FreeCAD exec()s this file; the real module registers the workbench
