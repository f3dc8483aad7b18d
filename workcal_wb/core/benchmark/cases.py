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
from ..simulate.cell import bunny_reference_poses


@dataclass
class Case:
    name: str
    group: str
    scan: np.ndarray  # (N, 3) mm, scanner frame
    model: Cloud  # frame X, mm
    truth: np.ndarray  # U = ^S X
    exact: bool  # truth known exactly (simulated) or only to ~0.1 deg (real data reference)
    tolerance_mm: float = 0.3  # what the match is told: above the scan's noise


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
    """Add what a shop scan also sees: the table patch under the part, a box beside it, stray points.

    Table and box together get as many points as the scan (spread uniformly over their visible
    faces, with the scan's noise), so the part is about half of the solid points, as when a scanner
    is zoomed on it; then ``stray_fraction`` of the result is uniform noise over the scene's box.
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
    box_size = 0.3 * size
    box_corner = base + 0.45 * size * a - 0.15 * size * b
    # (origin, u, v, extent): the table under the part, the box's top and two of its sides.
    faces = [(base - 0.6 * size * (a + b), a, b, 1.2 * size),
             (box_corner + box_size * up, a, b, box_size),
             (box_corner, a, up, box_size),
             (box_corner, b, up, box_size)]
    area = np.array([extent**2 for *_, extent in faces])
    counts = rng.multinomial(len(scan), area / area.sum())
    clutter = np.vstack([origin + extent * (rng.random((n, 1)) * u + rng.random((n, 1)) * v)
                         for (origin, u, v, extent), n in zip(faces, counts)])
    clutter = frames.apply(model_to_scan, clutter) + rng.normal(0, 0.5 * spacing, clutter.shape)
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


def bunny_cases(folder: Path, seed: int = 0, scans=BUNNY_SCANS) -> list[Case]:
    """Each real scan against bun_zipper.ply, clean and with the four degradations."""
    return list(iter_bunny_cases(folder, seed, scans))


def iter_bunny_cases(folder: Path, seed: int = 0, scans=BUNNY_SCANS):
    """bunny_cases made one scan at a time, when asked for (the same cases, in the same order), so a
    benchmark holds only the current scan's cases."""
    from ..readers import read_cloud

    rng = np.random.default_rng(seed)
    model = read_cloud(folder / "bun_zipper.ply", units="m")
    poses = bunny_reference_poses(folder)
    for name in scans:
        scan = read_cloud(folder / name, units="m").points
        motion = frames.random_motion(rng)
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
        del scan, moved
        for kind in list(variants):
            yield Case(f"{stem} {kind}", f"bunny {kind}", variants.pop(kind), model, truth, exact=False)


def match_case_groups(bunny: Path | None, seed: int = 0, quick: bool = False):
    """Every case of the match table, in groups that share one model: the bunny cases (when its data
    folder ``bunny`` is given), the simulated car and figurine, the depth camera's parts.  Each group's
    cases are made when asked for, so a caller holds one capture at a time."""
    if bunny is not None:
        yield iter_bunny_cases(bunny, seed, scans=BUNNY_SCANS[:2] if quick else BUNNY_SCANS)
    yield from iter_simulated_groups(seed, quick=quick)
    yield from iter_depth_camera_groups(seed, quick=quick)


# --- Simulated scans (exact truth) -------------------------------------------------------------

# A simulated region case needs this many workpiece points; a view that sees fewer is turned.
MIN_REGION_POINTS = 1000
# The zoom's finest pitch: finer than the 0.1 mm noise, a scan would be a fuzzy slab, not a surface.
MIN_PITCH_MM = 0.2


def simulated_cases(seed: int = 0, quick: bool = False) -> list[Case]:
    """Virtual-scanner captures of the car (25 cm) and the figurine (2 cm), 0.1 mm noise: the
    workpiece region of a capture zoomed on the workpiece (the paper's second, zoomed capture; the
    calibration matches such a region), and for the car also the whole scene with platform and
    L-block around it, as the default capture framing both objects sees it."""
    return [case for group in iter_simulated_groups(seed, quick) for case in group]


def iter_simulated_groups(seed: int = 0, quick: bool = False):
    """simulated_cases one model at a time (a list of that model's cases), made when asked for, so a
    benchmark holds only the cases of the model it is matching and can let that model go before the
    next one's scans are made."""
    for i in range(2 if quick else 5):
        azimuth = -75.0 + 35.0 * i  # the side facing away from the L-block, which can hide the workpiece
        for workpiece in ("car", "figurine"):
            yield _simulated_model_cases(workpiece, azimuth, seed + i, i)


def _simulated_model_cases(workpiece: str, azimuth: float, seed: int, i: int) -> list[Case]:
    """One model's simulated cases; the scene and the whole captures go when it returns (only the
    workpiece region of the zoomed capture is kept)."""
    from ..simulate.scanner import Scanner
    from ..simulate.scene import build_scene

    scene = build_scene(workpiece, seed=seed)
    model = scene.workpiece_model()
    zoomed = zoomed_on_workpiece(scene, azimuth, seed).scan(scene)
    turn = 0
    while zoomed.mask("workpiece").sum() < MIN_REGION_POINTS and turn < 360:  # hidden behind the L-block
        turn += 30
        zoomed = None  # one capture in memory at a time
        zoomed = zoomed_on_workpiece(scene, azimuth + turn, seed).scan(scene)
    cases = [Case(f"{workpiece} #{i} region", f"simulated {workpiece}, region",
                  zoomed.points[zoomed.mask("workpiece")], model, zoomed.U, exact=True)]
    if workpiece == "car":
        zoomed = None
        scan = Scanner.aimed_at(scene, azimuth_deg=azimuth, seed=seed, noise_sigma_mm=0.1).scan(scene)
        cases.append(Case(f"car #{i} whole scene", "simulated car, whole scene", scan.points, model, scan.U,
                          exact=True))
    return cases


DEPTH_CAMERA_GROUP = "depth camera, part on a table"
DEPTH_CAMERA_TOLERANCE_MM = 2.5


def depth_camera_parts() -> dict:
    """{name: closed mesh, z up} of the small parts a depth camera sees on its table."""
    from ..simulate import shapes

    return {"L-block": shapes.l_block(), "notched plate": shapes.plate(), "curved tile": shapes.shell()}


def iter_depth_camera_groups(seed: int = 0, quick: bool = False):
    """Small parts on a table beside a box and a cylinder as a depth camera sees them
    (simulate.depth_camera: 1-2 mm of noise, coarse and mixed pixels, the table in the crop), one
    part's views a group, at a tolerance above that noise."""
    from ..simulate.depth_camera import depth_camera_scan

    for name, model in depth_camera_parts().items():
        cases = []
        for view in range(1 if quick else 3):
            scan = depth_camera_scan(model, seed * 1000 + 100 + view)
            cases.append(Case(f"{name} #{view} on a table", DEPTH_CAMERA_GROUP, scan.points, model, scan.U, exact=True,
                              tolerance_mm=DEPTH_CAMERA_TOLERANCE_MM))
        yield cases


def zoomed_on_workpiece(scene, azimuth_deg: float, seed: int, elevation_deg: float = 45.0,
                        distance_mm: float = 1200.0, **settings):
    """A scanner 1.2 m away looking at the workpiece, zoomed so that it fills about two thirds of the
    image width (the default 640 x 480 image), but no finer than MIN_PITCH_MM; ``settings`` go to
    the Scanner (e.g. a coarser pitch for a quicker test)."""
    from ..simulate.scanner import Scanner

    points = scene.workpiece.in_base().points
    centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
    az, el = np.radians(azimuth_deg), np.radians(elevation_deg)
    position = centre + distance_mm * np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    pitch = max(MIN_PITCH_MM, 1.5 * Cloud(points).diagonal() / 640)
    return Scanner(position, centre, **{"pixel_pitch_mm": pitch, "noise_sigma_mm": 0.1, "seed": seed, **settings})


# --- Large scans as files (the large-scan table runs the commands on them as whole processes) ----

LARGE_PITCH_MM = 0.2 / np.sqrt(2.64)  # about 5 million points per capture of large_scanner's view


def large_scanner(scene, seed: int, pitch_mm: float = 0.2, shift_px=(0.0, 0.0)):
    """The car with platform and L-block seen from 0.8 m, the image zoomed to ``pitch_mm`` at the car and
    its window kept (the 0.2 mm capture is 1700 x 1300 pixels); ``shift_px`` moves the aim by a fraction
    of a pixel, so several captures interleave like one of a finer pitch."""
    from ..simulate.scanner import Scanner

    centre = scene.workpiece.in_base().points.mean(axis=0)
    scale = 0.2 / pitch_mm
    image_size = (round(1700 * scale), round(1300 * scale))
    first = Scanner(centre + np.array([300.0, -300.0, 700.0]), centre, pixel_pitch_mm=pitch_mm,
                    image_size=image_size, noise_sigma_mm=0.1, seed=seed)
    across = first.frame()[:3, :2] @ np.asarray(shift_px, float) * pitch_mm
    return Scanner(first.position, centre + across, pixel_pitch_mm=pitch_mm, image_size=image_size,
                   noise_sigma_mm=0.1, seed=seed)


def write_large_scan(path: Path, captures: int, seed: int = 0) -> np.ndarray:
    """A binary PLY (float32 x y z, mm) of ``captures`` captures of the car scene at LARGE_PITCH_MM
    (about 5 million points each), each aimed a fraction of a pixel off the first (a 2 x 2 interleave for
    4), all in the first capture's frame S, as a scanner merges its shots; one capture is in memory at a
    time.  Returns the true U = ^S X of the workpiece model (``large_model``)."""
    from ..simulate.scene import build_scene

    scene = build_scene("car", seed=seed)
    shifts = [(0.0, 0.0), (0.5, 0.5), (0.5, 0.0), (0.0, 0.5)][:captures]
    scans = [large_scanner(scene, seed + k, LARGE_PITCH_MM, shift) for k, shift in enumerate(shifts)]
    S_B = frames.invert(scans[0].frame())
    parts = []
    for scanner in scans:  # float32 in the first frame: 12 bytes a point kept, one capture's arrays at a time
        capture = scanner.scan(scene)
        parts.append(frames.apply(S_B @ capture.B_S, capture.points).astype("<f4"))
        del capture
    write_float32_ply(path, parts, f"{captures} simulated capture(s) of the car scene, seed {seed}")
    return S_B @ scene.W


def write_float32_ply(path: Path, parts, comment: str) -> None:
    """A binary PLY of the points in ``parts`` (arrays of x y z, mm) as float32, a sensor's format, with
    ``comment``; written beside and renamed when whole, so an interrupted run leaves no file to reuse."""
    parts = [np.asarray(part, dtype="<f4") for part in parts]
    header = (f"ply\nformat binary_little_endian 1.0\ncomment units mm\ncomment {comment}\n"
              f"element vertex {sum(map(len, parts))}\nproperty float x\nproperty float y\n"
              "property float z\nend_header\n").encode()
    partial = Path(f"{path}.part")
    with open(partial, "wb") as fh:
        fh.write(header)
        for part in parts:
            fh.write(part.tobytes())
    partial.replace(path)


def large_model(seed: int = 0) -> Cloud:
    """The workpiece model of write_large_scan's scene."""
    from ..simulate.scene import build_scene

    return build_scene("car", seed=seed).workpiece_model()
