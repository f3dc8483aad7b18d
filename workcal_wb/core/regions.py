"""Automatic scan regions: remove the platform, split what stands on it, find the reference and the workpiece.

The reference object and the platform are a constant scene, so no operator has to pick regions:
the largest plane seen is the platform; the points above it fall apart into objects; the reference
model is matched against the objects most like it in size; the workpiece is what remains and
matches its model.  The matches found on the way are kept, so calibration does not repeat them.
"""
from __future__ import annotations

import copy
import threading
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Mapping

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from . import frames, physics, pointops
from .errors import InputError, NotFound
from .geometry import SHAPE_WORDS, Cloud, shape_kind
from .match import VERDICT, MatchOptions, match
from .result import (AMBIGUOUS, FAILED, MISFIT, NOISE_ABOVE_TOLERANCE, OK, SEARCH_DOUBT, SPLIT_UNEXPLAINED,
                     MatchResult, Reason, codes)
from .surface import GATE_CELLS, SurfaceModel

@dataclass(frozen=True)
class PlatformSettings:
    """The platform: the plane the objects stand on, found among the scan's largest planes."""

    # The platform must hold at least this fraction of the scan to count as one (a dark table returns few
    # points); and, when its up side comes from the data (_up_side), at least supported_share of the points
    # off it must lie over it, up_side_share of those over its hull less the margin on one side.
    min_fraction: float = 0.05
    supported_share: float = 0.5
    up_side_share: float = 0.8
    all_on_one_side: float = 0.9
    # A platform's hull has at least this many times the area of the objects' footprint on it: a platform is larger
    # than what stands on it, a face of an object taken for one (in a scene without a platform) is not.
    footprint_ratio: float = 1.25
    # The largest planes tried in turn (most points first) until one is the platform.
    candidates: int = 5
    hull_margin_mm: float = 5.0
    hull_margin_spacings: float = 10.0
    # A given up direction picks the largest plane within this angle of square to it.
    max_up_deg: float = 30.0
    ransac_trials: int = 2000
    sample_points: int = 5000
    chunk: int = 100  # sample points weighed against every plane at once (1.6 MB: within a core's L2 cache)
    # Points weighed against the platform's outline at once: 65,536 x its edges x 8 bytes, a few MB
    # (the whole table of a 5M-point scan's points off the plane is hundreds of MB).
    hull_chunk: int = 1 << 16
    # Points this close to the platform plane (mm, plus a few scan spacings) are platform.
    band_mm: float = 1.0


PLATFORM = PlatformSettings()


@dataclass(frozen=True)
class ClusterSettings:
    """The clusters the points off the platform fall into, and which of them belong to an object."""

    # Objects are split where the gap between points exceeds this many scan spacings.
    link_spacings: float = 4.0
    # A cluster is a candidate for a model when its size is within these ratios of the model diagonal.
    size_ratio_range: tuple = (0.15, 1.5)
    min_points: int = 100
    # A cluster belongs to an object when this fraction of it lies near the placed model (lumps of clay
    # added later are connected to the workpiece and come along).  Below touching_share of the object's
    # clusters near its model, it touches something else and only its near points are kept.
    share: float = 0.5
    touching_share: float = 0.9


CLUSTERS = ClusterSettings()


@dataclass(frozen=True)
class LocateSettings:
    """What a match must explain to locate an object, and how often its search is tried."""

    # A match only locates an object when most matched points lie within the tolerance and most of the candidate
    # is explained (a wrong model placed "as well as it goes" scores far lower): the reference is rigid and
    # unchanged, the workpiece may have had clay added or carved.
    min_within_tolerance_pct: Mapping = field(default_factory=lambda: MappingProxyType({
        "reference": 80.0, "workpiece": VERDICT.min_within_tolerance_pct}))
    min_fitness: Mapping = field(default_factory=lambda: MappingProxyType({"reference": 0.8, "workpiece": 0.5}))
    # Global searches tried before a pose that explains less than good_fitness of its region is accepted,
    # unless a search comes back to a pose it found before (within these limits).
    search_attempts: int = 3
    same_pose_deg: float = 1.0
    same_pose_diagonals: float = 0.01
    good_fitness: Mapping = field(default_factory=lambda: MappingProxyType({"reference": 0.95, "workpiece": 0.9}))
    # Where the reference touches something, its region keeps only points this close to its surface: this
    # many times the scan's noise, and at least min_on_surface_mm.
    on_surface_noises: float = 5.0
    min_on_surface_mm: float = 0.5
    # A cluster that holds the model and more (objects touching) may put this small a share of its points on it.
    min_fitness_of_cluster: float = 0.05
    # Where objects touch, the points of their clusters on neither placed model (clay joining them, points at the
    # contact) stay under this share of the reference region's; a wrong pose leaves far more.
    unexplained_share: float = 0.25


LOCATE = LocateSettings()


@dataclass
class Located:
    """Regions as scan indices, and the matches that found them."""

    workpiece: np.ndarray
    reference: np.ndarray
    platform: np.ndarray
    workpiece_match: MatchResult
    reference_match: MatchResult
    warnings: list
    plane: "Platform | None" = None
    # The scan indices each match was made on (a region equal to them needs no match again).
    matched: dict | None = None
    spacing: float | None = None  # the scan's median spacing (mm)

    def as_dict(self) -> dict:
        return {"workpiece": self.workpiece, "reference": self.reference, "platform": self.platform,
                "source": "auto", "warnings": list(self.warnings)}


def find_regions(scan: Cloud, workpiece, reference, tolerance_mm: float = 0.3, seed: int = 0, up=None,
                 viewpoint=None, blas_threads: int | None = 1) -> dict:
    """The workpiece, reference and platform regions of ``scan`` as index arrays (see ``locate``)."""
    surfaces = [m if isinstance(m, SurfaceModel) else SurfaceModel(m, seed) for m in (workpiece, reference)]
    return locate(scan, *surfaces, tolerance_mm=tolerance_mm, seed=seed, up=up, viewpoint=viewpoint,
                  blas_threads=blas_threads).as_dict()


def locate(scan: Cloud, workpiece: SurfaceModel, reference: SurfaceModel, tolerance_mm: float = 0.3,
           seed: int = 0, progress=None, up=None, viewpoint=None, blas_threads: int | None = 1) -> Located:
    """Find the reference and the workpiece in a scene scan; NotFound names what could not be found
    and, where it can tell, why (a model the wrong size for every object, a tolerance below the noise).

    The scan may be in any frame: ``up`` (a direction) and ``viewpoint`` (the scanner's position),
    when known, say which side of the platform the objects stand on; otherwise the data do.
    ``blas_threads``: as in MatchOptions, for the whole search (the platform's planes too)."""
    with pointops.blas_threads(blas_threads):
        return _locate(scan, workpiece, reference, tolerance_mm, seed, progress, up, viewpoint, blas_threads)


def _locate(scan: Cloud, workpiece: SurfaceModel, reference: SurfaceModel, tolerance_mm: float, seed: int, progress,
            up, viewpoint, blas_threads: int | None) -> Located:
    points = scan.points
    valid = np.flatnonzero(np.isfinite(points).all(axis=1))
    if len(valid) < CLUSTERS.min_points:
        raise InputError(f"{scan.name}: only {len(valid)} valid points; a scene scan needs far more")
    on_scan = points[valid]  # the valid points, copied once
    kind = shape_kind(on_scan)
    if kind != "solid":
        raise NotFound(f"{scan.name}: the scan points lie {SHAPE_WORDS[kind]}; a scene scan shows the platform "
                       "and the objects standing on it")
    rng = np.random.default_rng(seed)
    spacing = pointops.median_spacing(on_scan, seed=seed)
    warnings = []
    platform = find_platform(on_scan, spacing, rng, up, viewpoint)
    if platform is None:
        warnings.append(f"{scan.name}: no platform plane found (no plane holds {PLATFORM.min_fraction:.0%} of the "
                        "points with the objects standing on one side of it); every point is treated as an object")
        platform_idx, objects = np.empty(0, dtype=np.int64), valid
        labels = _clusters(points[objects], CLUSTERS.link_spacings * spacing)
    else:
        platform_idx, objects, labels = valid[platform.below], valid[~platform.below], platform.labels
    report = progress or (lambda fraction, message: None)
    surfaces = {"reference": reference, "workpiece": workpiece}
    near_mm = {role: joins_within(role, spacing) for role in ("reference", "workpiece")}
    # Both orders search some clusters alike (the reference's own, when the workpiece is found first):
    # each cluster is searched once per model.
    context = dict(scan=scan, points=points, spacing=spacing, surfaces=surfaces, near_mm=near_mm, platform=platform,
                   searched={}, labels=labels,
                   tolerance_mm=tolerance_mm, options=dict(tolerance_mm=tolerance_mm, seed=seed,
                                                           min_fitness=LOCATE.min_fitness_of_cluster,
                                                           tolerance_gates=False, blas_threads=blas_threads,
                                                           viewpoint=None if viewpoint is None else tuple(viewpoint),
                                                           support=standing_on(platform)))
    # Leaving the pool waits for a search ahead still running: once both orders are searched nothing
    # waits for it, and ``stop`` ends it at its next phase.
    stop = threading.Event()
    with ThreadPoolExecutor(max_workers=1) as ahead:
        if blas_threads == 1:  # a second thread only with BLAS held to one (its own threads would spin)
            _search_ahead(ahead, objects, stop=stop, **context)
        try:
            found = _search_in_both_orders(objects, report, context)
        finally:
            stop.set()
    if isinstance(found, NotFound):
        raise found
    (workpiece_match, workpiece_idx, wp_touching, _), (reference_match, reference_idx, ref_touching, _) = (
        found["workpiece"], found["reference"])
    if ref_touching or wp_touching:  # where they meet, a point goes to the model it lies nearer to
        reference_idx = reference_idx[nearer_own_model(points[reference_idx], (reference, reference_match.matrix),
                                                       (workpiece, workpiece_match.matrix), near_mm["workpiece"])]
        # The reference is rigid and unchanged: clay pressed against it lies off its surface.
        within = max(LOCATE.min_on_surface_mm, LOCATE.on_surface_noises * reference_match.noise_mm)
        reference_idx = reference_idx[_on_surface(points[reference_idx], reference, reference_match.matrix, within)]
        workpiece_idx = workpiece_idx[nearer_own_model(points[workpiece_idx], (workpiece, workpiece_match.matrix),
                                                       (reference, reference_match.matrix), near_mm["reference"])]
        warnings.append(f"{scan.name}: the reference touches another object (the workpiece, clay or a clamp): the "
                        f"scan was split between the placed models; each region is only the points nearer its model")
        left = _unexplained(objects, labels, workpiece_idx, reference_idx)
        if left > LOCATE.unexplained_share * len(reference_idx) and reference_match.status == OK:
            reference_match.status = AMBIGUOUS
            reference_match.reasons.append(Reason(SPLIT_UNEXPLAINED, (
                f"{left} points of the objects that touch lie on neither placed model (more than "
                f"{LOCATE.unexplained_share:.0%} of the reference's {len(reference_idx)}): the models may split them "
                "wrongly (a pose that fits part of the reference); scan the objects apart, or give the regions")))
    return Located(workpiece_idx, reference_idx, platform_idx, workpiece_match, reference_match, warnings, platform,
                   {role: found[role][3] for role in ("workpiece", "reference")}, spacing)


def _search_in_both_orders(objects, report, context: dict):
    """The models found in turn, reference first (see _in_turn), or NotFound."""
    try:
        found = _in_turn(objects, ("reference", "workpiece"), report, **context)
    except NotFound as exc:
        found = exc
    # A reference not found, or not for sure, where objects may touch: the workpiece first, then the
    # reference in what is left of its cluster.
    if isinstance(found, NotFound) or found["reference"][0].status != OK:
        try:
            other = _in_turn(objects, ("workpiece", "reference"), report, **context)
        except NotFound:
            other = None
        if other is not None and (isinstance(found, NotFound) or _rank(other) > _rank(found)):
            found = other
    return found


def _search_ahead(pool: ThreadPoolExecutor, objects, scan, points, surfaces, platform, options, searched: dict, labels,
                  stop: threading.Event, **_) -> None:
    """Start the workpiece's search of its likeliest cluster while the reference is looked for: the
    workpiece is then looked for first in that cluster, unless the reference took it (two objects
    apart, the usual scene: the two searches run at once).  The same search, by the same seed, as the
    one _first_match would make (its result waits in ``searched``); ``stop`` ends it unfinished."""
    likeliest = {role: _candidates(points, objects, labels, surfaces[role])[:1] for role in ("reference", "workpiece")}
    if not likeliest["workpiece"] or (likeliest["reference"]
                                      and np.array_equal(likeliest["reference"][0][0], likeliest["workpiece"][0][0])):
        return
    members, larger = likeliest["workpiece"][0]
    searched[("workpiece", members.tobytes())] = pool.submit(
        _search, scan, points, members, larger, surfaces["workpiece"], options, "workpiece",
        _stands_on(platform, surfaces["workpiece"]), stop=stop)


def _stands_on(platform, surface: SurfaceModel):
    """Whether a pose U of the model stands on the platform (does not sink through it)."""
    return lambda U: not physics.sinks(platform, surface, U)


def _search(scan: Cloud, points, members, larger: bool, surface: SurfaceModel, options: dict, role: str, stands,
            stop=None):
    """The model's search of one candidate cluster: in a cluster larger than the model, no pose
    explains most of it, so searching again with other seeds cannot tell a better pose (see
    match_trusted); the split in _first_match judges the one found.  ``stop`` as in ``match``."""
    return match_trusted(Cloud(points[members], name=f"{role} candidate in {scan.name}"), surface, options, role,
                         stands, attempts=1 if larger else LOCATE.search_attempts, stop=stop, candidate=True)


def _unexplained(objects, labels, *regions) -> int:
    """How many points of the clusters (``labels`` of the ``objects``) the regions lie in belong to none of them."""
    taken = np.isin(objects, np.concatenate(regions))
    involved = np.isin(labels, np.unique(labels[taken]))
    return int(np.count_nonzero(involved & ~taken))


def _rank(found: dict) -> int:
    return sum(match.status == OK for match, *_ in found.values())


def _in_turn(objects, order, report, scan, points, spacing, surfaces, near_mm, platform, tolerance_mm,
             options, searched: dict, labels: np.ndarray) -> dict:
    """{role: (match, region indices, touching, indices the match was made on)} finding the models in
    ``order``, each in what the ones before left: a cluster the model explains only in part is split
    (see _on_model).  A pose that sinks the model through the ``platform`` locates nothing (objects
    stand on it).  ``labels``: the clusters of the objects."""
    found, left = {}, objects
    for step, role in enumerate(order):
        surface = surfaces[role]
        report(0.1 + 0.2 * step, f"looking for the {role} {surface.name}")
        stands = _stands_on(platform, surface)
        result, rejected, sunk, matched = _first_match(scan, points, left, labels, surface, options, role,
                                                       near_mm[role], stands, searched)
        if result is None:
            what = f"reference object {surface.name}" if role == "reference" else f"workpiece {surface.name}"
            raise NotFound(f"{what}: not found in {scan.name}: "
                           + _why_not_found(points, left, labels, surface, rejected, tolerance_mm, role, sunk))
        on = _on_model(points[left], labels, surface, result.matrix, near_mm[role])
        # Clay added since the model was made is part of the workpiece's clusters, so it joins the region.
        region = on.clusters if role == "workpiece" and not on.touching else on.region
        found[role] = (result, left[region], on.touching, matched)
        left = left[~region]
        # Whole clusters taken leave the others as they were; a split one may fall apart.
        labels = _renumbered(labels[~region]) if not on.touching and len(left) \
            else _clusters(points[left], CLUSTERS.link_spacings * spacing)
    return found


def standing_on(platform: "Platform | None") -> tuple | None:
    """A match's ``support`` option for the objects standing on ``platform``: a point on it, its normal
    up and its band (the plane's points lie within it)."""
    if platform is None:
        return None
    return tuple(float(v) for v in platform.centre), tuple(float(v) for v in platform.up), float(platform.band)


def joins_within(role: str, spacing: float) -> float:
    """How near its placed model (mm) a scan point joins an object's region, for a scan of this spacing:
    the workpiece's farther (clay added since its model was made lies a little off it)."""
    return max(2.0, 3 * spacing) if role == "reference" else max(3.0, 5 * spacing)


def refit(cloud: Cloud, surface: SurfaceModel, found: MatchResult, options: dict) -> MatchResult:
    """The match on a final region, started from the pose found while locating it; its candidates
    and ambiguity come from the global search that found it.  When the refit's verdict moved to
    another pose, the search's doubts were about the first one, and the one reason kept says so: the
    region's points were picked with the first pose, so a search of them alone cannot settle it (it
    finds the pose that picked them), and the physical checks, which weigh the first pose's rivals,
    do not clear it as a tie."""
    again = match(cloud, surface, init=found.matrix, **options)
    if again.status == OK and found.status == AMBIGUOUS:
        reasons = found.reasons
        if not _same_pose(again.matrix, found.matrix, surface):
            turned_deg = frames.rotation_between_deg(again.matrix, found.matrix)
            shift_mm = float(np.linalg.norm(frames.apply(again.matrix, surface.centre)
                                            - frames.apply(found.matrix, surface.centre)))
            reasons = [Reason(SEARCH_DOUBT, (
                f"this pose was refined from a first pose {turned_deg:.0f} deg and {shift_mm:.0f} mm away whose "
                f"search was in doubt [{'; '.join(map(str, found.reasons))}], and the points it was fitted to were "
                "picked with that first pose, so the doubt stands: check the pose in the 3D view, or scan "
                "the objects apart or give the regions"))]
        again.status, again.reasons, again.candidates, again.ties = AMBIGUOUS, reasons, found.candidates, found.ties
    again.timings_s = {**{f"locate {k}": v for k, v in found.timings_s.items()}, **again.timings_s}
    again.time_s += found.time_s
    return again


def match_trusted(cloud: Cloud, surface: SurfaceModel, options: dict, role: str, stands=None,
                  attempts: int = LOCATE.search_attempts, stop=None, candidate: bool = False) -> MatchResult:
    """Match, and when the pose does not explain the region, search again with other seeds and keep
    the pose that explains most of it: a global search can settle on a wrong pose of a partly seen,
    nearly symmetric object (an L-block flipped, or slid along an arm) that still fits its inliers.
    ``stands(U)``, when given, says whether a pose is physically possible; a possible pose beats any
    impossible one.  At most ``attempts`` searches.  A ``candidate`` cluster (locate's: it may hold
    another object) whose searches so far found no pose fitting its points within their noise (a
    misfit) is searched no more, neither by other seeds nor by the match's own second search with
    more hypotheses (MatchOptions.search_again): searched again, such a cluster never came back with a
    pose that fits (docs/tuning.md).  A region the user picked holds the object: its searches go on.
    ``stop`` as in ``match``."""
    def rank(result):
        possible = result.matrix is not None and (stands is None or stands(result.matrix))
        return result.status != FAILED, possible, result.fitness

    best, search_again = None, options.get("search_again", True) and not candidate
    for attempt in range(attempts):
        result = match(cloud, surface, stop=stop,
                       **{**options, "seed": options.get("seed", 0) + attempt, "search_again": search_again})
        # Back to a pose found before, or to one the search before listed beside its best (a tie two
        # searches settle either way).
        again = best is not None and any(_same_pose(result.matrix, U, surface)
                                         for U in [best.matrix] + [c.matrix for c in best.candidates[1:]])
        if best is None or rank(result) > rank(best):
            best = result
        if best.ok and best.fitness >= LOCATE.good_fitness[role] and rank(best)[1]:
            break
        if again:  # another search came back to the same pose: the search is not what falls short
            break
        if candidate and best.status == FAILED and MISFIT in codes(best.reasons):
            break
        too_small = result.coverage < options.get("min_coverage", MatchOptions.min_coverage)
        if too_small and result.fitness >= LOCATE.good_fitness[role]:
            break  # the pose puts the cloud on the model but it covers too little of it: too small to be it
    return best


def _same_pose(a: np.ndarray | None, b: np.ndarray | None, surface: SurfaceModel) -> bool:
    """Whether two poses (U, None where a match found none) place the model alike (within LOCATE.same_pose_deg
    and LOCATE.same_pose_diagonals)."""
    if a is None or b is None:
        return False
    return (frames.rotation_between_deg(a, b) < LOCATE.same_pose_deg
            and np.linalg.norm(a[:3, 3] - b[:3, 3]) < LOCATE.same_pose_diagonals * surface.diagonal)


@dataclass
class Platform:
    """The plane the objects stand on: a point on it, its unit normal pointing up (to the side the
    objects stand on), the mask of the points on or below it, and how "up" was told."""

    centre: np.ndarray
    up: np.ndarray
    below: np.ndarray
    band: float
    source: str
    # Clusters (see _clusters) of the points off it, in their order in the cloud it was found in: its
    # size test splits them, and the regions start from them.
    labels: np.ndarray | None = None

    def height(self, points: np.ndarray) -> np.ndarray:
        return (points - self.centre) @ self.up


def find_platform(points: np.ndarray, spacing: float, rng: np.random.Generator, up=None,
                  viewpoint=None) -> Platform | None:
    """The largest plane the objects stand on, if there is one (see ``_up_side``), in any frame.

    ``up`` (a direction the user gives) picks the largest plane square to it within PLATFORM.max_up_deg;
    otherwise the plane holding the most points.  Which side is up: ``up``, else the side the
    ``viewpoint`` (the scanner's position, given or read from the file) is on, else the side the
    objects stand on (_up_side)."""
    sample = points[rng.choice(len(points), min(len(points), PLATFORM.sample_points), replace=False)]
    band = PLATFORM.band_mm + 2 * spacing
    triples = sample[rng.integers(0, len(sample), (PLATFORM.ransac_trials, 3))]
    normals = np.cross(triples[:, 1] - triples[:, 0], triples[:, 2] - triples[:, 0])
    length = np.linalg.norm(normals, axis=1)
    keep = length > 1e-9
    if up is not None:
        up = np.asarray(up, dtype=float) / np.linalg.norm(up)
        keep &= np.abs(normals @ up) > np.cos(np.radians(PLATFORM.max_up_deg)) * np.maximum(length, 1e-12)
    if not keep.any():  # every sampled triple is collinear (or none is square to ``up``): no plane at all
        return None
    normals, triples = normals[keep] / length[keep, None], triples[keep]
    offsets = np.einsum("ij,ij->i", normals, triples[:, 0])
    near = np.empty((len(sample), len(normals)), dtype=bool)  # (sample, plane)
    for start in range(0, len(sample), PLATFORM.chunk):  # a chunk at a time: it stays in the cache
        distance = sample[start:start + PLATFORM.chunk] @ normals.T
        distance -= offsets
        near[start:start + PLATFORM.chunk] = np.abs(distance, out=distance) < band
    remaining = np.ones(len(sample), dtype=bool)
    for _ in range(PLATFORM.candidates):  # the largest plane, then the largest of the points left, ...
        counts = near[remaining].view(np.uint8).sum(axis=0, dtype=np.int64)  # bytes add faster than booleans
        best = int(np.argmax(counts))
        if counts[best] < PLATFORM.min_fraction * len(sample):
            return None
        platform = _platform_on(points, sample[near[:, best]], band, spacing, up, viewpoint)
        if platform is not None:
            return platform
        remaining &= ~near[:, best]
    return None


def _platform_on(points, inliers, band: float, spacing: float, up, viewpoint) -> Platform | None:
    """The platform on the plane fitted to ``inliers``, up where ``up``, the ``viewpoint`` or the
    objects say (see find_platform); None when the plane carries no objects on that side (see
    _up_side), or is no larger than what stands on it (see _larger_than_footprint), however its up
    side was told."""
    centre = inliers.mean(axis=0)
    normal = np.linalg.svd(inliers - centre, full_matrices=False)[2][2]
    outline = _outline(inliers, centre, normal)
    if outline is None:
        return None
    standing = _up_side(points, outline, centre, normal, band, spacing)
    if up is not None:
        side, source = float(np.sign(normal @ up)), "the given up direction"
    elif viewpoint is not None:
        side, source = float(np.sign(normal @ (np.asarray(viewpoint, float) - centre))), "the scanner's position"
    else:
        side, source = standing, "the objects standing on it"
    # A told side names which way is up, not which plane is the platform: the objects must stand on it
    # on that side (a horizontal face of an object, or a scanner above it, tells nothing of that).
    if side == 0 or standing != side:
        return None
    normal = side * normal
    height = (points - centre) @ normal
    below = height < band
    labels = _clusters(points[~below], CLUSTERS.link_spacings * spacing)
    if not _larger_than_footprint(points[~below], labels, outline, centre):
        return None
    return Platform(centre, normal, below, band, source, labels)


def _outline(inliers, centre, normal):
    """(in-plane axes, convex hull of the plane's points in them), or None when they span no area."""
    from scipy.spatial import ConvexHull, QhullError

    u = np.cross(normal, [1.0, 0.0, 0.0] if abs(normal[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    axes = np.vstack([u, np.cross(normal, u)])
    try:
        return axes, ConvexHull((inliers - centre) @ axes.T)
    except QhullError:
        return None


def _up_side(points, outline, centre, normal, band: float, spacing: float) -> float:
    """+1 or -1: the side of the plane the objects stand on, or 0 when the plane carries none.

    Off the plane, over the plane's own footprint (the convex hull of its points, less a margin, so
    that the platform's side faces do not count), are the objects standing on it: seen from the
    scanner's side, the plane hides whatever lies under it.  The plane is a platform only when those
    points lie on one side (at least PLATFORM.up_side_share of them, and PLATFORM.all_on_one_side of all the points off
    it but those at its outline, where its own side faces show from a low view) and it holds up most
    of the objects (at least PLATFORM.supported_share of the points off the plane lie over its hull): the face
    of an object holds up nothing but itself, and other objects stand below it."""
    axes, hull = outline
    height = (points - centre) @ normal
    off = np.abs(height) > band
    flat = (points[off] - centre) @ axes.T
    # <= 0 inside every edge; a block of points at a time (PLATFORM.hull_chunk)
    reach = np.concatenate([(flat[start:start + PLATFORM.hull_chunk] @ hull.equations[:, :2].T
                             + hull.equations[:, 2]).max(axis=1)
                            for start in range(0, len(flat), PLATFORM.hull_chunk)] or [np.zeros(0)])
    margin = max(PLATFORM.hull_margin_mm, PLATFORM.hull_margin_spacings * spacing)
    over, inside = reach <= 0, reach <= -margin
    # The platform's own side faces (seen from a low view) lie under its outline: they take no side.
    rim = np.abs(reach) < margin
    above = int(np.count_nonzero(height[off][inside] > 0))
    below = int(np.count_nonzero(inside)) - above
    side = 1.0 if above > below else -1.0
    if max(above, below) < CLUSTERS.min_points or over.mean() < PLATFORM.supported_share:
        return 0.0
    if (max(above, below) < PLATFORM.up_side_share * (above + below)
            or np.mean(side * height[off][~rim] > 0) < PLATFORM.all_on_one_side):
        return 0.0
    return side


def _larger_than_footprint(above, labels, outline, centre) -> bool:
    """Whether the plane is a platform by its size: its hull's area is at least PLATFORM.footprint_ratio times
    that of the objects standing on it (the hull of the points ``above`` it, projected on the
    plane, in clusters (``labels``) of CLUSTERS.min_points or more, so that stray points do not count).  A table
    holds what stands on it and more; a face of one object, taken for the platform in a scene
    without one, is smaller than the objects beside it."""
    from scipy.spatial import ConvexHull, QhullError

    axes, hull = outline
    counts = np.bincount(labels) if len(labels) else np.zeros(0, np.int64)
    objects = above[counts[labels] >= CLUSTERS.min_points] if len(labels) else above
    if len(objects) < CLUSTERS.min_points:
        return False
    try:
        footprint = ConvexHull((objects - centre) @ axes.T)
    except QhullError:  # the objects project on a line: they have no footprint to outgrow
        return True
    return hull.volume >= PLATFORM.footprint_ratio * footprint.volume  # a 2-d hull's volume is its area


def _clusters(points: np.ndarray, link: float) -> np.ndarray:
    """Connected components of points closer than ``link`` (computed on a link/2 voxel grid)."""
    if len(points) == 0:
        return np.empty(0, dtype=np.int64)
    voxel = link / 2
    keys = pointops.voxel_keys(points, voxel)
    cells, inverse = np.unique(keys, return_inverse=True)
    inverse = inverse.reshape(-1)
    counts = np.bincount(inverse, minlength=len(cells))
    centres = np.stack([np.bincount(inverse, points[:, k], len(cells)) for k in range(3)], axis=1) / counts[:, None]
    # An unbalanced tree builds in half the time and finds the same pairs (they only join components).
    pairs = cKDTree(centres, balanced_tree=False, compact_nodes=False).query_pairs(link, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(cells), len(cells)))
    _, cell_labels = connected_components(graph, directed=False)
    return cell_labels[inverse]


def in_clusters(points: np.ndarray, spacing: float) -> np.ndarray:
    """Which points belong to a cluster of at least CLUSTERS.min_points at the link objects are split by
    (CLUSTERS.link_spacings of the scan's ``spacing``): surfaces, not stray points nor mixed pixels strung
    sparsely along the rays past an edge."""
    labels = _clusters(points, CLUSTERS.link_spacings * spacing)
    return np.bincount(labels)[labels] >= CLUSTERS.min_points if len(labels) else np.zeros(0, bool)


def _present(labels: np.ndarray) -> np.ndarray:
    """The cluster labels that occur, in order (np.unique's answer, counted rather than sorted)."""
    return np.flatnonzero(np.bincount(labels)) if len(labels) else np.empty(0, dtype=np.int64)


def _renumbered(labels: np.ndarray) -> np.ndarray:
    """The labels numbered 0, 1, ... in their order, as np.unique's inverse numbers them."""
    present = _present(labels)
    number = np.zeros(labels.max() + 1, dtype=np.int64)
    number[present] = np.arange(len(present))
    return number[labels]


def _candidates(points, idx, labels, surface: SurfaceModel) -> list[tuple[np.ndarray, bool]]:
    """Clusters that could hold the model, each with whether it is larger than the model: those of
    its size, most alike first, then the larger ones (objects that touch, or clay joining them, make
    one cluster), smallest first."""
    alike, larger = [], []
    for members, diagonal in _clusters_of_size(points, idx, labels):
        ratio = diagonal / surface.diagonal
        if CLUSTERS.size_ratio_range[0] <= ratio <= CLUSTERS.size_ratio_range[1]:
            alike.append((abs(np.log(ratio)), -len(members), members))
        elif ratio > CLUSTERS.size_ratio_range[1]:
            larger.append((ratio, -len(members), members))
    return ([(members, False) for *_, members in sorted(alike, key=lambda item: item[:2])]
            + [(members, True) for *_, members in sorted(larger, key=lambda item: item[:2])])


def _clusters_of_size(points, idx, labels) -> list[tuple[np.ndarray, float]]:
    """(members, bounding-box diagonal) of each cluster of CLUSTERS.min_points or more, in label order,
    its members in their order in ``idx``: one sort for all of them, not one pass over every point per cluster."""
    if len(idx) == 0:
        return []
    order = np.argsort(labels, kind="stable")
    starts = np.flatnonzero(np.r_[True, np.diff(labels[order]) != 0])
    ends = np.r_[starts[1:], len(order)]
    large = ends - starts >= CLUSTERS.min_points
    if not large.any():
        return []
    sorted_points = points[idx[order]]
    low, high = np.minimum.reduceat(sorted_points, starts), np.maximum.reduceat(sorted_points, starts)
    return [(idx[order[start:end]], float(np.linalg.norm(high[k] - low[k])))
            for k, (start, end) in enumerate(zip(starts, ends)) if large[k]]


def _first_match(scan: Cloud, points, idx, labels, surface: SurfaceModel, options: dict, role: str, near_mm: float,
                 stands, searched: dict):
    """Match the model against its candidate clusters in turn; the first trustworthy match wins: one
    whose pose ``stands(U)`` (a pose through the platform fits one arm of a touching pair, not the object).

    A cluster the placed model explains only in part (it holds more: objects touching) is split: the
    match is judged again on the points near the placed model alone.  Returns (the match or None, the
    best match rejected for its share of points within the tolerance or None, whether a pose was
    rejected for sinking through the platform, the scan indices the match was made on): a rejected
    match that explains its cluster says the tolerance is below the noise.  ``searched`` keeps each cluster's search for the model (by role and
    members), so that it is not repeated; callers change the matches they get, so each gets a copy."""
    fallback, rejected, sunk = (None, None), None, False
    for members, larger in _candidates(points, idx, labels, surface):
        matched = members
        key = (role, members.tobytes())
        if key not in searched:
            searched[key] = _search(scan, points, members, larger, surface, options, role, stands)
        result = searched[key]
        result = copy.deepcopy(result.result() if isinstance(result, Future) else result)
        if result.matrix is not None and not stands(result.matrix):
            sunk = True
            continue
        if result.matrix is not None and result.fitness < LOCATE.min_fitness[role]:
            near = near_points(points[members], surface, result.matrix, near_mm)
            if near.sum() < CLUSTERS.min_points:
                continue
            matched = members[near]
            result = refit(Cloud(points[matched], name=f"{role} part of a candidate in {scan.name}"), surface,
                           result, {**options, "min_fitness": MatchOptions.min_fitness})
        noisy = result.noise_mm > result.tolerance_mm  # failed only because the tolerance is below the noise
        if (result.within_tolerance_pct < LOCATE.min_within_tolerance_pct[role]
                or result.fitness < LOCATE.min_fitness[role] or noisy):
            if (result.status != FAILED or noisy) and (rejected is None or result.fitness > rejected.fitness):
                rejected = result
            continue
        if result.ok:
            return result, rejected, sunk, matched
        if result.status != FAILED and result.fitness >= LOCATE.good_fitness[role]:
            return result, rejected, sunk, matched  # the object: its doubt is which pose, not which cluster
        if result.status != FAILED and fallback[0] is None:
            fallback = result, matched
    return fallback[0], rejected, sunk, fallback[1]


def _why_not_found(points, idx, labels, surface: SurfaceModel, rejected, tolerance_mm: float, role: str,
                   sunk: bool) -> str:
    """Why no object matched the model, as far as the objects' sizes, the best rejected match and
    poses through the platform tell."""
    if rejected is not None and rejected.noise_mm > tolerance_mm:
        said = [str(r) for r in rejected.reasons if r.code == NOISE_ABOVE_TOLERANCE]
        return f"the tolerance {tolerance_mm:g} mm is below the scan's noise: " + (said[0] if said else
                                                                                  f"{rejected.noise_mm:.2f} mm")
    if rejected is not None and rejected.fitness >= LOCATE.min_fitness[role]:
        return (f"the best object fits the model with RMS {rejected.rms_mm:.3f} mm, but only "
                f"{rejected.within_tolerance_pct:.0f}% of its points lie within the tolerance {tolerance_mm:g} mm "
                f"(at least {LOCATE.min_within_tolerance_pct[role]:.0f}% needed): the tolerance seems to be below the "
                "scan's noise; raise it")
    sizes = sorted((diagonal for _, diagonal in _clusters_of_size(points, idx, labels)), reverse=True)
    if not sizes:
        return "no object is left standing on the platform; is it in view?"
    if not any(CLUSTERS.size_ratio_range[0] <= size / surface.diagonal <= CLUSTERS.size_ratio_range[1]
               for size in sizes):
        shown = ", ".join(f"{size:.4g}" for size in sizes[:5])
        return (f"no object on the platform is the size of the model ({surface.diagonal:.4g} mm across; the objects "
                f"are {shown} mm across): is the model in the unit it was read in?")
    if sunk:
        return ("the only poses that fit an object put the model through the platform; is it in view, and is its "
                "model the right one?")
    return "no object of its size matches the model; is it in view, and is its model the right one?"


@dataclass
class _OnModel:
    clusters: np.ndarray  # points of the clusters that lie mostly on the placed model
    region: np.ndarray  # those clusters, or only their points near the model when they hold other things too
    touching: bool


def _on_model(points: np.ndarray, labels: np.ndarray, surface: SurfaceModel, U: np.ndarray, distance: float) -> _OnModel:
    """The object a placed model explains, as whole clusters (so a region's fitness stays meaningful);
    where its cluster holds more than the model explains (objects touching), only the points near it."""
    near = near_points(points, surface, U, distance)
    counts = np.bincount(labels, minlength=labels.max() + 1)
    on = np.bincount(labels, weights=near, minlength=len(counts))
    share = on / np.maximum(counts, 1)
    clusters = share[labels] >= CLUSTERS.share
    held = on[labels] >= CLUSTERS.min_points  # clusters the model explains a real part of
    touching = bool((held & (share[labels] < CLUSTERS.touching_share)).any())
    return _OnModel(clusters, held & near if touching else clusters, touching)


def nearer_own_model(points: np.ndarray, own, other, distance: float) -> np.ndarray:
    """Which points lie nearer to the ``own`` placed model than to the ``other`` ((SurfaceModel, U) each);
    points beyond ``distance`` of the other count as nearer to their own."""
    d_own = own[0].nearest(frames.apply(frames.invert(own[1]), points), np.inf)[0]
    d_other = other[0].nearest(frames.apply(frames.invert(other[1]), points), distance)[0]
    return d_own < d_other


def _on_surface(points: np.ndarray, surface: SurfaceModel, U: np.ndarray, within: float) -> np.ndarray:
    """Which points lie within ``within`` mm of the placed model's surface (point to plane)."""
    moved = frames.apply(frames.invert(U), points)
    _, idx, found = surface.nearest(moved, 2 * within + 2 * surface.spacing)
    return found & (np.abs(surface.plane_residuals(moved, idx)) <= within)


def near_points(points: np.ndarray, surface: SurfaceModel, U: np.ndarray, distance: float) -> np.ndarray:
    """Which scan points lie within ``distance`` of the model placed by U."""
    moved = frames.apply(frames.invert(U), points)
    # Only points within the model's box (and ``distance`` around it) can be near it: other objects are not.
    box = (moved >= surface.points.min(axis=0) - distance).all(axis=1) & (
        moved <= surface.points.max(axis=0) + distance).all(axis=1)
    found = np.zeros(len(points), dtype=bool)
    found[box] = _within(surface, moved[box], distance)
    return found


def _within(surface: SurfaceModel, points: np.ndarray, distance: float) -> np.ndarray:
    """Which points (model frame) lie within ``distance`` of a model sample, as the KD-tree says, but
    asking it only about the few the cell grid leaves open: a point within ``distance`` of its cell's
    nearest sample is near; one further from it than that plus the cell's diagonal is not (the
    cell's sample is at most a diagonal further than the point's own nearest)."""
    level = max(0, int(np.ceil(np.log2(distance / (GATE_CELLS * surface.spacing)))))
    grid = surface.grid_level(level)
    idx = grid.lookup(points)
    d = np.where(idx >= 0, pointops.lengths(points - surface.points[np.maximum(idx, 0)]), np.inf)
    near = d <= distance
    open_ = ~near & (d <= distance + np.sqrt(3) * grid.cell)
    if grid.bound < distance + np.sqrt(3) * grid.cell:  # an empty cell only says no sample within its bound
        open_ |= idx < 0
    near[open_] = surface.nearest(points[open_], distance)[2]
    return near
