"""The one geometry type WorkCal passes around: points in mm, optional normals, optional triangles."""
from __future__ import annotations

import zlib
from dataclasses import dataclass, field

import numpy as np

from .errors import InputError

# No scanner measures a point 1000 km away: a coordinate beyond this is a corrupt value (1e308), and
# kept it would overflow the geometry (squared distances, voxel indices) of every later step.
MAX_COORDINATE_MM = 1e9
SHAPE_BLOCK = 1 << 16  # points per block of shape_kind's scatter matrix


@dataclass
class Cloud:
    """A scan or a model.  ``triangles`` is set when the points are the vertices of a mesh, so the
    model can be matched as a surface rather than as its vertices.  ``sensors``, when a scan's file
    tells them, are the scanner positions (k x 3, mm, the points' frame) and ``sensor_of`` which of
    them saw each point (None: the first saw all)."""

    points: np.ndarray
    normals: np.ndarray | None = None
    triangles: np.ndarray | None = None
    name: str = "cloud"
    warnings: list[str] = field(default_factory=list)
    sensors: np.ndarray | None = None
    sensor_of: np.ndarray | None = None
    # CRC-32 of the arrays as ``checked`` passed them: a cloud checked once is not sorted for duplicates
    # again (seconds for millions of points) unless its data changed since.
    verified: int | None = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        self.points = np.ascontiguousarray(self.points, dtype=float).reshape(-1, 3)
        if self.normals is not None:
            self.normals = np.ascontiguousarray(self.normals, dtype=float).reshape(-1, 3)
        if self.triangles is not None:
            self.triangles = np.ascontiguousarray(self.triangles, dtype=np.int64).reshape(-1, 3)
        if self.sensors is not None:
            self.sensors = np.ascontiguousarray(self.sensors, dtype=float).reshape(-1, 3)
        if self.sensor_of is not None:
            self.sensor_of = np.ascontiguousarray(self.sensor_of, dtype=np.int64).reshape(-1)

    def __len__(self) -> int:
        return len(self.points)

    @property
    def is_mesh(self) -> bool:
        return self.triangles is not None and len(self.triangles) > 0

    def diagonal(self) -> float:
        """Length of the bounding-box diagonal in mm (0 for fewer than two points)."""
        if len(self.points) < 2:
            return 0.0
        return float(np.linalg.norm(self.points.max(axis=0) - self.points.min(axis=0)))

    def subset(self, indices, name: str | None = None) -> "Cloud":
        """The selected points (as a point cloud: triangles do not survive a subset)."""
        idx = np.asarray(indices)
        normals = None if self.normals is None else self.normals[idx]
        return Cloud(self.points[idx], normals, None, name or self.name, list(self.warnings), self.sensors,
                     None if self.sensor_of is None else self.sensor_of[idx])

    def transformed(self, T: np.ndarray) -> "Cloud":
        from .frames import apply, apply_vectors

        normals = None if self.normals is None else apply_vectors(T, self.normals)
        sensors = None if self.sensors is None else apply(T, self.sensors)
        return Cloud(apply(T, self.points), normals, self.triangles, self.name, list(self.warnings), sensors,
                     self.sensor_of)

    def sensor_indices(self) -> np.ndarray | None:
        """Which of ``sensors`` saw each point (None without sensors)."""
        if self.sensors is None:
            return None
        return np.zeros(len(self.points), dtype=np.int64) if self.sensor_of is None else self.sensor_of


def checked(cloud: Cloud, min_points: int = 1) -> Cloud:
    """Drop non-finite and duplicate points, and a mesh's faces that cover nothing, with a warning;
    refuse a cloud that is left too small.

    Scanners write NaN for pixels without a return and repeat points at seams; both are normal
    and only worth a warning, but a cloud with (almost) nothing left is an error that names it.
    Coordinates beyond MAX_COORDINATE_MM count as not finite.
    """
    pts = cloud.points
    if cloud.verified is not None and len(pts) >= min_points and cloud.verified == _crc(cloud):
        return cloud
    if len(pts) == 0:
        raise InputError(f"{cloud.name}: contains no points")
    finite = _within(pts, MAX_COORDINATE_MM)  # False for NaN too
    warnings = list(cloud.warnings)
    normals = cloud.normals
    if normals is not None:
        unusable = finite & ~_within(normals, np.inf)
        if unusable.any():  # a normal the scanner could not estimate says nothing against its point
            warnings.append(f"{cloud.name}: {int(unusable.sum())} points have NaN or infinite normals: the "
                            "file's normals were not used")
            normals = None
    if cloud.is_mesh:
        if not finite.all():
            raise InputError(f"{cloud.name}: {int((~finite).sum())} mesh vertices are NaN or infinite (or beyond "
                             f"{MAX_COORDINATE_MM / 1e6:g} km)")
        bad = (cloud.triangles < 0) | (cloud.triangles >= len(pts))
        if bad.any():
            raise InputError(f"{cloud.name}: faces refer to vertices that do not exist "
                             f"(indices outside 0..{len(pts) - 1})")
        collapsed = _collapsed_faces(pts, cloud.triangles)
        if collapsed.any():
            warnings.append(f"{cloud.name}: ignored {int(collapsed.sum())} faces with two corners at one point")
        repeated = _repeated_faces(cloud.triangles)
        if repeated.any():
            warnings.append(f"{cloud.name}: ignored {int(repeated.sum())} faces repeating an earlier face")
        if (collapsed | repeated).all():  # its vertices alone are no model of its surface
            raise InputError(f"{cloud.name}: none of its {len(collapsed)} faces covers any area (each has two "
                             "corners at one point)")
        return _verified(Cloud(pts, normals, cloud.triangles[~(collapsed | repeated)], cloud.name, warnings,
                               cloud.sensors, cloud.sensor_of))
    keep = finite  # a mask, not indices: a large scan's copies set a match's peak memory
    kept = int(keep.sum())
    if kept < len(pts):
        warnings.append(f"{cloud.name}: ignored {len(pts) - kept} points with NaN or infinite coordinates "
                        f"(or beyond {MAX_COORDINATE_MM / 1e6:g} km)")
    if kept == 0:
        raise InputError(f"{cloud.name}: all {len(pts)} points have NaN or infinite coordinates (or beyond "
                         f"{MAX_COORDINATE_MM / 1e6:g} km)")
    duplicate = _duplicates(pts if kept == len(pts) else pts[keep])
    if duplicate.any():
        warnings.append(f"{cloud.name}: ignored {int(duplicate.sum())} duplicate points")
        keep[np.flatnonzero(keep)[duplicate]] = False
        kept = int(keep.sum())
    if kept < min_points:
        raise InputError(f"{cloud.name}: only {kept} usable points, at least {min_points} needed")
    if kept == len(pts):
        return _verified(Cloud(pts, normals, None, cloud.name, warnings, cloud.sensors, cloud.sensor_of))
    return _verified(Cloud(pts[keep], None if normals is None else normals[keep], None, cloud.name, warnings,
                           cloud.sensors, None if cloud.sensor_of is None else cloud.sensor_of[keep]))


def _collapsed_faces(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Mask of the faces with two corners at one point as a distance query holds them (float32 about
    the vertices' mean, SurfaceModel._bvh): an edge whose squared length is 0 in float32 (equal corners,
    or corners a denormal apart).  Such a face covers nothing, and open3d's distance query aborts the
    whole process on one (an Eigen assertion)."""
    held = (points - points.mean(axis=0)).astype(np.float32)
    a, b, c = (held[triangles[:, i]] for i in range(3))
    with np.errstate(under="ignore"):
        return np.logical_or.reduce([np.einsum("ij,ij->i", e, e) == 0 for e in (b - a, c - b, a - c)])


def _repeated_faces(triangles: np.ndarray) -> np.ndarray:
    """Mask of the faces on the same three vertices as an earlier face (either winding): a copy covers
    nothing new, and a million copies would ask the model for billions of samples."""
    corners = np.sort(triangles, axis=1)
    order = np.lexsort(corners.T[::-1])  # by first, then second, then third corner; stable
    same = (corners[order[1:]] == corners[order[:-1]]).all(axis=1)
    mask = np.zeros(len(triangles), bool)
    mask[order[1:][same]] = True
    return mask


def _within(values: np.ndarray, limit: float) -> np.ndarray:
    """Rows of an (N, 3) array whose three values all lie within +-limit (NaN never does), a column at
    a time (numpy reduces along a short axis slowly)."""
    return (np.abs(values[:, 0]) <= limit) & (np.abs(values[:, 1]) <= limit) & (np.abs(values[:, 2]) <= limit)


def _verified(cloud: Cloud) -> Cloud:
    cloud.verified = _crc(cloud)
    return cloud


def _crc(cloud: Cloud) -> int:
    crc = zlib.crc32(cloud.points.data)
    for extra in (cloud.normals, cloud.triangles):
        crc = zlib.crc32(b"-" if extra is None else extra.data, crc)
    return crc


def _duplicates(points: np.ndarray) -> np.ndarray:
    """Mask of points equal to an earlier point.  Hashes of the coordinate bits bucket the points, and
    only those sharing a bucket under each of a few hashes are sorted by their key (stably) and
    compared exactly with their neighbours, so a collision cannot merge two points and millions of
    unique points are never sorted."""
    # Integer work in place, one column's copy at a time (+ 0.0: -0.0 as 0.0): a large scan's copies
    # set a match's peak memory.
    key = np.zeros(len(points), np.int64)
    for k, factor in enumerate((1000003, 999983, 1)):
        column = (points[:, k] + 0.0).view(np.int64)
        column *= factor
        key += column
    column = None
    order = None  # the candidates, ascending (None: every point)
    # A bucket is the top bits of a multiplicative hash of the key: the key's low bits are all zero for
    # coordinates that were float32 (most scanners' files), so they would put every point in one bucket.
    # About as many buckets as candidates: their int64 counts, not the scan, set the search's peak.
    for multiplier in _BUCKET_HASHES:
        candidates = len(points) if order is None else len(order)
        bits = int(np.clip(np.ceil(np.log2(candidates + 1)), 10, 23))
        bucket = (key.copy() if order is None else key[order]).view(np.uint64)
        bucket *= np.uint64(multiplier)
        bucket >>= np.uint64(64 - bits)
        bucket = bucket.view(np.int64)  # under 2**23
        shared = np.bincount(bucket, minlength=1 << bits) > 1
        order = np.flatnonzero(shared[bucket]) if order is None else order[shared[bucket]]
    order = order[np.argsort(key[order], kind="stable")]
    # The points sharing their key with another, by key and then by coordinates (stable): copies of a
    # point lie side by side even where a different point shares their key (it is linear in the
    # coordinates' bits), the first copy first.
    ties = key[order[1:]] == key[order[:-1]]
    in_run = np.zeros(len(order), bool)
    in_run[1:] |= ties
    in_run[:-1] |= ties
    order = order[in_run]
    order = order[np.lexsort((points[order, 2], points[order, 1], points[order, 0], key[order]))]
    later, earlier = order[1:], order[:-1]
    pairs = np.flatnonzero(key[later] == key[earlier])
    later, earlier = later[pairs], earlier[pairs]
    same = np.all(points[later] == points[earlier], axis=1)
    mask = np.zeros(len(points), bool)
    mask[later[same]] = True
    return mask


# Odd 64-bit multipliers (the golden ratio's and two of xxHash's primes), one per bucketing pass.
_BUCKET_HASHES = (0x9E3779B97F4A7C15, 0xC2B2AE3D27D4EB4F, 0x165667B19E3779F9)


# How a sentence says where points of each shape_kind lie.
SHAPE_WORDS = {"point": "all at one point (or within a nanometre of it)", "linear": "on a line", "planar": "on a plane",
               "solid": "spread in three dimensions"}


def shape_kind(points: np.ndarray) -> str:
    """'solid', 'planar', 'linear' or 'point': a pose can only be fitted to a 'solid' spread."""
    if len(points) < 3:
        return "point"
    mean, scatter = points.mean(axis=0), np.zeros((3, 3))
    for start in range(0, len(points), SHAPE_BLOCK):  # a block's centred copy, not a large scan's
        centred = points[start:start + SHAPE_BLOCK] - mean
        scatter += centred.T @ centred
    s = np.sqrt(np.maximum(np.linalg.eigvalsh(scatter / len(points)), 0))[::-1]
    if s[0] <= 1e-9:
        return "point"
    if s[1] < 5e-3 * s[0]:
        return "linear"
    if s[2] < 5e-3 * s[0]:
        return "planar"
    return "solid"
