"""FreeCAD-free core: frames, readers, matching, calibration, toolpaths, simulation, studies, reports."""
