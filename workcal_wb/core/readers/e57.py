"""E57, read with pye57: every scan in the file's frame, each with its scanner position."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError
from .common import _Parsed, _truncated


def _read_e57(path: Path, label: str) -> _Parsed:
    """Every scan of an E57 file in the file's common frame, each moved by its stored pose, with each
    scan's scanner position (the pose's translation) kept for the free-space test.  Points a scan marks
    invalid are dropped; each scan's point count is checked against its header."""
    try:
        import pye57
    except ImportError:
        from ..errors import MissingDependency

        raise MissingDependency(f"{label}: E57 files are read with the Python package pye57, which is not installed; "
                                "install it with: python3 -m pip install pye57 (in FreeCAD: the Addon Manager "
                                "installs it with WorkCal, or see the README)") from None
    from ..frames import from_quaternion_wxyz

    try:
        e57 = pye57.E57(str(path))
    except Exception as exc:  # libE57Format reports a broken file as its own exception types
        raise InputError(f"{label}: cannot be read as an E57 file ({exc})") from None
    points, sensors, sensor_of = [], [], []
    for index in range(e57.scan_count):
        try:
            header = e57.get_header(index)
            data = e57.read_scan_raw(index)
        except Exception as exc:
            raise InputError(f"{label}: scan {index} cannot be read ({exc})") from None
        if not all(f"cartesian{axis}" in data for axis in "XYZ"):
            raise InputError(f"{label}: scan {index} has no cartesian coordinates (cartesianX, Y, Z); WorkCal reads "
                             "E57 scans stored as x, y, z")
        xyz = np.column_stack([np.asarray(data[f"cartesian{axis}"], dtype=float) for axis in "XYZ"])
        if len(xyz) != header.point_count:
            raise _truncated(label, header.point_count, f"points in scan {index}", len(xyz))
        if "cartesianInvalidState" in data:
            xyz = xyz[np.asarray(data["cartesianInvalidState"]) == 0]
        pose = from_quaternion_wxyz(np.asarray(header.rotation, dtype=float), np.asarray(header.translation, float))
        points.append(xyz @ pose[:3, :3].T + pose[:3, 3])
        sensors.append(pose[:3, 3])
        sensor_of.append(np.full(len(xyz), index, dtype=np.int64))
    if not points:
        raise InputError(f"{label}: the E57 file holds no scans")
    return _Parsed(np.vstack(points), sensors=np.array(sensors), sensor_of=np.concatenate(sensor_of))
