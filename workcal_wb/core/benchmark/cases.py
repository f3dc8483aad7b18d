"""Benchmark cases: a scan, a model and the true pose, plus the degradations the issue names.

Every case moves its scan by a random rigid motion (seeded), so no method can profit from a scan
that already sits near its model.  ``truth`` is U = ^S X: model coordinates -> scan coordinates.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import frames, pointops
from ..geometry import Cloud


@dataclass
class Case:
    name: str
    group: str
    scan: np.ndarray  # (N, 3) mm, scanner frame
    model: Cloud  # frame X, mm
    truth: np.ndarray  # U = ^S X
    exact: bool  # truth known exactly (simulated) or only to ~0.1 deg (real data reference)


def random_motion(rng: np.random.Generator, shift_mm: float = 200.0) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    return frames.rigid(Rotation.random(random_state=int(rng.integers(2**31))).as_matrix(),
                        rng.uniform(-shift_mm, shift_mm, 3))


def with_noise_and_count(scan: np.ndarray, rng, count: int = 2000, sigma: float = 0.5) -> np.ndarray:
    """A sparse, noisy scan: ``count`` random points with Gaussian noise of ``sigma`` mm per axis."""
    picked = scan[rng.choice(len(scan), min(count, len(scan)), replace=False)]
    return picked + rng.normal(0, sigma, picked.shape)


def with_overlap(scan: np.ndarray, rng, fraction: float = 0.4) -> np.ndarray:
    """Keep ``fraction`` of the scan: the points on one side of a plane of random direction."""
    direction = rng.normal(size=3)
    height = scan @ (direction / np.linalg.norm(direction))
    return scan[height <= np.quantile(height, fraction)]


def with_clutter(scan: np.ndarray, model_to_scan: np.ndarray, model: Cloud, up: np.ndarray, rng,
                 stray_fraction: float = 0.2) -> np.ndarray:
    """Add what a shop scan also sees: the table under the part, a box beside it, stray points.

    Built in the model frame, where ``up`` is known, then moved into the scan frame.
    """
    spacing = pointops.median_spacing(scan)
    up = up / np.linalg.norm(up)
    a = np.cross(up, [1.0, 0, 0] if abs(up[0]) < 0.9 else [0, 1.0, 0])
    a /= np.linalg.norm(a)
    b = np.cross(up, a)
    heights = model.points @ up
    centre = model.points.mean(axis=0)
    size = model.diagonal()
    base = centre + (heights.min() - centre @ up) * up

    def grid(origin, u, v, extent_u, extent_v):
        s, t = np.meshgrid(np.arange(0, extent_u, spacing), np.arange(0, extent_v, spacing))
        return origin + s.reshape(-1, 1) * u + t.reshape(-1, 1) * v

    table = grid(base - 0.6 * size * (a + b), a, b, 1.2 * size, 1.2 * size)
    box_size = 0.3 * size
    box_corner = base + 0.45 * size * a - 0.15 * size * b
    box = np.vstack([grid(box_corner + box_size * up, a, b, box_size, box_size),
                     grid(box_corner, a, up, box_size, box_size),
                     grid(box_corner, b, up, box_size, box_size)])
    # The scanner sees only the part of the table and box on its side: keep what lies near the
    # scan's footprint (within the scan's extent, projected along up) to stay a single-view scene.
    clutter = frames.apply(model_to_scan, np.vstack([table, box]))
    lo, hi = scan.min(axis=0) - 0.3 * size, scan.max(axis=0) + 0.3 * size
    clutter = clutter[np.all((clutter > lo) & (clutter < hi), axis=1)]
    clutter += rng.normal(0, 0.5 * spacing, clutter.shape)
    scene = np.vstack([scan, clutter])
    n_stray = int(stray_fraction * len(scene) / (1 - stray_fraction))
    stray = rng.uniform(scene.min(axis=0), scene.max(axis=0), (n_stray, 3))
    return np.vstack([scene, stray])


def with_clay_change(scan: np.ndarray, rng, lump_mm: float = 4.0, carve_mm: float = 3.0,
                     radius_fraction: float = 0.08) -> np.ndarray:
    """Clay added and carved since the model was made: a smooth bump out and a dent in, each over a
    patch of ``radius_fraction`` of the scan's size, along the local normals (oriented outwards)."""
    size = np.linalg.norm(scan.max(axis=0) - scan.min(axis=0))
    radius = radius_fraction * size
    spacing = pointops.median_spacing(scan)
    normals = pointops.orient_consistently(scan, pointops.estimate_normals(scan, 4 * spacing))
    changed = scan.copy()
    first = scan[rng.integers(len(scan))]
    far = scan[np.argmax(np.linalg.norm(scan - first, axis=1))]  # second patch away from the first
    second = scan[np.argmin(np.linalg.norm(scan - (first + 0.5 * (far - first)), axis=1))]
    for centre, height in ((first, lump_mm), (second, -carve_mm)):
        d = np.linalg.norm(scan - centre, axis=1)
        bump = height * np.exp(-(d / (0.5 * radius)) ** 2) * (d < radius)
        changed += bump[:, None] * normals
    return changed


# --- Stanford bunny (real Cyberware scans, reference poses from bun.conf) -----------------------

BUNNY_SCANS = ("bun000.ply", "bun045.ply", "bun090.ply", "bun180.ply", "bun270.ply", "bun315.ply",
               "chin.ply", "ear_back.ply", "top2.ply", "top3.ply")
BUNNY_UP = np.array([0.0, 1.0, 0.0])  # the bunny model stands along +y


def bunny_reference_poses(folder: Path) -> dict[str, np.ndarray]:
    """scan -> model transforms from bun.conf: p_model = R(q)^T p_scan + t (see the data README)."""
    from scipy.spatial.transform import Rotation

    poses = {}
    for line in (folder / "bun.conf").read_text().splitlines():
        fields = line.split()
        if fields and fields[0] == "bmesh":
            t = np.array(fields[2:5], float) * 1000.0
            poses[fields[1]] = frames.rigid(Rotation.from_quat(np.array(fields[5:9], float)).as_matrix().T, t)
    return poses


def bunny_cases(folder: Path, seed: int = 0, scans=BUNNY_SCANS) -> list[Case]:
    """Each real scan against bun_zipper.ply, clean and with the four degradations."""
    from ..readers import read_cloud

    rng = np.random.default_rng(seed)
    model = read_cloud(folder / "bun_zipper.ply", units="m")
    poses = bunny_reference_poses(folder)
    cases = []
    for name in scans:
        scan = read_cloud(folder / name, units="m").points
        motion = random_motion(rng)
        truth = motion @ frames.invert(poses[name])  # model -> moved scan
        moved = frames.apply(motion, scan)
        stem = name.removesuffix(".ply")
        variants = {
            "clean": moved,
            "noise 0.5 mm, 2k pts": with_noise_and_count(moved, rng),
            "40 % overlap": with_overlap(moved, rng),
            "table, box, 20 % stray": with_clutter(moved, truth, model, BUNNY_UP, rng),
            "lump + carved patch": with_clay_change(moved, rng),
        }
        cases += [Case(f"{stem} {kind}", f"bunny {kind}", pts, model, truth, exact=False)
                  for kind, pts in variants.items()]
    return cases


# --- Simulated scans (exact truth) -------------------------------------------------------------

def simulated_cases(seed: int = 0, quick: bool = False) -> list[Case]:
    """Virtual-scanner captures of the car and the figurine: the workpiece region alone (as the
    calibration matches it) and, for the car, the whole scene with platform and L-block around it."""
    from ..simulate.scanner import Scanner
    from ..simulate.scene import build_scene

    cases = []
    count = 2 if quick else 5
    for i in range(count):
        for workpiece in ("car", "figurine"):
            scene = build_scene(workpiece, seed=seed + i)
            scan = Scanner.aimed_at(scene, azimuth_deg=20 + 70 * i, seed=seed + i, noise_sigma_mm=0.1).scan(scene)
            model = scene.workpiece_model()
            cases.append(Case(f"{workpiece} #{i} region", f"simulated {workpiece}, region",
                              scan.points[scan.mask("workpiece")], model, scan.U, exact=True))
            if workpiece == "car":
                cases.append(Case(f"car #{i} whole scene", "simulated car, whole scene", scan.points, model,
                                  scan.U, exact=True))
    return cases


def large_case(seed: int = 0) -> Case:
    """About a million points: the car scanned at a 0.2 mm pitch, platform around it included."""
    from ..simulate.scanner import Scanner
    from ..simulate.scene import build_scene

    scene = build_scene("car", seed=seed)
    centre = scene.workpiece.in_base().points.mean(axis=0)
    scanner = Scanner(centre + np.array([300.0, -300.0, 700.0]), centre, pixel_pitch_mm=0.2,
                      image_size=(1700, 1300), noise_sigma_mm=0.1, seed=seed)
    scan = scanner.scan(scene)
    return Case("car, 0.2 mm pitch", "large", scan.points, scene.workpiece_model(), scan.U, exact=True)
