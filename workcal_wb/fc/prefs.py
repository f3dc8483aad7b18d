"""WorkCal's user preferences, kept in FreeCAD's parameter tree (Preferences > WorkCal).

Every command reads its defaults here, so a value set on the preference page is what a new
calibration or export starts with.  Works headless too (freecadcmd has the same parameter tree).
"""
from __future__ import annotations

from pathlib import Path

import FreeCAD

from workcal_wb.core.match import METHODS
from workcal_wb.core.toolpath import FORMATS
from workcal_wb.core.toolpath.safety import DEFAULT_PATH_REACH_MM
from workcal_wb.core.units import MM_PER_UNIT

PATH = "User parameter:BaseApp/Preferences/Mod/WorkCal"

UNITS = ("mm", "cm", "m", "in", "um")
REGION_MODES = ("Auto", "Picked")

# name -> (kind, default); kinds map to ParamGet's typed getters and setters.
DEFAULTS = {
    # Unit of scan files without a unit of their own; "" = ask at the first import (fc.scan.preferred_units).
    "ScanUnits": ("string", ""),
    "ToleranceMm": ("float", 0.3),
    "Method": ("string", "robust"),
    "Seed": ("int", 0),
    "Resamples": ("int", 6),
    "Regions": ("string", "Auto"),
    "ExportFormat": ("string", "krl"),
    "DeviationRangeMm": ("float", 0.0),  # 0 = from the data
    # How far a toolpath's cutting moves may run from the workpiece model before an export refuses it.
    "PathReachMm": ("float", DEFAULT_PATH_REACH_MM),
    "ReportDir": ("string", ""),  # "" = a folder beside the document (or the temp folder)
    "PickVisibleOnly": ("int", 1),  # box and lasso picks take only the points not hidden by others
    # Prepared models kept between calibrations (core/model_cache.py): 0 prepares them anew every time.
    "KeepPreparedModels": ("int", 1),
    "ModelCacheDir": ("string", ""),  # "" = the user's cache folder (as the command line's default)
}


def _group():
    return FreeCAD.ParamGet(PATH)


def get(name: str):
    """The stored value of one preference, or its default; bad stored values fall back to the default."""
    kind, default = DEFAULTS[name]
    group = _group()
    if kind == "string":
        value = group.GetString(name, default) or default
    elif kind == "float":
        value = group.GetFloat(name, default)
    else:
        value = group.GetInt(name, default)
    if name == "ScanUnits" and value not in MM_PER_UNIT:
        value = default
    elif name == "Method" and value not in METHODS:
        value = default
    elif name == "Regions" and value not in REGION_MODES:
        value = default
    elif name == "ExportFormat" and value not in FORMATS:
        value = default
    elif name in ("ToleranceMm", "PathReachMm") and not value > 0:
        value = default
    elif name == "Resamples" and value < 1:
        value = default
    return value


def model_cache_folder() -> Path | None:
    """Where calibrations keep prepared models, as the preferences say; None when they keep none."""
    from workcal_wb.core.model_cache import default_folder

    if not get("KeepPreparedModels"):
        return None
    folder = get("ModelCacheDir").strip()
    return Path(folder).expanduser() if folder else default_folder()


def set(name: str, value) -> None:  # noqa: A001  (mirrors get)
    kind, _ = DEFAULTS[name]
    group = _group()
    if kind == "string":
        group.SetString(name, str(value))
    elif kind == "float":
        group.SetFloat(name, float(value))
    else:
        group.SetInt(name, int(value))


def all_values() -> dict:
    return {name: get(name) for name in DEFAULTS}


def reset() -> None:
    """Forget every stored WorkCal preference (tests use this to start from the defaults)."""
    group = _group()
    for name, (kind, _) in DEFAULTS.items():
        {"string": group.RemString, "float": group.RemFloat, "int": group.RemInt}[kind](name)
