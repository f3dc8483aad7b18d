"""Find U = ^S X, the pose that places a model into a scan: global search, refinement, verdict.

The work happens with scan points moved onto the model (scan -> model), because the model is the
complete surface: every scan point of the part has a true mate on it and clutter has none.  The
result reports U = (scan -> model)^-1.

The search compares poses by how many scan points they put on the model (weighted by closeness),
never by the fraction of the scan: clutter around the part dilutes every pose alike.  The verdict
then judges the best pose and its rivals (other poses of the search, and the model's near-symmetric
turns, always tried) by what the sensor should have seen from each (visibility.py): scan points on
the model's visible surface count for a pose, scan points it would hide and model surface missing
from the scan count against it.  When the verdict's best does not fit the scan within its limit,
the search runs once more with more hypotheses (only such scans pay for it; not where
MatchOptions.search_again is off, as for a calibration's clusters that may hold another object).
A pose is "ok" only when it explains the scan to within the scan's own noise, which must not
exceed the tolerance, covers a real part of the model, leaves no large share of the view
contradicted, pins every motion, and no rival is within the statistical noise of its evidence
(given the number of view cells and the measured noise) or better by the scan points it leaves far off the part (far_off_test).
The verdict's best has its near-symmetric turns tried again, each refined exactly like it, and so are
the search's turned rivals near it by the view (Judge._with_turns): one of them is the right pose when
the search handed over a flip, and only such a pose, as converged as the best and with both fitting
within FAR_OFF.fit noises, is no rival when it leaves significantly more points far off (or takes the
best's place when it leaves significantly fewer); a pose fitting worse than that is first tried for a
slide home (_slid_home), unless it misses the scan by more than REFINE.hopeless_fit times the verdict's
limit (nor is such a pose taken to the exact surface: a wrong model's poses are all such, and are
failed in seconds); a model that is symmetric (symmetry.py) makes every match ambiguous and the result names the
symmetry.  Otherwise the match fails or is ambiguous and says why.
"""
from __future__ import annotations

import time
from contextlib import contextmanager
from dataclasses import dataclass, replace
from statistics import NormalDist

import numpy as np

from . import frames, global_search, pointops, visibility
from .global_search import COARSE_VOXELS_PER_DIAGONAL
from .edges import centre_on_edges, has_weak_motion, slide, unit_twist
from .errors import InputError, Stopped
from .geometry import SHAPE_WORDS, Cloud, checked, shape_kind
from .refine import coarse_to_fine, refine, refine_exact
from .result import (AMBIGUOUS, BEHIND_SURFACE, FACE_CONTINUED, FAILED, FEW_POINTS, LOW_COVERAGE, MISFIT, NO_POSE,
                     NOISE_ABOVE_TOLERANCE, NOT_A_SURFACE, OK, OTHER_SIDE, OUTLINE_CONTINUED, RIVAL, RMS, SCAN_NOT_SOLID,
                     SYMMETRIC, THIN_WALL, THROUGH_SUPPORT, UNDER_CONSTRAINED, VIEW_CONTRADICTED, WITHIN_TOLERANCE,
                     Candidate, MatchResult, Reason, codes)
from .robust import MAD_TO_SIGMA
from .stability import gelfand, stability
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
    # A distinct pose is a rival (-> ambiguous) unless its view evidence is this many standard errors
    # below the best's; ``ambiguity_ratio``, if set, also makes any pose scoring at least that
    # fraction of the best a rival (a fixed margin on top of the test).
    rival_significance: float = 3.0
    ambiguity_ratio: float | None = None
    viewpoint: tuple | None = None  # the sensor's position in the scan's frame (mm); None: estimated
    # The plane the part stands on, when known (a calibration's platform): (a point on it, its normal up
    # towards the part, its band in mm), in the scan's frame; None: the scan's largest plane wider than the model.
    support: tuple | None = None
    min_fitness: float = 0.1  # fraction of the scan's points that must lie on the model
    min_coverage: float = 0.05  # fraction of the model surface that must be seen
    # Whether "ok" asks the RMS and the share within the tolerance that a calibration asks of a region
    # (VERDICT.min_within_tolerance_pct); a calibration's own matches leave it to its gates, which ask it after
    # the scan's distortion has been read (a scaled scan misfits, and says why there).
    tolerance_gates: bool = True
    max_fine_points: int = 20000  # the final pass uses a random subset of this size (statistics: VERDICT.points)
    # Whether a search whose verdict's best misfits the scan searches once more (SEARCH.retry_samples); a
    # calibration's search of a cluster that may hold another object does not (regions.match_trusted).
    search_again: bool = True
    seed: int = 0
    blas_threads: int | None = 1  # OpenBLAS threads while matching (pointops.blas_threads); None: leave them


@dataclass(frozen=True)
class SearchSettings:
    """The global search: RANSAC's hypotheses, the candidates refined from them, the retry."""

    # RANSAC poses kept by their votes, the distinct ones of them checked against the geometry, on at
    # most this many coarse scan points.
    ransac_kept: int = 200
    ransac_verified: int = 30
    verify_points: int = 600
    # Fewest coarse points worth describing by features, and how much finer than the default grid
    # the global search may go to get them.
    min_coarse_points: int = 350
    max_voxel_refinement: float = 2.0
    # RANSAC poses verified within this fraction of the best are refined (a symmetric twin scores as
    # much as the best; the half turns of a symmetric model are also tried after refinement).
    candidate_floor: float = 0.7
    # The best this many of them by that check are first taken quick_iterations steps towards the scan and
    # checked again, and the best ``MatchOptions.candidates`` of those are refined in full: a rough pose's
    # score says little of where it settles (an L-block seen low from its outer side ranks its right pose
    # behind many wrong turns until each has taken a few steps).
    pre_refined: int = 12
    quick_iterations: int = 10
    # Two hypotheses are one pose unless they differ by more than this turn (deg) or this share of the model
    # diagonal at the scan's centre; refined poses, by the finer pair.
    hypotheses_apart: tuple = (15.0, 0.1)
    refined_apart: tuple = (5.0, 0.05)
    # A search whose best pose does not fit the scan within the verdict's limit is run once more with
    # this many times the RANSAC hypotheses (unless MatchOptions.search_again is off).
    retry_samples: int = 5


SEARCH = SearchSettings()


@dataclass(frozen=True)
class RefineSettings:
    """Refinement: the points it runs on, the final polish, the widened gate and the slide home."""

    # Points of the middle refinement stage, where the gate shrinks: enough to average the noise.
    medium_points: int = 3000
    # Steps of the final robust pass on all the fine points, from a pose already within their noise.
    polish_iterations: int = 2
    # The verdict refines the best pose again from this many times its final gate, on this many points,
    # when at least misfit_share of its view cells show it a little off (see Judge.rank).
    wider_gate: float = 8.0
    wider_points: int = 500
    misfit_share: float = 0.01
    # A pose fitting worse than FAR_OFF.fit noises may rest in a local minimum a slide from home (a curved tile
    # turned along its curve): it is refined again from these shifts (mm RMS over its matched points) either way
    # along each motion of its fit, and the best of those replaces it when its residual scale is at most home_gain
    # times its own.
    home_shifts_mm: tuple = (2.0, 3.0)
    home_gain: float = 0.5
    # A pose missing the verdict's limit (VERDICT.max_noise_ratio noises plus the tolerance) by more than this
    # factor is no slide from fitting: it is neither slid home nor taken to the exact surface (costly on a mesh).
    hopeless_fit: float = 2.0
    # prepare fills the cell grids of the first prepared_levels levels: gates up to 4 x GATE_CELLS sample
    # spacings, 6 coarse voxels at the default voxel (a depth camera's tolerance asks for such gates).
    prepared_levels: int = 3


REFINE = RefineSettings()


@dataclass(frozen=True)
class VerdictSettings:
    """The verdict: the scan's noise and the points it is judged on, and what "ok" asks of a pose."""

    # Patches the scan's noise is measured on, points the statistics of the verdict are taken over (a
    # random subset: percentages to about half a percent), and points poses are weighed on (a few per
    # view cell) unless the call is close (see Judge._level).
    noise_probes: int = 300
    points: int = 10000
    evidence_points: int = 5000
    # A placed model must explain the scan to within its own noise: the robust residual scale may be
    # at most this many times the scan's noise (from local quadric fits) plus the tolerance.
    max_noise_ratio: float = 3.0
    # A match is "ok" only when at least this share (%) of its matched points lies within the tolerance,
    # as a calibration's workpiece region must (the reference must have more: regions).
    min_within_tolerance_pct: float = 50.0
    # Points that scatter about local quadric fits by more than this fraction of the fit's radius
    # are a volume, not a surface (surface scans, noisy sparse ones included, scatter far less).
    max_scatter: float = 0.3
    # The view evidence: a scan point counts fully on the model surface and nothing at evidence_sigmas
    # times the residual scale (the larger of the best pose's and the scan's and model's own noise).
    evidence_sigmas: float = 3.0
    # Least variance of one view cell's evidence difference between two poses (model and scan sampling):
    # a difference of under about 3 % of the cells is never significant.
    cell_variance_floor: float = 0.01
    # A pose contradicting more than this share of its view (scan points it would hide, surface it
    # should show missing) leaves a large part of the scan unexplained: the match fails.
    max_contradicted: float = 0.1
    # A part is thin (a plate, a shell: a scan of one face may be laid on the other) when its wall across
    # (SurfaceModel.wall_across) is thinner than thin_part of its diagonal, below solid bodies' and above shells';
    # the wall behind a scan is then measured where it lies, and is a wall up to thin_wall_diagonals.
    thin_part: float = 0.08
    thin_wall_diagonals: float = 0.25
    # Where the wall the scan sees is thinner than this many times the noise, which of its faces the scan
    # shows cannot be told (a thin plate or shell seen face-on through a noisy sensor): ambiguous.
    thin_wall_noises: float = 5.0


VERDICT = VerdictSettings()


@dataclass(frozen=True)
class RivalSettings:
    """Rivals of the best pose: global candidates and the model's near-symmetric turns."""

    # Global candidates and near-symmetric turns scoring below this fraction of the best are not
    # refined further: after the coarse stage they cannot come close to it.  Turns are scored on this
    # many points, and refined from this share of the model's diagonal (a turn about an axis a little off
    # lands that far from its home).
    floor: float = 0.6
    turn_points: int = 1000
    turn_gate: float = 0.25
    # Turns that start within this angle (deg) and share of the diagonal of each other are refined as one
    # (from turn_gate they end as one), first on quick_turn_points; a refined turn is a rival only when it
    # explains at least turn_floor of what the best explains at its gate and its residual scale is at most
    # turn_sigmas times the best's (a converged pose that leaves more unexplained, or fits that much worse,
    # is many standard errors behind by the view).
    turns_apart: tuple = (10.0, 0.1)
    quick_turn_points: int = 300
    turn_floor: float = 0.85
    turn_sigmas: float = 3.0
    # A pose in doubt has itself, its rivals and their turns moved, each by the shift (on a grid of
    # shift_voxels coarse voxels a step, at most shift_steps each way, out to shift_reach of the diagonal)
    # that most pairs of shift_points scan points and shift_samples model samples vote for, and the
    # shifts_refined with most votes refined: a part seen in part maps onto itself about another axis than
    # the whole model, and its turn lands too far from home to slide there.  One that explains shift_gain
    # times as much of the scan as the best is judged with it.
    shift_points: int = 50
    shift_samples: int = 1500
    shift_voxels: float = 2.0
    shift_steps: int = 5
    shift_reach: float = 0.25
    shift_gain: float = 1.1
    shifts_refined: int = 3
    # A rival of the search turned more than this (deg) from the best is refined to convergence like the
    # best's turns when it comes near it by the view (Judge._refine_rivals); one turned less is the best
    # laid through its wall, or slid, and stays as found.
    min_rival_turn_deg: float = 2.0


RIVALS = RivalSettings()


@dataclass(frozen=True)
class FarOffSettings:
    """The far-off test (far_off_test): which of two poses leaves more scan points far off the part."""

    # A scan point counts against a pose from VERDICT.evidence_sigmas residual scales off its surface, fully
    # from this many (further off is no further evidence: an outlier is an outlier).
    sigmas: float = 10.0
    # Up to this many points differing between two poses, the far-off test's chance is exact (all 2^n
    # sign patterns, their weights on a grid of 1/sign_flip_steps: sign_flip_z); beyond, its normal approximation.
    exact_sign_flips: int = 64
    sign_flip_steps: int = 256
    # The far-off test rules out a pose refined like the best only when the best's residual scale is at most
    # this many times the noise: right poses fit within it, a pose slid along a curved part (held by a few
    # points) does not.
    fit: float = 2.0


FAR_OFF = FarOffSettings()


@dataclass(frozen=True)
class ViewSettings:
    """The view: what the sensor should see of a placed model, from where, in how many pixels."""

    # Model samples a view is rendered from: quickly, and for a close call (within close_call times the
    # rival significance).
    samples: int = 6000
    samples_fine: int = 24000
    close_call: float = 2.0
    # View pixels: at least this many spacings of the verdict's scan points, and of the model's view
    # samples (so a surface covers its pixels), and no more than max_pixels over the scan.
    pixel_scan_spacings: float = 1.25
    pixel_model_spacings: float = 2.0
    max_pixels: int = 8000
    # An estimated viewpoint sits this many scan extents from the matched points, along their mean
    # normal; when more than max_facing_away of them face away from it, the scan was not taken from one
    # viewpoint (merged views) and the verdict falls back to scan points without visibility.
    distance_extents: float = 3.0
    max_facing_away: float = 0.2
    # The viewpoint is implied by the normals of samples inside faces, at least the gate or face_spacings
    # model spacings from a crease; unless fewer than min_on_faces of the matched samples lie so (a curved model).
    face_spacings: float = 2.0
    min_on_faces: float = 0.5
    # Before a pose is failed for contradicting the view, the view is tried again from an estimated
    # viewpoint turned by this angle and twice it (see Judge.least_contradicted).
    settle_step_deg: float = 15.0


VIEW = ViewSettings()


@dataclass(frozen=True)
class OutlineSettings:
    """The outline: scanned surface going on past a placed model's faces, and points behind its surface."""

    # When the scanned surface goes on past its outline along more than this share of it, the outline may be
    # misplaced (or another object lies flush with the part): the match is ambiguous.
    max_continued: float = 0.03
    # A pose leaves scan points continuing a model face past its edge (Judge.continued_faces): more than
    # max_continued_points of the verdict's points (and at least min_continued_points) make it ambiguous.
    max_continued_points: float = 0.03
    min_continued_points: int = 10
    # The cell grid levels whose lookups clear points for that check: those a 0.3 mm calibration fills
    # anyway (a coarser level would be filled, and kept in the model cache, for the check alone).
    grid_levels: int = 2
    # A face is flat where its samples' normals agree over flat_spacings model spacings (its edge
    # band is that wide); points beside it lie within reach_spacings scan spacings of the mesh
    # (a sparse scan's first point past an edge) and at most reach_samples model spacings, each
    # weighed against its ``samples`` nearest samples there, for at most ``seeds`` points (a
    # scan far sparser than the model asked for millions of pairs); runs of points in a plane are joined
    # across gaps of link_spacings scan spacings.  A face faces the sensor when its normal is
    # within 84 deg of the direction to it (a side face seen grazing counts; the view's own test,
    # visibility.FACING_COS, lets samples a little past grazing into the z-buffer).
    flat_spacings: float = 2.0
    reach_spacings: float = 3.0
    reach_samples: float = 12.0
    link_spacings: float = 4.0
    facing_cos: float = 0.1
    planes: int = 8
    seeds: int = 200
    samples: int = 256
    # A pose whose outline, seen from the sensor, holds more than this share of scan pixels whose points
    # lie behind its surface, inside the part (within off_band_gates evidence gates: further behind they
    # are hidden, a contradiction), leaves a large share of the scan unexplained: ambiguous.
    max_off: float = 0.1
    off_band_gates: float = 10.0


OUTLINE = OutlineSettings()


@dataclass(frozen=True)
class SupportSettings:
    """The plane the part stands on: which model faces rest on it, how far a pose may reach through it."""

    # A model face in the support's plane rests on it when its normal is within 60 deg of pointing into it.
    resting_cos: float = 0.5
    # A placed model may reach this many tolerances through the plane its scan's other points stand on (a table
    # wider than the model, _depth_through_support): right poses stay within it, shells slid along their bend do not.
    tolerances: float = 3.0
    # The fits leave out the support's points within this many noises of its plane (and within its band): the
    # table's scatter, but not more of a low part's own sides (a plate's), which hold its turn in the plane.
    band_noises: float = 2.5


SUPPORT = SupportSettings()


def match(scan: Cloud, model, init: np.ndarray | None = None, options: MatchOptions = MatchOptions(),
          stop=None, **overrides) -> MatchResult:
    """Match ``model`` (a Cloud or a prepared SurfaceModel, frame X) into ``scan`` (frame S).

    ``init``, when given, is a guess of U and replaces the global search.  Keyword overrides set
    MatchOptions fields.  Bad input raises InputError; a match that cannot be trusted comes back
    with status "failed" or "ambiguous" and the reasons.  ``stop`` (a threading.Event), once set,
    ends the match with errors.Stopped at the start of its next phase, or of the verdict's next pose
    (a search nobody waits for any more).
    """
    options = _checked_options(replace(options, **overrides))
    with pointops.blas_threads(options.blas_threads):
        result = _match(scan, model, init, options, stop=stop)
    pointops.hand_back_freed_heap()  # scan after scan: each match's temporaries are not carried into the next
    return result


def match_pose(scan: Cloud, model, init: np.ndarray, options: MatchOptions = MatchOptions(),
               **overrides) -> np.ndarray | None:
    """U exactly as ``match(scan, model, init)`` finds it, without the statistics and the verdict that
    follow once the pose is chosen (a bootstrap refit needs the pose alone); None where ``match``
    gives no matrix."""
    options = _checked_options(replace(options, **overrides))
    with pointops.blas_threads(options.blas_threads):
        found = _match(scan, model, init, options, pose_only=True)
    return found.matrix if isinstance(found, MatchResult) else found


def _match(scan: Cloud, model, init, options: MatchOptions, pose_only: bool = False, stop=None):
    timer = PhaseTimer(stop)
    with timer("model"):
        surface = model if isinstance(model, SurfaceModel) else SurfaceModel(checked(model, 3), options.seed)
    scan = checked(scan, MIN_SCAN_POINTS)
    rng = np.random.default_rng(options.seed)
    result = dict(method=options.method, scan_name=scan.name, model_name=surface.name,
                  tolerance_mm=options.tolerance_mm, n_scan_points=len(scan), seed=options.seed,
                  warnings=list(scan.warnings), timings_s=timer.phases)
    kind = shape_kind(scan.points)
    pointops.hand_back_freed_heap()  # the whole scan's checks are done: their temporaries would stay resident
    if kind != "solid":
        return MatchResult(FAILED, matrix=None, time_s=timer.total(), **result,
                           reasons=[Reason(SCAN_NOT_SOLID, f"{scan.name}: the scan points lie {SHAPE_WORDS[kind]}; "
                                                           "they cannot fix a pose")])
    fine = pointops.random_subset(scan.points, options.max_fine_points, rng)
    medium = pointops.random_subset(fine, REFINE.medium_points, rng)
    probes, probe_noise, probe_radius = pointops.local_noise(medium, rng, probes=VERDICT.noise_probes)
    noise, patch = (float(np.median(probe_noise)), float(np.median(probe_radius))) if len(probes) else (np.inf, 0.0)
    if not noise <= VERDICT.max_scatter * patch:
        return MatchResult(FAILED, matrix=None, time_s=timer.total(), **result,
                           reasons=[Reason(NOT_A_SURFACE, f"{scan.name}: the points do not lie on a surface (they "
                                                          f"scatter {noise:.2f} mm about local fits {patch:.2f} mm "
                                                          "across); a scan samples a surface")])

    # A coarse voxel finer than the scan's spacing leaves one point per voxel and features with too
    # few neighbours; the 12th neighbour of a surface point lies about two spacings away, and the
    # medium subset is sparser than the scan by the square root of their sizes (a surface).
    spacing = patch / 2 * np.sqrt(len(medium) / len(scan))
    voxel = options.coarse_voxel_mm or max(surface.diagonal / COARSE_VOXELS_PER_DIAGONAL, 1.5 * spacing)
    fit_limit = VERDICT.max_noise_ratio * noise + options.tolerance_mm  # the verdict's limit on the residual scale
    hopeless = REFINE.hopeless_fit * fit_limit
    if init is None:
        with timer("global search"):
            starts = _global_candidates(scan.points, surface, voxel, options, rng, min_voxel=1.5 * spacing)
        if not starts:
            return MatchResult(FAILED, matrix=None, time_s=timer.total(), **result,
                               reasons=[Reason(NO_POSE, "global search found no consistent pose: the scan may not "
                                                        "contain the model")])
        gate = voxel / 2  # where the coarse refinement of the global candidates left off
    else:
        starts = [(frames.invert(frames.as_transform(init, "initial guess")), 1.0)]
        gate = voxel  # a guess may be off by a few millimetres

    pointops.hand_back_freed_heap()  # the global search's temporaries: refinement's would pile on them
    sample, noise_points = fine[:VERDICT.points], medium[probes]
    support = (Support.given(sample, *options.support) if options.support is not None
               else Support.of(sample, voxel, surface.diagonal, options.seed))
    # The fits see the part, not what it stands on: the support's points by its foot would pull it
    # along the plane or tilt it.  The verdict weighs the whole scan, the support included.
    band = SUPPORT.band_noises * noise
    fine, medium = _off_support(fine, support, band), _off_support(medium, support, band)
    turned = {}  # pose (its bytes) -> its turns refined (_near_symmetric_turns): the verdict asks again for the best's

    def turns_of(state):
        key = state.T.tobytes()
        if key not in turned:
            timer.check()
            turned[key] = _near_symmetric_turns(state, medium, surface, gate, fit_limit)
        return turned[key]

    with timer("refine"):
        best, rivals = _refine(options.method, starts, medium, fine, surface, gate, options.tolerance_mm, hopeless,
                               turns_of)

    def judged(best, rivals):
        """(Judge, best, its ranking) of a best pose and its rivals (see Judge.rank)."""
        judge = Judge(sample, surface, (noise_points, probe_noise), spacing * np.sqrt(len(scan) / len(sample)),
                      options, [], support)

        def polish(state):
            timer.check()
            return _polish(state, fine, surface, options.tolerance_mm, hopeless)

        def widen(state):
            timer.check()  # a pose at a time: the verdict is the longest phase
            return _widened(state, medium, surface)

        def finish(state):
            return refine_given(state, medium, fine, surface, options.tolerance_mm, hopeless)

        return (judge, *judge.rank(best, rivals, polish, widen,
                                   lambda state: _through_the_wall(state, medium, surface, gate), turns_of, finish,
                                   lambda state, noise: _slid_home(state, medium, surface, noise, polish, hopeless)))

    with timer("verdict"):
        judge, chosen, ranking = judged(best, rivals)
    weighed = [best] + rivals  # the poses handed to the verdict (RefineStates; its best may be another)
    if (init is None and options.search_again and not chosen.sigma <= fit_limit
            and judge.scan_noise <= options.tolerance_mm):
        # The verdict's best does not fit the scan: the feature votes missed the pose (a scan that
        # sees little of the model).  Search once more, drawing SEARCH.retry_samples times as many
        # hypotheses (only such scans pay for it; not one noisier than the tolerance, which fails
        # whatever the pose).  When its best explains more scan points within the
        # limit, it is judged with its rivals, the first verdict's best and the first search's rivals
        # (one of them may be a flip of it); otherwise the first verdict stands, as without the second search.
        with timer("search again"):
            more = replace(options, ransac_samples=SEARCH.retry_samples * options.ransac_samples)
            again = _global_candidates(scan.points, surface, voxel, more, rng, min_voxel=1.5 * spacing)
            if again:
                retried, retried_rivals = _refine(options.method, again, medium, fine, surface, gate,
                                                  options.tolerance_mm, hopeless, turns_of)
                first, second = inlier_scores(medium, surface, [chosen.T, retried.T], fit_limit)
        if again and second > first:
            with timer("verdict"):
                weighed += [chosen, retried] + retried_rivals
                judge, chosen, ranking = judged(retried, [chosen] + rivals + retried_rivals)
    if pose_only:
        return frames.invert(chosen.T)
    warnings = result.pop("warnings")

    def verdict_of(judge, chosen, ranking):  # each verdict appends to a list of its own
        with timer("verdict"):
            return _verdict(scan, sample, surface, chosen, ranking, judge, options, voxel,
                            {**result, "warnings": warnings + judge.warnings}, timer)

    verdict = verdict_of(judge, chosen, ranking)
    # A pose in doubt for more than the model's symmetry may be a turn of the part seen (_shifted_turn):
    # judged again with every pose weighed before, its verdict stands unless it fails.  Not a thin part's:
    # laid on its wall's other face, a pose explains as many points, so a count cannot tell the faces.
    if (verdict.status == AMBIGUOUS and init is None and options.method == "robust"
            and set(codes(verdict.reasons)) != {SYMMETRIC}
            and not surface.wall_across < VERDICT.thin_part * surface.diagonal):
        with timer("turns shifted"):
            shifted = _shifted_turn(chosen, weighed, medium, surface, voxel, fit_limit)
        if shifted is not None:
            with timer("verdict"):
                shifted = refine_given(shifted, medium, fine, surface, options.tolerance_mm, hopeless)
                again = verdict_of(*judged(shifted, [chosen] + weighed))
            verdict = again if again.status != FAILED else verdict
    verdict.time_s = timer.total()
    return verdict


def prepare(surface: SurfaceModel) -> SurfaceModel:
    """Compute ahead of time everything model-side a match may use: the coarse features at the
    default voxel and the finer ones a partial scan may ask for, the whole nearest-sample grids
    the refinement looks up and a mesh's BVH for exact distances (the symmetries and view samples
    are found when the SurfaceModel is made).  A batch of matches against one model then pays for it once;
    without it the same work is done lazily, a little in each match (seconds for ~100k samples)."""
    voxel = surface.diagonal / COARSE_VOXELS_PER_DIAGONAL
    while voxel >= surface.diagonal / COARSE_VOXELS_PER_DIAGONAL / SEARCH.max_voxel_refinement:
        surface.coarse(voxel)
        voxel /= 1.25
    for level in range(REFINE.prepared_levels):
        surface.grid_level(level).precompute()
    surface.build_exact()
    pointops.hand_back_freed_heap()  # the building's temporaries: a kept model's process need not hold them
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
    if options.viewpoint is not None and not (np.shape(options.viewpoint) == (3,)
                                              and np.isfinite(np.asarray(options.viewpoint, float)).all()):
        raise InputError(f"viewpoint must be three finite coordinates in mm, got {options.viewpoint!r}")
    if options.support is not None and not (
            len(options.support) == 3 and all(np.shape(v) == (3,) for v in options.support[:2])
            and np.isfinite(np.concatenate([np.asarray(v, float) for v in options.support[:2]])).all()
            and np.linalg.norm(options.support[1]) > 0 and float(options.support[2]) >= 0):
        raise InputError(f"support must be (a point, a direction up, a band in mm), got {options.support!r}")
    if not options.rival_significance > 0:
        raise InputError(f"rival significance must be > 0 standard errors, got {options.rival_significance}")
    return options


class PhaseTimer:
    """Wall time per named phase, for the result's timings and the benchmark; a phase does not start
    once ``stop`` (a threading.Event) is set: errors.Stopped instead."""

    def __init__(self, stop=None):
        self.started = time.perf_counter()
        self.phases: dict[str, float] = {}
        self.stop = stop

    def check(self, before: str = "its next step") -> None:
        if self.stop is not None and self.stop.is_set():
            raise Stopped(f"match stopped before {before}: nothing waits for it any more")

    @contextmanager
    def __call__(self, name: str):
        self.check(f"its {name}")
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.phases[name] = self.phases.get(name, 0.0) + time.perf_counter() - t0

    def total(self) -> float:
        return time.perf_counter() - self.started


def _global_candidates(points: np.ndarray, surface: SurfaceModel, voxel: float, options: MatchOptions,
                       rng: np.random.Generator, min_voxel: float = 0.0) -> list[tuple[np.ndarray, float]]:
    """Distinct scan -> model poses from feature RANSAC, each refined on the coarse grid, with
    their scores, best first."""
    coarse = global_search.coarse_points(points, voxel)
    # A small piece of the model (partial overlap) leaves too few coarse points to describe:
    # refine the grid for it, down to SEARCH.max_voxel_refinement times finer but not below ``min_voxel``.
    finest = max(min_voxel, voxel / SEARCH.max_voxel_refinement)
    while len(coarse) < SEARCH.min_coarse_points and voxel / 1.25 >= finest:
        voxel /= 1.25
        coarse = global_search.coarse_points(points, voxel)
    coarse = global_search.without_large_plane(coarse, voxel, surface.diagonal, rng)
    pointops.hand_back_freed_heap()  # the whole scan's voxel grid is done: its temporaries would stay resident
    if len(coarse) < 10:
        return []
    features, normals = global_search.describe_scan(coarse, voxel)
    model_points, model_normals, model_features = surface.coarse(voxel)
    si, mi, side = global_search.feature_correspondences(features, model_features)
    poses, votes = global_search.ransac_poses(coarse[si], model_points[mi], side[:, None] * normals[si],
                                              model_normals[mi], 1.5 * voxel, rng, samples=options.ransac_samples,
                                              keep=SEARCH.ransac_kept, min_edge=3 * voxel)
    if len(poses) == 0:
        return []
    probe = pointops.random_subset(coarse, SEARCH.verify_points, rng)
    centre = probe.mean(axis=0)
    # Many hypotheses are near copies of the best one; a symmetric twin must not be crowded out.
    angle, share = SEARCH.hypotheses_apart
    poses = poses[global_search.distinct(poses, votes, centre, angle, share * surface.diagonal, SEARCH.ransac_verified)]
    verified = inlier_scores(probe, surface, poses, 1.5 * voxel)
    keep = [i for i in global_search.distinct(poses, verified, centre, angle, share * surface.diagonal)
            if verified[i] >= SEARCH.candidate_floor * verified.max()][:SEARCH.pre_refined]
    stepped = [refine(probe, surface, poses[i], 3 * voxel, voxel, SEARCH.quick_iterations, 1e-3).T for i in keep]
    rescored = inlier_scores(probe, surface, stepped, voxel)
    keep = global_search.distinct(stepped, rescored, centre, angle, share * surface.diagonal, options.candidates)
    refined = [coarse_to_fine([probe], surface, stepped[i], 3 * voxel, voxel / 2).T for i in keep]
    scores = inlier_scores(probe, surface, refined, voxel)
    angle, share = SEARCH.refined_apart
    order = global_search.distinct(refined, scores, centre, angle, share * surface.diagonal)
    return [(refined[i], float(scores[i])) for i in order if scores[i] > 0]


def _refine(method: str, starts, medium: np.ndarray, fine: np.ndarray, surface: SurfaceModel, gate: float,
            tolerance: float, hopeless: float, turns_of):
    """The best pose refined on all the fine points, and the distinct rivals refined on the medium
    ones (RefineStates, scan -> model).

    Every start within RIVALS.floor of the best coarse score is refined on the medium points first
    and the winner is chosen at the tightest gate any of them reached: coarse scores of a wrong pose
    can tie with the right one, but only the right one brings the residuals down to the noise.
    The near-symmetric turns of the winner (``turns_of``: _near_symmetric_turns) are tried as rivals
    too.  ``hopeless``: see _polish.
    """
    contenders = [T for T, score in starts if score >= RIVALS.floor * starts[0][1]]
    if len(contenders) == 1 and method != "robust":
        states = []
    else:
        states = [coarse_to_fine([medium], surface, T, gate, surface.spacing) for T in contenders]
        scores = inlier_scores(medium, surface, [s.T for s in states], min(s.gate for s in states))
        angle, share = SEARCH.refined_apart
        order = global_search.distinct([s.T for s in states], scores, medium.mean(axis=0), angle, share * surface.diagonal)
        contenders, states = [contenders[i] for i in order], [states[i] for i in order]
    if method == "robust":
        best = _polish(states[0], fine, surface, tolerance, hopeless)
    else:
        from .paper_methods import refine_paper

        best = refine_paper(method, fine, surface, contenders[0], gate)
    poses = [best] + states[1:] + turns_of(best)
    # In this order of preference, drop every pose that repeats an earlier one.
    keep = global_search.distinct([p.T for p in poses], -np.arange(len(poses)), medium.mean(axis=0), 5.0,
                                  0.05 * surface.diagonal)
    return best, [poses[i] for i in keep[1:]]


def _polish(state, fine: np.ndarray, surface: SurfaceModel, tolerance: float, hopeless: float):
    """A pose refined on the medium points, finished on all the fine ones.  When the robust fit
    leaves a motion nearly free against a mesh, it goes on against the exact surface and centres the
    pose between the edges that pin the motion (see edges), unless its residual scale is above
    ``hopeless`` (REFINE.hopeless_fit: sub-spacing slack is no matter for a pose that misses the scan)."""
    best = refine(fine, surface, state.T, state.gate, state.scale, REFINE.polish_iterations)
    best.iterations += state.iterations
    if (surface.is_mesh and best.sigma <= hopeless
            and has_weak_motion(fine, surface, best.T, best.gate, best.scale)):
        best = refine_exact(fine, surface, best)
        best.T, best.stability = centre_on_edges(fine, surface, best.T, best.gate, best.sigma, tolerance)
    return best


def refine_given(state, medium: np.ndarray, fine: np.ndarray, surface: SurfaceModel, tolerance: float,
                 hopeless: float = np.inf):
    """A pose refined on the ``medium`` points (a RefineState, scan -> model), finished as a match
    finishes its best: polished on all the ``fine`` points, refined again from a wider gate
    (_widened: a fit can stop an edge's width off) and polished again when that moved it.  A turn
    of the best (Judge._with_turns) and a bootstrap refit (calibration) are finished this way.
    ``hopeless``: see _polish."""
    best = _polish(state, fine, surface, tolerance, hopeless)
    wide = _widened(best, medium, surface)
    if _moved(wide.T, best.T, medium.mean(axis=0), best.gate):
        return _polish(wide, fine, surface, tolerance, hopeless)
    return best


def _shifted_turn(best, others: list, medium: np.ndarray, surface: SurfaceModel, voxel: float, fit_limit: float):
    """The best, one of the ``others`` weighed beside it, or a turn (_turns) of one of them that, moved
    by the shift their points and the model's samples vote for (_best_shift) and refined, explains
    RIVALS.shift_gain times as many of the ``medium`` points within ``fit_limit`` as the best, or None.
    The RIVALS.shifts_refined distinct ones with most votes are refined; none is tried when the best
    explains so many points that no pose could explain that many more.  A part seen in part (an L-block
    on two faces) maps onto itself about another axis than the whole model does: its turn lands a few
    centimetres from home, where the refinement settles on a face slid along another (a fit as tight as
    the right one, explaining less of the scan), and a search can hand over such a slid pose itself."""
    explained = inlier_scores(medium, surface, [best.T], fit_limit)[0]
    if RIVALS.shift_gain * explained > len(medium):
        return None
    reach = RIVALS.shift_reach * surface.diagonal
    step = max(RIVALS.shift_voxels * voxel, reach / RIVALS.shift_steps)
    centre = medium.mean(axis=0)
    apart = (RIVALS.turns_apart[0], RIVALS.turns_apart[1] * surface.diagonal)
    turned = np.concatenate([np.concatenate([pose.T[None], _turns(pose, medium, surface, pose.sigma <= fit_limit)])
                             for pose in [best, *others]])
    turned = turned[global_search.distinct(turned, np.zeros(len(turned)), centre, *apart)]
    # Spread over the scan: a small scan's medium points are in the file's order, scan line by scan line.
    voters = medium[::max(1, len(medium) // RIVALS.shift_points)][:RIVALS.shift_points]
    samples = surface.points[surface.view_order[:RIVALS.shift_samples]]
    shifted, votes = zip(*(_best_shift(T, voters, samples, reach, step) for T in turned))
    states = [coarse_to_fine([medium[:RIVALS.turn_points], medium], surface, shifted[i], step, surface.spacing)
              for i in global_search.distinct(shifted, votes, centre, *apart, RIVALS.shifts_refined)]
    scores = inlier_scores(medium, surface, [state.T for state in states], fit_limit)
    top = int(np.argmax(scores))
    return states[top] if scores[top] > 0 and scores[top] >= RIVALS.shift_gain * explained else None


def _best_shift(T: np.ndarray, points: np.ndarray, samples: np.ndarray, reach: float, step: float):
    """(``T`` (scan -> model) moved by the translation, on a grid of ``step`` within ``reach`` each way,
    that most pairs of ``points`` and model ``samples`` vote for (the shift that takes the point onto the
    sample, rounded to the grid); its votes).  A shift that lays the points on the surface collects the
    samples around each of them."""
    steps = int(round(reach / step))
    side = 2 * steps + 1
    cells = np.rint((samples[None] - frames.apply(T, points)[:, None]) / step).astype(np.int32).reshape(-1, 3) + steps
    cells = cells[((cells >= 0) & (cells < side)).all(axis=1)]
    votes = np.bincount((cells[:, 0] * side + cells[:, 1]) * side + cells[:, 2], minlength=side**3)
    best = int(np.argmax(votes))
    shift = (np.array(np.unravel_index(best, (side,) * 3)) - steps) * step
    return frames.rigid(translation=shift) @ T, int(votes[best])


def _near_symmetric_turns(best, medium: np.ndarray, surface: SurfaceModel, gate: float, fit_limit: float) -> list:
    """The best pose turned (_turns) and refined where the turns fit at all (RefineStates, see
    _refined_turns; ``gate``: the search's, ``fit_limit``: the verdict's limit on the residual scale).

    These are the poses a nearly symmetric part is mistaken for (turned over, end over end), and a
    feature search can miss them when the part's faces look alike, so they are always tried.  The
    patch's own half turns catch a scan laid inside out on a face (a flat face fits both ways; its
    edges and the sides beyond tell which), and a part seen on a few faces that fits its view turned
    about them.  The verdict tries the turns of its own best again, refined to convergence like it where
    they come near it (Judge._with_turns).
    """
    turned = _turns(best, medium, surface, best.sigma <= fit_limit)
    return _refined_turns(best, turned, medium, surface, gate, fit_limit)


def _turns(best, medium: np.ndarray, surface: SurfaceModel, exact_halves: bool = True) -> np.ndarray:
    """The best pose (scan -> model) turned by the model's near-symmetric turns (surface.flips: half
    turns about its principal axes and the turns that map most of it onto itself, each the model's
    best self-map; quarter turns of a near-square), by the exact half turns about its principal axes
    through its centroid (unless not ``exact_halves``: the flips are refined from them), and by half
    turns of the matched patch about its own principal axes."""
    from .symmetry import principal_axes, turn

    moved = frames.apply(best.T, medium[:RIVALS.turn_points])
    on_model = surface.nearest_cell(moved, best.gate)[2]
    patch = moved[on_model] if on_model.sum() >= MIN_SCAN_POINTS else moved
    about = [principal_axes(patch, np.ones(len(patch)))]
    if exact_halves:
        about.append(principal_axes(surface.points, np.ones(len(surface.points))))
    halves = [turn(axes[:, k], 180.0, centre) for centre, axes, _ in about for k in range(3)]
    return np.concatenate([surface.flips.reshape(-1, 4, 4), halves]) @ best.T


def _refined_turns(best, turned: np.ndarray, medium: np.ndarray, surface: SurfaceModel, gate: float,
                   fit_limit: float) -> list:
    """The ``turned`` poses (scan -> model) each refined, from the search's ``gate`` where it fits there,
    else (or when that does not bring it home) from RIVALS.turn_gate of the model's diagonal (on RIVALS.turn_points,
    then on the medium points), and kept when it then explains the scan about as well as the best
    (RIVALS.turn_floor of its score on RIVALS.turn_points at the best's gate, RIVALS.turn_sigmas of its residual scale),
    distinct from the best and each other (RefineStates).  Judged after they are refined, every time: a
    turn about an axis a little off (a patch's principal axis, or a model whose legs differ in length)
    lands a centimetre or more from its home and scores as nothing there, and from the search's gate
    it would never slide home; yet from the wide gate a turn that lands home from the search's (a curved
    tile's flip) may settle elsewhere.  A best that does not fit the scan (its residual scale above
    ``fit_limit``, the verdict's) is no yardstick for that: its turns are refined from the search's gate
    where they score RIVALS.floor of it there (a flip the search handed over comes home so)."""
    points = medium[:RIVALS.turn_points]
    centre = medium.mean(axis=0)
    best_at_gate = inlier_scores(points, surface, [best.T], gate)[0]
    # Turns that start as one pose end as one (a flip and the exact half turn about the same axis): refine
    # each once.
    if not best.sigma <= fit_limit:
        scores = inlier_scores(points, surface, turned, gate)
        starts = global_search.distinct(turned, scores, centre, RIVALS.turns_apart[0],
                                        RIVALS.turns_apart[1] * surface.diagonal)
        states = [coarse_to_fine([medium], surface, turned[i], gate, surface.spacing)
                  for i in starts if scores[i] >= RIVALS.floor * best_at_gate]
        return _apart_from(best, states, centre)
    starts = global_search.distinct(turned, np.zeros(len(turned)), centre, RIVALS.turns_apart[0],
                                    RIVALS.turns_apart[1] * surface.diagonal)
    best_score = inlier_scores(points, surface, [best.T], best.gate)[0]

    def as_well(state) -> bool:
        return (inlier_scores(points, surface, [state.T], best.gate)[0] >= RIVALS.turn_floor * best_score
                and not state.sigma > RIVALS.turn_sigmas * best.sigma)

    # A turn that fits at the search's gate is refined from there (it lands home when the part maps onto
    # itself); one that does not, or does not come home, first on a few points from the wide gate: one that
    # then explains much less than the best cannot come close to it on more.
    screened = (inlier_scores(points, surface, turned[starts], gate) >= RIVALS.floor * best_at_gate if len(starts)
                else np.zeros(0, bool))
    states = []
    for i, fits in zip(starts, screened):
        state = coarse_to_fine([medium], surface, turned[i], gate, surface.spacing) if fits else None
        if state is None or not as_well(state):
            quick = coarse_to_fine([medium[:RIVALS.quick_turn_points]], surface, turned[i],
                                   RIVALS.turn_gate * surface.diagonal, surface.spacing)
            if inlier_scores(points, surface, [quick.T], max(best.gate, quick.gate))[0] >= RIVALS.floor * \
                    inlier_scores(points, surface, [best.T], max(best.gate, quick.gate))[0]:
                state = coarse_to_fine([points, medium], surface, quick.T, quick.gate, surface.spacing)
        if state is not None and as_well(state):
            states.append(state)
    return _apart_from(best, states, centre)


def _apart_from(best, states: list, centre: np.ndarray) -> list:
    """The states that differ from the best and from each earlier one (2 degrees, two of the best's gates)."""
    poses = [best] + states
    keep = global_search.distinct([p.T for p in poses], -np.arange(len(poses)), centre, 2.0, 2 * best.gate)
    return [poses[i] for i in keep if i]


def _through_the_wall(state, medium: np.ndarray, surface: SurfaceModel, gate: float) -> list:
    """The pose shifted through the wall its scan lies on, onto the wall's other face, refined (a
    scan of one face of a thin plate or shell fits its back face nearly as well); [] without a wall."""
    if not surface.wall_across < VERDICT.thin_part * surface.diagonal:
        return []  # no thin plate or shell: every wall is a body's
    patch = frames.apply(state.T, medium[:RIVALS.turn_points])
    _, idx, found = surface.nearest_cell(patch, state.gate)
    patch, idx = patch[found], idx[found]
    if len(patch) < MIN_SCAN_POINTS:
        return []
    normal = surface.normals[idx].sum(axis=0)
    normal /= max(np.linalg.norm(normal), 1e-12)
    samples = surface.view_order[:VIEW.samples]
    pixel = VIEW.pixel_model_spacings * surface.spacing * np.sqrt(len(surface.points) / len(samples))
    centre = patch.mean(axis=0)
    view = visibility.View(centre + surface.diagonal * normal, centre, pixel).framed(patch, margin=0)
    pixels, _ = view.pixels(patch)
    seen = visibility.median_wall_thickness(view, surface.points[samples], surface.normals[samples],
                                            pixels[pixels >= 0], MIN_SCAN_POINTS)
    if not seen < VERDICT.thin_wall_diagonals * surface.diagonal:
        return []
    shifted = frames.rigid(translation=-seen * normal) @ state.T
    scores = inlier_scores(medium[:RIVALS.turn_points], surface, [state.T, shifted], state.gate)
    if scores[1] < RIVALS.floor * scores[0]:  # a solid body, not a thin wall
        return []
    return [coarse_to_fine([medium], surface, shifted, gate, surface.spacing)]


def inlier_scores(points: np.ndarray, surface: SurfaceModel, transforms, gate: float) -> np.ndarray:
    """For each transform, how many points it puts on the model, each weighted by how close it is
    (1 on the surface, 0 at the gate): a count, so clutter cannot dilute it; one grid lookup."""
    Ts = np.asarray(transforms).reshape(-1, 4, 4)
    moved = (np.matmul(points[None], Ts[:, :3, :3].transpose(0, 2, 1)) + Ts[:, None, :3, 3]).reshape(-1, 3)
    _, idx, found = surface.nearest_cell(moved, gate)
    r = np.where(found, surface.plane_residuals(moved, idx), gate)
    return np.clip(1 - (r / gate) ** 2, 0, 1).reshape(len(Ts), -1).sum(axis=1)


class Judge:
    """Weighs poses by their view evidence (visibility.evidence) on the verdict's scan points.

    All poses are judged from one viewpoint in the scan's frame, so their evidence compares cell by
    cell: the one given, or else the one implied by the pose that puts the most scan points on the
    model: the surface it matches faces the sensor, so the sensor sits along the middle of the
    matched model normals (visibility.viewing_direction).  (A pose that lays a scan inside out on a
    flat face implies the opposite side; it explains fewer points than the right one, the scan's
    edges and sides beyond the face, so it does not choose the viewpoint when the right pose is
    there.)  A scan whose matched normals face every way (views merged into one cloud) has no
    viewpoint: its poses are weighed by the scan points on the model.
    """

    def __init__(self, sample: np.ndarray, surface: SurfaceModel, probes, spacing: float,
                 options: MatchOptions, warnings: list, support: Support | None = None):
        self.surface, self.options, self.warnings = surface, options, warnings
        self.support = support  # the plane the part stands on, found in ``sample`` (Support.of)
        self.all_points, self.all_spacing = sample, spacing  # the fine level's points, and their spacing
        self.probes, self.probe_noise = probes  # points the scan's noise was measured about, and the noise there
        self.scan_noise = float(np.median(self.probe_noise))
        self.noise = float("nan")  # what residuals scatter by: the noise of the scan (on the part) and the model
        self.gate = float("nan")
        self.viewpoint, self.source, self.view = None, "none", None
        self.faces_viewpoint = None  # where continued_faces looks from, when not the viewpoint (_choose_view)
        self._distance_cache = {}  # (pose, gate) -> _distances
        self._level(fine=False)

    def _level(self, fine: bool) -> None:
        """Weigh on a few scan points and a coarse view (quick), or on all the verdict's points and
        a view with cells about a scan spacing wide (to tell near-symmetric poses apart)."""
        count = len(self.all_points) if fine else min(len(self.all_points), VERDICT.evidence_points)
        self.sample = self.all_points[:count]
        self.fine = fine
        spacing = self.all_spacing * np.sqrt(len(self.all_points) / count)
        self.view_samples = self.surface.view_order[:VIEW.samples_fine if fine else VIEW.samples]
        model_spacing = self.surface.spacing * np.sqrt(len(self.surface.points) / len(self.view_samples))
        self.pixel = max(VIEW.pixel_scan_spacings * spacing, VIEW.pixel_model_spacings * model_spacing,
                         spacing * np.sqrt(count / VIEW.max_pixels))
        if self.viewpoint is not None:
            self.view = visibility.ScanView.of(self.sample, visibility.View(self.viewpoint, self.target, self.pixel))

    def rank(self, best, rivals, polish, widen, through, turns, finish, home=lambda state, noise: state):
        """(best state, [Candidate, best first]): the poses not equivalent under the model's symmetries,
        weighed by view evidence.  Every pose is refined again
        from a wider gate first (``widen``): a fit can stop an edge's width off, its edge points dropped
        as outliers, and from further out it slides home.  A pose whose evidence is significantly above
        the best's becomes the best (``polish`` finishes it like the best), and a best whose view shows
        a misfit (scan points hidden or past its outline, surface missing) is widened again.  Then the
        best's near-symmetric turns (``turns``: _near_symmetric_turns), each that comes near it by the
        view refined to convergence like it (``finish``: refine_given) and slid ``home`` beside a best
        that fits, are weighed with it (_with_turns)."""
        if self.options.method == "robust":  # each pose slides home, or it is judged off its best
            rivals = [widen(r) for r in rivals]
            wide = widen(best)
            if _moved(wide.T, best.T, self.all_points.mean(axis=0), best.gate):
                best = polish(wide)
            # A rival that slid onto the best, or onto an earlier rival, is no rival; one a wall's
            # thickness away (on the other face) still is, so "the same" is within a few gates here.
            poses = [best] + rivals
            keep = global_search.distinct([p.T for p in poses], -np.arange(len(poses)), self.all_points.mean(axis=0),
                                          2.0, 2 * best.gate)
            rivals = [poses[i] for i in keep if i]
        rivals = self._distinct_under_symmetry(best, rivals)
        # The scan's noise where it lies on the model: clutter and stray points scatter differently.
        on_part = self.surface.nearest_cell(frames.apply(best.T, self.probes), best.gate)[2]
        if on_part.sum() >= MIN_SCAN_POINTS:
            self.scan_noise = float(np.median(self.probe_noise[on_part]))
        self.noise = float(np.hypot(self.scan_noise, self.surface.noise_mm))
        if self.options.method == "robust":
            best = home(best, self.noise)
        sigma = best.sigma if np.isfinite(best.sigma) else self.noise
        self.gate = VERDICT.evidence_sigmas * max(sigma, self.noise, 1e-6)
        poses = [best] + rivals
        lookups = [self._lookup(p.T) for p in poses]
        self._choose_view(poses, lookups)
        weighed = [self.evidence(p.T, lookup) for p, lookup in zip(poses, lookups)]
        if any(visibility.compare(weighed[0].cells, e.cells, VERDICT.cell_variance_floor)
               < VIEW.close_call * self.options.rival_significance for e in weighed[1:]):
            self._level(fine=True)  # a close call: weigh again, finely
            weighed = [self.evidence(p.T) for p in poses]
        if self.options.method == "robust":
            top = int(np.argmax([e.score for e in weighed]))
            if top and self._better(weighed[top], weighed[0]):
                poses = [polish(poses[top])] + poses[:top] + poses[top + 1:]
                weighed = [self.evidence(poses[0].T)] + weighed[:top] + weighed[top + 1:]
            wide = widen(poses[0]) if _misfit(weighed[0]) else poses[0]  # a clean view needs no second look
            if _moved(wide.T, poses[0].T, self.sample.mean(axis=0), poses[0].gate):
                evidence = self.evidence(wide.T)
                if self._better(evidence, weighed[0]):
                    poses[0] = polish(wide)
                    weighed[0] = self.evidence(poses[0].T)
            # The best laid on the other face of the wall it sees, judged like every rival.
            for other in through(poses[0]):
                if _moved(other.T, poses[0].T, self.sample.mean(axis=0), poses[0].gate):
                    poses.append(other)
                    weighed.append(self.evidence(other.T))
            # A turn is slid home only beside a best that fits the scan (within the verdict's limit): the turns
            # of a pose that does not (a model in another object's points) fit no better, and none comes home.
            fits = poses[0].sigma <= VERDICT.max_noise_ratio * self.noise + self.options.tolerance_mm
            poses, weighed, turned = self._with_turns(
                poses, weighed, turns(poses[0]), lambda t: home(finish(t), self.noise) if fits else finish(t))
        else:
            turned = [False] * len(poses)
        # The far-off test is weighed only for a result that could be "ok" (weigh_far_off): it costs an exact
        # distance per pose, and a failed result's status and reasons never depend on it.
        best_T, centre = poses[0].T, self.surface.centre[None]
        ranked = []
        for k, (p, e, t) in enumerate(zip(poses, weighed, turned)):
            ranked.append(Candidate(
                frames.invert(p.T), score=e.score,
                score_ratio=float(e.score / weighed[0].score) if weighed[0].score > 0 else 0.0,
                standard_errors_below_best=visibility.compare(weighed[0].cells, e.cells, VERDICT.cell_variance_floor)
                if k else 0.0,
                far_off_standard_errors=float("nan") if k else 0.0,
                from_the_other_side=bool(k) and self._from_the_other_side(best_T, p.T), turn_of_best=t,
                fits=self._fits(p), hidden_points=e.hidden, missing_cells=e.missing,
                rotation_from_best_deg=frames.rotation_between_deg(p.T, best_T),
                shift_from_best_mm=float(np.linalg.norm(frames.apply(frames.invert(p.T), centre)[0]
                                                        - frames.apply(frames.invert(best_T), centre)[0])),
                evidence=e))
        return poses[0], ranked

    def weigh_far_off(self, ranked: list) -> None:
        """Set each rival's far_off_standard_errors in a ranking (rank's): its far_off_test against the best."""
        if len(ranked) > 1:  # no rival: no far-off test
            best_distances = self._distances(ranked[0].to_model)
            for candidate in ranked[1:]:
                candidate.far_off_standard_errors = self._far_off(best_distances, candidate.to_model)

    def _fits(self, state) -> bool:
        """Whether a refined pose fits the scan within FAR_OFF.fit noises: only then are the points it
        leaves far off evidence against it rather than a sign that it has not converged."""
        return bool(state.sigma <= FAR_OFF.fit * self.noise)

    def _with_turns(self, poses: list, weighed: list, turns: list, finish):
        """(poses, their evidence, whether each is refined like the best): the best's near-symmetric turns
        (not a symmetry of the model away from it) join the poses, each replacing the rivals it repeats
        (refined less); a rival that repeats the best is dropped.  Each turn that comes within
        VIEW.close_call times the rival significance of the best by the view is first refined to
        convergence like it (``finish``); one further behind is listed as it is, a rival of no one.  The
        rivals of the search near the best by the view are refined so too (_refine_rivals).  A pose so
        refined that is better than the best by the view evidence, or as good by it and leaving
        significantly fewer scan points far off the part (far_off_test) while both fit within FAR_OFF.fit
        noises, becomes the best; the best it replaces is then one of its turns."""
        centre, sig = self.sample.mean(axis=0), self.options.rival_significance

        def near(a, b) -> bool:
            return (frames.rotation_between_deg(a.T, b.T) <= 2.0
                    and np.linalg.norm(frames.apply(a.T, centre[None]) - frames.apply(b.T, centre[None])) <= 2 * b.gate)

        def close(state) -> bool:
            return (visibility.compare(weighed[0].cells, self.evidence(state.T).cells, VERDICT.cell_variance_floor)
                    < VIEW.close_call * sig)

        turns = [t for t in turns if not near(t, poses[0])]
        finished = [close(t) for t in turns]
        turns = [finish(t) if done else t for t, done in zip(turns, finished)]
        kept = self._distinct_under_symmetry(poses[0], [t for t in turns if not near(t, poses[0])])
        finished = [done for t, done in zip(turns, finished) if any(t is k for k in kept)]
        turns = kept
        poses, weighed = list(poses), list(weighed)
        refined = self._refine_rivals(poses, weighed, finish)
        # A rival refined onto the best since it was found (widened, laid through the wall and back) is no
        # rival; one on the other face of a wall thinner than two gates lies as near, and still is.  A
        # rival _refine_rivals refined repeats only a pose refined as far (the best, a finished turn, an
        # earlier such rival), or a symmetric copy of one.
        rest = []
        for i in range(1, len(poses)):
            if i in refined:
                repeated = ([poses[0]] + [t for t, done in zip(turns, finished) if done]
                            + [poses[j] for j in rest if j in refined])
                if len(self._distinct_under_symmetry(poses[i], repeated)) < len(repeated):  # a symmetric copy
                    continue
            else:
                repeated = [poses[0]] + turns
            if not any(near(poses[i], t) and not self._faces_apart(t.T, poses[i].T) for t in repeated):
                rest.append(i)
        poses = [poses[0]] + turns + [poses[i] for i in rest]
        weighed = [weighed[0]] + [self.evidence(t.T) for t in turns] + [weighed[i] for i in rest]
        turned = [False] + finished + [i in refined for i in rest]
        if not any(turned):
            return poses, weighed, turned
        if not self.fine and any(visibility.compare(weighed[0].cells, e.cells, VERDICT.cell_variance_floor)
                                 < VIEW.close_call * sig for e, t in zip(weighed[1:], turned[1:]) if t):
            self._level(fine=True)  # a close call: weigh again, finely
            weighed = [self.evidence(p.T) for p in poses]
        for i in sorted((i for i in range(1, len(poses)) if turned[i]), key=lambda i: -weighed[i].score):
            z = visibility.compare(weighed[0].cells, weighed[i].cells, VERDICT.cell_variance_floor)
            if z < -sig or (z < sig and self._fits(poses[0]) and self._fits(poses[i])
                            and self._far_off(self._distances(poses[0].T), poses[i].T) <= -sig):
                poses[0], poses[i] = poses[i], poses[0]
                weighed[0], weighed[i] = weighed[i], weighed[0]
                break
        return poses, weighed, turned

    def _refine_rivals(self, poses: list, weighed: list, finish) -> list:
        """The indices of the rivals (poses[1:], their evidence ``weighed``) refined like the best
        (``finish``), in place.  A rival of the search turned more than RIVALS.min_rival_turn_deg from the
        best (less: the best laid through its wall, or slid) and within VIEW.close_call times the rival
        significance of it by the view stopped where its refinement did.  Refined, it replaces the pose
        found when it is still a rival by the view, or no further behind the best than found: a view the
        pose found explains as well as the best stays that evidence."""
        sig, refined = self.options.rival_significance, []
        for i in range(1, len(poses)):
            if frames.rotation_between_deg(poses[i].T, poses[0].T) <= RIVALS.min_rival_turn_deg:
                continue
            found_behind = visibility.compare(weighed[0].cells, weighed[i].cells, VERDICT.cell_variance_floor)
            if found_behind >= VIEW.close_call * sig:
                continue
            done = finish(poses[i])
            evidence = self.evidence(done.T)
            behind = visibility.compare(weighed[0].cells, evidence.cells, VERDICT.cell_variance_floor)
            if behind < sig or behind <= found_behind:
                poses[i], weighed[i] = done, evidence
                refined.append(i)
        return refined

    def _far_off(self, best_distances: np.ndarray, T: np.ndarray) -> float:
        """far_off_test of pose T (scan -> model) against the best, whose distances are given.  The
        support's points weigh for neither: a pose laid along the table explains them, the part's does not."""
        rival = self._distances(T)
        if self.support is not None:
            beside = ~self.support.on_plane
            best_distances, rival = best_distances[beside], rival[beside]
        return far_off_test(best_distances, rival, self.gate / VERDICT.evidence_sigmas)

    def _distances(self, T: np.ndarray) -> np.ndarray:
        """Each verdict point's distance from the model's surface under pose T (mm): exact against a
        mesh, inf where it is surely past FAR_OFF.sigmas scales (its nearest sample farther than that
        plus the samples' cover); against a point model the point-to-plane residual, or the distance
        past the nearest sample's neighbourhood (a point beyond the surface's edge), inf beyond the
        far-off reach.
        Computed once per pose (and gate): the best's and its turns' are asked for again by rank."""
        key = (np.asarray(T, float).tobytes(), self.gate)
        if key not in self._distance_cache:
            moved = frames.apply(T, self.all_points)
            saturated = FAR_OFF.sigmas * self.gate / VERDICT.evidence_sigmas  # far_off_test weighs farther points fully
            if self.surface.is_mesh:
                # Exact only where it can weigh less than fully: a mesh point within that is within it
                # plus the samples' cover of a sample, and an exact query far from a thin or round mesh
                # visits most of its BVH (seconds per pose).
                found = self.surface.nearest(moved, saturated + self.surface.sample_cover)[2]
                distances = np.full(len(moved), np.inf)
                distances[found] = self.surface.exact_distance(moved[found])
            else:
                d, idx, found = self.surface.nearest_cell(moved, saturated + self.surface.spacing)
                plane = np.abs(self.surface.plane_residuals(moved, idx))
                distances = np.where(found, np.maximum(plane, d - self.surface.spacing), np.inf)
            self._distance_cache[key] = distances
        return self._distance_cache[key]

    def _from_the_other_side(self, best: np.ndarray, rival: np.ndarray) -> bool:
        """Whether the rival, seen from the side of the part its own matched surface faces, would
        explain the scan about as well as the best: it implies a viewpoint on the other side (a
        thin wall, or a face laid inside out) and is not significantly worse by the scan points it
        puts on the model.  The view evidence, judged from one side, cannot rule such a rival out
        when the viewpoint is only estimated."""
        if self.view is None or not self.source.startswith("estimated"):
            return False
        lookups = [self._lookup(T) for T in (best, rival)]
        looks = [self._look(T, lookup) for T, lookup in zip((best, rival), lookups)]
        if looks[0] is None or looks[1] is None:
            return False
        weights = [np.clip(1 - (r / self.gate) ** 2, 0, 1) for _, _, r in lookups]
        return bool(looks[0] @ looks[1] < 0 and visibility.compare(weights[0], weights[1], VERDICT.cell_variance_floor)
                    < self.options.rival_significance)

    def _faces_apart(self, a: np.ndarray, b: np.ndarray) -> bool:
        """Whether poses a and b lay the scan on surfaces facing opposite ways (the two faces of a wall)."""
        looks = [self._look(T, self._lookup(T)) for T in (a, b)]
        return looks[0] is not None and looks[1] is not None and bool(looks[0] @ looks[1] < 0)

    def _look(self, T: np.ndarray, lookup):
        """The direction pose T's matched surface faces (visibility.viewing_direction), from its
        lookup (_lookup); None when it puts too few scan points on the model."""
        idx, found, r = lookup
        matched = found & (r < self.gate)
        if matched.sum() < MIN_SCAN_POINTS:
            return None
        return visibility.viewing_direction(self.surface.normals[idx[matched]] @ T[:3, :3])

    def _better(self, evidence: visibility.Evidence, than: visibility.Evidence) -> bool:
        return visibility.compare(evidence.cells, than.cells, VERDICT.cell_variance_floor) > self.options.rival_significance

    def _distinct_under_symmetry(self, best, rivals) -> list:
        """Rivals that no symmetry of the model maps onto the best or onto an earlier rival."""
        if len(self.surface.symmetry_orders) == 0:
            return rivals
        kept = []
        for r in rivals:
            if not any(self.surface.maps_onto_itself(r.T @ frames.invert(k.T)) for k in [best] + kept):
                kept.append(r)
        return kept

    def continued_faces(self, T: np.ndarray) -> int:
        """How many of the verdict's scan points lie off a mesh model under pose T but in the plane of a
        flat face of it facing the sensor, beside the face and joined to it by points in that plane
        (OUTLINE.link_spacings scan spacings apart at most): the scanned face goes on past the placed
        face's edge.  A pose that lays a face of the scan on a shorter face of the model leaves the rest
        of it so; the pixel test of visibility.evidence needs scan pixels next to the outline, which the
        rows of a sparse scan leave empty.  Clutter beside a part seldom lies in the plane of its faces.
        Off means farther from every sample than any point of the mesh can be (sample_cover): a point
        model has no such bound (its samples leave gaps), so it is not weighed so, nor a scan without
        a viewpoint (views merged into one cloud).  A finely sampled curved surface may pass as flat
        (SurfaceModel.flat is local), but points on its tangent plane lie off it only farther out than
        the reach unless it curves little."""
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components
        from scipy.spatial import cKDTree

        surface = self.surface
        if self.view is None or not surface.is_mesh:
            return 0
        moved = frames.apply(T, self.all_points)
        threshold = self.gate + surface.sample_cover
        # The cell grid clears most points (a cell's sample is no nearer a point than its nearest one),
        # so the KD-tree weighs the rest only, and a cached model's match seldom has to build it; not
        # through a coarser grid than OUTLINE.grid_levels (a CAD mesh's large faces have a large cover),
        # which would be filled for this alone, unless prepare filled it.
        level = surface.grid_level_for(threshold)
        maybe_off = (np.flatnonzero(~surface.nearest_cell(moved, threshold)[2])
                     if level < OUTLINE.grid_levels or surface.grid_filled(level) else np.arange(len(moved)))
        if self.support is not None:  # the plane the part stands on meets its side faces along its foot
            maybe_off = maybe_off[~self.support.on_plane[maybe_off]]
        if len(maybe_off) < OUTLINE.min_continued_points:
            return 0
        # Beside the model: within a few scan spacings (the rows of a sparse scan), at most
        # OUTLINE.reach_samples model spacings (the samples weighed per point).
        reach = threshold + min(OUTLINE.reach_spacings * self.all_spacing, OUTLINE.reach_samples * surface.spacing)
        # Only up to the reach (inf beyond): the tree's search for the nearest sample of a point far off
        # (clutter, stray points) visits much of it; 0.25-0.35 s of a cluttered scene's match.
        distance = surface.nearest(moved[maybe_off], reach)[0]
        far = distance > threshold
        off, distance = maybe_off[far], distance[far]  # the points off the model and their distances
        if len(off) < OUTLINE.min_continued_points:
            return 0
        # In a face's plane: within the gate, or a third of the tolerance where the noise is below it (an
        # exact scan's gate is 1e-6 mm, less than a found pose's own error).
        margin = max(self.gate, self.options.tolerance_mm / 3)
        beside = off[distance <= reach]
        if len(beside) == 0:
            return 0
        beside = beside[::-(-len(beside) // OUTLINE.seeds)]  # enough to seed any run worth a reason
        # (point, sample) pairs, its OUTLINE.samples nearest samples within reach, where the sample's
        # tangent plane holds the point.
        near = surface.tree.query(moved[beside], OUTLINE.samples, distance_upper_bound=reach)[1]
        found = near < len(surface.points)
        point, sample = np.broadcast_to(beside[:, None], near.shape)[found], near[found]
        normals = surface.normals[sample]
        held = np.abs(np.einsum("ij,ij->i", moved[point] - surface.points[sample], normals)) <= margin
        point, sample, normals = point[held], sample[held], normals[held]
        samples = np.unique(sample)
        towards = visibility.facing(frames.apply(frames.invert(T), surface.points[samples]),
                                    surface.normals[samples] @ T[:3, :3],
                                    self.viewpoint if self.faces_viewpoint is None else self.faces_viewpoint)
        usable = surface.flat(samples, OUTLINE.flat_spacings * surface.spacing) & (towards > OUTLINE.facing_cos)
        usable = usable[np.searchsorted(samples, sample)]
        point, sample, normals = point[usable], sample[usable], normals[usable]
        if len(point) == 0:
            return 0
        # One pass per plane (a face's samples share one up to rounding).
        offsets = np.einsum("ij,ij->i", normals, surface.points[sample])
        planes = np.column_stack([np.round(normals / np.radians(visibility.FLAT_DEG)), np.round(offsets / margin)])
        _, first, plane_of = np.unique(planes, axis=0, return_index=True, return_inverse=True)
        link = OUTLINE.link_spacings * self.all_spacing
        continued = np.zeros(len(moved), bool)
        for plane in np.argsort(-np.bincount(plane_of.ravel()))[:OUTLINE.planes]:
            seeds = point[plane_of.ravel() == plane]
            j = sample[first[plane]]
            on_plane = np.union1d(off[np.abs((moved[off] - surface.points[j]) @ surface.normals[j]) <= margin], seeds)
            pairs = cKDTree(moved[on_plane]).query_pairs(link, output_type="ndarray")
            graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(on_plane),) * 2)
            labels = connected_components(graph, directed=False)[1]
            seeded = np.isin(labels, labels[np.searchsorted(on_plane, seeds)])
            continued[on_plane[seeded]] = True
        return int(continued.sum())

    def _lookup(self, T: np.ndarray):
        """(nearest model sample, found, |point-to-plane residual|) of each sample point under T."""
        moved = frames.apply(T, self.sample)
        # The nearest sample may lie a spacing away along the surface from a point right on it.
        _, idx, found = self.surface.nearest_cell(moved, self.gate + self.surface.spacing)
        return idx, found, np.where(found, np.abs(self.surface.plane_residuals(moved, idx)), self.gate)

    def _choose_view(self, poses, lookups) -> None:
        """The viewpoint (given, or implied by the pose with the most scan points on the model) and
        the scan seen from it; none when the matched normals face every way."""
        top = int(np.argmax([np.sum(found & (r < self.gate)) for _, found, r in lookups]))
        idx, found, r = lookups[top]
        matched = found & (r < self.gate)
        normals = self.surface.normals[idx] @ poses[top].T[:3, :3]  # model normals in the scan's frame
        if self.support is not None:
            # A face laid in the support's plane facing into it rests on the support and is never seen:
            # the scan points there are the support's.  Counted, they are normals facing away from the
            # sensor, and the viewpoint implied by a pose that lays the part's foot on open table
            # (half a turn about the vertical) came out grazing, where its misfit shows nowhere.
            resting = (self.support.on_plane[:len(self.sample)]
                       & (normals @ self.support.normal < -SUPPORT.resting_cos))
            matched &= ~resting
        matched_normals = normals
        points, normals = self.sample[matched], normals[matched]
        if len(points) < MIN_SCAN_POINTS:
            return
        given = self.options.viewpoint
        if given is not None:
            away = np.mean(visibility.facing(points, normals, given) < visibility.FACING_COS)
            if away <= VIEW.max_facing_away:
                self._set_view(np.asarray(given, float), points.mean(axis=0), "given")
                self.faces_viewpoint = None
                return
            self.warnings.append(f"the given viewpoint ({', '.join(f'{v:g}' for v in given)}) mm sees "
                                 f"{away:.0%} of the matched surface from behind: not the scan's viewpoint; "
                                 "estimated from the scan instead")
        centre = points.mean(axis=0)
        reach = VIEW.distance_extents * np.linalg.norm(points.max(axis=0) - points.min(axis=0))
        viewpoint = centre + reach * visibility.viewing_direction(normals)
        away = np.mean(visibility.facing(points, normals, viewpoint) < visibility.FACING_COS)
        if away <= VIEW.max_facing_away:
            self._set_view(viewpoint, centre, "estimated from the matched surface: along the middle "
                                              f"of its normals, {VIEW.distance_extents:g} scan extents away")
            faces = self._inside_faces(idx, matched)
            self.faces_viewpoint = (centre + reach * visibility.viewing_direction(matched_normals[faces])
                                    if faces.any() else viewpoint)

    def _inside_faces(self, idx: np.ndarray, matched: np.ndarray) -> np.ndarray:
        """``matched`` less the points whose nearest samples lie near a crease (within the gate or
        VIEW.face_spacings model spacings), unless fewer than VIEW.min_on_faces of them would be left (a
        curved model).  A point within the gate of a crease may find its nearest sample on the face that
        turns away from the sensor; a few per cent of such normals pull the cone of those seen past the
        view.  The faces test (continued_faces) looks from the direction of these; the view's pixels keep
        the one of all matched samples, which their limits were set with."""
        inside = np.flatnonzero(matched)
        on_face = self.surface.flat(idx[inside], max(self.gate, VIEW.face_spacings * self.surface.spacing))
        if on_face.sum() < VIEW.min_on_faces * len(inside):
            return matched
        kept = matched.copy()
        kept[inside[~on_face]] = False
        return kept

    def least_contradicted(self, T: np.ndarray) -> float:
        """The smallest share of pose T's view contradicted, looking from the viewpoint and from
        around it.  An estimated viewpoint is only good to some 30 degrees, and the real sensor saw
        every scan point, so from where it was the right pose hides none: a pose is only found to
        contradict the view when it does so from all around.  (The poses are still compared from
        the one viewpoint: turning it for one pose would favour that pose.)"""
        share = _contradicted(self.evidence(T))
        if self.view is None or not self.source.startswith("estimated"):
            return share
        viewpoint, centre = self.viewpoint, self.target
        distance = np.linalg.norm(viewpoint - centre)
        for direction in visibility.cone((viewpoint - centre) / distance, VIEW.settle_step_deg, rings=2)[1:]:
            self._set_view(centre + distance * direction, centre, self.source)
            share = min(share, _contradicted(self.evidence(T)))
        self._set_view(viewpoint, centre, self.source)
        return share

    def _set_view(self, viewpoint, target, source: str) -> None:
        self.viewpoint, self.target, self.source = viewpoint, target, source
        self.view = visibility.ScanView.of(self.sample, visibility.View(viewpoint, target, self.pixel))

    def evidence(self, T: np.ndarray, lookup=None) -> visibility.Evidence:
        """The view evidence of pose T (scan -> model); without a view, each scan point's weight."""
        idx, found, r = self._lookup(T) if lookup is None else lookup
        weights = np.clip(1 - (r / self.gate) ** 2, 0, 1)
        if self.view is None:
            return visibility.Evidence(weights, 0, 0, int((weights > 0).sum()))
        on_model = weights > 0
        weights[visibility.facing(self.sample, self.surface.normals[idx] @ T[:3, :3], self.viewpoint)
                <= visibility.FACING_COS] = 0.0
        samples = self.view_samples
        # The support's points go on past the outline wherever the part stands on it: no evidence.
        standing_on = None if self.support is None else self.support.on_plane[:len(self.sample)]
        return visibility.evidence(self.view, weights, frames.apply(frames.invert(T), self.surface.points[samples]),
                                   self.surface.normals[samples] @ T[:3, :3], self.gate, self.gate + 2 * self.pixel,
                                   OUTLINE.off_band_gates * self.gate, on_model, standing_on)

    def wall_thickness(self, T: np.ndarray, evidence: visibility.Evidence) -> float:
        """Median thickness of the part where pose T explains the view (mm; inf without a view)."""
        if self.view is None:
            return float("inf")
        samples = self.view_samples
        thickness = visibility.wall_thickness(self.view.view, frames.apply(frames.invert(T), self.surface.points[samples]),
                                              self.surface.normals[samples] @ T[:3, :3])[self.view.cells]
        seen = thickness[evidence.cells > 0.5]
        return float(np.median(seen)) if len(seen) else float("inf")

    def viewpoint_info(self) -> dict:
        """Where the poses were judged from, and how that viewpoint was found (for the result)."""
        if self.view is None:
            return {"position_mm": None, "source": "none",
                    "note": "the matched surface faces every way (views merged into one cloud?): poses weighed by "
                            "the scan points on the model, without visibility"}
        return {"position_mm": self.viewpoint.tolist(), "source": self.source, "pixel_mm": float(self.pixel)}


def far_off_test(best: np.ndarray, rival: np.ndarray, sigma: float) -> float:
    """How many standard errors the scan points a rival pose leaves far off the surface outweigh
    those the best leaves: ``best`` and ``rival`` are each point's distance from the surface under
    either pose (mm), ``sigma`` the residual scale (the scan's measured noise, or the fit's if larger).

    The view cells (visibility.compare) count how many cells a pose explains; a flip that moves a
    notch or a rim leaves only a few tens of points off, in too few cells to tell, but it leaves them
    ten and more noises off, where noise puts no point.  Each point weighs a robust log-likelihood
    ratio, a truncated quadratic in its distance beyond the noise band: w(u) = clip((u^2 - 3^2) /
    (FAR_OFF.sigmas^2 - 3^2), 0, 1) for u = distance / sigma, so a point within VERDICT.evidence_sigmas of
    the surface counts nothing (within the noise, a pose's small misfit must not decide), one
    FAR_OFF.sigmas or more off counts fully, and no outlier counts more than that.  The per-point
    differences d = w(rival) - w(best) are paired (one scan, both poses): when the two poses explain
    the scan alike (a symmetry, a view that cannot tell), each difference is as likely either way,
    so their sum is tested against its sign-flip distribution (sign_flip_z): exactly when a few tens
    of points differ (nine points off the rival and none off the best score 3.1 standard errors,
    however far off each lies), about normally when more do.  Negative when the best leaves more
    far off."""
    def weight(distance):
        u2 = (distance / max(sigma, 1e-9)) ** 2
        return np.clip((u2 - VERDICT.evidence_sigmas**2) / (FAR_OFF.sigmas**2 - VERDICT.evidence_sigmas**2), 0.0, 1.0)

    return sign_flip_z(weight(rival) - weight(best))


def sign_flip_z(d: np.ndarray) -> float:
    """The paired differences ``d`` (weights in [-1, 1], each as likely positive as negative when
    nothing tells the poses apart) as a signed normal score: the standard normal quantile of the
    chance that their sum comes out further from zero on its side under random signs, plus half the
    chance that it comes out exactly as far (a one-sided mid-p value: the plain exact p-value of a
    discrete sum is conservative, its mid-p about as often below a level as a continuous one: nine
    differences all one way, 2^-10, 3.1 standard errors; eight, 2.9).  Exact, on a grid of
    1/FAR_OFF.sign_flip_steps, for up to FAR_OFF.exact_sign_flips nonzero differences (the normal approximation of a
    sum of a few unequal terms is poor: ten points all one way scored 2.8 to 3.2 by their sizes);
    beyond, the sum over its null standard deviation sqrt(sum d^2).  0 when the differences cancel."""
    steps = np.rint(np.asarray(d, float) * FAR_OFF.sign_flip_steps).astype(np.int64)
    steps = steps[steps != 0]
    total = int(steps.sum())
    if total == 0:
        return 0.0
    if len(steps) > FAR_OFF.exact_sign_flips:
        return total / float(np.sqrt(np.sum(steps.astype(float) ** 2)))
    chance = np.ones(1)  # chance[s] of the sum s - offset under random signs, built one difference at a time
    for k in np.abs(steps):
        grown = np.zeros(len(chance) + 2 * k)
        grown[:len(chance)] += chance / 2
        grown[2 * k:] += chance / 2
        chance = grown
    # The distribution is symmetric about its middle; a sum exactly as far out counts half (mid-p).
    at = len(chance) // 2 + abs(total)
    p = float(chance[at + 1:].sum() + chance[at] / 2)
    return float(np.copysign(-NormalDist().inv_cdf(p), total)) if p < 0.5 else 0.0


def _widened(state, medium: np.ndarray, surface: SurfaceModel):
    """The pose refined again from REFINE.wider_gate times its gate on a few points: one stage at the
    wide gate, and only when that moved it, down to the fine gate again."""
    gate = REFINE.wider_gate * state.gate
    wide = refine(medium[:REFINE.wider_points], surface, state.T, gate, gate / 3, max_iterations=10, tolerance=1e-4)
    if not _moved(wide.T, state.T, medium.mean(axis=0), state.gate):
        return wide
    return coarse_to_fine([medium], surface, wide.T, gate, surface.spacing)


def _slid_home(state, medium: np.ndarray, surface: SurfaceModel, noise: float, polish, hopeless: float):
    """The pose, or when it fits worse than FAR_OFF.fit noises, the pose refined again from
    REFINE.home_shifts_mm along each motion of its fit (the eigenvectors of its point-to-plane constraints,
    stability.gelfand) either way, polished, when that fits clearly better (REFINE.home_gain, both residual
    scales on the medium points the tries are refined on) and keeps at least as many scan points on
    the model.  A refinement that stopped in a local minimum (a pose slid along a curved part: the
    scan points past the part's end pull it nowhere, point-to-plane) is pulled home; a right pose
    (within FAR_OFF.fit noises) is never touched, nor is one whose residual scale is above ``hopeless``
    (REFINE.hopeless_fit: it is no slide from fitting; a wrong model's poses are all such)."""
    if not FAR_OFF.fit * noise < state.sigma <= hopeless:
        return state
    moved = frames.apply(state.T, medium)
    found, residuals, normals = surface.tangent_planes(moved, state.gate)
    if found.sum() < MIN_SCAN_POINTS:
        return state
    _, vecs, centre, radius = gelfand(moved[found], normals)
    # The tries are refined on the medium points: the pose's residual scale there is the one to beat
    # (a polished pose's own sigma is taken on the fine points), taken as refine takes it.
    here = MAD_TO_SIGMA * float(np.median(np.abs(residuals)))
    home, home_sigma = state, here
    for v in vecs.T:
        twist = unit_twist(v, centre, radius, moved[found])
        for amount in (*REFINE.home_shifts_mm, *(-a for a in REFINE.home_shifts_mm)):
            tried = refine(medium, surface, slide(twist, centre, amount) @ state.T, state.gate, state.scale)
            if tried.sigma < home_sigma:
                home, home_sigma = tried, tried.sigma
    if home is state or not home_sigma <= REFINE.home_gain * here:
        return state
    before, after = inlier_scores(medium, surface, [state.T, home.T], state.gate)
    return polish(home) if after >= before else state


def _contradicted(evidence: visibility.Evidence) -> float:
    """Share of the cells the model covers that contradict it (hidden, missing, continued)."""
    return float(np.count_nonzero(evidence.cells <= -0.5) / max(np.count_nonzero(evidence.cells), 1))


def _misfit(evidence: visibility.Evidence) -> bool:
    """Whether a pose's view shows signs of sitting a little off: REFINE.misfit_share of its cells
    contradicted (hidden, missing, continued past its outline) or behind its surface."""
    cells = max(int(np.count_nonzero(evidence.cells)), 1)
    return (np.count_nonzero(evidence.cells <= -0.5) + evidence.off) >= REFINE.misfit_share * cells


def _moved(T: np.ndarray, reference: np.ndarray, centre: np.ndarray, gate: float) -> bool:
    """Whether two poses differ by more than a quarter of the gate at ``centre`` or 0.1 degrees."""
    shift = np.linalg.norm(frames.apply(T, centre[None]) - frames.apply(reference, centre[None]))
    return shift > 0.25 * gate or frames.rotation_between_deg(T, reference) > 0.1


def _verdict(scan: Cloud, sample: np.ndarray, surface: SurfaceModel, best, ranked: list, judge: Judge,
             options: MatchOptions, voxel: float, result: dict, timer: PhaseTimer) -> MatchResult:
    """Deviation statistics on the (sub)sampled scan points, stability, the view evidence of the
    best pose and its rivals (``ranked``: Judge.rank's Candidates), the model's symmetries, and the
    status with its reasons: "failed" for what rules the pose out (_failures), else "ambiguous" for
    what leaves it in doubt (_doubts), else "ok"."""
    T = best.T
    fit = _Fit.of(sample, surface, T, best.gate, voxel)
    stab = best.stability if best.stability is not None else stability(fit.matched, surface.normals[fit.samples])
    for held in stab.get("held_by_edges", []):
        result["warnings"].append(f"{held['motion']} is held only by the model's edges: the data leave "
                                  f"+/-{held['slack_mm']:.3f} mm of play, the pose is centred in it")
    view = _view_summary(ranked[0].evidence, judge)
    failures = _failures(fit, judge, view, options, T)
    if not failures:
        judge.weigh_far_off(ranked)
    # A fit worse than FAR_OFF.fit noises (what is taken as explaining the scan to its noise) leaves
    # structure in the residuals that the cells' spread does not see (the part differs from its model,
    # the sensor has its own): the standard errors are stretched by the excess, as a least-squares
    # fit's are by the square root of its reduced chi-square.
    fit_to_noise = fit.sigma / max(judge.noise, 1e-9)
    view["required_standard_errors"] = options.rival_significance * max(1.0, fit_to_noise / FAR_OFF.fit)
    _mark_rivals(ranked, fit_to_noise <= FAR_OFF.fit, view["required_standard_errors"], options)
    doubts = [] if failures else _doubts(ranked, surface, judge, view, stab, options, T)
    status = FAILED if failures else AMBIGUOUS if doubts else OK
    n_in, distance = len(fit.distance), fit.distance
    percentiles = {str(q): float(np.percentile(distance, q)) for q in (50, 90, 95, 99)} if n_in else {}
    return MatchResult(
        status, matrix=frames.invert(T), fitness=fit.fitness, coverage=fit.coverage,
        rms_mm=fit.rms,
        mean_directed_hausdorff_mm=float(distance.mean()) if n_in else float("nan"),
        max_deviation_mm=float(distance.max()) if n_in else float("nan"),
        percentiles_mm=percentiles,
        within_tolerance_pct=fit.within_pct(options.tolerance_mm),
        gate_mm=float(best.gate), n_inliers=int(round(fit.fitness * len(scan))), iterations=int(best.iterations),
        time_s=timer.total(), stability=stab, candidates=ranked, reasons=failures + doubts,
        noise_mm=float(judge.scan_noise), viewpoint=judge.viewpoint_info(), view=view,
        symmetries=_symmetry_list(surface), ties=[r for r in doubts if r.code in (OTHER_SIDE, RIVAL)], **result)


@dataclass(frozen=True)
class _Fit:
    """How the placed model fits the verdict's scan points: the residuals of those within the gate (and
    which model samples they lie on), their share of the points, the model's coverage, the residual scale."""

    matched: np.ndarray  # the points within the gate, in the model's frame
    samples: np.ndarray  # the nearest model sample of each
    deviation: np.ndarray  # signed point-to-plane residuals (mm)
    fitness: float
    coverage: float
    sigma: float

    @property
    def distance(self) -> np.ndarray:
        return np.abs(self.deviation)

    @property
    def rms(self) -> float:
        return float(np.sqrt(np.mean(self.deviation**2))) if len(self.deviation) else float("nan")

    def within_pct(self, tolerance: float) -> float:
        """The share (%) of the matched points within ``tolerance`` of the model."""
        return float(100 * np.mean(self.distance <= tolerance)) if len(self.deviation) else 0.0

    @classmethod
    def of(cls, sample: np.ndarray, surface: SurfaceModel, T: np.ndarray, gate: float, voxel: float) -> "_Fit":
        moved = frames.apply(T, sample)
        _, idx, found = surface.nearest_cell(moved, gate)
        deviation = surface.plane_residuals(moved[found], idx[found])
        n_in = int(found.sum())
        return cls(moved[found], idx[found], deviation, n_in / len(sample),
                   _coverage(moved[found], surface, voxel) if n_in else 0.0,
                   MAD_TO_SIGMA * float(np.median(np.abs(deviation))) if n_in else float("inf"))


def _failures(fit: _Fit, judge: Judge, view: dict, options: MatchOptions, T: np.ndarray) -> list:
    """The Reasons that fail a pose: a scan noisier than the tolerance, too few points on the model or too
    little of it covered, a fit outside the noise, a view largely contradicted (from around the viewpoint
    too, an estimated one being rough)."""
    noise, tolerance = judge.scan_noise, options.tolerance_mm
    reasons = []
    if noise > tolerance:
        reasons.append(Reason(NOISE_ABOVE_TOLERANCE, (
            f"the scan's own noise is {noise:.2f} mm (scatter about local surface fits), more than the "
            f"{tolerance:g} mm tolerance, so no fit can be checked to {tolerance:g} mm "
            f"on this scan: give a tolerance of at least {noise:.2f} mm or use a less noisy sensor")))
    if len(fit.deviation) < MIN_SCAN_POINTS or fit.fitness < options.min_fitness:
        reasons.append(Reason(FEW_POINTS, f"only {fit.fitness:.1%} of the scan points lie on the model (at least "
                                          f"{options.min_fitness:.0%} needed): the scan may not contain this model"))
    if fit.coverage < options.min_coverage:
        reasons.append(Reason(LOW_COVERAGE, f"the matched points cover only {fit.coverage:.1%} of the model surface "
                                            f"(at least {options.min_coverage:.0%} needed)"))
    if fit.sigma > VERDICT.max_noise_ratio * noise + tolerance:
        reasons.append(Reason(MISFIT, (
            f"the model does not fit the scan within its noise: residual scale {fit.sigma:.2f} mm where "
            f"the scan's own noise is {noise:.2f} mm (at most {VERDICT.max_noise_ratio:g} x noise + "
            f"{tolerance} mm tolerance): the scan may not contain this model")))
    if options.tolerance_gates and fit.rms > tolerance:
        reasons.append(Reason(RMS, (
            f"the fit's RMS {fit.rms:.3f} mm is more than the {tolerance:g} mm tolerance: the part differs "
            "from its model by more than the tolerance allows, or the pose is off")))
    within = fit.within_pct(tolerance)
    if options.tolerance_gates and within < VERDICT.min_within_tolerance_pct:
        reasons.append(Reason(WITHIN_TOLERANCE, (
            f"only {within:.0f} % of the matched points lie within the {tolerance:g} mm "
            f"tolerance (at least {VERDICT.min_within_tolerance_pct:.0f} %): the part differs from its model by more "
            "than the tolerance allows, or the pose is off")))
    if view.get("contradicted_pct", 0.0) > 100 * VERDICT.max_contradicted:
        view["contradicted_pct"] = 100 * judge.least_contradicted(T)
    if view.get("contradicted_pct", 0.0) > 100 * VERDICT.max_contradicted:
        reasons.append(Reason(VIEW_CONTRADICTED, (
            f"the placed model contradicts {view['contradicted_pct']:.0f} % of the view, from the viewpoint "
            f"and from up to {2 * VIEW.settle_step_deg:g} degrees around it (at most {100 * VERDICT.max_contradicted:.0f} "
            f"%): it would hide {view['hidden_points']} scan points and {view['missing_cells']} view cells "
            "of its surface facing the sensor show nothing; the pose leaves much of the scan unexplained")))
    return reasons


def _mark_rivals(ranked: list, best_fits: bool, significance: float, options: MatchOptions) -> None:
    """Mark the Candidates after the best that are rivals: no worse than the best by the view's cells, or
    better by the points they leave far off (by ``significance`` standard errors), or seen from the other
    side (or scoring ``ambiguity_ratio`` of the best).  The far-off test rules out only a pose refined
    exactly like the best (its turns, its flip tried always, and rivals near it by the view; one
    significantly better by the view's cells, or as good by them and leaving
    significantly fewer points far off, took the best's place, see Judge._with_turns), and only when both
    it and the best fit the scan within FAR_OFF.fit noises (``best_fits``, on the verdict's points and on
    the fine ones): a pose refined less (or one that does not fit) can leave points far off by being
    unconverged, and on scans simulated by ray casting (open3d 0.19) ruling out such a right pose made a
    flip "ok"."""
    fits = best_fits and ranked[0].fits
    for c in ranked[1:]:
        ruled_out_far_off = fits and c.fits and c.turn_of_best and c.far_off_standard_errors >= significance
        c.rival = bool((c.standard_errors_below_best < significance and not ruled_out_far_off)
                       or c.far_off_standard_errors <= -significance or c.from_the_other_side
                       or (options.ambiguity_ratio is not None and c.score_ratio >= options.ambiguity_ratio))


def _doubts(ranked: list, surface: SurfaceModel, judge: Judge, view: dict, stab: dict, options: MatchOptions,
            T: np.ndarray) -> list:
    """The Reasons that leave a pose that fits in doubt: the model's symmetries, rivals (seen from the
    other side, or clearly different), view behind the placed surface, a wall too thin for the noise, the
    scanned surface going on past the outline or a face, the model reaching through the table, a motion
    the surface leaves free."""
    reasons = []
    symmetries = surface.symmetries()
    if symmetries:
        reasons.append(Reason(SYMMETRIC, "the model is symmetric: " + "; ".join(symmetries) + " (in the model's "
                                         "frame): no scan can tell these poses apart, U is one of them"))
    rivals = [c for c in ranked[1:] if c.rival]
    other_side = [c for c in rivals if c.from_the_other_side]
    if other_side:
        reasons.append(Reason(OTHER_SIDE, (
            f"{len(other_side)} pose(s) put about as many scan points on the model seen from the other side "
            f"of it (the closest {other_side[0].rotation_from_best_deg:.1f} deg away): which side of the "
            "part the scan shows cannot be told without the scanner's position (give it as viewpoint)")))
    rivals = [c for c in rivals if not c.from_the_other_side]
    if rivals:
        r = min(rivals, key=lambda c: c.standard_errors_below_best)
        reasons.append(Reason(RIVAL, (
            f"{len(rivals)} clearly different pose(s) explain the view about as well: the closest, "
            f"{r.rotation_from_best_deg:.1f} deg away, scores {r.score_ratio:.0%} of the best, only "
            f"{r.standard_errors_below_best:.1f} standard errors below it ({view['cells']} view cells, "
            f"residual scale {judge.gate / VERDICT.evidence_sigmas:.2f} mm){_far_off_words(r)}, where "
            f"{view['required_standard_errors']:.1f} would tell them apart{_stretched_words(view, options)}: "
            "the part may be nearly symmetric; see candidates")))
    if view.get("off_pct", 0.0) > 100 * OUTLINE.max_off:
        reasons.append(Reason(BEHIND_SURFACE, (
            f"{view['off_pct']:.0f} % of the view inside the placed model's outline lies behind its surface "
            f"(at most {100 * OUTLINE.max_off:.0f} %): clay carved away, or a wrong pose that leaves that share of "
            "the scan unexplained")))
    # Walls under two sample spacings are not resolved by the sampled model: only look for thinner ones.
    resolved = VERDICT.thin_wall_noises * judge.noise > 2 * surface.spacing
    thickness = judge.wall_thickness(T, ranked[0].evidence) if resolved else float("inf")
    if thickness < VERDICT.thin_wall_noises * judge.noise:
        reasons.append(Reason(THIN_WALL, (
            f"the part is only {thickness:.1f} mm thick where the scan sees it, less than "
            f"{VERDICT.thin_wall_noises:g} times the noise ({judge.noise:.2f} mm): on this scan its two faces "
            "cannot be told apart")))
    if view.get("continued_pct", 0.0) > 100 * OUTLINE.max_continued:
        reasons.append(Reason(OUTLINE_CONTINUED, (
            f"the scanned surface goes on past the placed model's outline along {view['continued_pct']:.0f} % "
            f"of it (at most {100 * OUTLINE.max_continued:.0f} %): the pose may be off by that part of the scan, "
            "or something lies flush with the part there")))
    continued = judge.continued_faces(T)
    if continued >= OUTLINE.min_continued_points and continued > OUTLINE.max_continued_points * len(judge.all_points):
        reasons.append(Reason(FACE_CONTINUED, (
            f"{continued} scan points ({continued / len(judge.all_points):.0%}) lie off the placed model in "
            "the plane of a face of it that they run on from: the scanned face goes on past the model's "
            "edge, so the pose may lay it on another face (or the scan is scaled, or something lies "
            "flush with the part)")))
    depth = _depth_through_support(judge.support, surface, T)
    if depth > SUPPORT.tolerances * options.tolerance_mm:
        reasons.append(Reason(THROUGH_SUPPORT, (
            f"the placed model reaches {depth:.1f} mm through the plane the rest of the scan stands on "
            f"(at most {SUPPORT.tolerances:g} times the tolerance): a part cannot be inside the table "
            "it stands on, so the pose may be slid or turned (or the part stands in a pocket below "
            "that plane)")))
    if not stab["constrained"]:
        reasons.append(Reason(UNDER_CONSTRAINED, "the matched surface does not fix every motion (under-constrained): "
                                                 "free " + "; ".join(stab["free_motions"])))
    return reasons


@dataclass(frozen=True)
class Support:
    """The plane the scan's part stands on: the largest plane in the scan wider than the model
    (global_search.large_plane), its normal turned to the side most of the scan's other points lie
    on (the side parts stand on), and which of the points it was found in lie on it."""

    on_plane: np.ndarray
    centre: np.ndarray
    normal: np.ndarray
    band: float  # mm each side of the plane

    def holds(self, points: np.ndarray) -> np.ndarray:
        """Which of ``points`` lie within the band of the plane."""
        return np.abs((points - self.centre) @ self.normal) <= self.band

    @classmethod
    def given(cls, points: np.ndarray, centre, normal, band: float):
        """The support a caller knows (a calibration's platform): the points within ``band`` mm of it."""
        centre, normal = np.asarray(centre, float), np.asarray(normal, float) / np.linalg.norm(normal)
        return cls(np.abs((points - centre) @ normal) <= band, centre, normal, float(band))

    @classmethod
    def of(cls, points: np.ndarray, voxel: float, model_diagonal: float, seed: int):
        """The support of scan ``points`` (None without such a plane)."""
        plane = global_search.large_plane(points, voxel, model_diagonal, np.random.default_rng(seed))
        if plane is None:
            return None
        on_plane, centre, normal = plane
        height = (points[~on_plane] - centre) @ normal
        if np.count_nonzero(height < -voxel) > np.count_nonzero(height > voxel):
            normal = -normal
        return cls(on_plane, centre, normal, voxel)


def _off_support(points: np.ndarray, support: Support | None, band: float) -> np.ndarray:
    """``points`` less those within ``band`` of the support (and its own band), unless too few would be left."""
    if support is None:
        return points
    kept = points[np.abs((points - support.centre) @ support.normal) > min(band, support.band)]
    return kept if len(kept) >= MIN_SCAN_POINTS else points


def _depth_through_support(support: Support | None, surface: SurfaceModel, T: np.ndarray) -> float:
    """How far (mm) the model placed by T (scan -> model) reaches through the scan's support; 0
    without one.  A shell slid along its bend still fits the scan where both overlap, but sinks one
    end into the table."""
    if support is None:
        return 0.0
    placed = frames.apply(frames.invert(T), surface.points)
    return float(max(0.0, -((placed - support.centre) @ support.normal).min()))


def _stretched_words(view: dict, options: MatchOptions) -> str:
    """Why more standard errors than ``rival_significance`` are asked, for a rival's reason."""
    if view["required_standard_errors"] <= options.rival_significance:
        return ""
    ratio = FAR_OFF.fit * view["required_standard_errors"] / options.rival_significance
    return (f" (the model explains the scan only to {ratio:.1f} times its noise: the part differs from its "
            "model, or the sensor has structure of its own)")


def _far_off_words(candidate: Candidate) -> str:
    """How a rival fares by the scan points it leaves far off, for its reason."""
    far = candidate.far_off_standard_errors
    return f", and {far:.1f} by the scan points it leaves far off the part" if far > -1 else (
        f", and {-far:.1f} above it by the scan points it leaves far off the part")


def _view_summary(evidence: visibility.Evidence, judge: Judge) -> dict:
    """How the best pose's view evidence reads: cells where the model is, the share contradicted."""
    involved = evidence.cells != 0
    summary = {"cells": int(involved.sum()), "explained_points": evidence.explained,
               "hidden_points": evidence.hidden, "missing_cells": evidence.missing,
               "continued_cells": evidence.continued,
               "evidence_gate_mm": judge.gate, "with_visibility": judge.view is not None}
    if judge.view is not None and involved.any():
        summary["contradicted_pct"] = float(100 * np.mean(evidence.cells[involved] <= -0.5))
        summary["continued_pct"] = float(100 * evidence.continued / max(evidence.outline, 1))
        summary["off_pct"] = float(100 * evidence.off / max(evidence.inside, 1))
    return summary


def _symmetry_list(surface: SurfaceModel) -> list:
    """The model's symmetries for the result (model frame): axis, a point on it, order, words."""
    from .symmetry import describe

    return [{"axis": a.tolist(), "point_mm": p.tolist(), "order": int(n), "deviation_mm": float(d),
             "description": describe(a, p, [n])[0]}
            for a, p, n, d in zip(surface.symmetry_axes, surface.symmetry_points, surface.symmetry_orders,
                                  surface.symmetry_deviations_mm)]


def _coverage(matched: np.ndarray, surface: SurfaceModel, voxel: float) -> float:
    """Fraction of the model's occupied cells (coarse voxels) that hold a matched point."""
    cells = surface.occupied_cells(voxel)
    return float(np.isin(cells, surface.cell_keys(matched, voxel), assume_unique=False).mean())
