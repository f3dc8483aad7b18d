"""Read scans and models (PLY, PCD, E57, XYZ-like text, STL, OBJ, OFF) into a checked ``Cloud`` in mm.

Where a scan file says where its scanner stood (PCD ``VIEWPOINT``, the pose of each E57 scan, a PLY
``comment viewpoint X Y Z`` line), the Cloud keeps it as ``sensors``.

A silently misread file would place the workpiece wrongly, so every problem with a file becomes an
``InputError`` that names the file and says what is wrong.  Point data is parsed with numpy in bulk;
Python loops only walk records whose length varies (mixed polygons, Cyberware ``range_grid``).

One module per format (ply, pcd, e57, xyz for the text clouds, stl, obj, off), each parsing bytes into
``common._Parsed``; ``common`` holds what they share, ``thinning`` reads a large binary PLY thinned.
Units are applied here, in ``read_cloud``.
"""
from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..files import checked_input, read_bytes
from ..geometry import Cloud, checked
from ..units import extent_warnings, mm_per_unit
from .common import _Parsed
from .e57 import _read_e57
from .obj import _parse_obj
from .off import _parse_off
from .pcd import _parse_pcd
from .ply import _parse_ply
from .stl import STL_RECORD, _parse_stl
from .thinning import LARGE_SCAN_POINTS, _thinned_ply
from .xyz import _parse_text_cloud

__all__ = ["LARGE_SCAN_POINTS", "STL_RECORD", "read_cloud"]


def read_cloud(path, units: str | None = "mm", name: str | None = None, unit_option: str = "unit",
               max_points: int | None = None) -> Cloud:
    """Read a point cloud or mesh file into a checked ``Cloud`` in mm.

    ``units`` is the file's length unit; ``None`` uses the ``comment units`` line of a PLY written by
    WorkCal (mm when there is none).  ``name`` defaults to the file name.  ``unit_option`` is how the
    caller's user sets the unit (e.g. "--model-units"), named in a warning about a suspect size.
    ``max_points``: a binary PLY point cloud holding more points is read in chunks and thinned as it
    is read (``_thinned_ply``), so it is never in memory whole; a warning says so.
    """
    path = Path(path)
    parse = _PARSERS.get(path.suffix.lower())
    if parse is None:
        raise InputError(f"{path}: unknown file type {path.suffix or '(no extension)'!r}; "
                         f"WorkCal reads {', '.join(_PARSERS)}")
    scale = None if units is None else mm_per_unit(units)  # a bad unit is refused before reading
    label = str(path)
    if parse is _read_e57:  # pye57 reads the file itself; E57 coordinates are metres by the standard
        checked_input(path)
        parsed, units = _read_e57(path, label), "m"
        scale = mm_per_unit(units)
    else:
        parsed = _thinned_ply(path, label, max_points) if max_points and parse is _parse_ply else None
        if parsed is None:
            parsed = _parsed(parse, read_bytes(path), label)
    if scale is None:
        units = parsed.units or "mm"
        try:
            scale = mm_per_unit(units)
        except InputError as exc:
            raise InputError(f"{label}: the file declares {exc}") from None
    with np.errstate(over="ignore"):  # a value too large in mm becomes inf: refused or dropped by checked
        points = parsed.points if scale == 1 else parsed.points * scale  # (no copy of millions of points in mm)
    sensors = None if parsed.sensors is None else parsed.sensors * scale
    cloud = checked(Cloud(points, parsed.normals, parsed.triangles, path.name, list(parsed.warnings), sensors,
                          parsed.sensor_of))
    cloud.name = name or path.name
    cloud.warnings += extent_warnings(cloud.points, path.name, units, unit_option)
    return cloud


def _parsed(parse, data: bytes, label: str) -> _Parsed:
    try:
        return parse(data, label)
    except (ValueError, IndexError, struct.error, OverflowError) as exc:
        # Parsers report every problem they know of; this keeps an unforeseen one an InputError.
        raise InputError(f"{label}: cannot be read as a {label.rsplit('.', 1)[-1]} file ({exc})") from None


_PARSERS = {".ply": _parse_ply, ".pcd": _parse_pcd, ".e57": _read_e57, ".xyz": _parse_text_cloud, ".asc": _parse_text_cloud,
            ".pts": _parse_text_cloud, ".csv": _parse_text_cloud, ".txt": _parse_text_cloud,
            ".stl": _parse_stl, ".obj": _parse_obj, ".off": _parse_off}
