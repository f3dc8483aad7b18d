"""One scene scan in, W = ^B X = V^-1 U out, with an honest uncertainty and quality gates.

U = ^S X comes from matching the workpiece region of the scan against X-A, V = ^S B from matching
the reference region against B-P (whose points are given in the robot base frame B).  Equation (1)
of the paper, W = V^-1 U, is the workpiece frame in the robot base frame: what the robot needs to
place the toolpath, B-m = W X-m.  (The paper's Table 1 prints its inverse, U^-1 V; see
docs/architecture.md.)
"""
from __future__ import annotations

import math
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace

import numpy as np

from . import frames, physics, pointops
from .distortion import distortion
from .edges import slide
from .errors import InputError, NotFound
from .geometry import Cloud
from .match import METHODS, MIN_SCAN_POINTS, REFINE, MatchOptions, match, match_pose, refine_given
from .off_model import off_model
from .refine import coarse_to_fine
from .regions import (LOCATE, find_platform, joins_within, locate, match_trusted, nearer_own_model, refit,
                      standing_on)
from .result import (AMBIGUOUS, DISTORTION, FAILED, NOT_FOUND, OK, RMS, SCAN_NOT_SOLID, UNCERTAINTY, WITHIN_TOLERANCE,
                     CalibrationResult, MatchResult, Reason, status_gate_code)
from .surface import SurfaceModel
from .surroundings import judged_in_surroundings


@dataclass(frozen=True)
class CalibrationOptions:
    """Knobs of a calibration; lengths in mm."""

    tolerance_mm: float = 0.3  # the paper's milling need: residuals and toolpath uncertainty must stay within it
    method: str = "robust"
    resamples: int = 6  # bootstrap refits of both matches for the uncertainty
    seed: int = 0
    # OpenBLAS threads while matching (pointops.blas_threads): one is fastest; None leaves the process's
    # setting alone (FreeCAD's worker threads: the GUI thread goes on using numpy meanwhile).
    blas_threads: int | None = 1
    # Where the scanner stood and which way is up, in the scan's frame (mm; a direction), when the user
    # knows; otherwise the scan's file tells the scanner's position, or both come from the data.
    scanner_origin: tuple | None = None
    up: tuple | None = None

    def __post_init__(self):
        if not (isinstance(self.tolerance_mm, (int, float)) and math.isfinite(self.tolerance_mm)
                and self.tolerance_mm > 0):
            raise InputError(f"tolerance must be a positive number of mm, not {self.tolerance_mm}")
        if self.method not in METHODS:
            raise InputError(f"unknown method {self.method!r}; choose one of {', '.join(METHODS)}")
        if not (isinstance(self.resamples, int) and self.resamples >= 1):
            raise InputError(f"resamples must be a whole number of at least 1, not {self.resamples}")
        if not (isinstance(self.seed, int) and 0 <= self.seed < 2**63):
            raise InputError(f"seed must be a whole number from 0 to 2**63 - 1, not {self.seed}")
        for name, words in (("scanner_origin", "three finite coordinates in mm"),
                            ("up", "three finite numbers, not all zero (a direction)")):
            value = getattr(self, name)
            if value is None:
                continue
            vector = np.asarray(value, dtype=float) if np.shape(value) == (3,) else None
            if vector is None or not np.isfinite(vector).all() or (name == "up" and not np.linalg.norm(vector) > 0):
                raise InputError(f"{name.replace('_', ' ')} must be {words}, not {value!r}")
            object.__setattr__(self, name, tuple(float(v) for v in vector))


@dataclass(frozen=True)
class BootstrapSettings:
    """The bootstrap refits that bound W's uncertainty (_uncertainty)."""

    # The bound is this many times the RMS displacement over the bootstrap refits (a 3D "3 sigma").
    factor: float = 3.0
    # Threads the bootstrap refits run on, and the resamples drawn at a time (8 MB for two regions of
    # 20k points: a default calibration's refits are drawn at once).
    refit_threads: int = 2
    drawn_at_once: int = 8
    # Points of the workpiece's surface the uncertainty is measured at (and the toolpath's, when given).
    surface_samples: int = 2000


BOOTSTRAP = BootstrapSettings()


@dataclass(frozen=True)
class InputChecks:
    """What the inputs of a calibration must agree with: the scans' units, the tolerance, the toolpath."""

    # Scans of one scene taken in the same units have extents within this factor of each other.
    unit_mismatch_ratio: float = 8.0
    # Model vertices this close (mm) are the same: float noise of a model read twice or copied.
    same_shape_mm: float = 1e-6
    # The largest tolerance (a share of the larger model's diagonal) a calibration can be checked to: past
    # it a model several percent the wrong size, or a pose a few degrees off, passes every gate.
    max_tolerance_of_size: float = 0.05
    # A toolpath works on the part: its median distance to the model surface, as a fraction of the model
    # diagonal, stays below this unless it was written in another unit or frame.
    toolpath_max_median_distance: float = 0.2


INPUT_CHECKS = InputChecks()


@dataclass(frozen=True)
class DistortionSampling:
    """Points per region the distortion check measures on: ``points`` where its match's residual RMS is
    ``rms_mm`` or less, more as the square of a larger RMS (the smallest strain it tells from noise goes
    as RMS / (lever x sqrt(points))), at most as many as a match is finished on (its queries cost per point)."""

    points: int = 5000
    rms_mm: float = 0.1


DISTORTION_SAMPLING = DistortionSampling()

# The match that located a region is its final one when the region holds at most this share of
# points more than it was made on (see _refit).
KEPT_MATCH_EXTRA = 0.02
# The share of a region its model explains, in percent, is given to hundredths (a gate's value is read).
EXPLAINED_DIGITS = 2


def calibrate(scans, workpiece, reference, *, regions=None, toolpath_points=None,
              options: CalibrationOptions = CalibrationOptions(), progress=None) -> CalibrationResult:
    """Compute U, V and W from a scene scan (one Cloud or several captures from the same position).

    ``workpiece`` (X-A) and ``reference`` (B-P, in B) are Clouds or prepared SurfaceModels.
    ``regions``: None to find them automatically, or {"workpiece": indices, "reference": indices}
    into the concatenated scan points.  ``toolpath_points`` (N x 3, mm, in X) are where the
    uncertainty matters most.  ``progress(fraction, message)`` is called as work proceeds; it may
    raise errors.Cancelled to stop.  Bad input raises InputError; a calibration that cannot be
    trusted comes back with status "failed" or "ambiguous" and the reasons.
    """
    # The whole of it on options.blas_threads, not only the matches: the bootstrap refits' small
    # products are slow on OpenBLAS's own threads on a busy machine (their threads spin).
    with pointops.blas_threads(options.blas_threads):
        return _calibrate(scans, workpiece, reference, regions, toolpath_points, options, progress)


def _same_shape(first, second) -> bool:
    """Whether two models (Clouds or SurfaceModels) have the same vertices, to INPUT_CHECKS.same_shape_mm:
    one file given for both objects, or a copy of it."""
    a, b = (np.asarray(m.vertices if isinstance(m, SurfaceModel) else m.points) for m in (first, second))
    return a.shape == b.shape and bool(np.all(np.abs(a - b) <= INPUT_CHECKS.same_shape_mm))


def _calibrate(scans, workpiece, reference, regions, toolpath_points, options: CalibrationOptions,
               progress) -> CalibrationResult:
    started = time.perf_counter()
    report = progress or (lambda fraction, message: None)
    scan = merge_scans(scans)
    if _same_shape(workpiece, reference):
        raise InputError(f"the workpiece model {workpiece.name} and the reference model {reference.name} are the same "
                         "shape at the same place: one of them is the wrong file (no scan can tell which object is "
                         "which); give the workpiece's model X-A and the reference object's model B-P")
    report(0.0, "preparing the models")
    surfaces = [m if isinstance(m, SurfaceModel) else SurfaceModel(m, options.seed) for m in (workpiece, reference)]
    workpiece_surface, reference_surface = surfaces
    larger = max(surfaces, key=lambda s: s.diagonal)  # the smaller may be in another unit: said where it is located
    if options.tolerance_mm > INPUT_CHECKS.max_tolerance_of_size * larger.diagonal:
        raise InputError(f"tolerance {options.tolerance_mm:g} mm is "
                         f"{100 * options.tolerance_mm / larger.diagonal:.0f} % of the size of {larger.name} "
                         f"(diagonal {larger.diagonal:.1f} mm): at most "
                         f"{100 * INPUT_CHECKS.max_tolerance_of_size:.0f} %, or a model several percent the wrong size "
                         "passes; give the tolerance the machining needs (mm)")
    if toolpath_points is not None:
        toolpath_points = _checked_toolpath(toolpath_points, workpiece_surface)
    match_options = dict(method=options.method, tolerance_mm=options.tolerance_mm, seed=options.seed,
                         blas_threads=options.blas_threads, tolerance_gates=False)  # the gates ask it, after distortion
    if scanner_origin(scan, options) is not None:  # the matches judge their views from where the scanner stood
        match_options["viewpoint"] = tuple(scanner_origin(scan, options))
    warnings = list(scan.warnings)

    if regions is None:
        try:
            found = locate(scan, workpiece_surface, reference_surface, options.tolerance_mm, options.seed,
                           progress=lambda f, m: report(0.6 * f, m), up=options.up,
                           viewpoint=scanner_origin(scan, options), blas_threads=options.blas_threads)
        except NotFound as exc:  # the calibration ran and found nothing to place: a failed result
            return _failed_before_matching(Reason(NOT_FOUND, str(exc)), "auto", scan, surfaces, toolpath_points,
                                           options, warnings, started)
        warnings += found.warnings
        region_idx = {"workpiece": found.workpiece, "reference": found.reference, "platform": found.platform}
        source = "auto"
        match_options["support"] = standing_on(found.plane)
        report(0.6, "refining both matches on their regions")
        U_match, V_match = (_refit(scan, region_idx[role], surface, getattr(found, f"{role}_match"),
                                   found.matched[role], match_options, role)
                            for role, surface in (("workpiece", workpiece_surface), ("reference", reference_surface)))
    else:
        source = "user"
        report(0.05, "finding the platform")
        scene = _physics_scene(scan, options, None, None)
        match_options["support"] = standing_on(scene.platform)
        # A box drawn loosely takes some of the platform: its points are no object's.
        picked = {role: _region(scan, regions, role) for role in ("workpiece", "reference")}
        region_idx, trimmed = {}, {}
        for role in ("workpiece", "reference"):
            region_idx[role] = np.setdiff1d(picked[role], _platform_indices(scan, scene))
            trimmed[role] = {"platform": len(picked[role]) - len(region_idx[role])}
            if len(region_idx[role]) < MIN_SCAN_POINTS:
                return _failed_before_matching(
                    Reason(SCAN_NOT_SOLID, f"{role} region: {trimmed[role]['platform']} of its {len(picked[role])} "
                                           "points lie in the platform's plane, a planar patch with no object on "
                                           f"it; pick the {role}", role),
                    "user", scan, surfaces, toolpath_points, options, warnings, started)
        report(0.1, "matching the reference region")
        V_match = match_trusted(_region_cloud(scan, region_idx["reference"], "reference"), reference_surface,
                                match_options, "reference")
        report(0.35, "matching the workpiece region")
        U_match = match_trusted(_region_cloud(scan, region_idx["workpiece"], "workpiece"), workpiece_surface,
                                match_options, "workpiece")
        (U_match, V_match), region_idx = _without_the_other_object(
            scan, region_idx, trimmed, dict(workpiece=workpiece_surface, reference=reference_surface),
            dict(workpiece=U_match, reference=V_match), scene.spacing, match_options)
        warnings += _trimmed_words(trimmed)

    if regions is None:
        scene = _physics_scene(scan, options, found.plane, found.spacing)
    report(0.65, "weighing both poses against the scan beside their regions")
    platform_idx = _platform_indices(scan, scene)
    given = dict(region_idx)
    for role, other, surface in (("workpiece", "reference", workpiece_surface),
                                 ("reference", "workpiece", reference_surface)):
        matched = U_match if role == "workpiece" else V_match
        matched, region_idx[role] = judged_in_surroundings(
            scan, given[role], np.union1d(platform_idx, given[other]), surface, matched, match_options, role,
            scene.spacing)
        U_match, V_match = (matched, V_match) if role == "workpiece" else (U_match, matched)
    report(0.7, "weighing the poses by contact with the platform and free space")
    U_match, V_match = (physics.decide(m, surface, scene, role, refit=lambda U, idx=region_idx[role], s=surface, r=role:
                                       match(_region_cloud(scan, idx, r), s, init=U, **match_options))
                        for m, surface, role in ((U_match, workpiece_surface, "workpiece"),
                                                 (V_match, reference_surface, "reference")))
    result = dict(workpiece=U_match, reference=V_match, tolerance_mm=options.tolerance_mm, seed=options.seed,
                  inputs=_inputs(scan, workpiece_surface, reference_surface, toolpath_points),
                  regions={**{k: np.asarray(v, dtype=np.int64) for k, v in region_idx.items()}, "source": source,
                           **({"trimmed": trimmed} if regions is not None else {})},
                  warnings=warnings + [f"workpiece match: {w}" for w in U_match.warnings]
                  + [f"reference match: {w}" for w in V_match.warnings])
    failed = [(role, m) for role, m in (("workpiece", U_match), ("reference", V_match)) if m.matrix is None]
    if failed:
        reasons = [r.within(f"{role} match failed", role) for role, m in failed for r in m.reasons]
        return CalibrationResult(FAILED, W=None, U=U_match.matrix, V=V_match.matrix, reasons=reasons,
                                 time_s=time.perf_counter() - started, **result)

    U, V = U_match.matrix, V_match.matrix
    W = frames.invert(V) @ U
    report(0.75, "estimating the uncertainty")
    uncertainty = _uncertainty(scan, region_idx, (workpiece_surface, reference_surface), (U_match, V_match), W,
                               toolpath_points, options, match_options)
    strained = _distortion(scan, region_idx, surfaces, (U_match, V_match), toolpath_points, options)
    uncertainty.update(distortion_shift_mm=strained["shift_mm"], distortion_scale_pct=strained["scale_pct"],
                       distortion_strain_pct=strained["largest_strain_pct"])
    uncertainty["distortion_unverified_shift_mm"] = strained["shift_if_scanner_mm"]
    if strained["workpiece_own_pct"]:
        result["warnings"].append(
            f"the workpiece reads a strain of {strained['workpiece_own_pct']:.2f} % against its model that the "
            "reference does not confirm: taken as the part's own (a part differs from its model: clay, a casting, "
            f"a model merged from other scans); were it the scanner's, W would move up to "
            f"{strained['shift_if_scanner_mm']:.3f} mm at the {'toolpath' if toolpath_points is not None else 'part'}. "
            "Only a reference that shows that strain can check the scanner: scan it so that two parallel faces "
            "show along each direction (an L-block's inner faces as well as its outer ones)")
    unexplained = _off_model(scan, region_idx, dict(workpiece=workpiece_surface, reference=reference_surface),
                             dict(workpiece=U_match, reference=V_match), scene.platform)
    result["regions"].update({f"{role}_off_model": found.indices for role, found in unexplained.items()},
                             off_model={role: found.note() for role, found in unexplained.items()})
    gates = _quality_gates(U_match, V_match, uncertainty, options.tolerance_mm, unexplained)
    status, reasons = _status(U_match, V_match, gates)
    report(1.0, f"calibration {status}")
    return CalibrationResult(status, W=W, U=U, V=V, uncertainty=uncertainty, quality_gates=gates, reasons=reasons,
                             time_s=time.perf_counter() - started, **result)


def _failed_before_matching(reason: Reason, source: str, scan: Cloud, surfaces, toolpath_points,
                            options: CalibrationOptions, warnings: list, started: float) -> CalibrationResult:
    """A failed result for a calibration that found nothing to match (no regions, no object in one)."""
    return CalibrationResult(FAILED, W=None, reasons=[reason], warnings=warnings, regions={"source": source},
                             tolerance_mm=options.tolerance_mm, seed=options.seed,
                             inputs=_inputs(scan, *surfaces, toolpath_points), time_s=time.perf_counter() - started)


def _platform_indices(scan: Cloud, scene: physics.Scene) -> np.ndarray:
    """The scan indices of the platform's points (on or below its plane); none without a platform."""
    if scene.platform is None:
        return np.empty(0, np.int64)
    return np.flatnonzero(np.isfinite(scan.points).all(axis=1))[scene.platform.below]


def _without_the_other_object(scan: Cloud, region_idx: dict, trimmed: dict, surfaces: dict, matches: dict,
                              spacing: float, match_options: dict):
    """((U match, V match), regions): each region given by hand without the points that lie on the other
    object's placed model (within regions.joins_within of it and nearer to it than to its own), counted in
    ``trimmed``; a region that lost some is matched again from its pose."""
    out = dict(region_idx)
    for role, other in (("workpiece", "reference"), ("reference", "workpiece")):
        own, theirs = matches[role], matches[other]
        if own.matrix is None or theirs.matrix is None:
            trimmed[role][other] = 0
            continue
        idx = region_idx[role]
        keep = nearer_own_model(scan.points[idx], (surfaces[role], own.matrix), (surfaces[other], theirs.matrix),
                                joins_within(other, spacing))
        trimmed[role][other] = int(np.count_nonzero(~keep))
        if trimmed[role][other] and keep.any():
            out[role] = idx[keep]
            matches[role] = refit(_region_cloud(scan, out[role], role), surfaces[role], own, match_options)
    return (matches["workpiece"], matches["reference"]), out


def _off_model(scan: Cloud, region_idx: dict, surfaces: dict, matches: dict, platform) -> dict:
    """Per role, its region's points off its placed model, what they are and where (off_model.off_model)."""
    return {role: off_model(scan.points, region_idx[role], surfaces[role], matches[role], role, platform,
                            (other, surfaces[other], matches[other], region_idx[other]))
            for role, other in (("workpiece", "reference"), ("reference", "workpiece"))}


def _trimmed_words(trimmed: dict) -> list:
    """The warnings that say what was left out of the regions given by hand."""
    words = []
    for role, other in (("workpiece", "reference"), ("reference", "workpiece")):
        parts = [f"{trimmed[role]['platform']} points on the platform's plane" if trimmed[role]["platform"] else "",
                 f"{trimmed[role][other]} points on the placed {other} model" if trimmed[role].get(other) else ""]
        parts = [p for p in parts if p]
        if parts:
            words.append(f"the {role} region given left out {' and '.join(parts)} (points of neither the {role} "
                         "nor its model: the box or lasso took them)")
    return words


def _physics_scene(scan: Cloud, options: CalibrationOptions, platform, spacing) -> physics.Scene:
    """The whole scan as the physical constraints see it: its points, their spacing, the platform
    (both found with the regions, or now for regions the user gave) and the scanner positions the
    user or the file gives."""
    valid = np.isfinite(scan.points).all(axis=1)
    points = scan.points[valid]
    if spacing is None:
        spacing = pointops.median_spacing(points, seed=options.seed)
    if platform is None:
        platform = find_platform(points, spacing, np.random.default_rng(options.seed), options.up,
                                 scanner_origin(scan, options))
    if options.scanner_origin is not None:
        return physics.Scene(points, spacing, platform, np.asarray([options.scanner_origin]))
    sensor_of = scan.sensor_indices()
    return physics.Scene(points, spacing, platform, scan.sensors, None if sensor_of is None else sensor_of[valid])


def scanner_origin(scan: Cloud, options: CalibrationOptions):
    """The scanner's position in the scan's frame, when the user or the file tells one position."""
    if options.scanner_origin is not None:
        return np.asarray(options.scanner_origin)
    if scan.sensors is not None and len(scan.sensors) == 1:
        return scan.sensors[0]
    return None


def merge_scans(scans) -> Cloud:
    """Captures from one scanner position, as one cloud; captures in different units are refused."""
    clouds = [scans] if isinstance(scans, Cloud) else list(scans)
    if not clouds:
        raise InputError("no scan given")
    sizes = [c.diagonal() for c in clouds]
    for cloud, size in zip(clouds, sizes):
        if len(cloud) == 0:
            raise InputError(f"{cloud.name}: the scan has no points")
        if size > 0 and max(sizes) / size > INPUT_CHECKS.unit_mismatch_ratio:
            raise InputError(f"{cloud.name}: extent {size:.4g} mm against {max(sizes):.4g} mm for the other capture(s): "
                             "the scans seem to be in different units (check --units per file)")
    if len(clouds) == 1:
        return clouds[0]
    points = np.vstack([c.points for c in clouds])
    sensors, sensor_of = None, None
    if all(c.sensors is not None for c in clouds):  # each capture's own sensor positions, numbered on
        offsets = np.cumsum([0] + [len(c.sensors) for c in clouds])
        sensors = np.vstack([c.sensors for c in clouds])
        sensor_of = np.concatenate([c.sensor_indices() + k for c, k in zip(clouds, offsets)])
    return Cloud(points, name=" + ".join(c.name for c in clouds), warnings=[w for c in clouds for w in c.warnings],
                 sensors=sensors, sensor_of=sensor_of)


def _checked_toolpath(points, surface: SurfaceModel) -> np.ndarray:
    """Toolpath points (X, mm) that plausibly work on the model: a path in inches or in another frame
    lies far from the model surface and is refused before it can place anything."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    if len(points) == 0 or not np.isfinite(points).all():
        raise InputError("toolpath: points must be finite and not empty")
    distance = float(np.median(surface.tree.query(points)[0]))
    if distance > INPUT_CHECKS.toolpath_max_median_distance * surface.diagonal:
        raise InputError(f"toolpath: its points lie a median {distance:.1f} mm from the workpiece model {surface.name} "
                         f"(diagonal {surface.diagonal:.1f} mm): it is in another unit or frame than the model X-A")
    return points


def _region(scan: Cloud, regions: dict, role: str) -> np.ndarray:
    idx = regions.get(role)
    if idx is None:
        raise InputError(f"{role} region: not given (pass both regions, or none for automatic regions)")
    idx = np.asarray(idx)
    if idx.dtype == bool:
        if len(idx) != len(scan):
            raise InputError(f"{role} region: a mask of {len(idx)} values for a scan of {len(scan)} points")
        idx = np.flatnonzero(idx)
    idx = idx.astype(np.int64).ravel()
    if len(idx) == 0:
        raise InputError(f"{role} region: empty; pick the {role} in the scan or use automatic regions")
    if idx.min() < 0 or idx.max() >= len(scan):
        raise InputError(f"{role} region: indices outside the scan's {len(scan)} points")
    return np.unique(idx)


def _region_cloud(scan: Cloud, idx: np.ndarray, role: str) -> Cloud:
    return scan.subset(idx, name=f"{role} region of {scan.name}")


def _refit(scan, idx, surface, found: MatchResult, matched: np.ndarray, options: dict, role: str) -> MatchResult:
    """The match on the final region: the one that found it when it was made on the region's points
    but for a few (at most KEPT_MATCH_EXTRA of them: specks near the placed model, clusters too
    small to search, that joined it), with the robust method regions are found with (the paper's
    methods match again) and the fitness a match asks (a candidate cluster is allowed less); else a
    match again from its pose."""
    if (options.get("method", "robust") == "robust"
            and np.isin(matched, idx).all() and len(idx) - len(np.unique(matched)) <= KEPT_MATCH_EXTRA * len(idx)
            and found.fitness >= options.get("min_fitness", MatchOptions.min_fitness)):
        return replace(found, scan_name=f"{role} region of {scan.name}")
    return refit(_region_cloud(scan, idx, role), surface, found, options)


def _inputs(scan: Cloud, workpiece: SurfaceModel, reference: SurfaceModel, toolpath_points) -> dict:
    return {"scan": scan.name, "scan_points": len(scan), "workpiece_model": workpiece.name,
            "reference_model": reference.name,
            "toolpath_points": 0 if toolpath_points is None else len(toolpath_points)}


def _uncertainty(scan, regions, surfaces, matches, W, toolpath_points, options, match_options) -> dict:
    """Displacement bound of W at the toolpath and at the workpiece surface, from bootstrap refits.

    Each refit draws the points of both regions with replacement (as many as the match itself fits
    to) and refines both poses from a start nudged off the solution (half the tolerance at the model's
    edge), from the gate the match ended at (at least twice the tolerance, so that the nudge is within
    it): where the data pins a pose the refit comes back; where it leaves a motion nearly free
    the refits stay spread, and so does W (a block seen on two faces is centred between its edges
    in every refit, see edges.py, so there the spread is how well its edges place it).  The bound is
    BOOTSTRAP.factor times the RMS displacement over the refits.  The studies check it against the
    true error (docs/studies.md).  The refits run on BOOTSTRAP.refit_threads threads when BLAS is held to
    one (numpy lets go of the interpreter in their array work); the draws and nudges are made in order, so
    the bound does not depend on the threads.
    """
    rng = np.random.default_rng(options.seed + 1)
    roles = ("workpiece", "reference")
    sizes = {role: len(regions[role]) for role in roles}
    n = {role: min(sizes[role], MatchOptions.max_fine_points) for role in roles}
    workpiece_surface = surfaces[0]
    surface_points = workpiece_surface.points[
        rng.choice(len(workpiece_surface.points), min(BOOTSTRAP.surface_samples, len(workpiece_surface.points)),
                   replace=False)]
    targets = {"surface": surface_points}
    if toolpath_points is not None:
        targets["toolpath"] = toolpath_points
    spread = {k: np.zeros(len(p)) for k, p in targets.items()}
    gates = [max(2 * options.tolerance_mm, m.gate_mm) for m in matches]  # max keeps the first when gate_mm is nan
    # Two threads only with BLAS held to one (FreeCAD's workers leave BLAS alone: its own threads would spin).
    threads = BOOTSTRAP.refit_threads if options.blas_threads == 1 else 1
    refits = []
    with ThreadPoolExecutor(max_workers=threads) as pool:
        # Drawn BOOTSTRAP.drawn_at_once at a time (the draws of 100 refits are 100 MB), all of them handed to
        # the pool at once: a thread that finishes its refit starts the next without waiting for the other's.
        for first in range(0, options.resamples, BOOTSTRAP.drawn_at_once):
            jobs = [(scan.points[rng.choice(regions[role], n[role], replace=True)], surface,
                     m.matrix @ _nudge(surface, options.tolerance_mm / 2, rng), gate, options, match_options)
                    for _ in range(min(BOOTSTRAP.drawn_at_once, options.resamples - first))
                    for role, surface, m, gate in zip(roles, surfaces, matches, gates)]
            refits += pool.map(lambda job: _refit_pose(*job), jobs)
    rotations = []
    for U_r, V_r in zip(refits[0::2], refits[1::2]):
        W_r = frames.invert(V_r) @ U_r
        rotations.append(frames.rotation_between_deg(W_r, W))
        for key, p in targets.items():
            spread[key] += np.sum((frames.apply(W_r, p) - frames.apply(W, p)) ** 2, axis=1)
    out = {"method": f"bootstrap: {options.resamples} refits of both matches on {n['workpiece']} + {n['reference']} "
                     f"resampled points from nudged starts, {BOOTSTRAP.factor:g} x the RMS displacement combined with "
                     "how far a pose centred between edges can be off (a uniform error within it)",
           "rotation_bound_deg": float(BOOTSTRAP.factor * np.sqrt(np.mean(np.square(rotations))))}
    for key, total in spread.items():
        bias = edge_bias(matches, W, targets[key])
        # Three standard uncertainties: the refits' spread, and the bias as an error anywhere within +-bias
        # (a uniform one's standard uncertainty is bias / sqrt(3)); alone, the bias is covered whole.
        per_point = BOOTSTRAP.factor * np.sqrt(total / options.resamples + bias ** 2 / 3)
        out[f"{key}_bound_mm"] = float(per_point.max())
        out[f"{key}_median_mm"] = float(np.median(per_point))
        out[f"{key}_edge_bias_mm"] = float(bias.max())
    return out


def edge_bias(matches, W: np.ndarray, points_X: np.ndarray) -> np.ndarray:
    """How far (mm) each point (workpiece frame X) can be moved by the poses' bias along the motions only
    their edges hold (edges.centre_on_edges: ``bias_mm`` each way along ``twist``), summed over the
    motions of both matches.  A refit centres alike, so this is what the bootstrap's spread leaves out."""
    bias = np.zeros(len(points_X))
    in_B = frames.apply(W, points_X)
    for m, points in zip(matches, (points_X, in_B)):  # the workpiece's motions act in X, the reference's in B
        for held in (m.stability or {}).get("held_by_edges", []):
            if "twist" not in held:
                continue
            moved = [frames.apply(slide(np.asarray(held["twist"]), np.asarray(held["centre"]), s * held["bias_mm"]),
                                  points) for s in (-1.0, 1.0)]
            bias += np.max([np.linalg.norm(p - points, axis=1) for p in moved], axis=0)
    return bias


def _distortion(scan, regions, surfaces, matches, toolpath_points, options) -> dict:
    """The scan's strain against the models and the shift of W it causes (distortion.distortion), on as
    many points of each region as tell a strain that matters from its fit's noise (DISTORTION_SAMPLING.points)."""
    rng = np.random.default_rng(options.seed)
    points = []
    for idx, m in zip((regions["workpiece"], regions["reference"]), matches):
        noise_factor = (m.rms_mm / DISTORTION_SAMPLING.rms_mm) ** 2 if np.isfinite(m.rms_mm) else np.inf
        n = int(min(MatchOptions.max_fine_points, np.ceil(DISTORTION_SAMPLING.points * max(noise_factor, 1.0))))
        points.append(scan.points[pointops.random_subset(idx, n, rng)])
    targets = surfaces[0].points if toolpath_points is None else toolpath_points
    # Each gate the widest of its match's own (every point the match was finished on stays), twice the
    # tolerance and three RMS (where the tolerance is below the noise: the gates fail it then).  Not
    # narrower: a 2 % scale put the ends of the reference 1.2 mm off it, beyond 0.6 mm, and the points left
    # near its middle showed no strain.
    gates = [float(np.nanmax([2 * options.tolerance_mm, 3 * m.rms_mm, m.gate_mm])) for m in matches]
    return distortion(points, surfaces, [m.matrix for m in matches], targets, gates)


def _refit_pose(points: np.ndarray, surface: SurfaceModel, start: np.ndarray, gate: float,
                options: CalibrationOptions, match_options: dict) -> np.ndarray:
    """U refined on resampled region points from a nudged start, the way a match refines a given
    pose (coarse to fine on a medium subset from ``gate``, then match.refine_given: finished on all
    the points, refined again from a wider gate) without the verdict around it: a refit needs the pose
    alone.  The paper's methods refit through their match."""
    if options.method != "robust":
        return match_pose(Cloud(points, name="resample"), surface, start, **match_options)
    rng = np.random.default_rng(options.seed)
    medium = pointops.random_subset(points, REFINE.medium_points, rng)
    state = coarse_to_fine([medium], surface, frames.invert(start), gate, surface.spacing)
    return frames.invert(refine_given(state, medium, points, surface, options.tolerance_mm).T)


def _nudge(surface: SurfaceModel, size_mm: float, rng: np.random.Generator) -> np.ndarray:
    """A random rigid motion (model frame) moving the model's points by about ``size_mm``: a turn
    about its centre that moves its edge by that much, and a shift of that size."""
    centre = surface.centre
    axis = rng.normal(size=3)
    angle = np.degrees(size_mm / (surface.diagonal / 2))
    turn = frames.rigid(frames.from_rotvec(np.radians(angle) * axis / np.linalg.norm(axis))[:3, :3])
    shift = rng.normal(size=3)
    return frames.rigid(translation=centre + size_mm * shift / np.linalg.norm(shift)) @ turn @ frames.rigid(
        translation=-centre)


def _quality_gates(U_match: MatchResult, V_match: MatchResult, uncertainty: dict, tolerance: float,
                   unexplained: dict) -> list:
    """The gates a calibration passes to be "ok", each with a stable "code" (its failing Reason's);
    ``unexplained``: per role, its region's points off its placed model (off_model.OffModel), for what
    to change when too many are."""
    gates = []
    for role, m in (("workpiece", U_match), ("reference", V_match)):
        gates.append({"code": status_gate_code(role), "name": f"{role} match status", "value": m.status, "limit": OK,
                      "passed": m.status == OK, "unit": ""})
        gates.append({"code": f"{role}_{RMS}", "name": f"{role} RMS", "value": m.rms_mm, "limit": tolerance,
                      "passed": bool(np.isfinite(m.rms_mm) and m.rms_mm <= tolerance), "unit": "mm"})
        share = LOCATE.min_within_tolerance_pct[role]
        gates.append({"code": f"{role}_{WITHIN_TOLERANCE}", "name": f"{role} points within tolerance",
                      "value": m.within_tolerance_pct, "limit": share, "passed": bool(m.within_tolerance_pct >= share),
                      "unit": "%"})
        gates.append({"code": f"{role}_explained", "name": f"{role} region explained by its model",
                      "value": round(100 * m.fitness, EXPLAINED_DIGITS), "limit": 100 * LOCATE.min_fitness[role],
                      "passed": bool(m.fitness >= LOCATE.min_fitness[role]), "unit": "%",
                      "why": unexplained[role].said(role)})
    key = "toolpath_bound_mm" if "toolpath_bound_mm" in uncertainty else "surface_bound_mm"
    where = "toolpath" if key.startswith("toolpath") else "workpiece surface"
    value = uncertainty[key]
    gates.append({"code": UNCERTAINTY, "name": f"uncertainty at the {where}", "value": value, "limit": tolerance,
                  "passed": bool(value <= tolerance), "unit": "mm"})
    # A distortion's shift is a bias the bootstrap cannot see: it has what the spread leaves of the tolerance.
    shift, limit = uncertainty["distortion_shift_mm"], max(tolerance - value, 0.0)
    gates.append({"code": DISTORTION, "name": f"shift of W by the scan distortion at the {where}", "value": shift,
                  "limit": round(limit, 4), "passed": bool(shift <= limit), "unit": "mm",
                  "why": f"the scan is {uncertainty['distortion_scale_pct']:+.2f} % in scale and strained up to "
                         f"{uncertainty['distortion_strain_pct']:.2f} % against the models: is the scanner's "
                         "calibration off, or a model's size?"})
    return gates


def _status(U_match: MatchResult, V_match: MatchResult, gates: list) -> tuple[str, list]:
    reasons = [r.within(f"{role} match", role) for role, m in (("workpiece", U_match), ("reference", V_match))
               for r in m.reasons]
    numeric_failures = [g for g in gates if not g["passed"] and g["unit"]]
    reasons += [Reason(g["code"], f"{g['name']} {g['value']:.3f} {g['unit']} is outside the limit {g['limit']} "
                                  f"{g['unit']}" + (f"; {g['why']}" if "why" in g else "")) for g in numeric_failures]
    if FAILED in (U_match.status, V_match.status) or numeric_failures:
        return FAILED, reasons
    if AMBIGUOUS in (U_match.status, V_match.status):
        return AMBIGUOUS, reasons
    return OK, reasons
