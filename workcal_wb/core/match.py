"""Find U = ^S X, the pose that places a model into a scan: global search, refinement, verdict.

The work happens with scan points moved onto the model (scan -> model), because the model is the
complete surface: every scan point of the part has a true mate on it and clutter has none.  The
result reports U = (scan -> model)^-1.

Poses are compared by how many scan points they put on the model (weighted by closeness), never by
the fraction of the scan: clutter around the part dilutes every pose alike.  A pose is trusted only
when it explains the scan to within the scan's own noise (plus the tolerance), covers a real part
of the model and pins every motion; a clearly different pose that fits almost as well (found by
the search, or a half turn of a symmetric model) makes it ambiguous.  Otherwise the match fails
and says why.
"""
from __future__ import annotations

import time
from contextlib import contextmanager
from dataclasses import dataclass, replace

import numpy as np

from . import frames, global_search, pointops
from .edges import centre_on_edges, has_weak_motion
from .errors import InputError
from .geometry import Cloud, checked, shape_kind
from .refine import MAD_TO_SIGMA, coarse_to_fine, refine, refine_exact
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
    ransac_samples: int = 40000
    candidates: int = 4  # distinct poses refined after the global search
    ambiguity_ratio: float = 0.9  # a distinct pose scoring this fraction of the best -> ambiguous
    min_fitness: float = 0.1  # fraction of the scan's points that must lie on the model
    min_coverage: float = 0.05  # fraction of the model surface that must be seen
    max_fine_points: int = 20000  # the final pass uses a random subset of this size (statistics: VERDICT_POINTS)
    seed: int = 0


COARSE_VOXELS_PER_DIAGONAL = 40
# RANSAC poses kept by their votes, the distinct ones of them checked against the geometry, on at
# most this many coarse scan points.
RANSAC_KEPT, RANSAC_VERIFIED, VERIFY_POINTS = 200, 30, 600
# Fewest coarse points worth describing by features, and how much finer than the default grid
# the global search may go to get them.
MIN_COARSE_POINTS, MAX_VOXEL_REFINEMENT = 350, 2.0
# RANSAC poses verified within this fraction of the best are refined (a symmetric twin scores as
# much as the best; the half turns of a symmetric model are also tried after refinement).
CANDIDATE_FLOOR = 0.7
# Steps of the final robust pass on all the fine points, from a pose already within their noise.
POLISH_ITERATIONS = 2
# Patches the scan's noise is measured on, and points the statistics of the verdict are taken
# over (a random subset: percentages to about half a percent).
NOISE_PROBES, VERDICT_POINTS = 300, 10000
# Points of the middle refinement stage, where the gate shrinks: enough to average the noise.
MEDIUM_POINTS = 3000
# Global candidates scoring below this fraction of the best are not refined further: after the
# coarse stage they cannot come within ``ambiguity_ratio`` of it.
RIVAL_FLOOR = 0.6
# A placed model must explain the scan to within its own noise: the robust residual scale may be
# at most this many times the scan's noise (from local quadric fits) plus the tolerance.  Right
# matches measured 1-2x (real bunny scans, simulated scans); a scan of another object 10-40x.
MAX_NOISE_RATIO = 3.0
# Points that scatter about local quadric fits by more than this fraction of the fit's radius
# are a volume, not a surface (surface scans measured below 0.1, noisy sparse ones included;
# a random blob 0.34).
MAX_SCATTER = 0.3


def match(scan: Cloud, model, init: np.ndarray | None = None, options: MatchOptions = MatchOptions(),
          **overrides) -> MatchResult:
    """Match ``model`` (a Cloud or a prepared SurfaceModel, frame X) into ``scan`` (frame S).

    ``init``, when given, is a guess of U and replaces the global search.  Keyword overrides set
    MatchOptions fields.  Bad input raises InputError; a match that cannot be trusted comes back
    with status "failed" or "ambiguous" and the reasons.
    """
    options = _checked_options(replace(options, **overrides))
    with pointops.single_threaded_blas():
        return _match(scan, model, init, options)


def _match(scan: Cloud, model, init, options: MatchOptions) -> MatchResult:
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
    fine = _subset(scan.points, options.max_fine_points, rng)
    medium = _subset(fine, MEDIUM_POINTS, rng)
    noise, patch = pointops.surface_noise(medium, rng, probes=NOISE_PROBES)
    if not noise <= MAX_SCATTER * patch:
        return MatchResult(FAILED, matrix=None, time_s=timer.total(), **result,
                           reasons=[f"{scan.name}: the points do not lie on a surface (they scatter {noise:.2f} mm "
                                    f"about local fits {patch:.2f} mm across); a scan samples a surface"])

    # A coarse voxel finer than the scan's spacing leaves one point per voxel and features with too
    # few neighbours; the 12th neighbour of a surface point lies about two spacings away, and the
    # medium subset is sparser than the scan by the square root of their sizes (a surface).
    spacing = patch / 2 * np.sqrt(len(medium) / len(scan))
    voxel = options.coarse_voxel_mm or max(surface.diagonal / COARSE_VOXELS_PER_DIAGONAL, 1.5 * spacing)
    if init is None:
        with timer("global search"):
            starts = _global_candidates(scan.points, surface, voxel, options, rng, min_voxel=1.5 * spacing)
        if not starts:
            return MatchResult(FAILED, matrix=None, time_s=timer.total(), **result,
                               reasons=["global search found no consistent pose: the scan may not contain the model"])
        gate = voxel / 2  # where the coarse refinement of the global candidates left off
    else:
        starts = [(frames.invert(frames.as_transform(init, "initial guess")), 1.0)]
        gate = voxel  # a guess may be off by a few millimetres

    with timer("refine"):
        best, rivals = _refine(options.method, starts, medium, fine, surface, gate, options.tolerance_mm)
        scores = inlier_scores(medium, surface, [best.T] + rivals, best.gate)
    with timer("verdict"):
        return _verdict(scan, fine[:VERDICT_POINTS], noise, surface, best, list(zip([best.T] + rivals, scores)),
                        options, voxel, result, timer)


def prepare(surface: SurfaceModel) -> SurfaceModel:
    """Compute ahead of time everything model-side a match may use: the coarse features at the
    default voxel and the finer ones a partial scan may ask for, and the whole nearest-sample
    grid the refinement looks up.  A batch of matches against one model then pays for it once;
    without it the same work is done lazily, a little in each match (seconds for ~100k samples)."""
    voxel = surface.diagonal / COARSE_VOXELS_PER_DIAGONAL
    while voxel >= surface.diagonal / COARSE_VOXELS_PER_DIAGONAL / MAX_VOXEL_REFINEMENT:
        surface.coarse(voxel)
        voxel /= 1.25
    for level in range(2):  # gates up to 2 x GATE_CELLS spacings: 3 coarse voxels at the default voxel
        surface.grid_level(level).precompute()
    return surface


def _checked_options(options: MatchOptions) -> MatchOptions:
    if options.method not in METHODS:
        raise InputError(f"unknown match method {options.method!r}; choose one of {', '.join(METHODS)}")
    if not 0 < options.tolerance_mm < float("inf"):
        raise InputError(f"match tolerance must be a finite number > 0 mm, got {options.tolerance_mm}")
    if not (isinstance(options.seed, int) and 0 <= options.seed < 2**63):
        raise InputError(f"match seed must be a whole number from 0 to 2**63 - 1, got {options.seed}")
    if options.coarse_voxel_mm is not None and not options.coarse_voxel_mm > 0:
        raise InputError(f"coarse voxel must be > 0 mm, got {options.coarse_voxel_mm}")
    return options


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
                       rng: np.random.Generator, min_voxel: float = 0.0) -> list[tuple[np.ndarray, float]]:
    """Distinct scan -> model poses from feature RANSAC, each refined on the coarse grid, with
    their scores, best first."""
    coarse = global_search.coarse_points(points, voxel)
    # A small piece of the model (partial overlap) leaves too few coarse points to describe:
    # refine the grid for it, down to MAX_VOXEL_REFINEMENT times finer but not below ``min_voxel``.
    finest = max(min_voxel, voxel / MAX_VOXEL_REFINEMENT)
    while len(coarse) < MIN_COARSE_POINTS and voxel / 1.25 >= finest:
        voxel /= 1.25
        coarse = global_search.coarse_points(points, voxel)
    coarse = global_search.without_large_plane(coarse, voxel, surface.diagonal, rng)
    if len(coarse) < 10:
        return []
    features, normals = global_search.describe_scan(coarse, voxel)
    model_points, model_normals, model_features = surface.coarse(voxel)
    si, mi, side = global_search.feature_correspondences(features, model_features)
    poses, votes = global_search.ransac_poses(coarse[si], model_points[mi], side[:, None] * normals[si],
                                              model_normals[mi], 1.5 * voxel, rng, samples=options.ransac_samples,
                                              keep=RANSAC_KEPT, min_edge=3 * voxel)
    if len(poses) == 0:
        return []
    probe = _subset(coarse, VERIFY_POINTS, rng)
    centre = probe.mean(axis=0)
    # Many hypotheses are near copies of the best one; a symmetric twin must not be crowded out.
    poses = poses[global_search.distinct(poses, votes, centre, 15.0, 0.1 * surface.diagonal, RANSAC_VERIFIED)]
    verified = inlier_scores(probe, surface, poses, 1.5 * voxel)
    keep = [i for i in global_search.distinct(poses, verified, centre, 15.0, 0.1 * surface.diagonal)
            if verified[i] >= CANDIDATE_FLOOR * verified.max()][:options.candidates]
    refined = [coarse_to_fine([probe], surface, poses[i], 3 * voxel, voxel / 2).T for i in keep]
    scores = inlier_scores(probe, surface, refined, voxel)
    order = global_search.distinct(refined, scores, centre, 5.0, 0.05 * surface.diagonal)
    return [(refined[i], float(scores[i])) for i in order if scores[i] > 0]


def _refine(method: str, starts, medium: np.ndarray, fine: np.ndarray, surface: SurfaceModel, gate: float,
            tolerance: float):
    """The best pose refined on all the fine points, and the distinct rivals refined on the medium ones.

    Every start within RIVAL_FLOOR of the best coarse score is refined on the medium points first
    and the winner is chosen at the tightest gate any of them reached: coarse scores of a wrong pose
    can tie with the right one, but only the right one brings the residuals down to the noise.
    When the robust fit leaves a motion nearly free against a mesh, it goes on against the exact
    surface and centres the pose between the edges that pin the motion (see edges).
    """
    contenders = [T for T, score in starts if score >= RIVAL_FLOOR * starts[0][1]]
    if len(contenders) == 1 and method != "robust":
        states = []
    else:
        states = [coarse_to_fine([medium], surface, T, gate, surface.spacing) for T in contenders]
        scores = inlier_scores(medium, surface, [s.T for s in states], min(s.gate for s in states))
        order = global_search.distinct([s.T for s in states], scores, medium.mean(axis=0), 5.0, 0.05 * surface.diagonal)
        contenders, states = [contenders[i] for i in order], [states[i] for i in order]
    if method == "robust":
        chosen = states[0]
        best = refine(fine, surface, chosen.T, chosen.gate, chosen.scale, POLISH_ITERATIONS)
        best.iterations += chosen.iterations
        if surface.is_mesh and has_weak_motion(fine, surface, best.T, best.gate, best.scale):
            best = refine_exact(fine, surface, best)
            best.T, best.stability = centre_on_edges(fine, surface, best.T, best.gate, best.sigma, tolerance)
    else:
        from .paper_methods import refine_paper

        best = refine_paper(method, fine, surface, contenders[0], gate)
    poses = [best.T] + [s.T for s in states[1:]] + _symmetric_twins(best, medium, surface, gate)
    # In this order of preference, drop every pose that repeats an earlier one.
    keep = global_search.distinct(poses, -np.arange(len(poses)), medium.mean(axis=0), 5.0, 0.05 * surface.diagonal)
    return best, [poses[i] for i in keep[1:]]


def _symmetric_twins(best, medium: np.ndarray, surface: SurfaceModel, gate: float) -> list[np.ndarray]:
    """The best pose turned by the model's half-turn self-maps, refined where they fit at all.

    Feature search can miss the twin of a symmetric part (a box's faces all look alike), so the
    flips a box, an ellipsoid or a cylinder maps onto itself are tried directly.
    """
    twins = surface.symmetry_flips @ best.T
    scores = inlier_scores(medium, surface, np.concatenate([best.T[None], twins]), best.gate)
    return [coarse_to_fine([medium], surface, T, gate, surface.spacing).T
            for T, score in zip(twins, scores[1:]) if score >= RIVAL_FLOOR * scores[0]]


def inlier_scores(points: np.ndarray, surface: SurfaceModel, transforms, gate: float) -> np.ndarray:
    """For each transform, how many points it puts on the model, each weighted by how close it is
    (1 on the surface, 0 at the gate): a count, so clutter cannot dilute it; one grid lookup."""
    Ts = np.asarray(transforms).reshape(-1, 4, 4)
    moved = (np.matmul(points[None], Ts[:, :3, :3].transpose(0, 2, 1)) + Ts[:, None, :3, 3]).reshape(-1, 3)
    _, idx, found = surface.nearest_cell(moved, gate)
    r = np.where(found, surface.plane_residuals(moved, idx), gate)
    return np.clip(1 - (r / gate) ** 2, 0, 1).reshape(len(Ts), -1).sum(axis=1)


def _verdict(scan: Cloud, sample: np.ndarray, noise: float, surface: SurfaceModel, best, candidates,
             options: MatchOptions, voxel: float, result: dict, timer: PhaseTimer) -> MatchResult:
    """Deviation statistics on the (sub)sampled scan points, stability, ambiguity and the status
    with reasons; ``noise`` is the scan's own (pointops.surface_noise)."""
    T, gate = best.T, best.gate
    moved = frames.apply(T, sample)
    _, idx, found = surface.nearest_cell(moved, gate)
    deviation = surface.plane_residuals(moved[found], idx[found])
    distance = np.abs(deviation)
    n_in = int(found.sum())
    fitness = n_in / len(sample)
    coverage = _coverage(moved[found], surface, voxel) if n_in else 0.0
    sigma = MAD_TO_SIGMA * float(np.median(distance)) if n_in else float("inf")
    stab = best.stability if best.stability is not None else stability(moved[found], surface.normals[idx[found]])
    for held in stab.get("held_by_edges", []):
        result["warnings"].append(f"{held['motion']} is held only by the model's edges: the data leave "
                                  f"+/-{held['slack_mm']:.3f} mm of play, the pose is centred in it")
    reasons, status = [], OK
    if n_in < MIN_SCAN_POINTS or fitness < options.min_fitness:
        reasons.append(f"only {fitness:.1%} of the scan points lie on the model (at least "
                       f"{options.min_fitness:.0%} needed): the scan may not contain this model")
    if coverage < options.min_coverage:
        reasons.append(f"the matched points cover only {coverage:.1%} of the model surface (at least "
                       f"{options.min_coverage:.0%} needed)")
    if sigma > MAX_NOISE_RATIO * noise + options.tolerance_mm:
        reasons.append(f"the model does not fit the scan within its noise: residual scale {sigma:.2f} mm where "
                       f"the scan's own noise is {noise:.2f} mm (at most {MAX_NOISE_RATIO:g} x noise + "
                       f"{options.tolerance_mm} mm tolerance): the scan may not contain this model")
    if reasons:
        status = FAILED
    best_score = candidates[0][1]
    listed = []
    centre = surface.points.mean(axis=0)
    for Tc, score in candidates:
        listed.append({"matrix": frames.invert(Tc).tolist(), "score": float(score),
                       "score_ratio": float(score / best_score) if best_score > 0 else 0.0,
                       "rotation_from_best_deg": frames.rotation_between_deg(Tc, T),
                       "shift_from_best_mm": float(np.linalg.norm(
                           frames.apply(frames.invert(Tc), centre[None])[0]
                           - frames.apply(frames.invert(T), centre[None])[0]))})
    rivals = sorted((c for c in listed[1:] if c["score_ratio"] >= options.ambiguity_ratio),
                    key=lambda c: -c["score_ratio"])
    if status == OK and rivals:
        reasons.append(f"{len(rivals)} clearly different pose(s) fit almost as well (best rival "
                       f"{rivals[0]['score_ratio']:.0%} of the best score, {rivals[0]['rotation_from_best_deg']:.1f} deg "
                       "away): the part may be symmetric; see candidates")
    if status == OK and not stab["constrained"]:
        reasons.append("the matched surface does not fix every motion (under-constrained): free "
                       + "; ".join(stab["free_motions"]))
    if reasons and status == OK:
        status = AMBIGUOUS
    percentiles = {str(q): float(np.percentile(distance, q)) for q in (50, 90, 95, 99)} if n_in else {}
    return MatchResult(
        status, matrix=frames.invert(T), fitness=fitness, coverage=coverage,
        rms_mm=float(np.sqrt(np.mean(deviation**2))) if n_in else float("nan"),
        mean_directed_hausdorff_mm=float(distance.mean()) if n_in else float("nan"),
        max_deviation_mm=float(distance.max()) if n_in else float("nan"),
        percentiles_mm=percentiles,
        within_tolerance_pct=float(100 * np.mean(distance <= options.tolerance_mm)) if n_in else 0.0,
        gate_mm=float(gate), n_inliers=int(round(fitness * len(scan))), iterations=int(best.iterations),
        time_s=timer.total(), stability=stab, candidates=listed, reasons=reasons, **result)


def _coverage(matched: np.ndarray, surface: SurfaceModel, voxel: float) -> float:
    """Fraction of the model's occupied cells (coarse voxels) that hold a matched point."""
    cells = surface.occupied_cells(voxel)
    return float(np.isin(cells, surface.cell_keys(matched, voxel), assume_unique=False).mean())
