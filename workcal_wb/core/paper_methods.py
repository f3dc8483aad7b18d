"""The paper's two shape measures as refinement methods, for comparison with the robust one.

D, the least-squares closest-point measure, is minimised by ICP (Besl and McKay 1992): find each
scan point's closest point on the model surface, move the scan by the rigid motion that best fits
those pairs in the least-squares sense (point-to-point, closed form), repeat.

H, the mean directed Hausdorff distance (mean over scan points of the distance to the nearest model
point), has no closed-form step.  As in the paper, its nearest-point search is accelerated by a
precomputed 3D space binning: a grid around the model whose cells store their nearest model point,
so each distance is one array lookup.  It is minimised by sampled derivatives: H is evaluated at
small steps along each of the 6 pose parameters around the current transform, the pose moves
downhill along that sampled gradient, and the step grows after a success and shrinks after a
failure until it is below the tolerance.

Both move scan points onto the model (scan -> model).  Like the robust method they only count points
within a gate that shrinks towards the measured residual scale, so clutter and the unseen part of
the model do not drag the pose; neither has a robust kernel, which is the paper's formulation.
"""
from __future__ import annotations

import numpy as np

from . import pointops
from .frames import from_rotvec
from .global_search import kabsch_batch
from .refine import RefineState, is_small
from .robust import MAD_TO_SIGMA
from .surface import SurfaceModel

PAPER_METHODS = ("icp", "hausdorff")
# Gate passes before giving up on shrinking it further, and steps per pass.
MAX_PASSES, ICP_ITERATIONS, HAUSDORFF_ITERATIONS = 8, 60, 150
# Hausdorff: points evaluated (a random subset: 13 evaluations per step), and the binning cell in
# model sample spacings (the grid is filled ahead of time over the whole gate, so not finer).
HAUSDORFF_POINTS, BINNING_CELLS = 4000, 2.0


def refine_paper(method: str, points: np.ndarray, surface: SurfaceModel, T: np.ndarray,
                 gate: float | None = None, tolerance: float = 1e-5) -> RefineState:
    """Refine ``T`` (scan -> model) by minimising D ("icp") or H ("hausdorff") over ``points``.

    ``gate`` (mm, default a 40th of the model diagonal) is where the search starts; ``tolerance``
    is the smallest step, in radians and in the same times the model diagonal in mm.
    """
    if method not in PAPER_METHODS:
        raise ValueError(f"paper method must be one of {PAPER_METHODS}, not {method!r}")
    gate = gate if gate is not None else surface.diagonal / 40
    if method == "hausdorff":
        points = pointops.random_subset(points, HAUSDORFF_POINTS, np.random.default_rng(0))
        grid = surface.grid(BINNING_CELLS * surface.spacing, gate)  # the binning, for every gate to come
        grid.precompute()
    state = RefineState(np.asarray(T, float).copy(), gate=gate)
    total = 0
    for _ in range(MAX_PASSES):
        if method == "icp":
            state = _icp(points, surface, state.T, gate, tolerance)
        else:
            state = _hausdorff(points, surface, grid, state.T, gate, tolerance)
        total += state.iterations
        new_gate = min(gate, max(surface.spacing, gate / 4, 4 * state.sigma + surface.spacing))
        if new_gate >= 0.9 * gate:
            break
        gate = new_gate
    state.iterations, state.gate = total, gate
    return state


def closest_points(moved: np.ndarray, surface: SurfaceModel, gate: float):
    """Each point's closest point on the model surface (the foot on the tangent plane of its nearest
    sample) and which points have one within ``gate``."""
    _, idx, found = surface.nearest_cell(moved, gate)
    n = surface.normals[idx]
    foot = moved - np.einsum("ij,ij->i", moved - surface.points[idx], n)[:, None] * n
    found &= np.linalg.norm(moved - foot, axis=1) <= gate
    return foot, found


def _icp(points, surface: SurfaceModel, T, gate, tolerance) -> RefineState:
    """Point-to-point ICP at a fixed gate: D = mean squared distance to the closest points."""
    state = RefineState(T.copy(), gate=gate)
    tol_shift = tolerance * surface.diagonal
    for it in range(ICP_ITERATIONS):
        moved = points @ state.T[:3, :3].T + state.T[:3, 3]
        foot, found = closest_points(moved, surface, gate)
        if found.sum() < 3:
            break
        distance = np.linalg.norm(moved[found] - foot[found], axis=1)
        state.sigma = MAD_TO_SIGMA * float(np.median(distance))
        step = kabsch_batch(moved[found][None], foot[found][None])[0]
        state.T = step @ state.T
        state.iterations = it + 1
        if is_small(step, tolerance, tol_shift):
            break
    return state


def hausdorff_distances(moved: np.ndarray, surface: SurfaceModel, grid, gate: float) -> np.ndarray:
    """Distance of each point to the model through the binning, capped at ``gate``.

    The cell's sample gives the tangent plane: the distance is the height above it, plus whatever
    lies beyond a cell sideways (so points off the model's edge are not measured to an endless plane).
    """
    idx = grid.lookup(moved)
    far = idx < 0
    idx = np.where(far, 0, idx)
    offset = moved - surface.points[idx]
    height = np.einsum("ij,ij->i", offset, surface.normals[idx])
    sideways = np.sqrt(np.maximum(np.einsum("ij,ij->i", offset, offset) - height**2, 0))
    distance = np.hypot(height, np.maximum(sideways - grid.cell, 0))
    return np.where(far, gate, np.minimum(distance, gate))


def _hausdorff(points, surface: SurfaceModel, grid, T, gate, tolerance) -> RefineState:
    """Minimise H at a fixed gate by sampled derivatives over 6 pose parameters around T: a rotation
    vector about the points' centre (scaled by their RMS radius, so its steps are mm at the
    surface) and a translation."""
    state = RefineState(T.copy(), gate=gate)
    moved = points @ T[:3, :3].T + T[:3, 3]
    centre = moved.mean(axis=0)
    radius = float(np.sqrt(((moved - centre) ** 2).sum(axis=1).mean())) or 1.0

    def pose(y):
        step = from_rotvec(y[:3] / radius)
        step[:3, 3] = y[3:] + centre - step[:3, :3] @ centre  # rotate about the centre
        return step @ state.T

    def H(y):
        P = pose(y)
        return hausdorff_distances(points @ P[:3, :3].T + P[:3, 3], surface, grid, gate).mean()

    step, smallest = gate / 4, tolerance * surface.diagonal
    current = H(np.zeros(6))
    for it in range(HAUSDORFF_ITERATIONS):
        if step < smallest:
            break
        probe = max(step / 2, smallest)
        gradient = np.array([(H(e) - H(-e)) / (2 * probe) for e in np.eye(6) * probe])
        norm = np.linalg.norm(gradient)
        if norm == 0:
            break
        trial = -step * gradient / norm
        value = H(trial)
        if value < current:
            state.T, current, step = pose(trial), value, step * 1.5
            moved = points @ state.T[:3, :3].T + state.T[:3, 3]
            centre = moved.mean(axis=0)
        else:
            step /= 2
        state.iterations = it + 1
    moved = points @ state.T[:3, :3].T + state.T[:3, 3]
    d = hausdorff_distances(moved, surface, grid, gate)
    state.sigma = MAD_TO_SIGMA * float(np.median(d[d < gate])) if (d < gate).any() else float("inf")
    return state
