"""A model's own symmetries, found once when it is prepared, and the near-symmetric turns every
match tries.

A symmetric part cannot tell a scan which of its symmetric poses it is in; a nearly symmetric one
can, but only by its small differences, so a match must try those poses and weigh them.  Both are
found from the principal axes of the surface samples: a rotation that maps the surface onto itself
keeps its centroid and its second moments, so a half turn is about a principal axis, a turn by any
other angle is about an axis whose two perpendicular moments are equal (and then any axis in that
plane may carry a half turn), and any axis at all is possible only when all three moments are equal
(a sphere, a cube).  Candidates are tried there, each refined by a few point-to-plane steps of the
surface against itself, and kept when the surface lands on itself within the tolerance.

A part can also map mostly onto itself by a turn about no principal axis (an L-block whose legs differ
by a centimetre: the half turn that swaps them moves its axes).  ``near_self_maps`` finds such turns by
registering the surface against itself: feature correspondences between points far apart, RANSAC,
each pose refined into the best self-map and kept when most of the surface lands on itself.

Everything found is plain numpy arrays (axes, points on them, orders, deviations): a cache of
prepared models can store them as they are.
"""
from __future__ import annotations

import numpy as np

from . import frames
from .robust import gauss_newton_step, geman_mcclure

# Surface samples a candidate is screened on, refined on, and checked on after refinement.
SCREEN_POINTS, REFINE_POINTS, CHECK_POINTS = 400, 500, 2000
# Two principal moments this close (relative) are taken as equal: the surface may turn about the
# third axis by any angle, or by 360/n for n up to MAX_ORDER.
EQUAL_MOMENTS = 0.03
MAX_ORDER = 12
# Turns by angles of no small order (not 360 k / n for n <= MAX_ORDER): both mapping the surface
# onto itself means any angle does.
GENERIC_ANGLES_DEG = (37.0, 83.0)
# In-plane axes tried for half turns when two moments are equal, and directions tried when all
# three are, on a half circle / hemisphere.
PLANE_AXES, SPHERE_AXES = 60, 120
# A candidate is refined only when SCREEN_QUANTILE of its moved samples land within this fraction of
# the model diagonal of the surface (an axis off by half a scanning step moves points a few percent
# of the size; a feature that breaks the symmetry moves more than a tenth of the surface, or is small).
SCREEN_FRACTION, SCREEN_QUANTILE = 0.04, 0.9
# Candidates refined at most per scan of axes.
MAX_REFINED = 12
# Nearest samples a moved sample is compared with (near an edge the nearest may be on the other face).
NEIGHBOURS = 4
# Self-registration steps of a candidate, and the share of the check points that must land on the
# surface within the tolerance (with matching normals) for a symmetry: a feature covering more than
# 0.3 % of the surface (an 8 x 8 mm mark on a 100 x 100 x 10 mm plate) breaks it.
REFINE_STEPS, MIN_LANDED = 8, 0.997
# A near self-map (near_self_maps) lands at least NEAR_SELF_SHARE of the check samples within
# LANDED_SPACINGS sample spacings of the surface (with matching normals), turns by at least
# MIN_TURN_DEG (a part sliding along itself, a long face, is not a turn a match confuses), and is one of
# at most MAX_NEAR_SELF_MAPS.  Correspondences pair points at least SELF_APART of the diagonal apart
# with their SELF_NEIGHBOURS nearest features; SELF_SAMPLES RANSAC samples, SELF_TRIED poses refined.
NEAR_SELF_SHARE, LANDED_SPACINGS, MIN_TURN_DEG, MAX_NEAR_SELF_MAPS = 0.8, 2.0, 20.0, 2
SELF_APART, SELF_NEIGHBOURS, SELF_SAMPLES, SELF_TRIED = 0.1, 4, 20000, 6
# Coarse points weighed against all the others at once (their offsets, 64 x n x 3 doubles), and poses
# voted on at once against all the correspondences (16 x n x 3 doubles, two arrays): a few MB each, where
# a model's preparation reaches its peak memory.
SELF_ROWS, SELF_VOTED = 64, 16
# Half turns about this many axes spread over a hemisphere are screened by how near their moved samples
# land (the median distance: a near self-map leaves a part of the surface off), the best few refined.
HALF_TURN_AXES, HALF_TURNS_TRIED, HALF_TURN_SCREEN = 200, 4, 100
# Moments within this ratio make a quarter turn about the third axis worth trying in every match
# (a near-square plate); the half turns about the principal axes are always tried.
NEAR_EQUAL_MOMENTS = 0.8


def principal_axes(points: np.ndarray, weights: np.ndarray):
    """(centroid, unit axes as columns ordered by ascending second moment, the moments) of points
    standing for ``weights`` of surface area each."""
    w = weights / weights.sum()
    centre = w @ points
    moments, axes = np.linalg.eigh(((points - centre) * w[:, None]).T @ (points - centre))
    return centre, axes, np.maximum(moments, 0.0)


def turn(axis, angle_deg: float, through) -> np.ndarray:
    """4x4 rotation by ``angle_deg`` about the line along ``axis`` through the point ``through``."""
    axis = np.asarray(axis, dtype=float)
    R = frames.from_rotvec(np.radians(angle_deg) * axis / np.linalg.norm(axis))[:3, :3]
    return frames.rigid(R, np.asarray(through) - R @ np.asarray(through))


def axis_of(T: np.ndarray, near):
    """(unit axis, point on it nearest the point ``near``, angle in degrees) of a rotation 4x4."""
    R, t = T[:3, :3], T[:3, 3]
    angle = np.degrees(np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1)))
    w, v = np.linalg.eig(R)
    axis = np.real(v[:, np.argmin(np.abs(w - 1))])
    axis /= np.linalg.norm(axis)
    # Points on the axis solve (I - R) p = t - (t . a) a; least squares picks one, then slide it.
    point = np.linalg.lstsq(np.eye(3) - R, t - (t @ axis) * axis, rcond=None)[0]
    return axis, point + ((np.asarray(near) - point) @ axis) * axis, angle


class SelfMatch:
    """Whether a rigid motion maps a sampled surface onto itself, and by how much it misses."""

    def __init__(self, points, normals, tree, spacing: float, diagonal: float, tolerance: float, seed: int = 0):
        pick = np.random.default_rng(seed).permutation(len(points))[:CHECK_POINTS]
        self.points, self.normals, self.tree = points, normals, tree
        self.check, self.screen, self.fit = pick, pick[:SCREEN_POINTS], pick[:REFINE_POINTS]
        self.tolerance = tolerance
        self.reach = 2 * spacing + 4 * tolerance  # a landed point has its nearest sample this close
        self.screen_limit = SCREEN_FRACTION * diagonal

    def _residuals(self, T, subset, reach: float | None = None):
        """Point-to-plane distance of each moved sample to the best of its NEIGHBOURS nearest
        samples within ``reach`` (default: a landed point's) whose normal agrees with its own (near an
        edge the nearest may lie on the other face); inf where none is near (or only a thin wall's
        other side is)."""
        moved = self.points[subset] @ T[:3, :3].T + T[:3, 3]
        d, j = self.tree.query(moved, NEIGHBOURS, distance_upper_bound=self.reach if reach is None else reach)
        found = np.isfinite(d)
        j = np.where(found, j, 0)
        r = np.abs(np.einsum("nkj,nkj->nk", moved[:, None] - self.points[j], self.normals[j]))
        agree = np.einsum("nj,nkj->nk", self.normals[subset] @ T[:3, :3].T, self.normals[j]) > 0.5
        r = np.where(found & agree, r, np.inf)
        best = np.argmin(r, axis=1)
        rows = np.arange(len(r))
        return r[rows, best], moved, j[rows, best], np.isfinite(r[rows, best])

    def screen_distance(self, T) -> float:
        """How far (SCREEN_QUANTILE) a few moved samples are from the surface (cheap, unrefined)."""
        moved = self.points[self.screen] @ T[:3, :3].T + T[:3, 3]
        return float(np.quantile(self.tree.query(moved)[0], SCREEN_QUANTILE))

    def deviation(self, T) -> float:
        """The distance within which MIN_LANDED of the check samples land on the surface (mm)."""
        r, *_ = self._residuals(T, self.check)
        return float(np.sort(r)[int(np.ceil(MIN_LANDED * len(r))) - 1])  # inf when too few land

    def refined(self, T, reach: float | None = None) -> np.ndarray:
        """T improved by point-to-plane steps of the moved samples against the surface, from samples
        ``reach`` mm off (default: a landed point's), the reach halving each step down to the default."""
        reach = self.reach if reach is None else reach
        scale = reach / 2
        for _ in range(REFINE_STEPS):
            r, moved, j, ok = self._residuals(T, self.fit, reach)
            reach = max(self.reach, reach / 2)
            if ok.sum() < 6:
                break
            signed = np.einsum("ij,ij->i", moved[ok] - self.points[j[ok]], self.normals[j[ok]])
            T = gauss_newton_step(moved[ok], self.normals[j[ok]], signed, geman_mcclure(signed, scale)) @ T
            scale = max(self.tolerance, scale / 2)
        return T

    def maps(self, T) -> tuple[bool, np.ndarray, float]:
        """(whether T, refined, maps the surface onto itself within the tolerance; the refined T;
        its deviation); a T that is not even close is not refined."""
        if self.screen_distance(T) > self.screen_limit:
            return False, T, float("inf")
        T = self.refined(T)
        deviation = self.deviation(T)
        return deviation <= self.tolerance, T, deviation


def find(points, normals, weights, tree, spacing: float, diagonal: float, tolerance: float, seed: int = 0) -> dict:
    """The rotation symmetries of a sampled surface (unit outward normals, the area each sample
    stands for, KD-tree of the points).

    Returns plain arrays: ``axes`` (k, 3), ``points`` (k, 3) one point on each axis, ``orders`` (k,)
    with n for an n-fold axis (2: a half turn) and 0 for any angle, ``deviations_mm`` (k,), and
    ``flips`` (m, 4, 4): the near-symmetric turns a match tries (see ``_flips``).
    """
    self_match = SelfMatch(points, normals, tree, spacing, diagonal, tolerance, seed)
    centre, axes, moments = principal_axes(points, weights)
    found = []  # (axis, point, order, deviation)

    def add(T, order, deviation):
        axis, point, _ = axis_of(T, centre)
        if axis @ (axes @ np.ones(3)) < 0:
            axis = -axis  # one sign per axis, so repeated runs and reports agree
        if not _near(axis, order, found, 5.0):
            found.append((axis, point, order, deviation))

    equal = [k for k in range(3) if _equal(*np.delete(moments, k))]
    for k in range(3):
        axis = axes[:, k]
        if k not in equal:  # distinct moments around it: only a half turn can keep them
            ok, T, deviation = self_match.maps(turn(axis, 180.0, centre))
            if ok:
                add(T, 2, deviation)
            continue
        generic = [self_match.maps(turn(axis, a, centre)) for a in GENERIC_ANGLES_DEG]
        if all(ok for ok, _, _ in generic):
            add(generic[0][1], 0, max(d for _, _, d in generic))
            continue
        for n in range(MAX_ORDER, 1, -1):
            ok, T, deviation = self_match.maps(turn(axis, 360.0 / n, centre))
            if ok:
                add(T, n, deviation)
                break
    continuous = [f for f in found if f[2] == 0]
    if len(equal) == 3 and len(continuous) < 2:
        # All moments equal (a cube, or a sphere seen as one axis): axes anywhere.
        candidates = [(d, n) for d in _hemisphere(SPHERE_AXES) for n in (0, 4, 3, 2)]
    elif len(equal) == 1:
        # Half turns about axes across the one axis with equal moments around it: all of them if
        # it turns by any angle, else up to n of them (found by scanning the plane).
        u, v = np.delete(axes, equal[0], axis=1).T
        angles = np.linspace(0, np.pi, 1 if continuous else PLANE_AXES, endpoint=False)
        candidates = [(np.cos(a) * u + np.sin(a) * v, 2) for a in angles]
    else:
        candidates = []
    _scan(candidates, centre, self_match, add, found)
    if len(continuous) == 1:  # turning it over about any axis across: one such axis says it
        across = [i for i, f in enumerate(found) if f[2] == 2 and abs(f[0] @ continuous[0][0]) < 0.1]
        found = [f for i, f in enumerate(found) if i not in across[1:]]
    return {"axes": np.array([f[0] for f in found]).reshape(-1, 3),
            "points": np.array([f[1] for f in found]).reshape(-1, 3),
            "orders": np.array([f[2] for f in found], dtype=np.int64),
            "deviations_mm": np.array([f[3] for f in found], dtype=float),
            "flips": _flips(centre, axes, moments, self_match)}


def _equal(a: float, b: float) -> bool:
    return abs(a - b) <= EQUAL_MOMENTS * max(a, b, 1e-12)


def _near(axis, order: int, found, degrees: float) -> bool:
    """Whether an axis of this order (or any angle) was found within ``degrees`` of ``axis``."""
    return any(abs(axis @ a) > np.cos(np.radians(degrees)) and o in (order, 0) for a, _, o, _ in found)


def _hemisphere(count: int) -> np.ndarray:
    """About ``count`` evenly spread unit directions with z >= 0 (a Fibonacci spiral)."""
    i = np.arange(count) + 0.5
    z = 1 - i / count
    phi = np.pi * (1 + 5**0.5) * i
    r = np.sqrt(1 - z * z)
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def _scan(candidates, centre, self_match: SelfMatch, add, found) -> None:
    """Screen (axis, order) candidates cheaply (order 0: a generic angle); refine and check those that
    come close, best first, skipping axes next to one already found."""
    if not candidates:
        return
    turns = [turn(axis, 360.0 / order if order else GENERIC_ANGLES_DEG[0], centre) for axis, order in candidates]
    distance = np.array([self_match.screen_distance(T) for T in turns])
    step = 180.0 / max(PLANE_AXES, np.sqrt(SPHERE_AXES))
    tried = []
    for i in np.argsort(distance, kind="stable"):
        axis, order = candidates[i]
        if distance[i] > self_match.screen_limit or len(tried) == MAX_REFINED:
            break
        if _near(axis, order, found + tried, 2 * step):
            continue
        tried.append((axis, None, order, None))
        ok, T, deviation = self_match.maps(turns[i])
        if ok and order == 0:
            ok, _, other = self_match.maps(turn(axis, GENERIC_ANGLES_DEG[1], centre))
            deviation = max(deviation, other)
        if ok:
            add(T, order, deviation)


def _flips(centre, axes, moments, self_match: SelfMatch) -> np.ndarray:
    """Half turns about the principal axes, and quarter turns about an axis whose two other moments
    nearly agree, each refined into the turn that best maps the surface onto itself (robustly: the
    features that break a near symmetry are outliers), leaving out those that are symmetries (they
    add nothing a match could tell).  The principal axes of a nearly symmetric part lean a little
    towards its odd features; the refined turn takes a scan of one side exactly onto the other."""
    turns = [turn(axes[:, k], 180.0, centre) for k in range(3)]
    for k in range(3):
        a, b = np.delete(moments, k)
        if min(a, b) >= NEAR_EQUAL_MOMENTS * max(a, b, 1e-12):
            turns += [turn(axes[:, k], 90.0, centre), turn(axes[:, k], -90.0, centre)]
    kept = []
    for T in turns:
        symmetric, refined, _ = self_match.maps(T)
        if not symmetric:
            kept.append(refined if self_match.screen_distance(refined) <= self_match.screen_limit else T)
    return np.array(kept).reshape(-1, 4, 4)


def near_self_maps(coarse_points, coarse_normals, features, voxel: float, self_match: "SelfMatch",
                   known: np.ndarray, centre: np.ndarray, spacing: float, diagonal: float,
                   seed: int = 0) -> np.ndarray:
    """(m, 4, 4) turns that map most of the surface onto itself without being symmetries, each refined
    into its best self-map, those in ``known`` (the flips) left out: the poses a match must weigh
    against each other whatever axis they turn about.  Tried: half turns about HALF_TURN_AXES directions
    through the surface's ``centre`` (a near self-map moves the centroid little), the HALF_TURNS_TRIED
    whose samples land nearest the surface; and the poses of a RANSAC of the surface against itself
    (_self_registrations), which also finds turns by other angles."""
    from .global_search import distinct

    turns = [turn(axis, 180.0, centre) for axis in _hemisphere(HALF_TURN_AXES)]
    screen = self_match.points[self_match.screen[:HALF_TURN_SCREEN]]
    # Bounded: a query for a point far off the surface visits most of the tree.
    landed = [np.median(self_match.tree.query(screen @ T[:3, :3].T + T[:3, 3],
                                              distance_upper_bound=self_match.screen_limit)[0]) for T in turns]
    tried = [turns[i] for i in np.argsort(landed, kind="stable")[:HALF_TURNS_TRIED]]
    tried += list(_self_registrations(coarse_points, coarse_normals, features, voxel, diagonal, seed))
    kept, shares = [], []
    for T in tried:
        T = self_match.refined(self_match.refined(T, 3 * voxel))
        r, *_ = self_match._residuals(T, self_match.check)
        share = float(np.mean(r <= LANDED_SPACINGS * spacing))
        if (share < NEAR_SELF_SHARE or frames.rotation_between_deg(T, np.eye(4)) < MIN_TURN_DEG
                or self_match.deviation(T) <= self_match.tolerance):
            continue
        kept.append(T)
        shares.append(share)
    if not kept:
        return np.empty((0, 4, 4))
    listed = np.concatenate([np.asarray(known).reshape(-1, 4, 4), np.array(kept)])
    order = distinct(listed, np.r_[np.full(len(listed) - len(kept), 2.0), shares], centre, 5.0, 0.05 * diagonal)
    new = [listed[i] for i in order if i >= len(listed) - len(kept)]
    return np.array(new[:MAX_NEAR_SELF_MAPS]).reshape(-1, 4, 4)


def _self_registrations(coarse_points, coarse_normals, features, voxel: float, diagonal: float, seed: int):
    """Distinct poses (at most SELF_TRIED) that RANSAC finds taking the coarse surface onto itself:
    each point paired with the SELF_NEIGHBOURS points of most alike features among those SELF_APART
    of the diagonal away or more (nearer, the identity would win)."""
    from .global_search import distinct, ransac_poses

    n = len(coarse_points)
    if n < 10:
        return np.empty((0, 4, 4))
    features = np.asarray(features, np.float32)
    squared = np.einsum("ij,ij->i", features, features)
    k = min(SELF_NEIGHBOURS, n - 1)
    pairs = []
    for start in range(0, n, SELF_ROWS):  # a block of rows at a time: n x n distances would not fit
        rows = slice(start, min(start + SELF_ROWS, n))
        d = squared[rows, None] - 2 * features[rows] @ features.T + squared[None]
        d[np.linalg.norm(coarse_points[rows, None] - coarse_points[None], axis=2) < SELF_APART * diagonal] = np.inf
        j = np.argpartition(d, k - 1, axis=1)[:, :k]
        ok = np.isfinite(np.take_along_axis(d, j, axis=1))
        pairs.append(np.column_stack([np.broadcast_to(np.arange(start, rows.stop)[:, None], j.shape)[ok], j[ok]]))
    i, j = np.concatenate(pairs).T
    if len(i) < 2:
        return np.empty((0, 4, 4))
    poses, votes = ransac_poses(coarse_points[i], coarse_points[j], coarse_normals[i], coarse_normals[j],
                                1.5 * voxel, np.random.default_rng(seed), samples=SELF_SAMPLES, keep=200,
                                min_edge=3 * voxel, chunk=SELF_VOTED)
    # Apart by the RANSAC's own precision: one turn aligned two ways (an L's legs at their outer corner or
    # at their ends) is two local minima of the refinement, and only one is the best self-map.
    return poses[distinct(poses, votes, coarse_points.mean(axis=0), 10.0, 2 * voxel, SELF_TRIED)]


def describe(axes, points, orders) -> list[str]:
    """The symmetries in words, in the model's frame, one sentence per kind of turn: "turning the
    part 90 degrees about its axis (0.00, 0.00, 1.00) through (...) mm gives the same surface"."""
    axes, points, orders = np.asarray(axes).reshape(-1, 3), np.asarray(points).reshape(-1, 3), np.asarray(orders)
    if (orders == 0).sum() >= 2:
        c = np.round(points[orders == 0][0], 1) + 0.0  # no "-0.0"
        return [f"turning the part by any angle about any axis through its centre ({c[0]:.1f}, {c[1]:.1f}, "
                f"{c[2]:.1f}) mm gives the same surface"]
    main = [i for i in range(len(orders)) if orders[i] != 2]
    # Half turns about axes across a main axis (one that turns by any angle or by 360/n, n >= 3) turn
    # the part over; a box's three half turns have no main axis.
    over = [i for i in range(len(orders)) if orders[i] == 2 and main and any(abs(axes[i] @ axes[j]) < 0.1 for j in main)]
    sentences = []
    for order in sorted(set(orders.tolist()), key=lambda n: (n != 0, -n)):
        group = [i for i in range(len(orders)) if orders[i] == order and i not in over]
        if not group:
            continue
        angle = "by any angle" if order == 0 else ("half a turn (180 degrees)" if order == 2 else f"{360 / order:g} degrees")
        first = _where(axes[group[0]], points[group[0]])
        about = f"about its axis {first}" if len(group) == 1 else f"about any of its {len(group)} axes such as {first}"
        fold = f" ({order}-fold symmetry)" if order > 2 else ""
        sentences.append(f"turning the part {angle} {about} gives the same surface{fold}")
    if over:
        which = ("any axis" if (orders == 0).any() else f"any of {len(over)} axes" if len(over) > 1 else "an axis")
        sentences.append(f"turning the part over, half a turn about {which} across its main axis such as "
                         f"{_where(axes[over[0]], points[over[0]])}, gives the same surface")
    return sentences


def _where(axis, point) -> str:
    axis, point = np.round(axis, 2) + 0.0, np.round(point, 1) + 0.0  # no "-0.00"
    return (f"({axis[0]:.2f}, {axis[1]:.2f}, {axis[2]:.2f}) through ({point[0]:.1f}, {point[1]:.1f}, "
            f"{point[2]:.1f}) mm")
