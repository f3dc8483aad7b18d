"""What a document calibrates: its scan, workpiece model (X-A), reference model (B-P) and toolpath.

The choice lives in one ``App::FeaturePython`` named "WorkCalSetup" (label "WorkCal setup"), so it is
saved with the document, shown in the tree and editable in the property editor.  FreeCAD clears a
link when its target is deleted.  The toolpath is chosen once here (a Path/CAM Job or operation, or
a G-code file remembered by its path) and used by the calibration (uncertainty at its cutting
points), the calibrated toolpath and the robot program alike.
"""
from __future__ import annotations

import os

import FreeCAD

from workcal_wb.core.errors import InputError
from workcal_wb.fc import models
from workcal_wb.fc.lookups import can_be_scan, is_scan
from workcal_wb.fc.proxies import Feature, add_properties, objects_of
from workcal_wb.fc.toolpath_input import jobs, read_source
from workcal_wb.fc.undo import transaction

translate = FreeCAD.Qt.translate
QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP

TYPE = "WorkCal::Setup"
SETUP_NAME = "WorkCalSetup"
ROLES = ("scan", "workpiece", "reference")
PROPERTIES = {"scan": "Scan", "workpiece": "Workpiece", "reference": "Reference"}
UNCHANGED = object()  # default of the setters: leave that role as it is
PROPERTY_LIST = [
    ("App::PropertyLink", "Scan", "WorkCal", QT_TRANSLATE_NOOP("App::Property", "The scene scan: the workpiece and "
                                                                              "the reference object seen at once "
                                                                              "(scanner frame S)")),
    ("App::PropertyLink", "Workpiece", "WorkCal", QT_TRANSLATE_NOOP("App::Property", "Model of the workpiece in its "
                                                                                   "own frame, the toolpath's (X-A "
                                                                                   "in frame X)")),
    ("App::PropertyLink", "Reference", "WorkCal", QT_TRANSLATE_NOOP("App::Property", "Model of the fixed reference "
                                                                                   "object, placed where it stands "
                                                                                   "in the robot base frame (B-P "
                                                                                   "in frame B)")),
    ("App::PropertyLink", "Toolpath", "WorkCal", QT_TRANSLATE_NOOP("App::Property", "The toolpath to carry into the "
                                                                                  "robot frame: a Path/CAM Job or "
                                                                                  "operation")),
    ("App::PropertyFile", "GcodeFile", "WorkCal", QT_TRANSLATE_NOOP("App::Property", "The toolpath as a G-code "
                                                                                      "file (used when Toolpath is "
                                                                                      "empty)")),
]


class SetupFeature(Feature):
    TYPE = TYPE

    def setup(self, obj) -> None:
        add_properties(obj, PROPERTY_LIST)


def setup_object(doc, create: bool = False):
    """The document's setup object (None when there is none and ``create`` is False)."""
    found = objects_of(doc, TYPE)
    if found or not create:
        return found[0] if found else None
    obj = doc.addObject("App::FeaturePython", SETUP_NAME)
    SetupFeature(obj)
    obj.Label = translate("WorkCal", "WorkCal setup")
    return obj


def get_setup(doc) -> dict:
    """{"scan": obj|None, "workpiece": obj|None, "reference": obj|None}."""
    obj = setup_object(doc) if doc is not None else None
    return {role: (getattr(obj, PROPERTIES[role], None) if obj is not None else None) for role in ROLES}


def set_setup(doc, scan=UNCHANGED, workpiece=UNCHANGED, reference=UNCHANGED):
    """Store the chosen objects (None clears a role; an omitted role stays).  Checks each object
    first (``check_setup``) and changes nothing when one is refused (InputError).
    The caller opens the undo transaction.  Returns the setup object."""
    final = check_setup(doc, scan, workpiece, reference)
    obj = setup_object(doc, create=True)
    for role, value in final.items():
        if getattr(obj, PROPERTIES[role]) is not value:
            setattr(obj, PROPERTIES[role], value)
    return obj


def check_setup(doc, scan=UNCHANGED, workpiece=UNCHANGED, reference=UNCHANGED) -> dict:
    """The setup these choices would give ({role: object or None}); InputError names a refused object.
    Cheap (no tessellation) and changes nothing."""
    chosen = {"scan": scan, "workpiece": workpiece, "reference": reference}
    current = get_setup(doc)
    final = {role: current[role] if value is UNCHANGED else value for role, value in chosen.items()}
    for role, obj in final.items():
        if obj is not None and obj.Document is not doc:
            raise InputError(f"{obj.Label!r} belongs to document {obj.Document.Label!r}, not {doc.Label!r}")
    if chosen["scan"] is not UNCHANGED and chosen["scan"] is not None and not can_be_scan(chosen["scan"]):
        raise InputError(f"{chosen['scan'].Label!r} is not a point cloud or mesh, so it cannot be the scan")
    for role in ("workpiece", "reference"):
        if chosen[role] is not UNCHANGED and chosen[role] is not None:
            models.check_model(chosen[role])
            if is_scan(chosen[role]):
                raise InputError(f"{chosen[role].Label!r} is the scan; the {role} model must be a model "
                                 "(Part shape, mesh or point cloud of the object itself)")
    if final["workpiece"] is not None and final["workpiece"] is final["reference"]:
        raise InputError(f"{final['workpiece'].Label!r} cannot be both the workpiece and the reference model")
    if final["workpiece"] is not None and final["reference"] is not None:
        why = models.same_model(final["workpiece"], final["reference"])
        if why:
            newer = "reference" if chosen["reference"] is not UNCHANGED else "workpiece"
            older = "workpiece" if newer == "reference" else "reference"
            thing = "reference object" if newer == "reference" else "workpiece"
            raise InputError(f"{final[newer].Label!r} cannot be the {newer} model: it is the {older} model "
                             f"{final[older].Label!r} again ({why}). Choose the {thing}'s own model")
    if final["scan"] is not None and final["scan"] in (final["workpiece"], final["reference"]):
        raise InputError(f"{final['scan'].Label!r} cannot be both the scan and a model")
    return final


def choose_models(doc, **chosen):
    """The use case behind Choose models: store the chosen objects (keywords scan/workpiece/reference;
    None clears, omitted stays) as one undo step; InputError names a refused object and the document
    is then unchanged.  Returns the setup object."""
    unknown = set(chosen) - set(ROLES)
    if unknown:
        raise InputError(f"unknown roles {sorted(unknown)}; choose among {', '.join(ROLES)}")
    with transaction(doc, translate("WorkCal", "Choose models")):
        obj = set_setup(doc, **chosen)
    now = get_setup(doc)
    FreeCAD.Console.PrintMessage("WorkCal: setup: scan {}, workpiece model {}, reference model {}\n".format(
        *(now[r].Label if now[r] is not None else "-" for r in ROLES)))
    return obj


# --- the toolpath ----------------------------------------------------------------------------------

def toolpath_of(doc):
    """The document's toolpath: the chosen Job/Path object, else the chosen G-code file (a path),
    else the document's only Path/CAM Job; None when there is no such choice."""
    obj = setup_object(doc) if doc is not None else None
    if obj is not None and obj.Toolpath is not None:
        return obj.Toolpath
    if obj is not None and obj.GcodeFile:
        return obj.GcodeFile
    found = jobs(doc) if doc is not None else []
    return found[0] if len(found) == 1 else None


def choose_toolpath(doc, source):
    """Remember the document's toolpath (one undo step): a Path/CAM Job or operation of ``doc``, a G-code
    file path, or None to forget it.  The toolpath is read first, so a file or object that is not a
    usable toolpath is refused (InputError) and nothing changes."""
    if source is not None:
        if not isinstance(source, (str, os.PathLike)) and getattr(source, "Document", None) is not doc:
            raise InputError(f"{getattr(source, 'Label', source)!r} is not an object of {doc.Label!r}")
        read_source(source)
    with transaction(doc, translate("WorkCal", "Choose toolpath")):
        obj = setup_object(doc, create=True)
        is_file = isinstance(source, (str, os.PathLike))
        obj.Toolpath = None if is_file else source
        obj.GcodeFile = os.path.abspath(os.fspath(source)) if is_file else ""
    return obj
