"""Small parts on a table as a depth camera sees them: coarse pixels, millimetres of range noise,
mixed pixels at every depth edge, the table and neighbouring objects in the cropped scan.

A part rests on the platform (its model's z up, lowest point on the table), turned at random about
the vertical; a box and a cylinder stand beside it, NEIGHBOUR_GAP_MM from its outline.  The camera looks
from any azimuth, ELEVATION_DEG above the table, DISTANCE_MM away, with PIXEL_MM pixels at the part,
range noise NOISE_MM along its rays and MIXED_SHARE of its returns mixed between the surfaces of a depth
edge.  The scan is cropped as a user crops it in a viewer: a ball around the part a CROP_MARGIN_MM wider
than its half diagonal, which keeps the table and parts of the neighbours.

``depth_camera_scan(mesh, seed)`` -> DepthCameraScan: the points in a frame of their own, what each lies on
(platform, workpiece, clutter or mixed), U = ^S X and a line on how it was drawn.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import frames
from ..geometry import Cloud
from . import shapes
from .scanner import Scanner
from .scene import PLATFORM_POSE, Scene, SceneObject

ELEVATION_DEG, DISTANCE_MM = (20.0, 60.0), (500.0, 900.0)
PIXEL_MM, NOISE_MM, MIXED_SHARE = (1.2, 2.0), (1.0, 2.0), (0.02, 0.05)
# The neighbours stand this far (mm) from the part's outline seen from above, their centres about
# NEIGHBOUR_RADIUS_MM further (half the box's diagonal), each within NEIGHBOUR_SPREAD_RAD of opposite sides.
NEIGHBOUR_GAP_MM, NEIGHBOUR_RADIUS_MM, NEIGHBOUR_SPREAD_RAD = (15.0, 60.0), 35.0, 0.6
CROP_MARGIN_MM = 20.0
# The image is this much wider than the crop, so that the crop is never cut by the image's edge.
IMAGE_MARGIN = 1.3


@dataclass
class DepthCameraScan:
    """A depth camera's cropped scan with its truth."""

    points: np.ndarray  # (N, 3) mm
    roles: np.ndarray  # per point: platform, workpiece, clutter or mixed
    U: np.ndarray  # ^S X
    notes: str


def depth_camera_scan(mesh: Cloud, seed: int) -> DepthCameraScan:
    """The part ``mesh`` (closed, z up) scanned as in the module docstring; what is drawn comes from ``seed``."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, 4040]))
    part = frames.rigid(frames.rot_z(rng.uniform(0.0, 360.0)))
    part[2, 3] = -frames.apply(part, mesh.points)[:, 2].min()
    footprint = frames.apply(part, mesh.points)
    centre = 0.5 * (footprint.min(axis=0) + footprint.max(axis=0))
    radius = 0.5 * np.linalg.norm(footprint.max(axis=0) - footprint.min(axis=0))
    objects = [SceneObject("platform", shapes.platform(), PLATFORM_POSE, "platform"),
               SceneObject(mesh.name, mesh, PLATFORM_POSE @ part, "workpiece")]
    first = rng.uniform(0.0, 2 * np.pi)
    for neighbour, lift, turn in ((shapes.box((60.0, 40.0, 30.0), edge_mm=3.0, name="box"), 30.0, 0.0),
                                  (shapes.cylinder(20.0, 50.0, edge_mm=3.0, name="cylinder"), 0.0, np.pi)):
        way = first + turn + rng.uniform(-NEIGHBOUR_SPREAD_RAD, NEIGHBOUR_SPREAD_RAD)
        reach = radius + rng.uniform(*NEIGHBOUR_GAP_MM) + NEIGHBOUR_RADIUS_MM
        spot = centre[:2] + reach * np.array([np.cos(way), np.sin(way)])
        pose = frames.rigid(frames.rot_z(rng.uniform(0.0, 360.0)), (*spot, lift))
        objects.append(SceneObject(neighbour.name, neighbour, PLATFORM_POSE @ pose, "clutter"))
    scene = Scene(objects, mesh, np.eye(4), seed=seed)

    azimuth, elevation = np.radians(rng.uniform(0.0, 360.0)), np.radians(rng.uniform(*ELEVATION_DEG))
    distance, pixel = rng.uniform(*DISTANCE_MM), rng.uniform(*PIXEL_MM)
    noise, mixed = rng.uniform(*NOISE_MM), rng.uniform(*MIXED_SHARE)
    target = frames.apply(PLATFORM_POSE, centre[None])[0]
    position = target + distance * np.array([np.cos(elevation) * np.cos(azimuth),
                                             np.cos(elevation) * np.sin(azimuth), np.sin(elevation)])
    side = int(2 * IMAGE_MARGIN * (radius + CROP_MARGIN_MM) / pixel) + 8
    scanner = Scanner(position, target, pixel_pitch_mm=pixel, image_size=(side, side), noise_sigma_mm=noise,
                      z_resolution_mm=0.0, mixed_pixel_share=mixed, seed=int(rng.integers(2**31)))
    scan = scanner.scan(scene, cast_rays=False)  # rasterised on every stack: the same scans everywhere
    S_B = frames.invert(scan.B_S)
    kept = np.linalg.norm(scan.points - frames.apply(S_B, target[None])[0], axis=1) <= radius + CROP_MARGIN_MM
    motion = frames.from_rotvec(rng.normal(size=3), rng.uniform(-500.0, 500.0, 3))
    points = frames.apply(motion, scan.points[kept])
    roles = np.array(scan.object_roles)[scan.labels]
    roles[scan.mixed] = "mixed"
    notes = (f"{np.degrees(elevation):.0f} deg up, {distance:.0f} mm, {pixel:.2f} mm pixels, {noise:.2f} mm noise, "
             f"{mixed:.1%} mixed pixels, {np.mean(roles[kept] == 'workpiece'):.0%} "
             "of the points on the part")
    return DepthCameraScan(points, roles[kept], motion @ S_B @ PLATFORM_POSE @ part, notes)
