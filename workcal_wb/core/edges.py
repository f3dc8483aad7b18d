"""Motions a part's faces leave nearly free but its edges pin: centre the pose between the edges.

A block seen on two faces slides along both.  Sliding it only pushes the few scan points near an
edge off the model, so the fit's valley along that motion is flat-bottomed and the refinement
stops anywhere in it, a few tenths of a mm from the truth (or wherever the noisiest edge points
pull it).  What the data do say is how far the pose can slide each way before more than a handful
of points leave the surface.  The pose is put in the middle of that interval (the edges' spill of
noise is alike on both sides) and the half-width is reported as the play the data leave; the
calibration's bootstrap refits centre again and so measure how well the middle is known.  A
motion with no edge within reach on one side is free (under-constrained).  Meshes only: edges
need the exact surface.
"""
from __future__ import annotations

import numpy as np

from . import frames
from .refine import past_edge
from .stability import describe_motion, gelfand
from .surface import SurfaceModel

# Gelfand eigenvalue ratio (see stability) below which a motion is checked against the edges.
WEAK_RATIO = 0.01
# The same ratio with the sampled surface's normals, below which a fit is checked at all: samples
# near an edge lend the side faces' normals to points of the top one, which props the ratio up.
CHECK_RATIO = 2 * WEAK_RATIO
# A point is off the model when farther than this many residual sigmas, and never closer than this
# fraction of the tolerance (a noise-free scan would otherwise count every tilt of a face) ...
OFF_SIGMAS, OFF_FLOOR_TOLERANCES = 3.0, 0.1
# ... and the slide has reached an edge when more of the points that cross an edge within reach
# are off than at the fewest, by more than EXTRA_OFF_POINTS and than COUNT_SIGMAS x the count's own
# jitter (points at the threshold cross it back and forth as the pose moves: ~ the square root of
# the count).  Points that cross no edge (a noisier face's tail, stray points) are not counted.
EXTRA_OFF_POINTS, COUNT_SIGMAS = 5, 3.0
# The slide is followed this many tolerances each way past the off threshold (a point at an edge is
# only off once it has gone the threshold past it); an edge farther out does not pin it.
REACH_TOLERANCES = 2.0
# Profile samples across the reach each way, then halvings of the step at each end.
PROFILE_STEPS, BISECTIONS = 12, 5
# A point crossing lies at a sharp edge of the model when, within SHARP_SPACINGS sample spacings of it,
# the surface's normals turn by more than SHARP_DEG (a block's edge turns 90; a smooth body's curvature
# a few degrees over that span).  Only sharp edges leave a scan's points stopping short of them.
SHARP_DEG, SHARP_SPACINGS, SHARP_NEIGHBOURS = 30.0, 3.0, 16


def has_weak_motion(points: np.ndarray, surface: SurfaceModel, T: np.ndarray, gate: float, scale: float) -> bool:
    """Whether the fit at ``T`` may leave a motion to the edges: a cheap look on the sampled surface,
    at the points the fit's kernel (``scale`` mm) counts as on it.  A block slid past its edge
    must not hide its weak motion behind the side faces its overhanging points find."""
    moved = frames.apply(T, points)
    _, idx, found = surface.nearest_cell(moved, gate)
    found[found] = np.abs(surface.plane_residuals(moved[found], idx[found])) <= scale
    return found.sum() >= 6 and gelfand(moved[found], surface.normals[idx[found]])[0][0] < CHECK_RATIO


def centre_on_edges(points: np.ndarray, surface: SurfaceModel, T: np.ndarray, gate: float, sigma: float,
                    tolerance_mm: float) -> tuple[np.ndarray, dict]:
    """Move ``T`` (scan -> model) to the middle of the edge interval along each weak motion and
    return it with the stability of the fit (see stability.stability) extended by
    ``held_by_edges``: for each such motion its description, eigenvalue, half-width ``slack_mm``, the most
    the middle can be off the truth ``bias_mm``, and the motion itself (``twist`` in units of 1 mm RMS over
    the points, about ``centre``; see ``slide``).  Motions not pinned within REACH_TOLERANCES tolerances each way (past the off
    threshold) are listed as free: their faces hold them weakly (WEAK_RATIO) and no edge pins them."""
    points = points[surface.nearest_cell(frames.apply(T, points), gate + surface.spacing)[2]]  # clutter is no edge
    moved = frames.apply(T, points)
    closest, normals = surface.closest_points(moved)
    # The faces' constraints only: a point past an edge is what pins a weak motion, not part of it.
    on = (np.linalg.norm(moved - closest, axis=1) <= gate) & ~past_edge(moved - closest, normals)
    if on.sum() < 6:
        return T, {"ratio": 0.0, "eigenvalues": [], "free_motions": ["too few matched points"],
                   "constrained": False, "held_by_edges": []}
    vals, vecs, centre, radius = gelfand(moved[on], normals[on])
    threshold = max(OFF_SIGMAS * sigma, OFF_FLOOR_TOLERANCES * tolerance_mm)
    reach = threshold + REACH_TOLERANCES * tolerance_mm
    free, held = [], []
    for i in np.flatnonzero(vals < WEAK_RATIO):
        twist = unit_twist(vecs[:, i], centre, radius, moved[on])
        interval = _edge_interval(frames.apply(T, points), surface, twist, centre, threshold, reach)
        if interval is None:  # faces that hold it weakly and no edge within reach: the data leave it free
            free.append(describe_motion(vecs[:, i], centre, radius))
            continue
        lo, hi, crossing = interval
        T = slide(twist, centre, (lo + hi) / 2) @ T
        # The truth lies where neither edge has begun to lose points: at least ``threshold`` in from each
        # end.  The middle is off it by at most the rest of the slack, when one edge's points run right up
        # to it and the other's stop short (a fold edge seen on both faces against a silhouette, whose
        # last pixels are mixed with what lies behind): a bias the refits, centring alike, cannot see.
        # A smooth body's near-symmetry spreads its points off alike both ways: no such bias.
        bias = max((hi - lo) / 2 - threshold, 0.0) if _at_sharp_edges(surface, crossing) else 0.0
        held.append({"motion": describe_motion(vecs[:, i], centre, radius), "eigenvalue": float(vals[i]),
                     "slack_mm": float((hi - lo) / 2), "bias_mm": float(bias),
                     "twist": twist.tolist(), "centre": centre.tolist()})
    return T, {"ratio": float(vals[0]), "eigenvalues": vals.tolist(), "free_motions": free,
               "constrained": not free, "held_by_edges": held}


def unit_twist(v: np.ndarray, centre: np.ndarray, radius: float, points: np.ndarray) -> np.ndarray:
    """A Gelfand eigenvector as (rotation vector rad/unit, translation mm/unit), scaled so that
    one unit moves ``points`` by 1 mm RMS: slack in those units is a distance."""
    twist = np.concatenate([v[:3] / radius, v[3:]])
    shift = np.cross(twist[:3], points - centre) + twist[3:]
    return twist / max(np.sqrt((shift**2).sum(axis=1).mean()), 1e-12)


def slide(twist, centre, amount: float) -> np.ndarray:
    """The rigid motion (4x4) of ``amount`` units of ``twist`` about ``centre``."""
    twist, centre = np.asarray(twist, float), np.asarray(centre, float)
    T = frames.from_rotvec(amount * twist[:3])
    T[:3, 3] = centre - T[:3, :3] @ centre + amount * twist[3:]
    return T


def _edge_interval(moved: np.ndarray, surface: SurfaceModel, twist, centre, threshold: float, reach: float):
    """(lo, hi, points): the amounts of ``twist`` between which the count of points off the surface stays
    within the allowance (EXTRA_OFF_POINTS, COUNT_SIGMAS) of its fewest, and the points that cross an edge
    within reach; None when the slide meets no edge within ``reach`` on a side."""
    def distance(points, amount):
        return surface.exact_distance(frames.apply(slide(twist, centre, amount), points))

    def off(points, amount):
        return distance(points, amount) > threshold

    # Only points whose distance changes by more than the threshold within reach can change the
    # count: those crossing an edge.  Points hovering at the threshold (a noisy face's tail, a
    # faceted round surface turned about its axis) would jitter the count without an edge.
    at_rest = distance(moved, 0.0)
    changing = ((np.abs(distance(moved, -reach) - at_rest) > threshold)
                | (np.abs(distance(moved, reach) - at_rest) > threshold))
    if changing.sum() <= EXTRA_OFF_POINTS:
        return None
    points = moved[changing]
    amounts = np.linspace(-reach, reach, 2 * PROFILE_STEPS + 1)
    counts = np.array([off(points, a).sum() for a in amounts])
    # Points left farther off than the whole reach are unexplained by the fit: where they lie beside
    # the part, its edge may be misplaced, so they widen the allowance as much as points that cross.
    far = np.count_nonzero(~changing & (at_rest > reach))
    limit = counts.min() + max(EXTRA_OFF_POINTS, COUNT_SIGMAS * np.sqrt(counts.min() + far))
    low = np.flatnonzero(counts <= limit)
    first, last = low[0], low[-1]
    if first == 0 or last == len(amounts) - 1:
        return None  # still in the valley at the end of reach

    def crossing(inside, outside):
        for _ in range(BISECTIONS):
            middle = (inside + outside) / 2
            inside, outside = (middle, outside) if off(points, middle).sum() <= limit else (inside, middle)
        return (inside + outside) / 2

    return crossing(amounts[first], amounts[first - 1]), crossing(amounts[last], amounts[last + 1]), points


def _at_sharp_edges(surface: SurfaceModel, points: np.ndarray) -> bool:
    """Whether most of ``points`` (model frame) lie at a sharp edge of the model (SHARP_DEG)."""
    near = surface.tree.query(points, SHARP_NEIGHBOURS, distance_upper_bound=SHARP_SPACINGS * surface.spacing)[1]
    found = near < len(surface.points)
    normals = surface.normals[np.where(found, near, 0)]
    turned = np.einsum("ikj,ij->ik", normals, normals[:, 0]) < np.cos(np.radians(SHARP_DEG))
    return bool(np.mean((turned & found).any(axis=1)) >= 0.5)
