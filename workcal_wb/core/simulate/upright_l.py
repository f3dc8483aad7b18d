"""Cell scans of an L-block standing on its foot beside a freeform part: a reference that nearly maps
onto itself, seen by a sensor with mixed pixels at its depth edges.

The reference is an L in profile: a foot FOOT_MM long and an upright standing on one end of it, both
legs LEG_THICKNESS_MM thick and WIDTH_MM wide, the outer legs differing by only LEG_DIFFERENCE_MM.  A half
turn about the axis that swaps foot and upright lays the block on the table again with most of its
surface where it was: only the longer leg's last centimetre and the top tell the poses apart.  The
workpiece (the Stanford bunny's zippered mesh when the data is there, else the figurine) stands on the
table a gap of GAP_MM away from the block, each turned at random about the vertical.  The scanner looks
from any azimuth, ELEVATION_DEG above the table, DISTANCE_MM away, with pixels PIXEL_MM wide at the
objects, range noise along its rays, and MIXED_SHARE of its returns mixed pixels at depth edges
(Scanner.mixed_pixel_share).  The scan is in the scanner's frame and carries no viewpoint, as a user
gives it with no hints.

``upright_l_scan(UprightLSpec(seed=...), bunny_folder)`` -> cell.CellScan with the exact truth; each
point's role is platform, reference, workpiece or mixed (a mixed pixel, whatever surfaces it lies
between).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from .. import frames
from ..errors import InputError
from ..geometry import Cloud
from . import shapes
from .cell import CellScan
from .scanner import Scanner
from .scene import PLATFORM_POSE, Scene, SceneObject

FOOT_MM, UPRIGHT_MM, LEG_THICKNESS_MM, WIDTH_MM = 80.0, 70.0, 20.0, 60.0
LEG_DIFFERENCE_MM = LEG_THICKNESS_MM + UPRIGHT_MM - FOOT_MM  # the outer legs: 80 mm along the table, 90 mm up
# Where things stand (drawn uniformly from each range): the block's centre within BLOCK_SPREAD_MM of the
# platform's middle, the gap between the two objects' outlines seen from above, the scanner's view.
BLOCK_SPREAD_MM = 100.0
GAP_MM = (20.0, 60.0)
ELEVATION_DEG, DISTANCE_MM = (25.0, 55.0), (650.0, 900.0)
PIXEL_MM = 0.45  # pixel width at the objects
MIXED_SHARE = (0.01, 0.03)
WORKPIECES = ("bunny", "figurine")
# The bunny's zippered mesh has its up axis along y.
BUNNY_UP_AXIS = 1


@dataclass(frozen=True)
class UprightLSpec:
    """One scene of the family; what is not given is drawn from ``seed``."""

    seed: int = 0
    noise_mm: float = 0.1
    workpiece: str = "bunny"  # bunny (needs the Stanford data) or figurine
    mixed_share: float | None = None  # None: drawn from MIXED_SHARE
    azimuth_deg: float | None = None
    elevation_deg: float | None = None
    draw: int = 0  # another draw of the sensor's noise and mixed pixels, the scene and view kept

    def __post_init__(self):
        if self.workpiece not in WORKPIECES:
            raise InputError(f"upright L scene: workpiece must be one of {WORKPIECES}, not {self.workpiece!r}")


def upright_l_block(edge_mm: float = 2.0) -> Cloud:
    """The L-block standing on its foot: foot along x on z = 0, upright at x < LEG_THICKNESS_MM."""
    top = LEG_THICKNESS_MM + UPRIGHT_MM
    return shapes._cell_union([[0.0, LEG_THICKNESS_MM, FOOT_MM], [0.0, WIDTH_MM], [0.0, LEG_THICKNESS_MM, top]],
                              lambda x, y, z: (z < LEG_THICKNESS_MM) | (x < LEG_THICKNESS_MM), edge_mm, "upright L-block")


def upright_l_scan(spec: UprightLSpec = UprightLSpec(), bunny_folder: Path | None = None) -> CellScan:
    """The scene of ``spec`` scanned (see the module docstring)."""
    rng = np.random.default_rng(np.random.SeedSequence([spec.seed, 46]))
    model, upright = workpiece(spec.workpiece, bunny_folder)
    block = upright_l_block()
    block_pose = frames.rigid(frames.rot_z(rng.uniform(0.0, 360.0)),
                              (*rng.uniform(-BLOCK_SPREAD_MM, BLOCK_SPREAD_MM, 2), 0.0))  # ^Q P
    block_pose = block_pose @ frames.rigid(translation=(-FOOT_MM / 2, -WIDTH_MM / 2, 0.0))
    standing = frames.rigid(frames.rot_z(rng.uniform(0.0, 360.0))) @ upright  # ^N' X: the part turned, on z
    body = frames.apply(standing, model.points)
    standing = frames.rigid(translation=(0.0, 0.0, -body[:, 2].min())) @ standing
    placed = _beside(frames.apply(standing, model.points), frames.apply(block_pose, block.points),
                     rng.uniform(*GAP_MM), rng.uniform(0.0, 2 * np.pi))
    workpiece_pose = PLATFORM_POSE @ placed @ standing  # ^B X
    scene = Scene([SceneObject("platform", shapes.platform(), PLATFORM_POSE, "platform"),
                   SceneObject(block.name, block, PLATFORM_POSE @ block_pose, "reference"),
                   SceneObject(model.name, model, workpiece_pose, "workpiece")], model, np.eye(4), seed=spec.seed)
    azimuth = rng.uniform(0.0, 360.0) if spec.azimuth_deg is None else spec.azimuth_deg
    elevation = rng.uniform(*ELEVATION_DEG) if spec.elevation_deg is None else spec.elevation_deg
    distance = rng.uniform(*DISTANCE_MM)
    mixed = rng.uniform(*MIXED_SHARE) if spec.mixed_share is None else spec.mixed_share
    draw = spec.seed if spec.draw == 0 else int(np.random.SeedSequence([spec.seed, spec.draw]).generate_state(1)[0])
    scanner = _scanner(scene, azimuth, elevation, distance, spec.noise_mm, mixed, draw)
    scan = scanner.scan(scene)
    roles = np.array(scan.object_roles)[scan.labels]
    roles[scan.mixed] = "mixed"
    order = rng.permutation(len(scan.points))
    cloud = Cloud(scan.points[order], name=f"upright L-block and {spec.workpiece} #{spec.seed}")
    up = frames.invert(scan.B_S)[:3, :3] @ np.array([0.0, 0.0, 1.0])
    cell = CellScan(cloud, roles[order], scene.W, np.eye(4), scan.B_S, np.zeros(3), up, model,
                    scene.reference_model(), spec, scanner)
    cell.notes.append(f"azimuth {azimuth:.0f} deg, elevation {elevation:.0f} deg, {distance:.0f} mm, "
                      f"{mixed:.1%} mixed pixels, {spec.noise_mm} mm noise")
    return cell


def workpiece(name: str, bunny_folder: Path | None) -> tuple[Cloud, np.ndarray]:
    """(the model X-A as a closed outward mesh, ^N X: its upright frame, z up, from X)."""
    if name == "figurine":
        return shapes.figurine(), frames.invert(shapes.FIGURINE_BODY_IN_X)
    from ..pointops import signed_volume
    from ..readers import read_cloud

    path = Path(bunny_folder or "") / "bun_zipper.ply"
    if bunny_folder is None or not path.is_file():
        raise InputError(f"upright L scene: the bunny workpiece needs the Stanford bunny mesh {path}")
    mesh = read_cloud(path, units="m", name="bun_zipper.ply")
    triangles = mesh.triangles if signed_volume(mesh.points, mesh.triangles) > 0 else mesh.triangles[:, ::-1]
    axes = np.roll(np.eye(3), 2 - BUNNY_UP_AXIS, axis=0)  # rows: the model's axes that become x, y, z
    return Cloud(mesh.points, triangles=triangles, name=mesh.name), frames.rigid(axes)


def _beside(part: np.ndarray, block: np.ndarray, gap: float, direction: float) -> np.ndarray:
    """^Q N'': the part's points (on the table, in Q) slid horizontally so that, seen from above, they
    lie ``gap`` mm from the block's on the side ``direction`` (radians about z) points to."""
    tree = cKDTree(block[:, :2])
    outline = part[:: max(1, len(part) // 5000), :2]
    way = np.array([np.cos(direction), np.sin(direction)])
    start = block[:, :2].mean(axis=0) - outline.mean(axis=0)

    def clearance(t):
        return tree.query(outline + start + t * way)[0].min()

    lo, hi = 0.0, 50.0
    while clearance(hi) < gap:
        lo, hi = hi, 2 * hi
    for _ in range(40):  # the nearest slide that keeps the gap
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if clearance(mid) < gap else (lo, mid)
    return frames.rigid(translation=(*(start + hi * way), 0.0))


def _scanner(scene: Scene, azimuth: float, elevation: float, distance: float, noise: float, mixed: float,
             seed: int) -> Scanner:
    """A scanner ``distance`` mm from the middle of both objects, its image just wide enough for them at
    PIXEL_MM pixels."""
    points = np.vstack([scene.workpiece.in_base().points, scene.reference_model().points])
    target = 0.5 * (points.min(axis=0) + points.max(axis=0))
    az, el = np.radians(azimuth), np.radians(elevation)
    position = target + distance * np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    seen = frames.apply(frames.invert(Scanner(position, target).frame()), points)
    half = np.abs(seen[:, :2] / seen[:, 2:]).max(axis=0) * distance / PIXEL_MM
    size = tuple(int(2 * 1.1 * h) + 8 for h in half)
    return Scanner(position, target, pixel_pitch_mm=PIXEL_MM, image_size=size, noise_sigma_mm=noise,
                   mixed_pixel_share=mixed, seed=seed)
