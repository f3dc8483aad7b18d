"""A region's pose weighed against the scan around it: the points beside the region that its pose
leaves unexplained.

A region is picked with a pose (automatic regions keep the clusters the placed model explains) or
drawn by hand, and either way it may leave out the part of the object that tells its near-symmetric
poses apart: an L-block whose legs differ by a centimetre, the top of its upright cut off by the
workpiece in front of it, fits its region turned over as well as the right way up.  The scan beside
the region shows the rest of the object.  So every object is matched once more on its region and the
scan points within SURROUNDINGS_DIAGONALS of its placed model that belong to no other region nor the
platform, with a global search: a pose that explains the region as well as the region's own and
explains more of what lies beside it replaces it (its region grows by the points it explains there),
and a pose the surroundings leave tied with it makes the match ambiguous.  Clutter beside a part
(a clamp, a neighbour) fits no pose of the model, so it changes nothing.
"""
from __future__ import annotations

import numpy as np

from . import frames
from .geometry import Cloud
from .match import inlier_scores, match
from .regions import in_clusters, joins_within, near_points
from .result import AMBIGUOUS, FAILED, OK, MatchResult
from .surface import SurfaceModel

# The surroundings: scan points within this share of the model's diagonal of the placed model.
SURROUNDINGS_DIAGONALS = 0.25
# Surroundings with fewer points than this share of the region beyond it (and at least MIN_EXTRA) add
# nothing to weigh.
EXTRA_SHARE, MIN_EXTRA = 0.01, 30
# Another pose replaces the region's when it explains at least REGION_SHARE of what the region's
# pose explains of the region, and more of the surroundings by at least EXTRA_SHARE of the region.
REGION_SHARE = 0.98
# What a reason found with the scan beside the region is said to be of.
BESIDE = "with the scan beside its region"
# Two poses are one within these limits (degrees; share of the diagonal at the model's centre).
SAME_DEG, SAME_DIAGONALS = 1.0, 0.01


def judged_in_surroundings(cloud: Cloud, region: np.ndarray, excluded: np.ndarray, surface: SurfaceModel,
                           found: MatchResult, options: dict, role: str, spacing: float):
    """(the match, its region): ``found`` on ``region`` (scan indices into ``cloud``, whose points are
    ``spacing`` mm apart) weighed against the surfaces around it, ``excluded`` (the platform's, the
    other object's) left out."""
    if found.matrix is None or found.status == FAILED:
        return found, region
    points = cloud.points
    others = np.ones(len(points), bool)
    others[region] = False
    others[excluded] = False
    others &= np.isfinite(points).all(axis=1)
    candidates = np.flatnonzero(others)
    beside = candidates[near_points(points[candidates], surface, found.matrix,
                                    SURROUNDINGS_DIAGONALS * surface.diagonal)]
    beside = beside[in_clusters(points[beside], spacing)]  # surfaces: no pose explains stray or mixed pixels
    if len(beside) < max(MIN_EXTRA, EXTRA_SHARE * len(region)):
        return found, region
    wide_idx = np.union1d(region, beside)
    wide = match(cloud.subset(wide_idx, name=f"{role} region of {cloud.name} and the scan beside it"), surface,
                 **options)
    if wide.matrix is None:
        return found, region
    if _same_pose(wide.matrix, found.matrix, surface):
        if wide.ties and found.status == OK:  # the surroundings leave the region's pose tied with another
            found.status = AMBIGUOUS
            said = [r.within(BESIDE) for r in wide.ties]
            found.reasons += said
            found.ties += said
            found.candidates = wide.candidates
        return found, region
    gate = max(found.gate_mm, wide.gate_mm) if np.isfinite(found.gate_mm) else wide.gate_mm
    to_model = [frames.invert(found.matrix), frames.invert(wide.matrix)]
    on_region = inlier_scores(points[region], surface, to_model, gate)
    on_beside = inlier_scores(points[beside], surface, to_model, gate)
    if not (on_region[1] >= REGION_SHARE * on_region[0]
            and on_beside[1] - on_beside[0] >= max(MIN_EXTRA, EXTRA_SHARE * len(region))):
        return found, region
    grown = np.union1d(region, beside[near_points(points[beside], surface, wide.matrix, joins_within(role, spacing))])
    final = match(cloud.subset(grown, name=f"{role} region of {cloud.name}"), surface, init=wide.matrix, **options)
    turned = frames.rotation_between_deg(found.matrix, wide.matrix)
    shift = float(np.linalg.norm(frames.apply(found.matrix, surface.centre[None])
                                 - frames.apply(wide.matrix, surface.centre[None])))
    final.constraints = found.constraints + [
        f"the pose its region alone gave ({turned:.0f} deg and {shift:.0f} mm from this one) explains "
        f"{on_beside[0]:.0f} of the {len(beside)} scan points beside the region, this pose {on_beside[1]:.0f}; "
        f"the region grew by {len(grown) - len(region)} of them"]
    if wide.status != OK and final.status == OK:  # the search on the surroundings stays in doubt
        final.status = AMBIGUOUS
        final.reasons += [r.within(BESIDE) for r in wide.reasons]
        final.ties = list(final.reasons)
        final.candidates = wide.candidates
    return final, grown


def _same_pose(a: np.ndarray, b: np.ndarray, surface: SurfaceModel) -> bool:
    shift = np.linalg.norm(frames.apply(a, surface.centre[None]) - frames.apply(b, surface.centre[None]))
    return frames.rotation_between_deg(a, b) < SAME_DEG and shift < SAME_DIAGONALS * surface.diagonal
