"""Which scan, workpiece model (X-A) and reference model (B-P) a document's calibration uses.

The choice lives in one ``App::FeaturePython`` named "WorkCalSetup" (label "WorkCal setup") with three
``App::PropertyLink`` properties, so it is saved with the document, shown in the tree and editable in
the property editor.  FreeCAD clears a link when its target is deleted.
"""
from __future__ import annotations

from workcal_wb.core.errors import InputError
from workcal_wb.fc import init as fc_init
from workcal_wb.fc import models
from workcal_wb.fc import scan as fc_scan
from workcal_wb.fc.proxies import Proxy

SETUP_TYPE = "WorkCal::Setup"
SETUP_NAME = "WorkCalSetup"
ROLES = ("scan", "workpiece", "reference")
PROPERTIES = {"scan": "Scan", "workpiece": "Workpiece", "reference": "Reference"}
UNCHANGED = object()  # set_setup default: leave that role as it is


class SetupFeature(Proxy):
    Type = SETUP_TYPE
    STATE = {"Type": SETUP_TYPE}

    def __init__(self, obj):
        obj.Proxy = self
        obj.addProperty("App::PropertyLink", "Scan", "WorkCal", "The scene scan (frame S)")
        obj.addProperty("App::PropertyLink", "Workpiece", "WorkCal", "Model of the workpiece X-A, in its "
                        "own frame X (the toolpath's frame)")
        obj.addProperty("App::PropertyLink", "Reference", "WorkCal", "Model of the reference object B-P, "
                        "placed in the robot base frame B")

    def execute(self, obj):
        pass


def setup_object(doc, create: bool = False):
    """The document's setup object (None when there is none and ``create`` is False)."""
    obj = doc.getObject(SETUP_NAME)
    if obj is None or getattr(getattr(obj, "Proxy", None), "Type", None) != SETUP_TYPE:
        obj = next((o for o in doc.Objects if getattr(getattr(o, "Proxy", None), "Type", None) == SETUP_TYPE),
                   None)
    if obj is None and create:
        obj = doc.addObject("App::FeaturePython", SETUP_NAME)
        SetupFeature(obj)
        obj.Label = "WorkCal setup"
        fc_init.attach_view_provider(obj, "Setup")
    return obj


def get_setup(doc) -> dict:
    """{"scan": obj|None, "workpiece": obj|None, "reference": obj|None}."""
    obj = setup_object(doc) if doc is not None else None
    return {role: (getattr(obj, PROPERTIES[role], None) if obj is not None else None) for role in ROLES}


def set_setup(doc, scan=UNCHANGED, workpiece=UNCHANGED, reference=UNCHANGED):
    """Store the chosen objects (None clears a role; an omitted role stays).  Checks each object
    first (cheaply: no tessellation) and changes nothing when one is refused (InputError).
    The caller opens the undo transaction.  Returns the setup object."""
    chosen = {"scan": scan, "workpiece": workpiece, "reference": reference}
    current = get_setup(doc)
    final = {role: current[role] if value is UNCHANGED else value for role, value in chosen.items()}
    for role, obj in final.items():
        if obj is not None and obj.Document is not doc:
            raise InputError(f"{obj.Label!r} belongs to document {obj.Document.Label!r}, not {doc.Label!r}")
    if chosen["scan"] is not UNCHANGED and chosen["scan"] is not None and not fc_scan.can_be_scan(chosen["scan"]):
        raise InputError(f"{chosen['scan'].Label!r} is not a point cloud or mesh, so it cannot be the scan")
    for role in ("workpiece", "reference"):
        if chosen[role] is not UNCHANGED and chosen[role] is not None:
            models.check_model(chosen[role])
            if fc_scan.is_scan(chosen[role]):
                raise InputError(f"{chosen[role].Label!r} is the scan; the {role} model must be a model "
                                 "(Part shape, mesh or point cloud of the object itself)")
    if final["workpiece"] is not None and final["workpiece"] is final["reference"]:
        raise InputError(f"{final['workpiece'].Label!r} cannot be both the workpiece and the reference model")
    if final["scan"] is not None and final["scan"] in (final["workpiece"], final["reference"]):
        raise InputError(f"{final['scan'].Label!r} cannot be both the scan and a model")
    obj = setup_object(doc, create=True)
    for role, value in final.items():
        if getattr(obj, PROPERTIES[role]) is not value:
            setattr(obj, PROPERTIES[role], value)
    return obj
