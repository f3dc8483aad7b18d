"""Find U = ^S X, the pose that places a model into a scan: global search, refinement, verdict.

The work happens with scan points moved onto the model (scan -> model), because the model is the
complete surface: every scan point of the part has a true mate on it and clutter has none.  The
result reports U = (scan -> model)^-1.
"""
from __future__ import annotations

import time
from contextlib import contextmanager
from dataclasses import dataclass, replace

import numpy as np

from . import frames, pointops
from .errors import InputError
from .features import fpfh
from .geometry import Cloud, checked, shape_kind
from .global_search import distinct, feature_correspondences, ransac_poses
from .refine import coarse_to_fine
from .result import AMBIGUOUS, FAILED, OK, MatchResult
from .stability import stability
from .surface import SurfaceModel

METHODS = ("robust", "icp", "hausdorff")

# Fewest scan points a pose is fitted to; below this any answer is a guess.
MIN_SCAN_POINTS = 30


@dataclass(frozen=True)
class MatchOptions:
    """Every knob of a match.  Lengths in mm; ``None`` means derived from the data."""

    method: str = "robust"
    tolerance_mm: float = 0.3
    coarse_voxel_mm: float | None = None  # default: model diagonal / COARSE_VOXELS_PER_DIAGONAL
    ransac_samples: int = 30000
    candidates: int = 4  # distinct poses refined after the global search
    ambiguity_ratio: float = 0.9  # a distinct pose scoring this fraction of the best -> ambiguous
    min_fitness: float = 0.1  # fraction of scan points that must lie on the model
    min_coverage: float = 0.05  # fraction of the model surface that must be seen
    max_fine_points: int = 20000  # the final passes use a random subset of this size
    seed: int = 0


COARSE_VOXELS_PER_DIAGONAL = 50
# RANSAC poses checked against the geometry; distinct ones within half the best score are refined.
RANSAC_VERIFIED = 30
# Points of the middle refinement stage, where the gate shrinks: enough to average the noise.
MEDIUM_POINTS = 5000


def match(scan: Cloud, model, init: np.ndarray | None = None, options: MatchOptions = MatchOptions(),
          **overrides) -> MatchResult:
    """Match ``model`` (a Cloud or a prepared SurfaceModel, frame X) into ``scan`` (frame S).

    ``init``, when given, is a guess of U and replaces the global search.  Keyword overrides set
    MatchOptions fields.  Bad input raises InputError; a match that cannot be trusted comes back
    with status "failed" or "ambiguous" and the reasons.
    """
    options = replace(options, **overrides)
    if options.method not in METHODS:
        raise InputError(f"unknown match method {options.method!r}; choose one of {', '.join(METHODS)}")
    timer = PhaseTimer()
    with timer("model"):
        surface = model if isinstance(model, SurfaceModel) else SurfaceModel(checked(model, 3), options.seed)
    scan = checked(scan, MIN_SCAN_POINTS)
    rng = np.random.default_rng(options.seed)
    result = dict(method=options.method, scan_name=scan.name, model_name=surface.name,
                  tolerance_mm=options.tolerance_mm, n_scan_points=len(scan), seed=options.seed,
                  warnings=list(scan.warnings), timings_s=timer.phases)
    kind = shape_kind(scan.points)
    if kind != "solid":
        return MatchResult(FAILED, matrix=None, time_s=timer.total(), **result,
                           reasons=[f"{scan.name}: the scan points are {kind}; they cannot fix a pose"])

    voxel = options.coarse_voxel_mm or surface.diagonal / COARSE_VOXELS_PER_DIAGONAL
    if init is None:
        with timer("global search"):
            starts = _global_candidates(scan.points, surface, voxel, options, rng)
        if not starts:
            return MatchResult(FAILED, matrix=None, time_s=timer.total(), **result,
                               reasons=["global search found no consistent pose: the scan may not contain the model"])
    else:
        starts = [frames.invert(frames.as_transform(init, "initial guess"))]

    with timer("refine"):
        medium = _subset(scan.points, MEDIUM_POINTS, rng)
        fine = _subset(scan.points, options.max_fine_points, rng)
        floor = max(surface.spacing, pointops.median_spacing(scan.points, seed=options.seed))
        best = _refine(options.method, [medium, fine], surface, starts[0], voxel, floor)
        rivals = [_refine(options.method, [medium], surface, T, voxel, floor).T for T in starts[1:]]
        scores = _scores(medium, surface, [best.T] + rivals, best.gate)
    with timer("verdict"):
        return _verdict(scan, surface, best, list(zip([best.T] + rivals, scores)), options, voxel, result, timer)


class PhaseTimer:
    """Wall time per named phase, for the result's timings and the benchmark."""

    def __init__(self):
        self.started = time.perf_counter()
        self.phases: dict[str, float] = {}

    @contextmanager
    def __call__(self, name: str):
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.phases[name] = self.phases.get(name, 0.0) + time.perf_counter() - t0

    def total(self) -> float:
        return time.perf_counter() - self.started


def _subset(points: np.ndarray, limit: int, rng: np.random.Generator) -> np.ndarray:
    return points if len(points) <= limit else points[rng.choice(len(points), limit, replace=False)]


def _global_candidates(points: np.ndarray, surface: SurfaceModel, voxel: float, options: MatchOptions,
                       rng: np.random.Generator) -> list[np.ndarray]:
    """Distinct scan -> model poses from feature RANSAC, each refined on the coarse grid, best first."""
    coarse, _ = pointops.voxel_downsample(points, voxel)
    if len(coarse) < 10:
        return []
    normals = pointops.orient_consistently(coarse, pointops.estimate_normals(coarse, 2 * voxel))
    model_points, _, model_features = surface.coarse(voxel)
    si, mi = feature_correspondences(fpfh(coarse, normals, 5 * voxel), model_features)
    poses, _ = ransac_poses(coarse[si], model_points[mi], 1.5 * voxel, rng, samples=options.ransac_samples,
                            keep=RANSAC_VERIFIED, min_edge=3 * voxel)
    if len(poses) == 0:
        return []
    verified = _scores(coarse, surface, poses, 1.5 * voxel)
    centre = coarse.mean(axis=0)
    keep = [i for i in distinct(list(poses), verified, centre, 10.0, 0.1 * surface.diagonal)[:options.candidates]
            if verified[i] >= 0.5 * verified.max()]
    refined = [coarse_to_fine([coarse], surface, poses[i], 3 * voxel, voxel / 2).T for i in keep]
    scores = _scores(coarse, surface, refined, voxel)
    order = distinct(refined, scores, centre, 5.0, 0.05 * surface.diagonal)
    return [refined[i] for i in order]


def _refine(method: str, stages, surface: SurfaceModel, T: np.ndarray, gate: float, floor: float):
    if method == "robust":
        return coarse_to_fine(stages, surface, T, gate, floor)
    from .paper_methods import refine_paper

    return refine_paper(method, stages[-1], surface, T)


def _scores(points: np.ndarray, surface: SurfaceModel, transforms, gate: float) -> np.ndarray:
    """For each transform, the fraction of points on the model, each weighted by how close it is
    (1 on the surface, 0 at the gate); all transforms in one tree query."""
    Ts = np.asarray(transforms).reshape(-1, 4, 4)
    moved = (np.matmul(points[None], Ts[:, :3, :3].transpose(0, 2, 1)) + Ts[:, None, :3, 3]).reshape(-1, 3)
    _, idx, found = surface.nearest(moved, gate)
    r = np.where(found, surface.plane_residuals(moved, idx), gate)
    return np.clip(1 - (r / gate) ** 2, 0, 1).reshape(len(Ts), -1).mean(axis=1)


def _coverage(moved_inliers: np.ndarray, surface: SurfaceModel, voxel: float) -> float:
    """Fraction of the model's occupied voxels that hold at least one matched scan point."""
    origin = surface.points.min(axis=0) - voxel

    def occupied(p):
        cells = np.floor((p - origin) / voxel).astype(np.int64)
        return np.unique((cells[:, 0] << 42) | (cells[:, 1] << 21) | cells[:, 2])

    model_cells = occupied(surface.points)
    return float(np.isin(model_cells, occupied(moved_inliers), assume_unique=True).mean())


def _verdict(scan: Cloud, surface: SurfaceModel, best, candidates, options: MatchOptions, voxel: float,
             result: dict, timer: PhaseTimer) -> MatchResult:
    """Deviation statistics on all scan points, stability, ambiguity and the status with reasons."""
    T = best.T
    gate = best.gate
    moved = frames.apply(T, scan.points)
    _, idx, found = surface.nearest(moved, gate)
    deviation = surface.plane_residuals(moved[found], idx[found])
    distance = np.abs(deviation)
    n_in = int(found.sum())
    fitness = n_in / len(scan)
    coverage = _coverage(moved[found], surface, voxel) if n_in else 0.0
    stab = stability(moved[found], surface.normals[idx[found]])
    reasons, status = [], OK
    if n_in < MIN_SCAN_POINTS or fitness < options.min_fitness:
        reasons.append(f"only {fitness:.1%} of the scan points lie on the model (at least "
                       f"{options.min_fitness:.0%} needed): the scan may not contain this model")
    if coverage < options.min_coverage:
        reasons.append(f"the matched points cover only {coverage:.1%} of the model surface (at least "
                       f"{options.min_coverage:.0%} needed)")
    if reasons:
        status = FAILED
    best_score = candidates[0][1]
    listed = []
    centre = surface.points.mean(axis=0)
    for Tc, score in candidates:
        listed.append({"matrix": frames.invert(Tc).tolist(), "score": score,
                       "score_ratio": score / best_score if best_score > 0 else 0.0,
                       "rotation_from_best_deg": frames.rotation_between_deg(Tc, T),
                       "shift_from_best_mm": float(np.linalg.norm(
                           frames.apply(frames.invert(Tc), centre[None])[0]
                           - frames.apply(frames.invert(T), centre[None])[0]))})
    rivals = [c for c in listed[1:] if c["score_ratio"] >= options.ambiguity_ratio]
    if status == OK and rivals:
        status = AMBIGUOUS
        reasons.append(f"{len(rivals)} clearly different pose(s) fit almost as well (best rival "
                       f"{rivals[0]['score_ratio']:.0%} of the best score, {rivals[0]['rotation_from_best_deg']:.1f} deg "
                       "away): the part may be symmetric; see candidates")
    if status == OK and not stab["constrained"]:
        status = AMBIGUOUS
        reasons.append("the matched surface does not fix every motion (under-constrained): free "
                       + "; ".join(stab["free_motions"]))
    percentiles = {str(q): float(np.percentile(distance, q)) for q in (50, 90, 95, 99)} if n_in else {}
    return MatchResult(
        status, matrix=frames.invert(T), fitness=fitness, coverage=coverage,
        rms_mm=float(np.sqrt(np.mean(deviation**2))) if n_in else float("nan"),
        mean_directed_hausdorff_mm=float(distance.mean()) if n_in else float("nan"),
        max_deviation_mm=float(distance.max()) if n_in else float("nan"),
        percentiles_mm=percentiles,
        within_tolerance_pct=float(100 * np.mean(distance <= options.tolerance_mm)) if n_in else 0.0,
        gate_mm=float(gate), n_inliers=n_in, iterations=int(best.iterations), time_s=timer.total(),
        stability=stab, candidates=listed, reasons=reasons, **result)
