"""Automatic scan regions: remove the platform, split what stands on it, find the reference and the workpiece.

The reference object and the platform are a constant scene, so no operator has to pick regions:
the largest plane seen is the platform; the points above it fall apart into objects; the reference
model is matched against the objects most like it in size; the workpiece is what remains and
matches its model.  The matches found on the way are kept, so calibration does not repeat them.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from . import frames, pointops
from .errors import InputError, NotFound
from .geometry import Cloud, shape_kind
from .match import match
from .result import FAILED, MatchResult
from .surface import SurfaceModel

# The platform must hold at least this fraction of the scan to count as one.
MIN_PLATFORM_FRACTION = 0.15
PLANE_RANSAC_TRIALS = 300
PLANE_SAMPLE_POINTS = 5000
# Points this close to the platform plane (mm, plus a few scan spacings) are platform.
PLATFORM_BAND_MM = 1.0
# Objects are split where the gap between points exceeds this many scan spacings.
LINK_SPACINGS = 4.0
# A cluster is a candidate for a model when its size is within these ratios of the model diagonal.
SIZE_RATIO_RANGE = (0.15, 1.5)
MIN_CLUSTER_POINTS = 100
# A cluster belongs to an object when this fraction of it lies near the placed model (lumps of clay
# added later are connected to the workpiece and come along).  Below TOUCHING_SHARE of the object's
# clusters near its model, it touches something else and only its near points are kept.
CLUSTER_SHARE = 0.5
TOUCHING_SHARE = 0.9
# A match only locates an object when most matched points lie within the tolerance and most of the
# candidate is explained: the reference is rigid and unchanged, the workpiece may have had clay added
# or carved.  A wrong model placed "as well as it goes" scores far lower (measured: 10-30 % within
# tolerance for an ellipsoid or the L-block on a car; fitness 0.36-0.86 for flipped L-block poses).
MIN_WITHIN_TOLERANCE_PCT = {"reference": 80.0, "workpiece": 50.0}
MIN_FITNESS = {"reference": 0.8, "workpiece": 0.5}
# Global searches tried before a pose that explains less than GOOD_FITNESS of its region is accepted.
SEARCH_ATTEMPTS = 3
GOOD_FITNESS = {"reference": 0.95, "workpiece": 0.9}


@dataclass
class Located:
    """Regions as scan indices, and the matches that found them."""

    workpiece: np.ndarray
    reference: np.ndarray
    platform: np.ndarray
    workpiece_match: MatchResult
    reference_match: MatchResult
    warnings: list

    def as_dict(self) -> dict:
        return {"workpiece": self.workpiece, "reference": self.reference, "platform": self.platform,
                "source": "auto", "warnings": list(self.warnings)}


def find_regions(scan: Cloud, workpiece, reference, tolerance_mm: float = 0.3, seed: int = 0,
                 blas_threads: int | None = 1) -> dict:
    """The workpiece, reference and platform regions of ``scan`` as index arrays (see ``locate``)."""
    surfaces = [m if isinstance(m, SurfaceModel) else SurfaceModel(m, seed) for m in (workpiece, reference)]
    return locate(scan, *surfaces, tolerance_mm=tolerance_mm, seed=seed, blas_threads=blas_threads).as_dict()


def locate(scan: Cloud, workpiece: SurfaceModel, reference: SurfaceModel, tolerance_mm: float = 0.3,
           seed: int = 0, progress=None, blas_threads: int | None = 1) -> Located:
    """Find the reference and the workpiece in a scene scan; NotFound names what could not be found
    and, where it can tell, why (a model the wrong size for every object, a tolerance below the noise).
    ``blas_threads``: as in MatchOptions."""
    points = scan.points
    valid = np.flatnonzero(np.isfinite(points).all(axis=1))
    if len(valid) < MIN_CLUSTER_POINTS:
        raise InputError(f"{scan.name}: only {len(valid)} valid points; a scene scan needs far more")
    kind = shape_kind(points[valid])
    if kind != "solid":
        raise NotFound(f"{scan.name}: the scan points are {kind}; a scene scan shows the platform and the "
                       "objects standing on it")
    rng = np.random.default_rng(seed)
    spacing = pointops.median_spacing(points[valid], seed=seed)
    warnings = []
    platform = _platform(points[valid], spacing, rng)
    if platform is None:
        warnings.append(f"{scan.name}: no platform plane found (no plane holds {MIN_PLATFORM_FRACTION:.0%} of the "
                        "points); every point is treated as an object")
        platform_idx, objects = np.empty(0, dtype=np.int64), valid
    else:
        platform_idx, objects = valid[platform], valid[~platform]
    labels = _clusters(points[objects], LINK_SPACINGS * spacing)
    report = progress or (lambda fraction, message: None)

    report(0.1, f"looking for the reference {reference.name}")
    options = dict(tolerance_mm=tolerance_mm, seed=seed, min_fitness=0.3, blas_threads=blas_threads)
    reference_match, rejected = _first_match(scan, points, objects, labels, reference, options, "reference")
    if reference_match is None:
        raise NotFound(f"reference object {reference.name}: not found in {scan.name}: "
                       + _why_not_found(points, objects, labels, reference, rejected, tolerance_mm, "reference"))
    on_reference = _on_model(points[objects], labels, reference, reference_match.matrix, max(2.0, 3 * spacing))
    if on_reference.touching:
        warnings.append(f"{scan.name}: the reference touches another object; its region is only the points "
                        "near its model")
    reference_idx = objects[on_reference.region]

    report(0.3, f"looking for the workpiece {workpiece.name}")
    rest, rest_labels = objects[~on_reference.region], labels[~on_reference.region]
    workpiece_match, rejected = _first_match(scan, points, rest, rest_labels, workpiece, options, "workpiece")
    if workpiece_match is None:
        raise NotFound(f"workpiece {workpiece.name}: not found in {scan.name}: "
                       + _why_not_found(points, rest, rest_labels, workpiece, rejected, tolerance_mm, "workpiece"))
    # Clay added since the model was made is part of the workpiece's clusters, so it joins the region.
    on_workpiece = _on_model(points[rest], rest_labels, workpiece, workpiece_match.matrix, max(3.0, 5 * spacing))
    workpiece_idx = rest[on_workpiece.clusters]
    return Located(workpiece_idx, reference_idx, platform_idx, workpiece_match, reference_match, warnings)


def match_trusted(cloud: Cloud, surface: SurfaceModel, options: dict, role: str) -> MatchResult:
    """Match, and when the pose does not explain the region, search again with other seeds and keep
    the pose that explains most of it: a global search can settle on a wrong pose of a partly seen,
    nearly symmetric object (an L-block flipped, or slid along an arm) that still fits its inliers."""
    best = None
    for attempt in range(SEARCH_ATTEMPTS):
        result = match(cloud, surface, **{**options, "seed": options.get("seed", 0) + attempt})
        if best is None or (result.status != FAILED, result.fitness) > (best.status != FAILED, best.fitness):
            best = result
        if best.ok and best.fitness >= GOOD_FITNESS[role]:
            break
    return best


def _platform(points: np.ndarray, spacing: float, rng: np.random.Generator) -> np.ndarray | None:
    """Mask of the points on or below the largest plane, if it is large enough to be the platform.

    "Below" is the side away from the scanner (the origin of S): nothing seen there can be an
    object standing on the platform."""
    sample = points[rng.choice(len(points), min(len(points), PLANE_SAMPLE_POINTS), replace=False)]
    band = PLATFORM_BAND_MM + 2 * spacing
    triples = sample[rng.integers(0, len(sample), (PLANE_RANSAC_TRIALS, 3))]
    normals = np.cross(triples[:, 1] - triples[:, 0], triples[:, 2] - triples[:, 0])
    length = np.linalg.norm(normals, axis=1)
    keep = length > 1e-9
    if not keep.any():  # every sampled triple is collinear: there is no plane at all
        return None
    normals, triples = normals[keep] / length[keep, None], triples[keep]
    offsets = np.einsum("ij,ij->i", normals, triples[:, 0])
    counts = (np.abs(sample @ normals.T - offsets) < band).sum(axis=0)
    best = int(np.argmax(counts))
    if counts[best] < MIN_PLATFORM_FRACTION * len(sample):
        return None
    inliers = sample[np.abs(sample @ normals[best] - offsets[best]) < band]
    centre = inliers.mean(axis=0)
    normal = np.linalg.svd(inliers - centre, full_matrices=False)[2][2]
    if normal @ (-centre) < 0:  # make the normal point towards the scanner
        normal = -normal
    height = (points - centre) @ normal
    return height < band


def _clusters(points: np.ndarray, link: float) -> np.ndarray:
    """Connected components of points closer than ``link`` (computed on a link/2 voxel grid)."""
    if len(points) == 0:
        return np.empty(0, dtype=np.int64)
    voxel = link / 2
    keys = pointops.voxel_keys(points, voxel)
    cells, inverse = np.unique(keys, return_inverse=True)
    centres = np.zeros((len(cells), 3))
    np.add.at(centres, inverse, points)
    centres /= np.bincount(inverse)[:, None]
    pairs = cKDTree(centres).query_pairs(link, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(cells), len(cells)))
    _, cell_labels = connected_components(graph, directed=False)
    return cell_labels[inverse]


def _candidates(points, idx, labels, surface: SurfaceModel) -> list[np.ndarray]:
    """Clusters that could be the model by size, most alike first."""
    if len(idx) == 0:
        return []
    out = []
    for label in np.unique(labels):
        members = idx[labels == label]
        if len(members) < MIN_CLUSTER_POINTS:
            continue
        ratio = Cloud(points[members]).diagonal() / surface.diagonal
        if SIZE_RATIO_RANGE[0] <= ratio <= SIZE_RATIO_RANGE[1]:
            out.append((abs(np.log(ratio)), -len(members), members))
    return [members for *_, members in sorted(out, key=lambda item: item[:2])]


def _first_match(scan: Cloud, points, idx, labels, surface: SurfaceModel, options: dict, role: str):
    """Match the model against its candidate clusters in turn; the first trustworthy match wins.

    Returns (the match or None, the best match rejected for its share of points within the tolerance
    or None): a rejected match that explains its cluster says the tolerance is below the noise."""
    fallback, rejected = None, None
    for members in _candidates(points, idx, labels, surface):
        result = match_trusted(Cloud(points[members], name=f"{role} candidate in {scan.name}"), surface, options, role)
        noisy = result.noise_mm > result.tolerance_mm  # failed only because the tolerance is below the noise
        if (result.within_tolerance_pct < MIN_WITHIN_TOLERANCE_PCT[role] or result.fitness < MIN_FITNESS[role]
                or noisy):
            if (result.status != FAILED or noisy) and (rejected is None or result.fitness > rejected.fitness):
                rejected = result
            continue
        if result.ok:
            return result, rejected
        if result.status != FAILED and fallback is None:
            fallback = result
    return fallback, rejected


def _why_not_found(points, idx, labels, surface: SurfaceModel, rejected, tolerance_mm: float, role: str) -> str:
    """Why no object matched the model, as far as the objects' sizes and the best rejected match tell."""
    if rejected is not None and rejected.noise_mm > tolerance_mm:
        said = [r for r in rejected.reasons if "own noise" in r]
        return f"the tolerance {tolerance_mm:g} mm is below the scan's noise: " + (said[0] if said else
                                                                                  f"{rejected.noise_mm:.2f} mm")
    if rejected is not None and rejected.fitness >= MIN_FITNESS[role]:
        return (f"the best object fits the model with RMS {rejected.rms_mm:.3f} mm, but only "
                f"{rejected.within_tolerance_pct:.0f}% of its points lie within the tolerance {tolerance_mm:g} mm "
                f"(at least {MIN_WITHIN_TOLERANCE_PCT[role]:.0f}% needed): the tolerance seems to be below the "
                "scan's noise; raise it")
    sizes = sorted((Cloud(points[idx[labels == label]]).diagonal() for label in np.unique(labels)
                    if np.sum(labels == label) >= MIN_CLUSTER_POINTS), reverse=True) if len(idx) else []
    if not sizes:
        return "no object is left standing on the platform; is it in view?"
    if not any(SIZE_RATIO_RANGE[0] <= size / surface.diagonal <= SIZE_RATIO_RANGE[1] for size in sizes):
        shown = ", ".join(f"{size:.4g}" for size in sizes[:5])
        return (f"no object on the platform is the size of the model ({surface.diagonal:.4g} mm across; the objects "
                f"are {shown} mm across): is the model in the unit it was read in?")
    return "no object of its size matches the model; is it in view, and is its model the right one?"


@dataclass
class _OnModel:
    clusters: np.ndarray  # points of the clusters that lie mostly on the placed model
    region: np.ndarray  # those clusters, or only their points near the model when they hold other things too
    touching: bool


def _on_model(points: np.ndarray, labels: np.ndarray, surface: SurfaceModel, U: np.ndarray, distance: float) -> _OnModel:
    """The object a placed model explains, as whole clusters (so a region's fitness stays meaningful)."""
    near = _near(points, surface, U, distance)
    counts = np.bincount(labels, minlength=labels.max() + 1)
    share = np.bincount(labels, weights=near, minlength=len(counts)) / np.maximum(counts, 1)
    clusters = share[labels] >= CLUSTER_SHARE
    touching = clusters.any() and near[clusters].mean() < TOUCHING_SHARE
    return _OnModel(clusters, clusters & near if touching else clusters, bool(touching))


def _near(points: np.ndarray, surface: SurfaceModel, U: np.ndarray, distance: float) -> np.ndarray:
    """Which scan points lie within ``distance`` of the model placed by U."""
    _, _, found = surface.nearest(frames.apply(frames.invert(U), points), distance)
    return found
