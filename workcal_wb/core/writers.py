"""Write clouds and meshes as PLY, XYZ and binary STL.

Writes are atomic and refuse NaN, infinite values and broken faces, so a file WorkCal leaves behind
is either complete and valid or not there at all.
"""
from __future__ import annotations

import numpy as np

from .atomic import atomic_write_bytes
from .errors import InputError
from .geometry import Cloud
from .readers import STL_RECORD
from .units import mm_per_unit


def write_ply(path, cloud: Cloud, binary: bool = True, units: str = "mm") -> None:
    """PLY with normals and faces when the cloud has them; ``comment units`` lets
    ``read_cloud(path, units=None)`` restore the scale."""
    points = _checked_points(path, cloud, units)
    vertex_names = ["x", "y", "z"] + (["nx", "ny", "nz"] if cloud.normals is not None else [])
    vertices = points if cloud.normals is None else np.hstack([points, cloud.normals])
    triangles = cloud.triangles if cloud.is_mesh else np.zeros((0, 3), dtype=np.int64)
    header = ["ply", f"format {'binary_little_endian' if binary else 'ascii'} 1.0",
              f"comment units {units}", "comment written by WorkCal",
              f"element vertex {len(vertices)}", *(f"property double {name}" for name in vertex_names)]
    if len(triangles):
        header += [f"element face {len(triangles)}", "property list uchar int vertex_indices"]
    header.append("end_header\n")
    if binary:
        faces = np.zeros(len(triangles), dtype=[("corners", "u1"), ("indices", "<i4", (3,))])
        faces["corners"] = 3
        faces["indices"] = triangles
        body = vertices.astype("<f8").tobytes() + faces.tobytes()
    else:
        body = (_text_rows(vertices, "%r") + _text_rows(triangles, "%d", prefix="3 ")).encode()
    atomic_write_bytes(path, "\n".join(header).encode() + body)


def write_xyz(path, cloud: Cloud, units: str = "mm") -> None:
    """One 'x y z' line per point ('x y z nx ny nz' under a '# x y z nx ny nz' header with normals)."""
    points = _checked_points(path, cloud, units)
    if cloud.normals is None:
        text = _text_rows(points, "%r")
    else:
        text = "# x y z nx ny nz\n" + _text_rows(np.hstack([points, cloud.normals]), "%r")
    atomic_write_bytes(path, text.encode())


def write_stl(path, cloud: Cloud) -> None:
    """Binary STL in mm (STL has no unit field; mm is what CAD and CAM tools assume)."""
    if not cloud.is_mesh:
        raise InputError(f"{path}: {cloud.name} has no triangles; STL can only hold a mesh")
    corners = _checked_points(path, cloud, "mm")[cloud.triangles]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    lengths = np.linalg.norm(normals, axis=1, keepdims=True)
    records = np.zeros(len(corners), dtype=STL_RECORD)
    records["normal"] = np.divide(normals, lengths, out=np.zeros_like(normals), where=lengths > 0)
    records["corners"] = corners
    title = f"WorkCal binary STL, units mm: {cloud.name}".encode("ascii", "replace")[:80]
    atomic_write_bytes(path, title.ljust(80) + np.uint32(len(records)).tobytes() + records.tobytes())


def _checked_points(path, cloud: Cloud, units: str) -> np.ndarray:
    """The points in ``units``, after refusing what would make a file that cannot be read back."""
    scale = mm_per_unit(units)
    if len(cloud.points) == 0:
        raise InputError(f"{path}: {cloud.name} has no points to write")
    if not np.isfinite(cloud.points).all():
        raise InputError(f"{path}: {cloud.name} has NaN or infinite coordinates; nothing was written")
    if cloud.normals is not None and cloud.normals.shape != cloud.points.shape:
        raise InputError(f"{path}: {cloud.name} has {len(cloud.normals)} normals for {len(cloud.points)} points")
    if cloud.normals is not None and not np.isfinite(cloud.normals).all():
        raise InputError(f"{path}: {cloud.name} has NaN or infinite normals; nothing was written")
    if cloud.is_mesh and ((cloud.triangles < 0) | (cloud.triangles >= len(cloud.points))).any():
        raise InputError(f"{path}: {cloud.name} has faces that refer to vertices that do not exist; "
                         "nothing was written")
    return cloud.points / scale


def _text_rows(values: np.ndarray, number_format: str, prefix: str = "") -> str:
    """Rows of numbers in one formatting call; '%r' on Python floats is the shortest exact form."""
    if len(values) == 0:
        return ""
    row = prefix + " ".join([number_format] * values.shape[1]) + "\n"
    return (row * len(values)) % tuple(values.ravel().tolist())
