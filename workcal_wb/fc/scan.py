"""Scan document objects: the full cloud for matching, regions picked on it, and reading scan files.

A WorkCal scan is a ``Points::FeaturePython`` whose ``Points`` hold every point of the scan (FreeCAD
saves them in the .FCStd as binary data).  The 3D view shows all of them: even software OpenGL redraws
a million-point cloud fast enough, so no decimated display copy is kept.  FreeCAD stores coordinates as
float32 (about 0.1 um at 1.5 m from the origin); ``make_scan`` rounds the cloud to float32 at once so
a scan gives the same numbers before and after save/reopen.

Converting FreeCAD's point list to numpy is slow for large clouds, so the scan's proxy keeps
the numpy cloud until ``Points`` or ``Placement`` change.

Regions are index arrays into ``scan_cloud(obj).points``, stored as ``App::PropertyIntegerList``
(500,000 indices set in 0.03 s and save in 0.06 s).  Any ``Points::Feature`` or ``Mesh::Feature`` can
serve as a scan too: the region properties are added to it when first set.

Coordinates: ``scan_cloud`` returns the points as FreeCAD's kernel gives them, i.e. with the
object's own ``Placement`` applied (normally the identity for a scan).  That frame is the scan frame
S of the calibration.

``import_scan`` is the File > Import use case (read, add, make it the document's scan, one undo
step); the GUI reads big files in a worker thread first with ``read_scan_file``, which remembers the
last file it read, so the command it then records and runs (replayable headless) reads nothing twice.
"""
from __future__ import annotations

import os

import numpy as np

import FreeCAD
import Points

from workcal_wb.core.errors import InputError
from workcal_wb.core.geometry import Cloud, checked
from workcal_wb.core.readers import read_cloud
from workcal_wb.core.units import extent_warnings, mm_per_unit, unit_warning
from workcal_wb.fc.memo import LastResult
from workcal_wb.fc.placements import matrix_of
from workcal_wb.fc.lookups import SCAN_TYPE, is_scan, kernel_of
from workcal_wb.fc.proxies import Feature
from workcal_wb.fc.setup import set_setup
from workcal_wb.fc.undo import transaction

PARAMS = "User parameter:BaseApp/Preferences/Mod/WorkCal"
TYPE = SCAN_TYPE
QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP
REGION_SOURCES = ["none", "user", "auto"]
# Region properties, also added to foreign Points/Mesh objects used as scans.
WORKPIECE_PROP, REFERENCE_PROP, SOURCE_PROP = "WorkpieceRegion", "ReferenceRegion", "Source"
# Shown in the property editor: short names (they must fit its first column), the group says "Regions".
WORKPIECE_COUNT_PROP, REFERENCE_COUNT_PROP = "Workpiece", "Reference"
# What WorkCal 0.1 called the shown ones (scans it saved are brought up to date when reopened).
OLD_REGION_PROPS = {"RegionSource": SOURCE_PROP, "WorkpiecePoints": None, "ReferencePoints": None}
REGION_GROUP = "Regions"
# Files read by FreeCAD's Points module instead of workcal_wb.core.readers.
FREECAD_POINT_FORMATS = (".e57",)
SCAN_EXTENSIONS = (".ply", ".pcd", ".xyz", ".asc", ".pts", ".csv", ".txt", ".e57", ".stl", ".obj", ".off")


class ScanFeature(Feature):
    """Proxy of a WorkCal scan; caches the numpy cloud (never saved)."""

    TYPE = TYPE
    _cloud = None

    def setup(self, obj) -> None:
        for name, tip in (("Units", QT_TRANSLATE_NOOP("App::Property", "Length unit the file was read in; the "
                                                                       "points are stored in mm")),
                          ("SourceFile", QT_TRANSLATE_NOOP("App::Property", "File the scan was read from"))):
            if name not in obj.PropertiesList:
                obj.addProperty("App::PropertyString", name, "Scan", tip, 0, True)
        if "PointCount" not in obj.PropertiesList:
            obj.addProperty("App::PropertyInteger", "PointCount", "Scan",
                            QT_TRANSLATE_NOOP("App::Property", "Number of points"), 0, True)
        _add_region_properties(obj)

    def onChanged(self, obj, prop):
        if prop in ("Points", "Placement"):
            self._cloud = None

    def onDocumentRestored(self, obj):
        self._cloud = None
        source = obj.RegionSource if "RegionSource" in obj.PropertiesList else None
        for name in OLD_REGION_PROPS:
            if name in obj.PropertiesList:
                obj.removeProperty(name)
        super().onDocumentRestored(obj)
        if source in ("user", "auto"):
            try:
                set_regions(obj, getattr(obj, WORKPIECE_PROP), getattr(obj, REFERENCE_PROP), source=source)
            except InputError:  # stale regions: said when they are used
                pass
            obj.purgeTouched()


def point_count(obj) -> int:
    kind, kernel = kernel_of(obj)
    return 0 if kind is None else int(kernel.CountPoints)


def make_scan(doc, cloud: Cloud, name: str = "Scan", units: str = "mm", source: str = ""):
    """A WorkCal scan object holding every point of ``cloud`` (mm, scan frame S)."""
    if cloud is None or len(cloud.points) == 0:
        raise InputError(f"scan {getattr(cloud, 'name', name)!r}: contains no points")
    mm_per_unit(units)  # refuse an unknown unit name
    points = np.asarray(cloud.points, dtype=np.float32).astype(np.float64)
    if not np.all(np.isfinite(points)):
        raise InputError(f"scan {cloud.name!r}: has NaN or infinite coordinates (read it with read_cloud, "
                         "which drops them)")
    normals = None
    if cloud.normals is not None and len(cloud.normals) == len(points):
        normals = np.asarray(cloud.normals, dtype=np.float32).astype(np.float64)
    obj = doc.addObject("Points::FeaturePython", _object_name(name))
    proxy = ScanFeature(obj)
    obj.Label = name
    obj.Units = units
    obj.SourceFile = str(source)
    obj.Points = Points.Points(list(map(tuple, points.tolist())))
    if normals is not None:
        obj.addProperty("Points::PropertyNormalList", "Normal", "Scan", "Surface normal of each point")
        obj.Normal = list(map(tuple, normals.tolist()))
    obj.PointCount = len(points)
    proxy._cloud = Cloud(points, normals, None, obj.Label, list(cloud.warnings))
    return obj


def _object_name(label: str) -> str:
    """A valid object name from a label (FreeCAD makes it unique)."""
    base = "".join(c if c.isalnum() else "_" for c in os.path.splitext(label)[0]) or "Scan"
    return base if not base[0].isdigit() else "Scan_" + base


def scan_cloud(obj) -> Cloud:
    """All points of a scan object, in mm, in the scan frame S (the object's Placement applied).

    Accepts WorkCal scans, any Points object (normals kept when it has a matching ``Normal``
    property) and Mesh objects (their vertices).  The arrays are copies: changing them does not
    change the object.
    """
    if obj is None:
        raise InputError("no scan given: import a scan first (WorkCal > Import scan)")
    kind, kernel = kernel_of(obj)
    label = getattr(obj, "Label", repr(obj))
    if kind is None:
        raise InputError(f"{label!r} is not a point cloud or mesh, so it cannot be used as a scan; "
                         "select a scan (Points or Mesh object)")
    if kernel.CountPoints == 0:
        raise InputError(f"scan {label!r}: contains no points")
    proxy = getattr(obj, "Proxy", None)
    cached = getattr(proxy, "_cloud", None) if is_scan(obj) else None
    if cached is None:
        if kind == "points":
            points = np.array([tuple(v) for v in kernel.Points], dtype=np.float64).reshape(-1, 3)
        else:
            points = np.array([tuple(v) for v in kernel.Topology[0]], dtype=np.float64).reshape(-1, 3)
        normals = _normals(obj, len(points))
        cached = Cloud(points, normals, None, label)
        if is_scan(obj):
            proxy._cloud = cached
    normals = None if cached.normals is None else cached.normals.copy()
    return Cloud(cached.points.copy(), normals, None, label, list(cached.warnings))


def _normals(obj, count: int):
    normals = getattr(obj, "Normal", None)
    if not normals or len(normals) != count:
        return None
    rotation = matrix_of(obj.Placement)[:3, :3]
    return np.array([tuple(v) for v in normals], dtype=np.float64).reshape(-1, 3) @ rotation.T


# --- regions -------------------------------------------------------------------------------------

REGION_PROPERTIES = [
    ("App::PropertyIntegerList", WORKPIECE_PROP, "Indices of the scan points on the workpiece"),
    ("App::PropertyIntegerList", REFERENCE_PROP, "Indices of the scan points on the reference object"),
    ("App::PropertyEnumeration", SOURCE_PROP, "Who set the regions: picked by the user (user) or found "
                                              "automatically (auto)"),
    ("App::PropertyInteger", WORKPIECE_COUNT_PROP, "Number of points in the workpiece region"),
    ("App::PropertyInteger", REFERENCE_COUNT_PROP, "Number of points in the reference region"),
]


def _add_region_properties(obj) -> None:
    for kind, name, tip in REGION_PROPERTIES:
        if name not in obj.PropertiesList:
            read_only = name not in (WORKPIECE_PROP, REFERENCE_PROP)
            obj.addProperty(kind, name, REGION_GROUP, tip, 0, read_only)
            if name == SOURCE_PROP:
                setattr(obj, SOURCE_PROP, REGION_SOURCES)
    # Long index lists are unreadable in the property editor; the counts stand for them.
    obj.setEditorMode(WORKPIECE_PROP, 2)
    obj.setEditorMode(REFERENCE_PROP, 2)


def has_regions(obj) -> bool:
    """Cheap: whether any region is set (reads the counts, not the index lists)."""
    return bool(getattr(obj, WORKPIECE_COUNT_PROP, 0) or getattr(obj, REFERENCE_COUNT_PROP, 0))


def get_regions(obj) -> dict:
    """{"workpiece": int index array or None, "reference": ... or None, "source": "user"|"auto"|None}.

    Indices refer to ``scan_cloud(obj).points``; InputError when they no longer fit the scan."""
    if not hasattr(obj, SOURCE_PROP):
        return {"workpiece": None, "reference": None, "source": None}
    count = point_count(obj)
    regions = {}
    for role, prop in (("workpiece", WORKPIECE_PROP), ("reference", REFERENCE_PROP)):
        values = np.asarray(getattr(obj, prop), dtype=np.int64)
        if len(values) and (values.min() < 0 or values.max() >= count):
            raise InputError(f"scan {obj.Label!r}: the {role} region refers to points that no longer exist "
                             f"(the scan has {count} points); pick the region again")
        regions[role] = values if len(values) else None
    source = getattr(obj, SOURCE_PROP)
    regions["source"] = None if source == "none" or not (len(getattr(obj, WORKPIECE_PROP)) or
                                                         len(getattr(obj, REFERENCE_PROP))) else source
    return regions


def set_regions(obj, workpiece=None, reference=None, source: str = "user") -> None:
    """Store both regions (index arrays into ``scan_cloud(obj).points``; None or empty = not set).

    Indices are sorted and made unique; a point cannot be in both regions.  Nothing changes when
    the input is refused (InputError).  The caller opens the undo transaction."""
    if source not in ("user", "auto"):
        raise InputError(f"region source must be 'user' or 'auto', not {source!r}")
    if kernel_of(obj)[0] is None:
        raise InputError(f"{getattr(obj, 'Label', obj)!r} is not a point cloud or mesh; regions can only "
                         "be set on a scan")
    count = point_count(obj)
    checked_regions = {}
    for role, values in (("workpiece", workpiece), ("reference", reference)):
        if values is None:
            checked_regions[role] = np.empty(0, dtype=np.int64)
            continue
        values = np.asarray(values)
        if values.dtype == bool:
            if len(values) != count:
                raise InputError(f"the {role} mask has {len(values)} entries, scan {obj.Label!r} has "
                                 f"{count} points")
            values = np.flatnonzero(values)
        if values.size and values.dtype.kind not in "iu":
            raise InputError(f"the {role} region must be integer point indices, not {values.dtype}")
        values = np.unique(values.astype(np.int64).ravel())
        if len(values) and (values[0] < 0 or values[-1] >= count):
            raise InputError(f"the {role} region has indices outside 0..{count - 1} "
                             f"(scan {obj.Label!r} has {count} points)")
        checked_regions[role] = values
    both = np.intersect1d(checked_regions["workpiece"], checked_regions["reference"], assume_unique=True)
    if len(both):
        raise InputError(f"{len(both)} points are in both the workpiece and the reference region; "
                         "a point belongs to one object")
    _add_region_properties(obj)
    setattr(obj, WORKPIECE_PROP, checked_regions["workpiece"].tolist())
    setattr(obj, REFERENCE_PROP, checked_regions["reference"].tolist())
    setattr(obj, WORKPIECE_COUNT_PROP, len(checked_regions["workpiece"]))
    setattr(obj, REFERENCE_COUNT_PROP, len(checked_regions["reference"]))
    empty = not (len(checked_regions["workpiece"]) or len(checked_regions["reference"]))
    setattr(obj, SOURCE_PROP, "none" if empty else source)


# --- files ---------------------------------------------------------------------------------------

def preferred_units() -> str:
    """The ScanUnits preference ('' when the user was never asked)."""
    return FreeCAD.ParamGet(PARAMS).GetString("ScanUnits", "")


def set_preferred_units(units: str) -> None:
    mm_per_unit(units)
    FreeCAD.ParamGet(PARAMS).SetString("ScanUnits", units)


def declared_units(path) -> str | None:
    """The unit a file declares: metres for E57 (the standard's unit; FreeCAD's reader passes the
    numbers through unscaled), ``comment units mm`` of a PLY written by WorkCal; else None."""
    ext = os.path.splitext(str(path))[1].lower()
    if ext == ".e57":
        return "m"
    if ext != ".ply":
        return None
    try:
        with open(path, "rb") as stream:
            head = stream.read(4096)
    except OSError:
        return None
    for line in head.split(b"end_header")[0].splitlines():
        words = line.decode("latin-1").split()
        if len(words) == 3 and words[:2] == ["comment", "units"]:
            return words[2]
    return None


_last_read = LastResult()


def read_scan_file(path, units: str = "mm") -> Cloud:
    """A scan file as a checked Cloud in mm.  ``units`` is the file's unit; a PLY that declares its
    unit is read in that unit (E57: metres).  E57 goes through FreeCAD's Points module (touches documents, so call
    it from the main thread); everything else through workcal_wb.core.readers (thread-safe).  The last
    file read is remembered (by path, size, time and unit), so reading it again costs nothing."""
    path = str(path)
    ext = os.path.splitext(path)[1].lower()
    mm_per_unit(units)
    try:
        stat = os.stat(path)
        key = (os.path.abspath(path), stat.st_size, stat.st_mtime_ns, units)
    except OSError:
        key = None
    cloud = _last_read.get(key)
    if cloud is None:
        declared = declared_units(path)
        if ext in FREECAD_POINT_FORMATS:
            cloud = _read_with_freecad(path, declared or units)
        else:
            cloud = read_cloud(path, units=None if declared else units)
        _last_read.put(key, cloud)
    return cloud


def _read_with_freecad(path: str, units: str) -> Cloud:
    scale = mm_per_unit(units)
    if not os.path.isfile(path):
        raise InputError(f"{path}: file does not exist")
    previous = FreeCAD.ActiveDocument
    doc = FreeCAD.newDocument("WorkCalRead", "WorkCalRead", True)
    try:
        Points.insert(path, doc.Name)
        kernels = [o.Points for o in doc.Objects if hasattr(o, "Points") and hasattr(o.Points, "CountPoints")]
        if not kernels or sum(k.CountPoints for k in kernels) == 0:
            raise InputError(f"{path}: FreeCAD's point reader found no points in it")
        points = np.concatenate([np.array([tuple(v) for v in k.Points], dtype=np.float64).reshape(-1, 3)
                                 for k in kernels])
    except InputError:
        raise
    except Exception as exc:  # FreeCAD raises plain RuntimeError/Base.FreeCADError for unreadable files
        raise InputError(f"{path}: FreeCAD cannot read it as a point cloud ({exc})") from None
    finally:
        FreeCAD.closeDocument(doc.Name)
        if previous is not None:
            FreeCAD.setActiveDocument(previous.Name)
    cloud = checked(Cloud(points * scale, name=os.path.basename(path)))
    cloud.warnings += extent_warnings(cloud.points, cloud.name, units)
    return cloud


def import_scan(doc, path, units: str = "mm", name: str | None = None):
    """Read a scan file into ``doc`` as a WorkCal scan and make it the document's scan (WorkCal setup),
    in one undo step; returns the new object.  InputError names the file when it cannot be read; the
    document is then unchanged.  Warnings about the file (e.g. its extent and unit) go to the Report view."""
    cloud = read_scan_file(path, units)
    used = declared_units(path) or units
    with transaction(doc, FreeCAD.Qt.translate("WorkCal", "Import scan")):
        obj = make_scan(doc, cloud, name or os.path.basename(str(path)), used, str(path))
        set_setup(doc, scan=obj)
        doc.recompute()
    for text in cloud.warnings:
        FreeCAD.Console.PrintWarning(f"WorkCal: {text}\n")
    FreeCAD.Console.PrintMessage(f"WorkCal: imported {obj.Label} ({len(cloud)} points, read as {used})\n")
    return obj


def change_units(obj, units: str):
    """Read the scan ``obj`` again from its file in ``units`` (the unit its numbers are in), in one undo
    step; its regions stay (the same points, in the same order).  InputError names the scan when it has
    no file to read again, when the file declares its own unit, or when the file cannot be read."""
    mm_per_unit(units)
    label = getattr(obj, "Label", repr(obj))
    if not is_scan(obj) or not getattr(obj, "SourceFile", ""):
        raise InputError(f"scan {label!r} was not read from a file, so it cannot be read again in another unit")
    path = obj.SourceFile
    declared = declared_units(path)
    if declared and declared != units:
        raise InputError(f"scan {label!r}: its file {os.path.basename(path)} says its unit is {declared}; it is "
                         f"read in {declared} only")
    if not os.path.isfile(path):
        raise InputError(f"scan {label!r}: its file {path} no longer exists, so it cannot be read again")
    cloud = read_scan_file(path, units)
    if len(cloud) != point_count(obj):
        raise InputError(f"scan {label!r}: its file {os.path.basename(path)} now holds {len(cloud)} points, the "
                         f"scan {point_count(obj)}; import it again instead")
    doc = obj.Document
    with transaction(doc, FreeCAD.Qt.translate("WorkCal", "Scan unit")):
        points = np.asarray(cloud.points, dtype=np.float32).astype(np.float64)
        obj.Points = Points.Points(list(map(tuple, points.tolist())))
        obj.Units = units
        doc.recompute()
    FreeCAD.Console.PrintMessage(f"WorkCal: {label} read again in {units}\n")
    return obj


def scan_unit_warning(obj) -> tuple[str, str | None]:
    """(warning, the unit to read it in instead) when the scan's size says its file was read in the wrong
    unit, else ("", None).  Only for scans read from a file whose unit can be changed."""
    units = getattr(obj, "Units", "") if is_scan(obj) else ""
    if not units or not getattr(obj, "SourceFile", "") or declared_units(obj.SourceFile):
        return "", None
    return unit_warning(scan_cloud(obj).points, obj.Label, units)
