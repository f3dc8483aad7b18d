"""Toolpaths in, calibrated robot and CNC programs out (FreeCAD-free).

Read a path in the workpiece frame X (``read_gcode``, or ``workcal_wb.fc.toolpath`` for FreeCAD Path/CAM
jobs), then ``export`` it through W = ^B X to KRL, RAPID, URScript, Fanuc LS, G-code or CSV (a robot program
checked against the robot that runs it when one is given: reach.py).
"""
from .exporters import FORMATS, export, format_for
from .exporters.gcode import format_gcode
from .gcode import parse_gcode, read_gcode
from .model import ARC_CCW, ARC_CW, LINEAR, RAPID, Event, Move, RotaryTable, Toolpath
from .safety import (MACHINES, CalibrationNotOk, Envelope, ExportOptions, ExportRefused, ReachRefused, ToolTilted,
                     checked_placement)
from .transform import DEFAULT_CHORD_TOL_MM, linearised, path_points, placement, transformed

__all__ = ["FORMATS", "export", "format_for", "format_gcode", "parse_gcode", "read_gcode", "ARC_CCW", "ARC_CW", "LINEAR", "RAPID",
           "Event", "Move", "RotaryTable", "Toolpath", "MACHINES", "CalibrationNotOk", "Envelope", "ExportOptions",
           "ExportRefused", "ReachRefused", "ToolTilted",
           "checked_placement", "DEFAULT_CHORD_TOL_MM", "linearised", "path_points", "placement", "transformed"]
