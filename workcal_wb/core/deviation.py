"""Signed deviation of scan points from a placed model: the colour map that shows where clay changed."""
from __future__ import annotations

import numpy as np

from . import frames
from .surface import SurfaceModel

# Points farther than this fraction of the model diagonal from its surface have no meaningful
# deviation (they belong to something else) and come back as NaN.
FAR_FRACTION = 0.1


def signed_deviations(points_S: np.ndarray, model, U: np.ndarray, far_mm: float | None = None) -> np.ndarray:
    """Signed distance (mm) of each scan point to the model surface placed by U = ^S X.

    Positive outside the model (material added), negative inside (material removed).  ``model``
    is a Cloud or a prepared SurfaceModel in its own frame X; points farther than ``far_mm``
    (default a tenth of the model diagonal) are NaN.
    """
    surface = model if isinstance(model, SurfaceModel) else SurfaceModel(model)
    far = far_mm if far_mm is not None else FAR_FRACTION * surface.diagonal
    in_model = frames.apply(frames.invert(frames.as_transform(U, "U")), np.asarray(points_S, dtype=float).reshape(-1, 3))
    distance, idx, found = surface.nearest(in_model, far)
    out = np.full(len(in_model), np.nan)
    if not found.any():
        return out
    side = np.sign(surface.plane_residuals(in_model[found], idx[found]))
    exact = surface.exact_distance
    magnitude = exact(in_model[found]) if exact is not None else distance[found]
    out[found] = np.where(side == 0, 1.0, side) * magnitude
    return out


def deviation_stats(deviations: np.ndarray, tolerance_mm: float) -> dict:
    """Summary numbers of a deviation map (NaN points are left out and counted)."""
    d = deviations[np.isfinite(deviations)]
    if len(d) == 0:
        return {"n_points": 0, "n_far": int(len(deviations))}
    return {
        "n_points": int(len(d)), "n_far": int(len(deviations) - len(d)),
        "mean_mm": float(d.mean()), "rms_mm": float(np.sqrt(np.mean(d**2))),
        "min_mm": float(d.min()), "max_mm": float(d.max()),
        "within_tolerance_pct": float(100 * np.mean(np.abs(d) <= tolerance_mm)),
        "tolerance_mm": float(tolerance_mm),
    }

