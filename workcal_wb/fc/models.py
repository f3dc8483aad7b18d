"""Models (workpiece X-A, reference B-P) from FreeCAD objects and files, as core ``Cloud``s.

A Part shape is tessellated and a mesh keeps its triangles, so both are matched as surfaces; a point
cloud gives points only.  Coordinates are the object's as the document shows them (its Placement,
and that of any containing App::Part, applied): the document frame is the workpiece frame X for the
workpiece model and the robot base frame B for the reference model.
"""
from __future__ import annotations

import os

import numpy as np

import FreeCAD

from workcal_wb.core.errors import InputError
from workcal_wb.core.geometry import Cloud, checked
from workcal_wb.core.readers import read_cloud
from workcal_wb.fc.lookups import kernel_of
from workcal_wb.fc.placements import container_matrix

# Tessellation chord error: a small fraction of the model size, within these bounds (mm).  The
# matcher's tolerance is 0.3 mm, so even the coarsest bound stays well below it.
DEFLECTION_FRACTION = 2e-4
DEFLECTION_RANGE_MM = (0.005, 0.05)
CAD_EXTENSIONS = (".step", ".stp", ".iges", ".igs", ".brep", ".brp")
MESH_EXTENSIONS = (".stl", ".obj", ".off", ".ply")
POINT_EXTENSIONS = (".pcd", ".xyz", ".asc", ".pts", ".csv", ".txt")
MODEL_EXTENSIONS = CAD_EXTENSIONS + MESH_EXTENSIONS + POINT_EXTENSIONS


def _label(obj) -> str:
    return getattr(obj, "Label", None) or getattr(obj, "Name", None) or repr(obj)


def kind_of(obj):
    """("mesh"|"points"|"shape"|None, data) without expensive work."""
    kind, kernel = kernel_of(obj)
    if kind is not None:
        return kind, kernel
    if hasattr(obj, "Shape") or getattr(obj, "TypeId", "") in ("App::Link", "App::LinkPython", "App::Part"):
        import Part

        try:
            shape = Part.getShape(obj)
        except Exception:  # Part.getShape raises for objects it cannot turn into a shape
            return None, None
        return "shape", shape
    return None, None


def is_model_object(obj) -> bool:
    """Whether ``obj`` is of a kind ``model_cloud`` accepts (it may still be empty)."""
    return kind_of(obj)[0] is not None


def check_model(obj) -> str:
    """Raise InputError naming ``obj`` unless it is a usable model; returns its kind.  Cheap: no tessellation."""
    kind, data = kind_of(obj)
    label = _label(obj)
    if kind is None:
        type_id = getattr(obj, "TypeId", type(obj).__name__)
        raise InputError(f"{label!r} ({type_id}) is not a Part shape, mesh or point cloud, so it cannot be "
                         "used as a model")
    if kind == "mesh" and data.CountFacets == 0:
        raise InputError(f"model {label!r}: the mesh has no faces")
    if kind == "points" and data.CountPoints == 0:
        raise InputError(f"model {label!r}: the point cloud contains no points")
    if kind == "shape":
        if data.isNull():
            raise InputError(f"model {label!r}: its shape is empty")
        if not data.Faces:
            raise InputError(f"model {label!r}: its shape has no faces (only {len(data.Edges)} edges and "
                             f"{len(data.Vertexes)} vertices); a model needs a solid or surfaces")
    return kind


def deflection_for(shape) -> float:
    low, high = DEFLECTION_RANGE_MM
    return float(min(high, max(low, DEFLECTION_FRACTION * shape.BoundBox.DiagonalLength)))


def model_cloud(obj, deflection_mm: float | None = None, role: str = "") -> Cloud:
    """The model as a Cloud in mm: triangles for shapes and meshes, points for point clouds.  ``role``
    ("workpiece", "reference") names what is missing when ``obj`` is None."""
    if obj is None:
        raise InputError(f"no {role + ' ' if role else ''}model given: choose it first (WorkCal > Choose models; "
                         "a Part shape, mesh or point cloud)")
    kind = check_model(obj)
    data = kind_of(obj)[1]
    label = _label(obj)
    if kind == "shape":
        vertices, facets = data.tessellate(deflection_mm or deflection_for(data))
        points = np.array([tuple(v) for v in vertices], dtype=np.float64).reshape(-1, 3)
        triangles = np.array(facets, dtype=np.int64).reshape(-1, 3)
        if not len(triangles):
            raise InputError(f"model {label!r}: tessellating its shape gave no triangles")
        cloud = Cloud(points, None, triangles, label)
    elif kind == "mesh":
        vertices, facets = data.Topology
        cloud = Cloud(np.array([tuple(v) for v in vertices], dtype=np.float64).reshape(-1, 3), None,
                      np.array(facets, dtype=np.int64).reshape(-1, 3), label)
        cloud = _with_parent_placement(obj, cloud)
    else:
        cloud = Cloud(np.array([tuple(v) for v in data.Points], dtype=np.float64).reshape(-1, 3), name=label)
        cloud = _with_parent_placement(obj, cloud)
    return checked(cloud)


def _with_parent_placement(obj, cloud: Cloud) -> Cloud:
    """Mesh and Points kernels already apply the object's own Placement; add that of containers."""
    T = container_matrix(obj)
    return cloud if T is None else cloud.transformed(T)


def import_model_file(doc, path, units: str = "mm", name: str | None = None):
    """Add a model file to ``doc``: STEP/IGES/BREP as Part::Feature (they carry their own unit),
    STL/OBJ/OFF/PLY meshes as Mesh::Feature, point files as Points::Feature (read in ``units``)."""
    path = str(path)
    ext = os.path.splitext(path)[1].lower()
    label = name or os.path.basename(path)
    if ext not in MODEL_EXTENSIONS:
        raise InputError(f"{path}: unknown model file type {ext or '(no extension)'!r}; WorkCal reads "
                         f"{', '.join(MODEL_EXTENSIONS)}")
    if not os.path.isfile(path):
        raise InputError(f"{path}: file does not exist")
    if ext in CAD_EXTENSIONS:
        import Part

        try:
            shape = Part.read(path)
        except Exception as exc:  # OCC reports unreadable files as Part.OCCError / RuntimeError
            raise InputError(f"{path}: cannot be read as a {ext[1:].upper()} file ({exc})") from None
        if shape.isNull() or not shape.Faces:
            raise InputError(f"{path}: contains no surfaces")
        obj = doc.addObject("Part::Feature", _object_name(label))
        obj.Shape = shape
        remember_file(obj, path, "")  # a CAD file carries its own unit
    else:
        cloud = read_cloud(path, units=units)
        obj = add_model(doc, cloud, label)
        remember_file(obj, path, units)
        for warning in cloud.warnings:
            FreeCAD.Console.PrintWarning(f"WorkCal: {warning}\n")
    obj.Label = label
    return obj


# The file a mesh or point model was read from and the unit it was read in, kept on the object so the
# unit can be changed later (CAD files carry their own unit, so their models have neither).
SOURCE_FILE_PROP, UNITS_PROP, FILE_GROUP = "SourceFile", "Units", "Model file"


def remember_file(obj, path, units: str) -> None:
    for name, tip in ((SOURCE_FILE_PROP, "File the model was read from"),
                      (UNITS_PROP, "Length unit the file was read in; the model is stored in mm")):
        if name not in obj.PropertiesList:
            obj.addProperty("App::PropertyString", name, FILE_GROUP, tip, 0, True)
    setattr(obj, SOURCE_FILE_PROP, str(path))
    setattr(obj, UNITS_PROP, units)


def source_file(obj) -> str:
    """The file the model was read from ("" when it was not read by WorkCal from a file)."""
    return getattr(obj, SOURCE_FILE_PROP, "") or ""


def file_units(obj) -> str:
    """The unit a mesh or point model's file was read in ("" for CAD files and models not read from a file)."""
    return getattr(obj, UNITS_PROP, "") if source_file(obj) else ""


def change_units(obj, units: str):
    """Read the model ``obj`` again from its file in ``units``, in one undo step; InputError names the model
    when it has no file to read again or the file cannot be read."""
    from workcal_wb.core.units import mm_per_unit
    from workcal_wb.fc.undo import transaction

    mm_per_unit(units)
    label, path = _label(obj), source_file(obj)
    if not file_units(obj):
        raise InputError(f"model {label!r} was not read from a mesh or point file, so its unit cannot be changed "
                         "(CAD files carry their own unit)")
    if not os.path.isfile(path):
        raise InputError(f"model {label!r}: its file {path} no longer exists, so it cannot be read again")
    cloud = read_cloud(path, units=units)
    doc = obj.Document
    with transaction(doc, FreeCAD.Qt.translate("WorkCal", "Model unit")):
        placement = obj.Placement
        if hasattr(obj, "Mesh"):
            import Mesh

            obj.Mesh = Mesh.Mesh(([FreeCAD.Vector(*p) for p in cloud.points.tolist()],
                                  [tuple(t) for t in cloud.triangles.tolist()]))
        else:
            import Points

            obj.Points = Points.Points(list(map(tuple, cloud.points.tolist())))
        obj.Placement = placement
        setattr(obj, UNITS_PROP, units)
        doc.recompute()
    FreeCAD.Console.PrintMessage(f"WorkCal: {label} read again in {units}\n")
    return obj


def same_model(first, second) -> str:
    """Why ``first`` and ``second`` are the same model loaded twice ("read from the same file X", "the same
    shape"), or "" when they are not.  Cheap: file names, then counts and bounding boxes, no tessellation."""
    files = source_file(first), source_file(second)
    if all(files) and os.path.normcase(os.path.abspath(files[0])) == os.path.normcase(os.path.abspath(files[1])):
        return f"read from the same file {os.path.basename(files[0])}"
    (kind, a), (other_kind, b) = kind_of(first), kind_of(second)
    if kind is None or kind != other_kind:
        return ""
    if kind == "shape":
        size = (len(a.Faces), len(a.Edges), len(a.Vertexes), round(a.Area, 6)), \
               (len(b.Faces), len(b.Edges), len(b.Vertexes), round(b.Area, 6))
    elif kind == "mesh":
        size = (a.CountPoints, a.CountFacets), (b.CountPoints, b.CountFacets)
    else:
        size = (a.CountPoints,), (b.CountPoints,)
    if size[0] != size[1] or not _same_box(a.BoundBox, b.BoundBox):
        return ""
    return "the same shape at the same place"


# Bounding boxes this close (mm) are the same box: float noise of a copied or re-read shape.
SAME_BOX_MM = 1e-6


def _same_box(a, b) -> bool:
    return all(abs(getattr(a, k) - getattr(b, k)) <= SAME_BOX_MM
               for k in ("XMin", "YMin", "ZMin", "XMax", "YMax", "ZMax"))


def model_unit_warning(obj) -> tuple[str, str | None]:
    """(warning, the unit to read it in instead) when the model's size says its file was read in the wrong
    unit, else ("", None)."""
    from workcal_wb.core.units import unit_warning

    units = file_units(obj)
    if not units:
        return "", None
    kind, data = kind_of(obj)
    source = data.Topology[0] if kind == "mesh" else data.Points if kind == "points" else []
    points = np.array([tuple(v) for v in source], dtype=np.float64).reshape(-1, 3)
    return unit_warning(points, _label(obj), units)


def import_model(doc, path, units: str = "mm"):
    """The use case behind "Model from file": ``import_model_file`` as one undo step, recomputed."""
    from workcal_wb.fc.undo import transaction

    with transaction(doc, FreeCAD.Qt.translate("WorkCal", "Import model")):
        obj = import_model_file(doc, path, units)
        doc.recompute()
    return obj


def add_model(doc, cloud: Cloud, label: str):
    """``cloud`` as a new object of ``doc``: a Mesh::Feature when it has triangles, else a Points::Feature."""
    if cloud.is_mesh:
        import Mesh

        vectors = [FreeCAD.Vector(*p) for p in cloud.points.tolist()]
        obj = doc.addObject("Mesh::Feature", _object_name(label))
        obj.Mesh = Mesh.Mesh((vectors, [tuple(t) for t in cloud.triangles.tolist()]))
    else:
        import Points

        obj = doc.addObject("Points::Feature", _object_name(label))
        obj.Points = Points.Points(list(map(tuple, cloud.points.tolist())))
    obj.Label = label
    return obj


def _object_name(label: str) -> str:
    base = "".join(c if c.isalnum() else "_" for c in os.path.splitext(label)[0]) or "Model"
    return base if not base[0].isdigit() else "Model_" + base


def read_model_file(path, units: str = "mm") -> Cloud:
    """A model file as a Cloud without touching any open document (a scratch document is used for
    CAD files and closed again): how headless commands read STEP/IGES/BREP."""
    doc = FreeCAD.newDocument("WorkCalScratch", hidden=True)
    try:
        return model_cloud(import_model_file(doc, path, units))
    finally:
        FreeCAD.closeDocument(doc.Name)

