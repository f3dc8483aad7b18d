"""Signed deviation of scan points from a placed model: the colour map that shows where clay changed.

``DeviationScale`` is the one colour scale of a deviation map, used by FreeCAD's 3D view and by the
HTML report alike, so a colour means the same deviation wherever it is seen.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import frames
from .errors import InputError
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



# The scale reaches full colour this many tolerances away from the surface unless told otherwise:
# a designer reads the map against the tolerance, so the tolerance, not the data's extremes, sets it.
LIMIT_TOLERANCES = 3.0
WITHIN = (0.12, 0.68, 0.22)  # green: within the tolerance
ADDED = ((1.0, 0.86, 0.0), (0.86, 0.05, 0.0))  # yellow just past +tolerance, red at +limit
REMOVED = ((0.0, 0.82, 0.95), (0.05, 0.15, 0.85))  # cyan just past -tolerance, blue at -limit
BEYOND_ADDED, BEYOND_REMOVED = (0.45, 0.0, 0.25), (0.2, 0.0, 0.45)  # past the limit: darker, still the same side
NO_SURFACE = (0.62, 0.62, 0.62)  # grey: no model surface near the point


@dataclass(frozen=True)
class DeviationScale:
    """Colours of signed deviations: green within +/- ``tolerance_mm``, yellow to red for material added
    and cyan to blue for material removed, full colour at +/- ``limit_mm``, darker past it, grey for NaN."""

    tolerance_mm: float
    limit_mm: float

    @classmethod
    def for_tolerance(cls, tolerance_mm: float, limit_mm: float | None = None) -> "DeviationScale":
        """The scale of a calibration's tolerance; ``limit_mm`` None or 0 means LIMIT_TOLERANCES tolerances."""
        tolerance_mm = float(tolerance_mm)
        if not (np.isfinite(tolerance_mm) and tolerance_mm > 0):
            raise InputError(f"deviation colour scale: the tolerance must be a positive number of mm, not {tolerance_mm}")
        limit = float(limit_mm) if limit_mm else LIMIT_TOLERANCES * tolerance_mm
        if not (np.isfinite(limit) and limit > tolerance_mm):
            raise InputError(f"deviation colour scale: its limit ({limit:g} mm) must lie past the tolerance "
                             f"({tolerance_mm:g} mm)")
        return cls(tolerance_mm, limit)

    def colours(self, deviations) -> np.ndarray:
        """(N, 3) RGB in 0..1 for signed deviations in mm (NaN: grey)."""
        d = np.asarray(deviations, dtype=float).reshape(-1)
        out = np.tile(np.array(NO_SURFACE), (len(d), 1))
        finite = np.isfinite(d)
        out[finite] = WITHIN
        for sign, (near, far), beyond in ((1.0, ADDED, BEYOND_ADDED), (-1.0, REMOVED, BEYOND_REMOVED)):
            outside = finite & (sign * np.where(finite, d, 0.0) > self.tolerance_mm)
            t = np.clip((sign * d[outside] - self.tolerance_mm) / (self.limit_mm - self.tolerance_mm), 0.0, 1.0)
            out[outside] = np.array(near) * (1 - t[:, None]) + np.array(far) * t[:, None]
            out[finite & (sign * np.where(finite, d, 0.0) > self.limit_mm)] = beyond
        return out

    def ticks(self) -> list[float]:
        """The values a legend labels, top to bottom: the limit, the tolerance, zero and their negatives."""
        return [self.limit_mm, self.tolerance_mm, 0.0, -self.tolerance_mm, -self.limit_mm]

    def to_dict(self) -> dict:
        return {"tolerance_mm": self.tolerance_mm, "limit_mm": self.limit_mm}
