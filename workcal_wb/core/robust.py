"""Robust point-to-plane maths shared by refinement (refine.py) and a model's self-matching (symmetry.py).

The weighted Gauss-Newton step of point-to-plane residuals, the Geman-McClure kernel that weighs them,
and the factor that turns a median absolute deviation into a noise scale.
"""
from __future__ import annotations

import numpy as np

from .frames import from_rotvec

# Median absolute deviation -> standard deviation for Gaussian noise.
MAD_TO_SIGMA = 1.4826


def gauss_newton_step(points: np.ndarray, normals: np.ndarray, residuals: np.ndarray,
                      weights: np.ndarray) -> np.ndarray:
    """One weighted point-to-plane step: the small motion (4x4) that best zeroes the residuals.

    Linearised about the current pose, a rotation w and translation t change residual i by
    (p_i x n_i) . w + n_i . t; solved in coordinates centred on the points for conditioning.
    """
    centre = weights @ points / weights.sum()
    p = points - centre
    J = np.empty((len(p), 6))  # [p x n, n], the cross product written out (np.cross is slow on many rows)
    J[:, 0] = p[:, 1] * normals[:, 2] - p[:, 2] * normals[:, 1]
    J[:, 1] = p[:, 2] * normals[:, 0] - p[:, 0] * normals[:, 2]
    J[:, 2] = p[:, 0] * normals[:, 1] - p[:, 1] * normals[:, 0]
    J[:, 3:] = normals
    Jw = J * weights[:, None]
    H = J.T @ Jw
    g = Jw.T @ residuals
    try:
        x = -np.linalg.solve(H + 1e-9 * np.trace(H) * np.eye(6), g)
    except np.linalg.LinAlgError:
        return np.eye(4)
    step = from_rotvec(x[:3])
    # The rotation acted about `centre`: move it back to the origin.
    step[:3, 3] = x[3:] + centre - step[:3, :3] @ centre
    return step


def geman_mcclure(residuals: np.ndarray, scale: float) -> np.ndarray:
    """Each residual's weight under the Geman-McClure kernel of this scale: 1 at zero, ~(scale/r)^4 far out."""
    return (scale**2 / (scale**2 + residuals**2)) ** 2
