"""Robust point-to-plane refinement, coarse to fine.

Scan points are moved onto the model surface (scan -> model; the caller inverts to get U).  Each
stage gates correspondences by distance and weights plane residuals with a Geman-McClure kernel;
between stages both the gate and the kernel scale shrink towards the measured noise, so clutter,
the unseen part of the model and clay added or carved since the model was made stop pulling the
pose once it is close.  Point-to-plane converges in a few Gauss-Newton steps per stage.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from . import pointops
from .robust import MAD_TO_SIGMA, gauss_newton_step, geman_mcclure
from .surface import SurfaceModel

# Exact point-to-surface steps at most (each one closest-point query of every point).
EXACT_ITERATIONS = 30
# An offset from the closest surface point that leaves the face normal by more than acos(EDGE_COSINE)
# (~8 deg) comes from an edge or a corner; below EDGE_MIN_MM its direction is float32 noise.
EDGE_COSINE, EDGE_MIN_MM = 0.99, 1e-3


@dataclass
class RefineState:
    T: np.ndarray  # scan -> model
    iterations: int = 0
    sigma: float = float("inf")  # robust residual scale of the last stage (mm)
    gate: float = float("inf")
    scale: float = float("inf")  # Geman-McClure kernel scale of the last stage (mm)
    stability: dict | None = None  # set when the fit checked its weak motions (edges.centre_on_edges)


def refine(points: np.ndarray, model: SurfaceModel, T: np.ndarray, gate: float, scale: float,
           max_iterations: int = 30, tolerance: float = 1e-5) -> RefineState:
    """Iterate weighted point-to-plane steps at a fixed gate and kernel scale until the motion is
    below ``tolerance`` (radians, and the same times the model diagonal in mm).  ``sigma`` comes
    from the residuals of the last step, taken before it moved the pose by almost nothing."""
    state = RefineState(T.copy(), gate=gate, scale=scale)
    tol_shift = tolerance * model.diagonal
    for it in range(max_iterations):
        moved = points @ state.T[:3, :3].T + state.T[:3, 3]
        found, r, normals = model.tangent_planes(moved, gate)
        if len(r) < 6:
            break
        state.sigma = MAD_TO_SIGMA * pointops.median(np.abs(r))
        step = gauss_newton_step(moved[found], normals, r, geman_mcclure(r, scale))
        state.T = step @ state.T
        state.iterations = it + 1
        if is_small(step, tolerance, tol_shift):
            break
    return state


def refine_exact(points: np.ndarray, model: SurfaceModel, state: RefineState,
                 max_iterations: int = EXACT_ITERATIONS, tolerance: float = 1e-5) -> RefineState:
    """Continue ``state`` with steps against the exact closest point of a mesh model, at its gate
    and kernel scale.

    Sampled surfaces blur every edge over a sample spacing, and edges are all that pin a motion
    the faces leave nearly free (a block seen on two faces slides along both): there the sampled
    fit stops a few tenths of a mm off.  A scan point past an edge is pulled back along its offset
    from the edge (the gradient of the distance), not along a face normal that ignores the edge.
    Such a motion converges by a constant factor per step, hence the many steps allowed.
    """
    state = replace(state, T=state.T.copy())
    tol_shift = tolerance * model.diagonal
    for _ in range(max_iterations):
        moved = points @ state.T[:3, :3].T + state.T[:3, 3]
        # Far points cost the exact query most and count for nothing: the sampled surface drops them.
        moved = moved[model.nearest_cell(moved, state.gate + model.spacing)[2]]
        closest, normals = model.closest_points(moved)
        offset = moved - closest
        distance = np.linalg.norm(offset, axis=1)
        found = distance <= state.gate
        if found.sum() < 6:
            break
        moved, offset = moved[found], offset[found]
        directions = np.where(past_edge(offset, normals[found])[:, None],
                              offset / np.maximum(distance[found], 1e-12)[:, None], normals[found])
        r = np.einsum("ij,ij->i", offset, directions)
        state.sigma = MAD_TO_SIGMA * pointops.median(np.abs(r))
        step = gauss_newton_step(moved, directions, r, geman_mcclure(r, state.scale))
        state.T = step @ state.T
        state.iterations += 1
        if is_small(step, tolerance, tol_shift):
            break
    return state


def past_edge(offset: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Whether each point's closest surface point is on an edge or a corner rather than inside a
    face (see EDGE_COSINE, EDGE_MIN_MM)."""
    distance = np.linalg.norm(offset, axis=1)
    return (distance > EDGE_MIN_MM) & (np.abs(np.einsum("ij,ij->i", offset, normals)) < EDGE_COSINE * distance)


def is_small(step: np.ndarray, angle_rad: float, shift_mm: float) -> bool:
    """Whether an iteration's motion is below both limits: the fit has converged."""
    angle = np.arccos(np.clip((np.trace(step[:3, :3]) - 1) / 2, -1, 1))
    return angle < angle_rad and np.linalg.norm(step[:3, 3]) < shift_mm


def coarse_to_fine(stages: list[np.ndarray], model: SurfaceModel, T: np.ndarray, gate: float,
                   floor: float, iterations_per_pass: int = 10, tolerance: float = 1e-4) -> RefineState:
    """Refine through point sets of growing density.  After each pass the gate shrinks towards
    4 sigma plus the model's sample spacing (never below ``floor`` mm) and the kernel scale towards
    2.5 sigma, sigma being the measured residual scale; a density is done when neither shrinks
    by more than 10 %.  The default ``tolerance`` (see ``refine``) leaves the last 0.01 deg to a
    final pass on more points."""
    state = RefineState(T, gate=gate)
    scale, min_scale = gate / 3, 1e-4 * model.diagonal
    total = 0
    for points in stages:
        for _ in range(8):
            state = refine(points, model, state.T, gate, scale, iterations_per_pass, tolerance)
            total += state.iterations
            # Shrink towards the targets, at most 4x per pass so a poor sigma cannot strand the pose.
            new_gate = min(gate, max(floor, gate / 4, 4 * state.sigma + model.spacing))
            new_scale = min(scale, max(min_scale, scale / 4, 2.5 * state.sigma))
            if new_gate >= 0.9 * gate and new_scale >= 0.9 * scale:
                break
            gate, scale = new_gate, new_scale
    state.iterations, state.gate, state.scale = total, gate, scale
    return state
