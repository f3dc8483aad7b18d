"""How far a scan's own distortion moves W: a scanner whose scale or axes are off.

A scan that its scanner made 0.5 % too large still fits each model closely: each rigid match takes up
what it can of the distortion, the residuals stay small and so does the bootstrap spread, which only
sees the noise.  But W joins two matches that sit apart, and each took up the distortion about its own
region: W moves by about the distortion times their distance (0.5 % of 300 mm is 1.5 mm), an "ok" with a
wrong pose.  So the distortion is measured: one symmetric strain for the whole scan (its turning part is
a rigid motion, harmless), fitted with one small rigid motion per region by point-to-plane least squares
(Tukey-weighted), on the points near their models (every point a match was finished on among them),
linearised at the final poses and again where each step leaves the points (FIT.iterations).  What each
region's rigid motion takes up of that strain, differenced between the two regions at the toolpath, is
how far W moves.  Noise must not read as strain: near a block's edges it reads one-sided whichever
plane a point is measured against, so on meshes those points are left out (FIT.edge_deg); and each point's
lever is its foot on its face, not the point, whose noise moves lever and residual together
(_linearised).  What the check reads on distorted and on clean scenes: docs/tuning.md.

Whose strain is it?  The reference is the cell's standard (rigid, its model exact): along the strains
it shows, its points tell the scanner's.  Along the others (two faces of a block seen do not show its
scale) only the workpiece can tell, and its strain may be the scanner's or its own: a workpiece differs
from its model often enough (clay, a casting; a real range scan against a model zippered from several),
and that does not move W.  So the workpiece's strain there counts only where
both objects agree that the scan is strained: the reference reads a strain along what it shows and the
workpiece reads the same there (within WHOSE.agreement).  Otherwise it is taken as the part's own, and the
calibration warns with the reading and how far it would move W were it the scanner's
(``shift_if_scanner_mm``): only a reference that shows that strain can tell.

The scale and the strains that keep the volume count only along the directions the points show them
in (READING.shown_mm): a small part beside a reference of flat faces leaves some stretches and
shears nearly rigid on both, and along those the fit would read a percent of strain out of the models'
and the sensor's micrometres.  A strain no point shows is not found: the check is blind to it, as every
fit is.  Nor is a strain within the noise of its own fit (READING.significance).

Only the calibration can see a distortion: a lone match has no second region for it to move against,
its pose is the best rigid fit of a scan of another size.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import chdtri

from . import frames
from .robust import MAD_TO_SIGMA
from .surface import SurfaceModel

# The six components of a symmetric strain, as (row, column); (0, 1) stands for both (0, 1) and (1, 0).
STRAIN_COMPONENTS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))
_R2, _R3, _R6 = np.sqrt(2.0), np.sqrt(3.0), np.sqrt(6.0)
# Strains of unit (Frobenius) size as columns of components: the scale, then five that keep the volume.
STRAIN_BASIS = np.array([[1 / _R3, 1 / _R3, 1 / _R3, 0, 0, 0],
                         [1 / _R2, -1 / _R2, 0, 0, 0, 0],
                         [1 / _R6, 1 / _R6, -2 / _R6, 0, 0, 0],
                         [0, 0, 0, 1 / _R2, 0, 0],
                         [0, 0, 0, 0, 1 / _R2, 0],
                         [0, 0, 0, 0, 0, 1 / _R2]]).T
@dataclass(frozen=True)
class ReadingSettings:
    """Which strains the check reads: those the points show, beyond the noise of its fit."""

    # A direction of strain counts when a unit strain along it, after the best rigid motion of each region,
    # moves the points off their models by at least this RMS (mm): 5 um for a 0.1 % strain.
    shown_mm: float = 5.0
    # A scale's information below this share of a shown direction's is rounding: none to free (_strain).
    scale_rounding: float = 1e-9
    # A strain counts when the squares it explains are beyond this quantile of what noise explains (chi-square):
    # noise alone must not read as a strain.
    significance: float = 0.999


READING = ReadingSettings()


@dataclass(frozen=True)
class FitSettings:
    """The strain's fit: its robust weights, its linearisations, the points it is made on."""

    # Tukey's biweight: a point weighs nothing beyond this many robust scales of its region, since mixed pixels
    # and multipath along a silhouette lie off the surface on one side and, weighed fully, read as the scan growing.
    tukey_scales: float = 4.685
    reweights: int = 3
    # The fit is linearised where the points lie, at most this many times, each where the strain found so far leaves
    # them, until a step is below ``settled`` (unit-size strain: 3 um over 300 mm): once reads a large strain short.
    iterations: int = 4
    settled: float = 1e-5
    # On a mesh, a point counts only where the faces nearest a gate inside and outside its foot turn less than this
    # from its face or its back (a thin wall): near an edge, noise pushes points nearer the side face, reading short.
    edge_deg: float = 30.0
    # A region with fewer points near its model than this shows no strain.
    min_points: int = 50


FIT = FitSettings()


@dataclass(frozen=True)
class WhoseSettings:
    """Whose strain it is: the scanner's, or the workpiece's own (it differs from its model)."""

    # A workpiece whose strain along the reference's differs from what the reference reads by more than this
    # (unit-size strain) differs from its model: a scanner's strain reads alike on both objects.
    agreement: float = 5e-4
    # A part differs from its model by a few tenths of a percent over the whole (unit-size strain), not by this:
    # a workpiece reading more is taken as the scanner, or a large scale would pass as the part's own.
    own_limit: float = 0.015


WHOSE = WhoseSettings()


def distortion(regions, surfaces, poses, targets: np.ndarray, gates) -> dict:
    """The scan's strain and the largest shift of W at ``targets`` (model X points) it causes.

    ``regions``: the scan points of the workpiece and the reference; ``surfaces``: their models;
    ``poses``: U and V (model to scan); ``gates``: how far (mm) a point of each may lie from its model.
    """
    centre = np.mean(np.concatenate(regions), axis=0)
    total, as_scanned, own = np.zeros(len(STRAIN_COMPONENTS)), None, None
    for _ in range(FIT.iterations):
        blocks = [_linearised(points, surface, pose, gate, centre)
                  for points, surface, pose, gate in zip(regions, surfaces, poses, gates)]
        if min(len(residuals) for residuals, _, _ in blocks) < FIT.min_points:
            break
        # Whose strain it is, is told on the points as scanned; the steps after it refine that strain.
        step, own, on_workpiece, weights, not_shown = _step(blocks, own)
        if as_scanned is None:  # what the matches took up, they took up of the points as scanned
            as_scanned, as_read, unverified = (blocks, weights), on_workpiece, (not_shown if own else 0)
        total += step
        if np.linalg.norm(step) < FIT.settled:
            break
        # Undone so far: the next step is linearised where the points now lie, nearer their models.
        regions = [points + _displacement(points - centre, step, _rigid(rigid, -(residuals + strains @ step), w))
                   for points, (residuals, strains, rigid), w in zip(regions, blocks, weights)]
    if as_scanned is None:
        return {"strain": np.zeros((3, 3)), "scale_pct": 0.0, "largest_strain_pct": 0.0, "shift_mm": 0.0,
                "workpiece_own_pct": 0.0, "shift_if_scanner_mm": 0.0}
    at = frames.apply(poses[0], targets) - centre
    strain = -_matrix(total)  # the fit found the steps undoing the strain
    return {"strain": strain, "scale_pct": float(100 * np.trace(strain) / 3),
            "largest_strain_pct": float(100 * np.abs(np.linalg.eigvalsh(strain)).max()),
            "shift_mm": _shift(total, *as_scanned, at),
            "workpiece_own_pct": float(100 * np.linalg.norm(as_read)) if own else 0.0,
            "shift_if_scanner_mm": _shift(total + unverified, *as_scanned, at) if own else 0.0}


def _shift(total: np.ndarray, blocks, weights, at: np.ndarray) -> float:
    """The largest shift of W at the points ``at`` (about the centre) that the strain ``total`` (STRAIN_BASIS
    coefficients of the steps undoing it) causes: what each match's rigid motion takes up of it (its
    weighted least-squares answer to it alone), differenced between the two regions."""
    taken_up = [_rigid(rigid, strains @ total, w) for (_, strains, rigid), w in zip(blocks, weights)]
    difference = taken_up[0] - taken_up[1]
    return float(np.linalg.norm(np.cross(difference[:3], at) + difference[3:], axis=1).max())


def _step(blocks, own: bool | None = None):
    """(strain step, whether the workpiece's strain is its own, its reading, the points' weights, the
    scan's reading along what the reference does not show) of one linearisation; ``own``: as told
    before (None: tell it here)."""
    on_reference, shown, reference_weights = _measured(blocks[1:])
    on_workpiece, _, _ = _measured(blocks[:1])
    on_both, _, weights = _measured(blocks)
    not_shown = on_both - shown @ (shown.T @ on_both)
    # The reference is the cell's standard: along the strains it shows, what it shows is the scanner's.
    # Along the others only the workpiece can tell, and it may be the scanner or the model: counted only
    # when both objects agree that the scan is strained (the reference reads a strain along what it shows,
    # and the workpiece the same there); else it differs from its model (a clay, a real range scan), and
    # its strain is its own.
    # A strain beyond WHOSE.own_limit is no part's own, and the reference's reading of it may be cut short (its
    # ends beyond the gates): the whole scan's reading counts.
    if np.linalg.norm(on_workpiece) > WHOSE.own_limit:
        return on_both, False, on_workpiece, weights, not_shown
    if own is None:
        own = not (np.linalg.norm(shown.T @ on_reference) > 0
                   and _disagree(on_workpiece, blocks[1:], reference_weights, shown) <= WHOSE.agreement)
    step = shown @ (shown.T @ on_reference) + (0 if own else not_shown)
    return step, own, on_workpiece, weights, not_shown


def _matrix(coefficients: np.ndarray) -> np.ndarray:
    """The symmetric 3 x 3 strain of STRAIN_BASIS ``coefficients``."""
    strain = np.zeros((3, 3))
    for value, (row, column) in zip(STRAIN_BASIS @ coefficients, STRAIN_COMPONENTS):
        strain[row, column] = strain[column, row] = value
    return strain


def _displacement(x: np.ndarray, coefficients: np.ndarray, rigid: np.ndarray) -> np.ndarray:
    """How the strain and the small rigid motion (turn, shift) move the points ``x`` (about the centre)."""
    return x @ _matrix(coefficients) + np.cross(rigid[:3], x) + rigid[3:]


def _measured(blocks):
    """The strain (STRAIN_BASIS coefficients) the regions' points show, the directions it was measured
    along (orthonormal columns) and the points' final weights; none when within the noise of its fit."""
    weights = [np.ones(len(residuals)) for residuals, _, _ in blocks]
    for round_ in range(FIT.reweights + 1):
        coefficients, explained, directions = _strain(blocks, weights)
        left = [_left(block, coefficients, w) for block, w in zip(blocks, weights)]
        if round_ < FIT.reweights:
            weights = [_biweights(e) for e in left]
    weight, residuals = np.concatenate(weights), np.concatenate(left)
    noise = np.sum(weight * residuals ** 2) / max(np.sum(weight) - 6 * (len(blocks) + 1), 1.0)
    if not explained > noise * chdtri(max(directions.shape[1], 1), 1 - READING.significance):  # chi-square quantile
        coefficients = np.zeros(len(STRAIN_COMPONENTS))
    return coefficients, directions, weights


def _disagree(strain: np.ndarray, blocks, weights, shown: np.ndarray) -> float:
    """How far ``strain`` along the directions ``shown`` lies from what the points read along them,
    the strain's other components held (the reference does not show a scale of 1 %, but it leaks into
    what it reads along the strains it shows: read freely, they disagreed with a workpiece's 0.07 %)."""
    if not shown.shape[1]:
        return 0.0
    information, gradient, _ = _information(blocks, weights)
    others = np.linalg.svd(np.eye(6) - shown @ shown.T)[0][:, :6 - shown.shape[1]]
    held = others @ (others.T @ strain)
    read = _solve(shown.T @ information @ shown, shown.T @ (gradient - information @ held))
    return float(np.linalg.norm(shown.T @ strain - read))


def _information(blocks, weights) -> tuple[np.ndarray, np.ndarray, float]:
    """The weighted normal equations of the strain, each region's rigid motion eliminated, and the
    points' total weight."""
    information, gradient, total = np.zeros((6, 6)), np.zeros(6), 0.0
    for (residuals, strains, rigid), w in zip(blocks, weights):
        cross = strains.T @ (rigid * w[:, None])
        through_rigid = _solve(rigid.T @ (rigid * w[:, None]), np.column_stack([cross.T, rigid.T @ (w * residuals)]))
        information += strains.T @ (strains * w[:, None]) - cross @ through_rigid[:, :6]
        gradient -= strains.T @ (w * residuals) - cross @ through_rigid[:, 6]
        total += w.sum()
    return information, gradient, total


def _strain(blocks, weights) -> tuple[np.ndarray, float, np.ndarray]:
    """The strain (STRAIN_BASIS coefficients) that with a rigid motion per region best undoes the
    residuals, within the scale and the volume-keeping directions the points show (READING.shown_mm); the
    weighted squares it explains, and those directions."""
    information, gradient, total = _information(blocks, weights)
    if not total > 0:  # every point weighs nothing: nothing to measure
        return np.zeros(6), 0.0, np.zeros((6, 0))
    scale, volume = information[0, 0], information[1:, 1:]
    # The volume-keeping strains with the scale free; none to free when the regions' motions take it up
    # whole (one face seen: its information is zero but for rounding, and so are its cross terms).
    if scale > READING.scale_rounding * READING.shown_mm ** 2 * total:
        volume = volume - np.outer(information[1:, 0], information[0, 1:]) / scale
    values, vectors = np.linalg.eigh(volume)
    shown = np.sqrt(np.maximum(values, 0.0) / total) >= READING.shown_mm
    directions = np.zeros((6, 1 + shown.sum()))
    directions[0, 0] = 1.0
    directions[1:, 1:] = vectors[:, shown]
    if not np.sqrt(max(scale, 0.0) / total) >= READING.shown_mm:
        directions = directions[:, 1:]
    reduced = directions.T @ information @ directions
    coefficients = _solve(reduced, directions.T @ gradient)
    return directions @ coefficients, coefficients @ reduced @ coefficients, directions


def _left(block, coefficients: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """A region's residuals once the strain and the region's best rigid motion are undone."""
    residuals, strains, rigid = block
    strained = residuals + strains @ coefficients
    return strained + rigid @ _rigid(rigid, -strained, weights)


def _rigid(rigid: np.ndarray, target: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """The small rigid motion (turn, shift) that best moves the points by ``target`` along their normals."""
    return _solve(rigid.T @ (rigid * weights[:, None]), rigid.T @ (weights * target))


def _solve(matrix: np.ndarray, right: np.ndarray) -> np.ndarray:
    """A symmetric system; a motion the points leave free (a sphere's turns) gets the least-norm answer."""
    return np.linalg.lstsq(matrix, right, rcond=1e-12)[0]


def _biweights(residuals: np.ndarray) -> np.ndarray:
    """Tukey's biweight of each residual of one region, on the region's robust scale."""
    scale = MAD_TO_SIGMA * np.median(np.abs(residuals - np.median(residuals)))
    u = residuals / (FIT.tukey_scales * scale) if scale > 0 else np.zeros(len(residuals))
    return np.where(np.abs(u) < 1, (1 - u ** 2) ** 2, 0.0)


def _linearised(points: np.ndarray, surface: SurfaceModel, pose: np.ndarray, gate: float, centre: np.ndarray):
    """Point-to-plane residuals of the points within ``gate`` of their model at ``pose``, and their
    derivatives (in the scan's frame, about ``centre``) by the strains of STRAIN_BASIS and by a small
    rigid motion.  On a mesh, each point against its exact closest face, away from the face's edges
    (FIT.edge_deg): near an edge the noise is read short on one side (a point pushed into a block near its
    edge is nearer the side face) or on a face not its own.  A point model has only its samples' tangent
    planes; the nearest sample may lie up to a spacing beside a point's foot."""
    in_model = frames.apply(frames.invert(pose), points)
    if surface.is_mesh:
        feet, normals = surface.closest_points(in_model)
        near = np.flatnonzero(np.linalg.norm(in_model - feet, axis=1) <= gate)  # not NaN (a point not finite)
        alike = np.cos(np.radians(FIT.edge_deg))
        for side in (-gate, gate):  # the faces nearest a gate inside and outside the foot: its face or its back
            _, beside = surface.closest_points(feet[near] + side * normals[near])
            near = near[np.abs(np.einsum("ij,ij->i", beside, normals[near])) >= alike]
        normals = normals[near]
        residuals = np.einsum("ij,ij->i", in_model[near] - feet[near], normals)
    else:
        _, index, found = surface.nearest(in_model, gate + surface.spacing)
        near = np.flatnonzero(found)
        residuals = surface.plane_residuals(in_model[near], index[near])
        kept = np.abs(residuals) <= gate
        near, residuals = near[kept], residuals[kept]
        normals = surface.normals[index[near]]
    # The lever is the point's foot on its face's (or sample's tangent) plane, not the point: a point's noise
    # moves its residual and its lever together, and their product reads as a strain beyond what the noise
    # explains (at 0.35 mm, 2-4 times the chi-square's mean: 4-14 % of draws of noise on undistorted low
    # views read a strain).
    x = frames.apply(pose, in_model[near] - residuals[:, None] * normals) - centre
    normals = normals @ pose[:3, :3].T
    components = np.column_stack([normals[:, r] * x[:, c] + (normals[:, c] * x[:, r] if r != c else 0)
                                  for r, c in STRAIN_COMPONENTS])
    return residuals, components @ STRAIN_BASIS, np.column_stack([np.cross(x, normals), normals])
