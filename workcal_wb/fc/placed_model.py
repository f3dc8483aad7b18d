"""A model shown where a calibration puts it: a copy of its geometry that follows the calibration.

Two views of a calibration, so a designer can check it at a glance:

* **on the scan** (frame S): the workpiece model placed by U and the reference model by V, over the
  scan points they were matched to; for an ambiguous result ``Candidate`` steps through the other
  poses the match found;
* **in the robot frame** (frame B): the workpiece model placed by W, beside the reference model,
  where the robot will machine it.

Not an ``App::Link``: undoing the creation of a link corrupts the document in FreeCAD before 1.1 (a
nameless ghost object, duplicated by redo, and a crash when the document closes: FreeCAD issues
17900 and 18326).  A copy is undone like any other object, and rebuilt by recompute whenever the
model or the calibration changes.
"""
from __future__ import annotations

import numpy as np

import FreeCAD

from workcal_wb.core import choice, frames
from workcal_wb.core.errors import InputError
from workcal_wb.fc import models
from workcal_wb.fc.lookups import result_of
from workcal_wb.fc.placements import container_matrix, matrix_of, placement
from workcal_wb.fc.proxies import Feature, add_properties, objects_of
from workcal_wb.fc.undo import transaction

translate = FreeCAD.Qt.translate
QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP

TYPE = "WorkCal::PlacedModel"
ON_SCAN, IN_ROBOT_FRAME = "Scan", "RobotBase"
ROLES = ("workpiece", "reference")
# The document object type that can hold a copy of each kind of model.
TYPES = {"shape": "Part::FeaturePython", "mesh": "Mesh::FeaturePython", "points": "Points::FeaturePython"}
GEOMETRY = {"shape": "Shape", "mesh": "Mesh", "points": "Points"}
LABELS = {(ON_SCAN, "workpiece"): QT_TRANSLATE_NOOP("WorkCal", "Workpiece model on the scan"),
          (ON_SCAN, "reference"): QT_TRANSLATE_NOOP("WorkCal", "Reference model on the scan"),
          (IN_ROBOT_FRAME, "workpiece"): QT_TRANSLATE_NOOP("WorkCal", "Workpiece model in the robot frame")}
PROPERTIES = [
    ("App::PropertyLink", "Source", "Placed model", QT_TRANSLATE_NOOP("App::Property", "The model that is shown placed")),
    ("App::PropertyLink", "Calibration", "Placed model", QT_TRANSLATE_NOOP("App::Property", "The calibration that "
                                                                                          "places it")),
    ("App::PropertyEnumeration", "Frame", "Placed model", QT_TRANSLATE_NOOP(
        "App::Property", "Scan: over the scan points (workpiece by U, reference by V); RobotBase: in the robot base "
                         "frame (workpiece by W)")),
    ("App::PropertyEnumeration", "Role", "Placed model", QT_TRANSLATE_NOOP("App::Property", "Which model it is")),
    ("App::PropertyInteger", "Candidate", "Placed model", QT_TRANSLATE_NOOP(
        "App::Property", "0: the calibration's pose; 1, 2...: the other poses the match found (for an ambiguous "
                         "result)")),
]


def candidates(calibration, role: str) -> list:
    """The poses of ``role``'s model the calibration's match could not tell apart, best first, as
    (4x4 model -> scan transform, the model symmetry that gives it or None): the pose the calibration
    found (first also after a person chose another), the rival poses the match found that nothing ruled
    out, and the poses the model's symmetries give when the match says it is symmetric
    (``core.choice.poses``)."""
    return [(p.matrix, p.symmetry) for p in choice.poses(result_of(calibration), role)]


def candidate_poses(calibration, role: str) -> list:
    """The 4x4 model -> scan transforms of ``candidates``, the calibration's own first."""
    return [T for T, _ in candidates(calibration, role)]


def pose(calibration, role: str, frame: str, candidate: int = 0) -> np.ndarray:
    """Where the model of ``role`` is drawn (a 4x4 from its document coordinates)."""
    poses = candidate_poses(calibration, role)
    if not poses:
        raise InputError(f"{calibration.Label}: the {role} match found no pose")
    if not 0 <= candidate < len(poses):
        raise InputError(f"{calibration.Label}: the {role} match has {len(poses)} pose(s), no pose {candidate}")
    if frame == ON_SCAN:
        return poses[candidate]
    if role != "workpiece":
        raise InputError("the reference model is in the robot base frame already")
    result = result_of(calibration)
    if result.V is None:
        raise InputError(f"{calibration.Label}: the reference match failed, there is no W")
    return result.W if candidate == 0 else frames.invert(result.V) @ poses[candidate]  # 0: W, also a chosen one


class PlacedModel(Feature):
    """Copies the Source model's geometry, as the document shows it, and places it by the calibration."""

    TYPE = TYPE

    def setup(self, obj):
        add_properties(obj, PROPERTIES, read_only=("Source", "Calibration", "Frame", "Role"))
        if not obj.getEnumerationsOfProperty("Frame"):
            obj.Frame = [ON_SCAN, IN_ROBOT_FRAME]
            obj.Frame = IN_ROBOT_FRAME  # what files of earlier WorkCal versions held
        if not obj.getEnumerationsOfProperty("Role"):
            obj.Role = list(ROLES)
            obj.Role = "workpiece"

    def execute(self, obj):
        source, calibration = obj.Source, obj.Calibration
        if source is None or calibration is None:
            return
        T = pose(calibration, obj.Role, obj.Frame, obj.Candidate)
        kind, data = models.kind_of(source)
        data = data.copy()
        if kind == "shape":  # Part.getShape placed it as the document shows it, containers included
            source_matrix = matrix_of(data.Placement)
        else:  # Mesh and Points kernels carry the object's own Placement; containers come on top
            container = container_matrix(source)
            source_matrix = matrix_of(source.Placement) if container is None else container @ matrix_of(source.Placement)
        data.Placement = FreeCAD.Placement()
        setattr(obj, GEOMETRY[kind], data)
        obj.Placement = placement(T @ source_matrix)


def find(calibration, role: str = "workpiece", frame: str = IN_ROBOT_FRAME):
    """The placed model of ``calibration`` for ``role`` in ``frame``, or None."""
    return next((o for o in objects_of(calibration.Document, TYPE)
                 if o.Calibration is calibration and o.Role == role and o.Frame == frame), None)


def make_placed_model(calibration, role: str = "workpiece", frame: str = IN_ROBOT_FRAME):
    """The model of ``role`` placed by ``calibration`` in ``frame`` (new, or the one it already has).
    No transaction: see ``show_on_scan`` and ``show_in_robot_frame``."""
    existing = find(calibration, role, frame)
    if existing is not None:
        return existing
    if (frame, role) not in LABELS:
        raise InputError(f"no placed {role} model in frame {frame!r}")
    source = calibration.Workpiece if role == "workpiece" else calibration.Reference
    if source is None:
        raise InputError(f"{calibration.Label}: has no {role} model to place")
    kind = models.check_model(source)
    pose(calibration, role, frame)  # refuse before the document changes
    obj = calibration.Document.addObject(TYPES[kind], f"{calibration.Name}_{role.capitalize()}{frame}")
    PlacedModel(obj)
    obj.Frame, obj.Role = frame, role
    obj.Source, obj.Calibration = source, calibration
    obj.Label = translate("WorkCal", LABELS[(frame, role)])
    obj.recompute()
    return obj


def add_on_scan(calibration) -> list:
    """The models placed over the scan, for each match that found a pose (no transaction: the caller's)."""
    return [make_placed_model(calibration, role, ON_SCAN) for role in ROLES if candidate_poses(calibration, role)]


def show_on_scan(calibration) -> list:
    """The models placed over the scan (workpiece by U, reference by V); the missing ones are added in
    one undo step."""
    found = [o for o in (find(calibration, role, ON_SCAN) for role in ROLES) if o is not None]
    if len(found) == len([r for r in ROLES if candidate_poses(calibration, r)]):
        return found
    doc = calibration.Document
    with transaction(doc, translate("WorkCal", "Show the models on the scan")):
        found = add_on_scan(calibration)
        doc.recompute()
    return found


def show_in_robot_frame(calibration):
    """The workpiece model placed by W in the robot base frame, in one undo step."""
    doc = calibration.Document
    with transaction(doc, translate("WorkCal", "Show the workpiece model in the robot frame")):
        obj = make_placed_model(calibration, "workpiece", IN_ROBOT_FRAME)
        doc.recompute()
    return obj


def show_candidate(calibration, candidate: int):
    """Place the workpiece and reference models on the scan at their ``candidate``-th pose (0: the
    calibration's own; clamped per role to the poses found).  Not an undo step: a way of looking."""
    shown = []
    for obj in show_on_scan(calibration):
        count = len(candidate_poses(calibration, obj.Role))
        obj.Candidate = min(max(int(candidate), 0), max(count - 1, 0))
        obj.recompute()
        shown.append(obj)
    return shown


def show_chosen(calibration) -> None:
    """Place the models on the scan at the poses the calibration holds: the chosen one of the match a
    person chose a pose of, the best of the other (no transaction: the caller's)."""
    record = result_of(calibration).choice
    for obj in (find(calibration, role, ON_SCAN) for role in ROLES):
        if obj is not None:
            obj.Candidate = record.index if record is not None and record.role == obj.Role else 0
            obj.recompute()


# Of the model's points, the share that moves most between two poses: where a scan tells them apart.
TELLING_SHARE = 0.1
# The model is its own image under the turn between two poses when this share of its points lands
# within the tolerance of its surface (the rest: edges and sampling).
SYMMETRIC_SHARE = 0.95


def tie_breaker(calibration, role: str, candidate: int = 1) -> str:
    """The sentence on what would tell the calibration's pose of ``role`` from its ``candidate``-th rival:
    that no scan can when the model is symmetric under the turn between them, else where on the model
    the two differ most."""
    from workcal_wb.core.surface import SurfaceModel

    found = candidates(calibration, role)
    if len(found) <= candidate:
        return ""
    name = translate("WorkCal", "workpiece") if role == "workpiece" else translate("WorkCal", "reference object")
    symmetric = translate("WorkCal", "The {} model is symmetric ({}): no scan can tell these poses apart; only a "
                                     "feature that breaks the symmetry (a mark, a fixture) would.")
    rival, symmetry = found[candidate]
    if symmetry is not None:
        return symmetric.format(name, symmetry.get("description", ""))
    tolerance = result_of(calibration).tolerance_mm
    source = calibration.Workpiece if role == "workpiece" else calibration.Reference
    surface = SurfaceModel(models.model_cloud(source, role=role))
    points = surface.points
    moved = frames.apply(frames.invert(found[0][0]) @ rival, points)  # the rival, in the best pose's model frame
    _, idx, near = surface.nearest(moved, 3 * surface.spacing + tolerance)
    onto = near & (np.abs(surface.plane_residuals(moved, idx)) <= tolerance)
    if onto.mean() >= SYMMETRIC_SHARE:
        return symmetric.format(name, translate("WorkCal", "turned as the other pose turns it, it covers itself"))
    apart = np.linalg.norm(moved - points, axis=1)
    telling = points[apart >= np.quantile(apart, 1 - TELLING_SHARE)]
    x, y, z = telling.mean(axis=0)
    return translate("WorkCal", "The two poses of the {} differ most around ({:.0f}, {:.0f}, {:.0f}) mm on its "
                                "model, by up to {:.1f} mm: a scan that sees that part clearly, or a region picked to "
                                "include it, would tell them apart.").format(name, x, y, z, apart.max())
