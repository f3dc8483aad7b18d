"""Document look-ups the object modules share: which object is a WorkCal scan or calibration, an
object's points or mesh kernel, a calibration's stored result, an object's name for messages.

They live apart from the objects' own modules (scan.py, calibration_object.py), which make and update
those objects out of the other modules of this folder: every module can read a scan or a calibration
through this one without importing the module that builds it.
"""
from __future__ import annotations

from workcal_wb.core.errors import InputError
from workcal_wb.core.result import CalibrationResult
from workcal_wb.fc.proxies import objects_of, type_of

# What each kind's proxy names itself (its TYPE, saved with the document).
SCAN_TYPE = "WorkCal::Scan"
CALIBRATION_TYPE = "WorkCal::Calibration"


def label(obj) -> str:
    """How a message names an object: its label, else its name, else what it is."""
    return getattr(obj, "Label", None) or getattr(obj, "Name", None) or str(obj)


def is_scan(obj) -> bool:
    """A WorkCal scan object (made by ``make_scan``)."""
    return type_of(obj) == SCAN_TYPE


def can_be_scan(obj) -> bool:
    """An object ``scan_cloud`` accepts: a WorkCal scan, any Points object or a Mesh object (cheap test)."""
    return kernel_of(obj)[0] is not None


def kernel_of(obj):
    """("points"|"mesh"|None, the object's Points or Mesh kernel), cheaply: nothing is copied."""
    if obj is None:
        return None, None
    pts = getattr(obj, "Points", None)
    if hasattr(pts, "CountPoints") and hasattr(pts, "Points"):
        return "points", pts
    mesh = getattr(obj, "Mesh", None)
    if hasattr(mesh, "Topology") and hasattr(mesh, "CountFacets"):
        return "mesh", mesh
    return None, None


def is_calibration(obj) -> bool:
    """A WorkCal calibration object (made by ``calibration_object.make_calibration``)."""
    return type_of(obj) == CALIBRATION_TYPE


def find_calibrations(doc) -> list:
    """The document's calibration objects."""
    return objects_of(doc, CALIBRATION_TYPE)


def result_of(obj) -> CalibrationResult:
    """The CalibrationResult stored on a calibration object."""
    if not is_calibration(obj):
        raise InputError(f"{label(obj)}: not a WorkCal calibration")
    if not obj.ResultJson:
        raise InputError(f"{obj.Label}: the calibration has not been computed yet")
    return CalibrationResult.from_text(obj.ResultJson, f"calibration {obj.Label!r}")
