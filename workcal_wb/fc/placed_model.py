"""The workpiece model shown where W puts it, in the robot base frame B: a copy that follows W.

Not an ``App::Link``: undoing the creation of a link corrupts the document in FreeCAD before 1.1 (a
nameless ghost object, duplicated by redo, and a crash when the document closes: FreeCAD issues
17900 and 18326).  A copy of the model's geometry is undone like any other object.  It is rebuilt
by recompute whenever the model or the calibration changes, so it always shows X-A moved by W.
"""
from __future__ import annotations

import FreeCAD

from workcal_wb.core.errors import InputError
from workcal_wb.fc import init as fc_init
from workcal_wb.fc import models
from workcal_wb.fc.placements import container_matrix, matrix_of, placement
from workcal_wb.fc.proxies import Feature

ROLE = "WorkCalPlacedModel"  # value of the hidden WorkCalRole property
# The document object type that can hold a copy of each kind of model.
TYPES = {"shape": "Part::FeaturePython", "mesh": "Mesh::FeaturePython", "points": "Points::FeaturePython"}
GEOMETRY = {"shape": "Shape", "mesh": "Mesh", "points": "Points"}


class PlacedModel(Feature):
    """Copies the Source model's geometry, as the document shows it, and places it by the
    Calibration's W."""

    def setup(self, obj):
        for kind, name, tip in (
                ("App::PropertyLink", "Source", "The workpiece model X-A that is shown placed"),
                ("App::PropertyLink", "Calibration", "The calibration whose W places it"),
                ("App::PropertyString", "WorkCalRole", "What this object is to WorkCal")):
            if not hasattr(obj, name):
                obj.addProperty(kind, name, "Placed model", tip)
        obj.setEditorMode("WorkCalRole", 2)
        obj.WorkCalRole = ROLE
        for name in ("Source", "Calibration"):
            obj.setEditorMode(name, 1)

    def execute(self, obj):
        source, calibration = obj.Source, obj.Calibration
        if source is None or calibration is None:
            return
        kind, data = models.kind_of(source)
        if kind == "shape":  # Part.getShape placed it as the document shows it, containers included
            data = data.copy()
            shape_matrix = matrix_of(data.Placement)
            data.Placement = FreeCAD.Placement()
            setattr(obj, GEOMETRY[kind], data)
            obj.Placement = placement(matrix_of(calibration.Placement) @ shape_matrix)
        elif kind is not None:
            container = container_matrix(source)
            source_matrix = matrix_of(source.Placement)
            if container is not None:
                source_matrix = container @ source_matrix
            data = data.copy()
            data.Placement = FreeCAD.Placement()
            setattr(obj, GEOMETRY[kind], data)
            obj.Placement = placement(matrix_of(calibration.Placement) @ source_matrix)


def find(calibration):
    """The placed model of ``calibration``, or None."""
    return next((o for o in calibration.InList if getattr(o, "WorkCalRole", None) == ROLE), None)


def make_placed_model(calibration):
    """The workpiece model of ``calibration`` placed by its W (new, or the one it already has)."""
    existing = find(calibration)
    if existing is not None:
        return existing
    source = calibration.Workpiece
    if source is None:
        raise InputError(f"{calibration.Label}: has no workpiece model to place")
    kind = models.check_model(source)
    obj = calibration.Document.addObject(TYPES[kind], f"{calibration.Name}_PlacedModel")
    PlacedModel(obj)
    fc_init.attach_view_provider(obj, "PlacedModel")
    obj.Source, obj.Calibration = source, calibration
    obj.Label = f"{source.Label} in B ({calibration.Label})"
    obj.recompute()
    return obj
