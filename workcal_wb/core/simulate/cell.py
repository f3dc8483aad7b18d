"""Scene scans as they come from a real cell, not as the simulator's defaults make them.

``cell_scan(CellSpec(...))`` varies what a plain simulation keeps fixed, so that a calibration that
passes proves the method and not the generator:

* the frame the points are exported in: the scanner's own ("sensor"), a frame with z up on the
  table whose origin may lie under it (a turntable, the Stanford scans: "table"), or any rigid
  frame (a scan re-saved by other software: "arbitrary");
* the layout: workpiece and reference apart, touching, or joined by a bridge of clay;
* where the scanner stands: the default view of the L-block's inner faces, or any azimuth and
  elevation (the reference seen from every side);
* the workpiece: the simulated car or figurine, or a real Stanford bunny range scan placed by its
  bun.conf pose (the mesh is rendered only to hide what the real scan's points hide);
* the platform: fully seen, sparse (a dark table returns few points), partly seen (only near the
  objects) or not there at all; and stray points (dust, mixed pixels) on the rays in front of the surfaces.

Every point keeps its role, the truth is exact (bunny: as good as bun.conf), and the scanner's
position and the table's "up" are known in the export frame, for the tests of what a file can tell.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import frames
from ..errors import InputError
from ..geometry import Cloud
from .scanner import DEFAULT_AZIMUTH_DEG, DEFAULT_DISTANCE_MM, DEFAULT_ELEVATION_DEG, Scanner
from .scene import PLATFORM_POSE, build_scene, contact

FRAMES = ("sensor", "table", "arbitrary")
PLATFORMS = ("full", "sparse", "partial", "none")
WORKPIECES = ("car", "figurine", "bunny")
# A sparse platform keeps this share of its points; a partly seen one only those within
# PARTIAL_REACH_MM (seen from above) of the objects.
SPARSE_SHARE, PARTIAL_REACH_MM = 0.06, 40.0
# The bunny scans whose scanner looked from above the bunny's horizon (the others look up from below
# the table), and the bunny model's up axis.
BUNNY_SCANS_FROM_ABOVE = ("bun000.ply", "bun045.ply", "bun090.ply", "bun180.ply", "bun270.ply", "bun315.ply",
                          "top2.ply", "top3.ply")
BUNNY_UP = np.array([0.0, 1.0, 0.0])
# A real scan point is hidden when a rendered surface lies this far (mm) in front of it on its pixel.
OCCLUDED_MM = 1.0
# Stray points lie on real rays, at this range of fractions of the depth of the surface the ray meets.
STRAY_DEPTH = (0.6, 0.995)
# Touching objects are seen from this high above by default: a view into the gap between them.
CONTACT_ELEVATION_DEG = 65.0
# Image size of the simulated scanner: about 90k points over the scene, quick to calibrate.
IMAGE = (368, 276)


@dataclass(frozen=True)
class CellSpec:
    """What varies in a cell scan; every choice is drawn from ``seed`` where it is random."""

    workpiece: str = "car"  # car, figurine or bunny (needs ``bunny_folder`` in cell_scan)
    layout: str = "apart"  # apart, touching or bridge (clay joins workpiece and reference)
    frame: str = "sensor"  # sensor, table or arbitrary
    platform: str = "full"  # full, sparse, partial or none
    azimuth_deg: float | None = None  # None: the default view, or along the contact when objects touch
    elevation_deg: float | None = None  # None: 45 deg, or CONTACT_ELEVATION_DEG when objects touch
    stray_fraction: float = 0.0  # stray points added, as a share of the scan
    noise_mm: float = 0.1
    seed: int = 0

    def __post_init__(self):
        for name, allowed in (("workpiece", WORKPIECES), ("layout", ("apart", "touching", "bridge")),
                              ("frame", FRAMES), ("platform", PLATFORMS)):
            if getattr(self, name) not in allowed:
                raise InputError(f"cell scan: {name} must be one of {allowed}, not {getattr(self, name)!r}")


@dataclass
class CellScan:
    """A cell scan in its export frame F with the truth: W = ^B X, U = ^F X, V = ^F B."""

    cloud: Cloud  # points in F (mm)
    roles: np.ndarray  # per point: platform, reference, workpiece, clutter, bridge or stray
    W: np.ndarray
    F_S: np.ndarray  # ^F S: the export frame from the scanner's frame
    B_S: np.ndarray
    scanner_origin: np.ndarray  # in F
    up: np.ndarray  # the platform's normal (B's z) in F
    workpiece_model: Cloud  # X-A
    reference_model: Cloud  # B-P
    spec: CellSpec
    scanner: Scanner = None
    notes: list = field(default_factory=list)

    @property
    def V(self) -> np.ndarray:
        return self.F_S @ frames.invert(self.B_S)

    @property
    def U(self) -> np.ndarray:
        return self.V @ self.W

    def mask(self, role: str) -> np.ndarray:
        return self.roles == role

    def platform_height_over_origin(self) -> float:
        """How far the platform's top lies above the export frame's origin, along up (mm)."""
        top = frames.apply(self.V, np.array([PLATFORM_POSE[:3, 3]]))[0]
        return float(top @ self.up)

    def moved(self, T: np.ndarray) -> "CellScan":
        """The same scan exported in another frame: every point, and the truth, moved by T."""
        cloud = self.cloud.transformed(T)
        return CellScan(cloud, self.roles, self.W, T @ self.F_S, self.B_S, frames.apply(T, self.scanner_origin[None])[0],
                        T[:3, :3] @ self.up, self.workpiece_model, self.reference_model, self.spec, self.scanner,
                        list(self.notes))


def cell_scan(spec: CellSpec = CellSpec(), bunny_folder: Path | None = None) -> CellScan:
    """Simulate one scan of the cell as ``spec`` says (see the module docstring)."""
    rng = np.random.default_rng(np.random.SeedSequence([spec.seed, 11]))
    bunny = _bunny(bunny_folder, spec, rng) if spec.workpiece == "bunny" else None
    if bunny is None:
        scene = build_scene(spec.workpiece, seed=spec.seed, layout=spec.layout, platform=spec.platform != "none")
        scanner = Scanner.aimed_at(scene, _azimuth(scene, spec, rng), _elevation(spec), image_size=IMAGE,
                                   noise_sigma_mm=spec.noise_mm, seed=spec.seed)
    else:
        scene = build_scene(bunny["mesh"], seed=spec.seed, layout=spec.layout, platform=spec.platform != "none",
                            rotation=bunny["rotation"])
        scanner = _scanner_along(scene, bunny["direction"], spec)
    scan = scanner.scan(scene)
    points, roles = scan.points, np.array(scan.object_roles)[scan.labels]
    if bunny is not None:  # the real range scan instead of the rendered mesh, where nothing hides it
        real = frames.apply(scan.V @ scene.W @ bunny["scan_to_model"], bunny["points"])
        real = real[~_hidden(real, scan, scanner)]
        keep = roles != "workpiece"
        points, roles = np.vstack([points[keep], real]), np.concatenate([roles[keep], np.full(len(real), "workpiece")])
    points, roles = _platform_seen(points, roles, spec, scan, rng)
    if spec.stray_fraction > 0:  # dust and mixed pixels: returns along real rays, short of the surface
        n = int(spec.stray_fraction * len(points))
        stray = points[rng.integers(len(points), size=n)] * rng.uniform(STRAY_DEPTH[0], STRAY_DEPTH[1], (n, 1))
        points, roles = np.vstack([points, stray]), np.concatenate([roles, np.full(n, "stray")])
    order = rng.permutation(len(points))  # a file lists points in its own order
    points, roles = points[order], roles[order]
    F_S = _export_frame(spec, scan.B_S, rng)
    cloud = Cloud(frames.apply(F_S, points), name=f"cell scan {spec.workpiece} {spec.layout} {spec.frame} "
                                                  f"{spec.platform} #{spec.seed}")
    up = F_S[:3, :3] @ frames.invert(scan.B_S)[:3, :3] @ np.array([0.0, 0.0, 1.0])
    workpiece_model = bunny["model"] if bunny is not None else scene.workpiece_model()
    return CellScan(cloud, roles, scene.W, F_S, scan.B_S, F_S[:3, 3].copy(), up, workpiece_model,
                    scene.reference_model(), spec, scanner)


def _azimuth(scene, spec: CellSpec, rng) -> float:
    """The spec's azimuth; by default the usual view, or, where the objects touch, a view along the
    gap between them (from either end, by the seed), so that the scan shows where they meet."""
    if spec.azimuth_deg is not None:
        return spec.azimuth_deg
    if spec.layout == "apart":
        return DEFAULT_AZIMUTH_DEG
    _, away = contact(scene)
    return float(np.degrees(np.arctan2(away[1], away[0]))) + rng.choice([-60.0, 60.0])


def _elevation(spec: CellSpec) -> float:
    if spec.elevation_deg is not None:
        return spec.elevation_deg
    return DEFAULT_ELEVATION_DEG if spec.layout == "apart" else CONTACT_ELEVATION_DEG


def _export_frame(spec: CellSpec, B_S: np.ndarray, rng) -> np.ndarray:
    """^F S: the frame the points are written in."""
    if spec.frame == "sensor":
        return np.eye(4)
    if spec.frame == "table":  # z up on the table, turned and shifted (a turntable's centre); may lie under it
        F_B = frames.rigid(frames.rot_z(rng.uniform(0, 360)), (*rng.uniform(-200, 200, 2), rng.uniform(-50, 250)))
        return F_B @ frames.invert(PLATFORM_POSE) @ B_S
    return frames.random_motion(rng, shift_mm=1000.0)


def _platform_seen(points, roles, spec: CellSpec, scan, rng):
    """The platform's points as the spec sees it: all, a sparse share, or only near the objects."""
    on = roles == "platform"
    if spec.platform == "sparse":
        drop = on & (rng.random(len(points)) > SPARSE_SHARE)
    elif spec.platform == "partial":
        from scipy.spatial import cKDTree

        in_q = frames.apply(frames.invert(PLATFORM_POSE) @ scan.B_S, points)
        objects = in_q[~on & np.isin(roles, ("reference", "workpiece"))][:, :2]
        reach = cKDTree(objects).query(in_q[on][:, :2], distance_upper_bound=PARTIAL_REACH_MM)[0]
        drop = np.zeros(len(points), dtype=bool)
        drop[np.flatnonzero(on)[~np.isfinite(reach)]] = True
    else:
        return points, roles
    return points[~drop], roles[~drop]


def bunny_reference_poses(folder: Path, conf: str = "bun.conf") -> dict[str, np.ndarray]:
    """scan -> model transforms from a Stanford .conf file: p_model = R(q)^T p_scan + t (see the
    data README); the same reading holds for the dragon's dragonStandRight.conf."""
    from scipy.spatial.transform import Rotation

    poses = {}
    for line in (folder / conf).read_text().splitlines():
        fields = line.split()
        if fields and fields[0] == "bmesh":
            t = np.array(fields[2:5], float) * 1000.0
            poses[fields[1]] = frames.rigid(Rotation.from_quat(np.array(fields[5:9], float)).as_matrix().T, t)
    return poses


def _bunny(folder: Path | None, spec: CellSpec, rng) -> dict:
    """A real bunny range scan (chosen by the seed) as the workpiece: its points, the pose bun.conf gives
    them, the model, and how the bunny must rest so that its scanner looks from the spec's direction."""
    from ..pointops import signed_volume
    from ..readers import read_cloud

    if folder is None or not (Path(folder) / "bun.conf").exists():
        raise InputError(f"cell scan: the bunny workpiece needs the Stanford bunny data (bun.conf) in {folder}")
    folder = Path(folder)
    name = BUNNY_SCANS_FROM_ABOVE[int(rng.integers(len(BUNNY_SCANS_FROM_ABOVE)))]
    model = read_cloud(folder / "bun_zipper.ply", units="m", name="bun_zipper.ply")
    triangles = model.triangles if signed_volume(model.points, model.triangles) > 0 else model.triangles[:, ::-1]
    scan_to_model = bunny_reference_poses(folder)[name]
    sensor = scan_to_model[:3, :3] @ np.array([0.0, 0.0, 1.0])  # the Cyberware looked along -z of its scan
    az, el = np.radians(DEFAULT_AZIMUTH_DEG if spec.azimuth_deg is None else spec.azimuth_deg), np.radians(_elevation(spec))
    direction = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    # Turn the bunny so that its scanner's direction is the spec's and its up axis as near B's z as that allows.
    rotation = _frame(direction, np.array([0.0, 0.0, 1.0])) @ _frame(sensor, BUNNY_UP).T
    return {"points": read_cloud(folder / name, units="m").points, "scan_to_model": scan_to_model,
            "model": model, "mesh": Cloud(model.points, triangles=triangles, name=model.name),
            "rotation": rotation, "direction": direction, "name": name}


def _frame(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """Columns: ``first`` and the part of ``second`` square to it, and their cross product."""
    a = first / np.linalg.norm(first)
    b = second - (second @ a) * a
    b /= np.linalg.norm(b)
    return np.column_stack([a, b, np.cross(a, b)])


def _scanner_along(scene, direction: np.ndarray, spec: CellSpec) -> Scanner:
    """A scanner looking at the workpiece's middle from ``direction`` (so the real scan's rays agree),
    aimed at the middle of workpiece and reference, zoomed so that both fit."""
    workpiece = scene.workpiece.in_base().points
    points = np.vstack([workpiece, scene.reference_model().points])
    target = 0.5 * (points.min(axis=0) + points.max(axis=0))
    position = 0.5 * (workpiece.min(axis=0) + workpiece.max(axis=0)) + DEFAULT_DISTANCE_MM * direction
    pitch = Scanner.fitting_pitch(position, target, points, IMAGE)
    return Scanner(position, target, pixel_pitch_mm=pitch, image_size=IMAGE, noise_sigma_mm=spec.noise_mm,
                   seed=spec.seed)


def _hidden(points: np.ndarray, scan, scanner: Scanner) -> np.ndarray:
    """Which points (S) lie behind a rendered surface other than the workpiece's on their pixel, or
    outside the image."""
    cols, rows = scanner.image_size
    k = scanner.pixel_pitch_mm / scanner.focus_distance_mm
    col = np.round(points[:, 0] / points[:, 2] / k + 0.5 * (cols - 1)).astype(np.int64)
    row = np.round(points[:, 1] / points[:, 2] / k + 0.5 * (rows - 1)).astype(np.int64)
    outside = (col < 0) | (col >= cols) | (row < 0) | (row >= rows) | (points[:, 2] <= 0)
    depth = np.full(rows * cols, np.inf)
    others = np.array(scan.object_roles)[scan.labels] != "workpiece"
    np.minimum.at(depth, scan.pixels[others, 0] * cols + scan.pixels[others, 1], scan.points[others, 2])
    pixel = np.where(outside, 0, row * cols + col)
    return outside | (depth[pixel] < points[:, 2] - OCCLUDED_MM)
