"""The FreeCAD GUI layer: workbench, commands, task panels, 3D-view picking.  Calls only workcal_wb.fc."""
