"""Physical constraints that tell apart poses a match leaves tied: contact with the platform and free space.

A match judges a pose by the points of its own region.  The whole scene knows more.  An object stands
on the platform: a pose that sinks it through the plane is impossible, and one that lifts it off is
wrong when another pose stands it on the plane.  And every scan point is the end of a ray from the
scanner through free space: a pose that puts solid material where the scanner saw through to
something behind it (the table, the other object) is wrong, and so is one whose surfaces facing the
scanner, inside what it looked at and hidden by nothing, show no points at all.

``decide(match, surface, scene, role)`` weighs the best pose and its rivals (the candidates that made
the match ambiguous) by these constraints: a rival that breaks one the best keeps is ruled out and the
result says which constraint decided; a best that breaks one a rival keeps gives way to the rival; a
tie that survives stays ambiguous with a sentence on what would break it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import frames, visibility
from .result import AMBIGUOUS, FAILED, MANY_WAYS, OK, SINKS, TIE_UNBROKEN, MatchResult, Reason
from .surface import SurfaceModel

# A pose stands on the platform when its lowest point lies within this many platform bands (the plane's
# thickness in the scan) of it; lower, it sinks through it; higher, it floats.
CONTACT_BANDS = 2.0
# Model samples rendered for the free-space test, view pixels this many of their spacings wide (and at
# least PIXEL_SCAN_SPACINGS scan spacings), and the silhouette eroded by this many pixels (an estimated
# viewpoint is only good to some degrees: the edges of a silhouette are not trusted).
SAMPLES, PIXEL_SAMPLE_SPACINGS, PIXEL_SCAN_SPACINGS = 12000, 2.0, 2.0
ERODE_PIXELS = {"known": 1, "estimated": 3}
# Scan points this far behind the placed surface (mm, and at least DEPTH_PIXELS pixels) were seen through it.
DEPTH_MARGIN_MM, DEPTH_PIXELS = 5.0, 2.0
# A tie is broken by the constraints only when the search listed at most this many rivals: a longer list is a
# sample, and ruling out its few may leave standing a pose the search never listed.
MAX_RULED_OUT = 2
# A rival breaks free space when it contradicts at least this many more view pixels than the best,
# and this share of its own interior more.
MIN_PIXELS, MIN_SHARE = 25, 0.1


def contact(platform, surface: SurfaceModel, U: np.ndarray) -> float:
    """Height of the model's lowest point, placed by U, above the platform (mm; negative: below it):
    the platform's up direction taken into the model's frame, so that the samples are not moved."""
    up_in_model = U[:3, :3].T @ platform.up
    return float((surface.points @ up_in_model).min() + (U[:3, 3] - platform.centre) @ platform.up)


def sinks(platform, surface: SurfaceModel, U: np.ndarray) -> bool:
    """Whether the model placed by U reaches through the platform (None: no platform, nothing sinks)."""
    return platform is not None and contact(platform, surface, U) < -CONTACT_BANDS * platform.band


@dataclass
class Scene:
    """What the whole scan says beyond a match's region: all its points, the platform (or None), and
    the scanner positions it was taken from, when known (k x 3, with each point's index)."""

    points: np.ndarray
    spacing: float
    platform: object | None = None  # regions.Platform
    sensors: np.ndarray | None = None
    sensor_of: np.ndarray | None = None

    def free_space(self, surface: SurfaceModel, U: np.ndarray, viewpoint: np.ndarray | None) -> dict:
        """View pixels where the placed model contradicts the rays: seen through (scan points behind
        its surface, none on it) and unseen (its surface facing the scanner inside the scan's
        footprint, with no point anywhere along the pixel), over its silhouette's interior."""
        views = []
        if self.sensors is not None:
            owner = np.zeros(len(self.points), np.int64) if self.sensor_of is None else self.sensor_of
            views = [(position, self.points[owner == k], "known") for k, position in enumerate(self.sensors)]
        elif viewpoint is not None:
            views = [(np.asarray(viewpoint, float), self.points, "estimated")]
        out = {"seen_through": 0, "unseen": 0, "interior": 0}
        for position, points, source in views:
            for key, value in _free_space(surface, U, position, points, self.spacing, source).items():
                out[key] += value
        return out


def _free_space(surface: SurfaceModel, U, viewpoint, points, spacing: float, source: str) -> dict:
    samples = surface.view_order[:SAMPLES]
    placed = frames.apply(U, surface.points[samples])
    normals = surface.normals[samples] @ U[:3, :3].T
    sample_spacing = surface.spacing * np.sqrt(len(surface.points) / len(samples))
    pixel = max(PIXEL_SAMPLE_SPACINGS * sample_spacing, PIXEL_SCAN_SPACINGS * spacing)
    view = visibility.View(viewpoint, placed.mean(axis=0), pixel).framed(placed, margin=2)
    rows, cols = view.shape
    front, index = visibility.front(view, placed, normals)
    solid = (front < np.inf).reshape(rows, cols)
    from scipy import ndimage

    interior = ndimage.binary_erosion(solid, np.ones((3, 3), bool), iterations=ERODE_PIXELS[source]).ravel()
    pixel_of, depth = view.pixels(points)
    inside = pixel_of >= 0
    pixel_of, depth = pixel_of[inside], depth[inside]
    margin = max(DEPTH_MARGIN_MM, DEPTH_PIXELS * pixel)
    surface_depth = front[pixel_of]
    on_or_before = np.zeros(rows * cols, bool)
    on_or_before[pixel_of[depth <= surface_depth + margin]] = True
    behind = np.zeros(rows * cols, bool)
    behind[pixel_of[depth > surface_depth + margin]] = True
    seen_through = interior & behind & ~on_or_before
    any_point = np.zeros((rows, cols), bool)
    any_point.ravel()[pixel_of] = True
    around = ndimage.binary_dilation(any_point, np.ones((3, 3), bool)).ravel()
    footprint = np.zeros(rows * cols, bool)
    footprint[visibility.footprint(view, pixel_of)] = True
    cos = np.zeros(rows * cols)
    there = index >= 0
    cos[there] = visibility.facing(placed[index[there]], normals[index[there]], viewpoint)
    unseen = interior & footprint & ~around & (cos > visibility.MISSING_COS)
    return {"seen_through": int(seen_through.sum()), "unseen": int(unseen.sum()), "interior": int(interior.sum())}


def decide(match: MatchResult, surface: SurfaceModel, scene: Scene, role: str, refit=None) -> MatchResult:
    """The match with its tie broken where the constraints can (see the module docstring); ``refit(U)``
    refines a rival that becomes the best.  Sinking through the platform fails a match outright."""
    if match.matrix is None or match.status == FAILED:
        return match
    viewpoint = (match.viewpoint or {}).get("position_mm")
    poses = [np.asarray(match.matrix)] + [c.matrix for c in match.candidates[1:] if c.rival]
    # Free space only weighs poses against each other: a match without rivals needs only the platform.
    checks = [_check(surface, scene, U, viewpoint, free=len(poses) > 1) for U in poses]
    possible = [i for i, c in enumerate(checks) if not c["sinks"]]
    if not possible:
        match.status = FAILED
        match.reasons.append(Reason(SINKS, f"the placed {role} model sinks {-checks[0]['height']:.1f} mm through the "
                                           "platform in every pose that fits: the platform or the model is not the "
                                           "one in the scan"))
        return match
    best = _cleanest(checks, possible)
    if best != 0 and refit is not None:  # the best breaks a constraint a rival keeps: the rival it is
        why = _ruled_out(checks[0], checks[best], scene)
        replaced = refit(poses[best])
        if replaced.matrix is not None and replaced.status != FAILED:
            replaced.constraints = match.constraints + [
                f"the pose the scan alone preferred was ruled out by {why[0]}: {why[1]}; the pose "
                f"{frames.rotation_between_deg(poses[0], poses[best]):.1f} deg from it keeps it"]
            replaced.reasons = [r for r in replaced.reasons if r not in match.ties]
            replaced.ties = []
            return replaced
    rivals = [i for i in range(1, len(poses))]
    survivors = []
    listed = [c for c in match.candidates[1:] if c.rival]
    for i in rivals:
        why = _ruled_out(checks[i], checks[0], scene)
        if why is None:
            survivors.append(i)
            continue
        listed[i - 1].ruled_out_by = why[0]
        match.constraints.append(f"a rival pose {frames.rotation_between_deg(poses[0], poses[i]):.1f} deg away was "
                                 f"ruled out by {why[0]}: {why[1]}")
    if rivals and not survivors and match.ties:
        if len(rivals) > MAX_RULED_OUT:
            match.reasons.append(Reason(MANY_WAYS, (
                f"the view fits the {role} in {len(rivals) + 1} ways; the platform and free space "
                f"rule out the {len(rivals)} the search listed, but a view that fits it in so many "
                "ways may fit it in others the search did not list: scan again from where the part "
                "shows more of its shape, or give the regions")))
        else:
            match.reasons = [r for r in match.reasons if r not in match.ties]
            match.ties = []
            if not match.reasons and match.status == AMBIGUOUS:
                match.status = OK
    elif survivors and match.ties:
        match.reasons.append(Reason(TIE_UNBROKEN, _what_would_break(surface, poses[0], poses[survivors[0]], role)))
    if checks[0]["sinks"] and match.status == OK:
        match.status = FAILED
        match.reasons.append(Reason(SINKS, f"the placed {role} model sinks {-checks[0]['height']:.1f} mm through the "
                                           "platform"))
    return match


def _check(surface, scene: Scene, U, viewpoint, free: bool = True) -> dict:
    out = {"sinks": False, "floats": False, "height": 0.0, "free": None}
    if scene.platform is not None:
        height = contact(scene.platform, surface, U)
        tolerance = CONTACT_BANDS * scene.platform.band
        out.update(height=height, sinks=height < -tolerance, floats=height > tolerance)
    if free and (scene.sensors is not None or viewpoint is not None):
        out["free"] = scene.free_space(surface, U, viewpoint)
    return out


def _bad(check: dict) -> int:
    free = check["free"]
    return 0 if free is None else free["seen_through"] + free["unseen"]


def _cleanest(checks: list, possible: list) -> int:
    """Of the possible poses, the first (the best by the scan) unless another stands on the platform
    where it floats, or contradicts clearly fewer rays."""
    best = possible[0]
    for i in possible[1:]:
        if _ruled_out(checks[best], checks[i], None) is not None:
            best = i
    return best


def _ruled_out(rival: dict, best: dict, scene) -> tuple[str, str] | None:
    """(constraint, why) when ``rival`` breaks a constraint that ``best`` keeps, else None."""
    if rival["sinks"] and not best["sinks"]:
        return "platform contact", f"it sinks {-rival['height']:.1f} mm through the platform"
    if rival["floats"] and not best["floats"] and not best["sinks"]:
        return "platform contact", (f"it floats {rival['height']:.1f} mm above the platform where the other pose "
                                    "stands on it")
    if rival["free"] is not None and best["free"] is not None:
        more = _bad(rival) - _bad(best)
        if more >= max(MIN_PIXELS, MIN_SHARE * max(rival["free"]["interior"], 1)):
            through, unseen = rival["free"]["seen_through"], rival["free"]["unseen"]
            return "free space", (f"it puts solid material on {through} view pixels where the scanner saw through "
                                  f"to something behind it, and {unseen} pixels of its surface facing the scanner "
                                  "show no point (against "
                                  f"{best['free']['seen_through']} and {best['free']['unseen']} for the other pose)")
    return None


def _what_would_break(surface: SurfaceModel, best: np.ndarray, rival: np.ndarray, role: str) -> str:
    """Where the two poses differ on the part, and from where a scan would see it."""
    placed = frames.apply(best, surface.points)
    other = frames.apply(rival, surface.points)
    from scipy.spatial import cKDTree

    apart = cKDTree(other).query(placed, distance_upper_bound=0.05 * surface.diagonal)[0] == np.inf
    if not apart.any():
        apart = np.ones(len(placed), bool)
    where = placed[apart].mean(axis=0)
    facing = (surface.normals[apart] @ best[:3, :3].T).mean(axis=0)
    facing /= max(np.linalg.norm(facing), 1e-12)
    return (f"nothing in the scene tells these poses apart: to break the tie, scan again from where the part of the "
            f"{role} on which they differ shows (around ({where[0]:.0f}, {where[1]:.0f}, {where[2]:.0f}) mm in the "
            f"scan, facing ({facing[0]:.2f}, {facing[1]:.2f}, {facing[2]:.2f})), or give the {role} a feature this "
            "view shows")
