"""A structured-light range scanner like the paper's Minolta VI-700, rendering a Scene by ray casting
(open3d, where it works) or by our own z-buffer.

The scanner frame S has its origin at the scanner, z along the viewing direction, x to the right
and y down in the image.  Pixel (r, c) samples the ray through ((c - cx) k, (r - cy) k, 1) with
k = pitch / focus distance, so neighbouring samples are ``pixel_pitch_mm`` apart at the focus
distance (0.35 mm is the VI-700's finest); the zoom changes the pitch, not the image size.

Each return is the nearest surface along its ray (exact occlusion), dropped when the ray meets the
surface at more than ``max_incidence_deg`` from its normal, displaced along the ray by Gaussian
noise and rounded to multiples of ``z_resolution_mm`` in depth (z of S), like the VI-700's 0.11 mm.
Not modelled: the projector's shadowing (triangulation baseline), stand-off limits, reflectance.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from .. import frames, raycast
from ..errors import InputError
from ..geometry import Cloud
from ..pointops import triangle_normals_and_areas
from .raster import front_triangles

DEFAULT_AZIMUTH_DEG = 45.0  # sees the L-block's inner faces, with the workpiece beside it, not in front
DEFAULT_ELEVATION_DEG = 45.0
DEFAULT_DISTANCE_MM = 1200.0  # the paper's "approximately 1.2 m scanning distance"
_NEAR_MM = 1.0  # triangles closer to the scanner plane than this are not rendered
# A depth edge: neighbouring pixels whose surfaces lie more than this apart in depth (mm).  A mixed pixel
# there returns a depth this share of the way from the near surface to the far one (drawn uniformly).
MIXED_JUMP_MM, MIXED_SPAN = 5.0, (0.1, 0.9)


@dataclass
class Scanner:
    position: tuple  # in B, mm
    look_at: tuple  # in B, mm; the focus distance is |look_at - position|
    up: tuple = (0.0, 0.0, 1.0)  # in B; the image's "up" (-y of S) points as close to it as possible
    pixel_pitch_mm: float = 0.35
    image_size: tuple = (640, 480)  # (columns, rows)
    z_resolution_mm: float = 0.11  # 0 = no quantisation
    noise_sigma_mm: float = 0.1  # along the ray
    max_incidence_deg: float = 75.0
    seed: int = 0
    mixed_pixel_share: float = 0.0  # returns turned into mixed pixels at depth edges, as a share of all returns

    def __post_init__(self):
        self.position = np.asarray(self.position, dtype=float)
        self.look_at = np.asarray(self.look_at, dtype=float)
        if self.focus_distance_mm <= _NEAR_MM:
            raise InputError("scanner: look_at must be away from the scanner position")
        if np.linalg.norm(np.cross(self.look_at - self.position, self.up)) < 1e-9 * self.focus_distance_mm:
            raise InputError("scanner: the up vector is parallel to the viewing direction")
        if self.pixel_pitch_mm <= 0 or min(self.image_size) < 1:
            raise InputError(f"scanner: pitch must be > 0 mm and the image at least 1 x 1, got "
                             f"{self.pixel_pitch_mm} mm, {self.image_size}")
        if self.noise_sigma_mm < 0 or self.z_resolution_mm < 0 or not 0 < self.max_incidence_deg <= 90:
            raise InputError("scanner: noise and z resolution must be >= 0 mm, max incidence in (0, 90] deg")
        if not 0 <= self.mixed_pixel_share < 1:
            raise InputError(f"scanner: the share of mixed pixels must be in [0, 1), got {self.mixed_pixel_share}")

    @property
    def focus_distance_mm(self) -> float:
        return float(np.linalg.norm(self.look_at - self.position))

    @property
    def window_mm(self) -> tuple[float, float]:
        """Width and height of the scanned area at the focus distance."""
        return self.image_size[0] * self.pixel_pitch_mm, self.image_size[1] * self.pixel_pitch_mm

    def frame(self) -> np.ndarray:
        """^B S: the scanner's frame in the robot base frame."""
        z = (self.look_at - self.position) / self.focus_distance_mm
        x = np.cross(z, self.up)
        x /= np.linalg.norm(x)
        return frames.rigid(np.column_stack([x, np.cross(z, x), z]), self.position)

    def zoomed(self, pixel_pitch_mm: float) -> "Scanner":
        """The same scanner, not moved, with the zoom set to another pitch (a second capture)."""
        return replace(self, pixel_pitch_mm=pixel_pitch_mm)

    def to_dict(self) -> dict:
        return {"position_mm": self.position.tolist(), "look_at_mm": self.look_at.tolist(), "up": list(self.up),
                "pixel_pitch_mm": self.pixel_pitch_mm, "image_size": list(self.image_size),
                "focus_distance_mm": self.focus_distance_mm, "z_resolution_mm": self.z_resolution_mm,
                "noise_sigma_mm": self.noise_sigma_mm, "max_incidence_deg": self.max_incidence_deg,
                "seed": self.seed, "mixed_pixel_share": self.mixed_pixel_share}

    def ray_directions(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Directions in S through pixel centres, scaled so that z = 1 (a point is depth * direction)."""
        k = self.pixel_pitch_mm / self.focus_distance_mm
        return np.column_stack([(cols - 0.5 * (self.image_size[0] - 1)) * k,
                                (rows - 0.5 * (self.image_size[1] - 1)) * k, np.ones(len(rows))])

    def scan(self, scene, normals: bool = False, cast_rays: bool | None = None) -> "ScanResult":
        """One capture of the scene: points in S (mm) labelled with the index of the object they lie on.
        ``cast_rays``: find each pixel's surface by open3d's ray casting (True), by our z-buffer
        (False), or by ray casting where it works (None; see raycast)."""
        started = time.perf_counter()
        B_S = self.frame()
        vertices, triangles, owner = _all_triangles_in(scene, frames.invert(B_S))
        face_normals, _ = triangle_normals_and_areas(vertices, triangles)
        corners = vertices[triangles]
        # Closed outward meshes: only faces turned towards the scanner can be seen or hide anything.
        facing = np.flatnonzero((np.einsum("ij,ij->i", face_normals, corners[:, 0]) < 0)
                                & (corners[:, :, 2].min(axis=1) > _NEAR_MM))
        cols, rows = self.image_size
        if raycast.works() if cast_rays is None else cast_rays:
            pixel = np.arange(rows * cols)
            directions = self.ray_directions(*np.divmod(pixel, cols))
            depth, tri = raycast.cast(vertices, triangles[facing], np.zeros(3), directions)
            pixel = np.flatnonzero(tri >= 0)
            tri, depth = tri[pixel], depth[pixel]  # directions have z = 1: the distance along them is the depth
        else:
            corners = corners[facing]
            k = self.pixel_pitch_mm / self.focus_distance_mm
            image_centre = 0.5 * (np.array(self.image_size, dtype=float) - 1)
            pixel, tri, inverse_depth = front_triangles(corners[:, :, :2] / corners[:, :, 2:] / k + image_centre,
                                                        1.0 / corners[:, :, 2], (rows, cols))
            depth = 1.0 / inverse_depth
        tri = facing[tri]
        pixel_rows, pixel_cols = pixel // cols, pixel % cols
        direction = self.ray_directions(pixel_rows, pixel_cols)
        length = np.linalg.norm(direction, axis=1)
        cos_incidence = -np.einsum("ij,ij->i", face_normals[tri], direction) / length
        seen = cos_incidence >= np.cos(np.radians(self.max_incidence_deg))
        direction, length, tri, depth = direction[seen], length[seen], tri[seen], depth[seen]
        rng = np.random.default_rng(self.seed)
        depth = depth + rng.normal(0.0, self.noise_sigma_mm, len(depth)) / length
        mixed = np.zeros(len(depth), bool)
        if self.mixed_pixel_share > 0:
            depth, mixed = _mixed_pixels(pixel[seen], depth, (rows, cols), self.mixed_pixel_share,
                                         np.random.default_rng([self.seed, 1]))
        if self.z_resolution_mm > 0:
            depth = np.round(depth / self.z_resolution_mm) * self.z_resolution_mm
        return ScanResult(
            points=depth[:, None] * direction,
            labels=owner[tri],
            pixels=np.column_stack([pixel_rows[seen], pixel_cols[seen]]),
            normals=face_normals[tri] if normals else None,
            object_names=[o.name for o in scene.objects],
            object_roles=[o.role for o in scene.objects],
            B_S=B_S,
            W=scene.W,
            scanner=self,
            time_s=time.perf_counter() - started,
            mixed=mixed,
        )

    @classmethod
    def aimed_at(cls, scene, azimuth_deg: float = DEFAULT_AZIMUTH_DEG, elevation_deg: float = DEFAULT_ELEVATION_DEG,
                 distance_mm: float = DEFAULT_DISTANCE_MM, margin: float = 0.1, **settings) -> "Scanner":
        """A scanner ``distance_mm`` from the middle of workpiece and reference, looking at it, from the
        given direction (azimuth about B's z from +x, elevation above the horizontal), zoomed so that
        both fit in the image with ``margin`` to spare (unless ``pixel_pitch_mm`` is given)."""
        points = np.vstack([scene.workpiece.in_base().points, scene.reference_model().points])
        target = 0.5 * (points.min(axis=0) + points.max(axis=0))
        az, el = np.radians(azimuth_deg), np.radians(elevation_deg)
        position = target + distance_mm * np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
        image_size = settings.pop("image_size", cls.image_size)
        pitch = settings.pop("pixel_pitch_mm", None)
        if pitch is None:
            pitch = cls.fitting_pitch(position, target, points, image_size, margin)
        return cls(position, target, pixel_pitch_mm=pitch, image_size=image_size, **settings)

    @classmethod
    def fitting_pitch(cls, position, target, points: np.ndarray, image_size, margin: float = 0.1) -> float:
        """The pitch at which the outermost of ``points`` (B) lands on the image border, plus margin."""
        seen = frames.apply(frames.invert(cls(position, target).frame()), points)
        slope = np.abs(seen[:, :2] / seen[:, 2:]).max(axis=0) / (0.5 * np.array(image_size))
        return (1 + margin) * float(np.linalg.norm(np.asarray(target) - position)) * float(slope.max())


def _mixed_pixels(pixel: np.ndarray, depth: np.ndarray, shape: tuple, share: float, rng):
    """(depths, which returns are mixed): up to ``share`` of the returns, drawn among the pixels on
    either side of a depth edge (a 4-neighbour more than MIXED_JUMP_MM away in depth), each moved along
    its ray to a depth between the edge's near and far surface."""
    rows, cols = shape
    image = np.full(rows * cols, np.inf)
    image[pixel] = depth
    image = image.reshape(rows, cols)
    near_of, far_of = np.full((rows, cols), np.nan), np.full((rows, cols), np.nan)
    for a, b in (((slice(None), slice(None, -1)), (slice(None), slice(1, None))),
                 ((slice(None, -1), slice(None)), (slice(1, None), slice(None)))):
        for here, there in ((a, b), (b, a)):
            d, e = image[here], image[there]
            with np.errstate(invalid="ignore"):
                edge = np.isfinite(d) & np.isfinite(e) & (np.abs(d - e) > MIXED_JUMP_MM)
            near, far = near_of[here], far_of[here]
            near[edge], far[edge] = np.minimum(d, e)[edge], np.maximum(d, e)[edge]
    candidates = np.flatnonzero(np.isfinite(near_of.ravel()))
    index = np.full(rows * cols, -1)
    index[pixel] = np.arange(len(pixel))
    chosen = rng.permutation(candidates)[:int(round(share * len(depth)))]
    span = rng.uniform(*MIXED_SPAN, len(chosen))
    out, mixed = depth.copy(), np.zeros(len(depth), bool)
    near, far = near_of.ravel()[chosen], far_of.ravel()[chosen]
    out[index[chosen]] = near + span * (far - near)
    mixed[index[chosen]] = True
    return out, mixed


def scan_part(mesh: Cloud, pose: np.ndarray, direction, distance_mm: float = 600.0, samples: int = 20000,
              **settings) -> "ScanResult":
    """One capture of ``mesh`` alone (no platform, no reference) placed at ``pose`` (^B X), by a
    scanner ``distance_mm`` from its middle along ``direction`` (towards the scanner, in B), zoomed
    so that about ``samples`` pixels fall on a square the size of the part's diagonal.  ``settings``
    go to the Scanner (noise_sigma_mm, z_resolution_mm, seed, ...)."""
    from .scene import object_scene

    placed = frames.apply(pose, mesh.points)
    centre = 0.5 * (placed.min(axis=0) + placed.max(axis=0))
    direction = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
    size = float(np.linalg.norm(placed.max(axis=0) - placed.min(axis=0)))
    pitch = size / np.sqrt(samples)
    side = int(1.2 * size / pitch) + 8
    up = (0.0, 0.0, 1.0) if abs(direction[2]) < 0.9 else (1.0, 0.0, 0.0)
    scanner = Scanner(centre + distance_mm * direction, centre, up=up, pixel_pitch_mm=pitch, image_size=(side, side),
                      **settings)
    return scanner.scan(object_scene(mesh, pose))


def _all_triangles_in(scene, S_B: np.ndarray):
    """Every object's vertices moved into S, their triangles re-indexed into one list, and each
    triangle's object index."""
    vertices = [frames.apply(S_B @ obj.pose, obj.mesh.points) for obj in scene.objects]
    offsets = np.cumsum([0] + [len(v) for v in vertices])
    triangles = np.vstack([obj.mesh.triangles + offset for obj, offset in zip(scene.objects, offsets)])
    owner = np.concatenate([np.full(len(obj.mesh.triangles), i) for i, obj in enumerate(scene.objects)])
    return np.vstack(vertices), triangles, owner


def scanner_ring(scene, k: int, distance: float = DEFAULT_DISTANCE_MM, elevation: float = DEFAULT_ELEVATION_DEG,
                 seed: int = 0, arc_deg: float = 360.0, azimuth_deg: float = DEFAULT_AZIMUTH_DEG,
                 **settings) -> list:
    """k scanner placements spread evenly over ``arc_deg`` of azimuth centred on ``azimuth_deg``.

    The seed jitters each placement a little (azimuth by a tenth of the spacing, elevation by up to
    3 deg, distance by up to 5 %) as a tripod would be set down, and gives each its own noise seed.
    One placement (k = 1) is the default set-up.
    """
    if k < 1:
        raise InputError(f"scanner ring: need at least one position, got {k}")
    rng = np.random.default_rng(seed)
    spacing = arc_deg / k
    ring = []
    for i in range(k):
        jitter = rng.uniform(-1.0, 1.0, 3) if k > 1 else np.zeros(3)
        ring.append(Scanner.aimed_at(
            scene,
            azimuth_deg=azimuth_deg + arc_deg * ((i + 0.5) / k - 0.5) + 0.1 * spacing * jitter[0],
            elevation_deg=elevation + 3.0 * jitter[1],
            distance_mm=distance * (1 + 0.05 * jitter[2]),
            seed=seed + i,
            **settings,
        ))
    return ring


@dataclass
class ScanResult:
    """One capture: points in S with per-point ground truth, and the true frames."""

    points: np.ndarray  # (N, 3) in S, mm
    labels: np.ndarray  # (N,) index into object_names / object_roles
    pixels: np.ndarray  # (N, 2) image row and column of each point
    normals: np.ndarray | None  # (N, 3) true outward surface normals in S, if asked for
    object_names: list
    object_roles: list
    B_S: np.ndarray  # ^B S
    W: np.ndarray  # ^B X
    scanner: Scanner
    time_s: float = 0.0
    mixed: np.ndarray | None = None  # (N,) whether each return is a mixed pixel (between two surfaces)

    @property
    def V(self) -> np.ndarray:
        """^S B: the robot base frame seen from the scanner."""
        return frames.invert(self.B_S)

    @property
    def U(self) -> np.ndarray:
        """^S X: the workpiece model frame seen from the scanner (so W = V^-1 U)."""
        return self.V @ self.W

    def mask(self, role: str) -> np.ndarray:
        """Which points lie on objects of this role ("platform", "reference", "workpiece", "clutter")."""
        return np.isin(self.labels, [i for i, r in enumerate(self.object_roles) if r == role])

    def counts(self) -> dict:
        """Number of points per role."""
        return {role: int(self.mask(role).sum()) for role in dict.fromkeys(self.object_roles)}

    def cloud(self, role: str | None = None, name: str = "scan") -> Cloud:
        """The points (of one role, or all) as a Cloud in S."""
        keep = slice(None) if role is None else self.mask(role)
        return Cloud(self.points[keep], None if self.normals is None else self.normals[keep], name=name)
