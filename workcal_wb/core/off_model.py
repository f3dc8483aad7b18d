"""The points of a region that its placed model leaves unexplained, and where they lie, in words a
person can act on.

A region drawn by hand, loosely, takes points that are not its object: a band of the platform beside
the object's foot (raised past the band the calibration leaves out by itself: a mat, a plate's rim,
the plane's own tilt), part of the other object, a clamp.  They lower the share of the region its
model explains.  ``off_model`` finds them (their scan indices are kept in the result, drawn in red in
the 3D view and in the report) and says what they are, on which side of the region they lie, and the
one thing to change.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .regions import near_points

# Off-model points within this height of the platform's plane are the platform's: the objects rise
# tens of millimetres above it, and their own points near it lie on their models.
NEAR_PLATFORM_MM = 10.0
# Off-model points within this distance of the other object's placed model (or in its region) are the
# other object's: its unmodelled bits (clay added, a mixed pixel at its edge) lie a few mm off it.
NEAR_OTHER_MM = 5.0
# What most of the off-model points are (the platform's, the other object's) describes them all:
# "most" is at least this share.
MOST = 0.5
# The height said for the platform's points ("within 4 mm of the platform's plane") is the one under
# which this share of them lie.
SAID_SHARE = 0.8
# The off-model points lie on one side of the region when their middle is at least this share of the
# region's half-width (measured the way they lie) from the middle of its box; nearer, they are spread.
SIDE_SHARE = 0.25
# They lie toward (or away from) the other object when the way they lie from the region's middle is
# within this angle of the way to (or from) the other region's middle.
TOWARD_DEG = 45.0
# The gate a match without one (NaN) is measured with, mm.
DEFAULT_GATE_MM = 1.0
AXES = "XYZ"


@dataclass
class OffModel:
    """A region's points off its placed model: their scan ``indices``, their ``middle`` (mm, in the
    scan; the region's middle when there are none), where they lie and what to change, in words
    (both empty when there are none)."""

    indices: np.ndarray
    middle: np.ndarray
    where: str = ""
    change: str = ""

    @property
    def count(self) -> int:
        return len(self.indices)

    def note(self) -> dict:
        """What a result keeps besides the indices: {"count", "where", "change"}."""
        return {"count": self.count, "where": self.where, "change": self.change}

    def said(self, role: str) -> str:
        """The sentence a failed gate gives as its why."""
        x, y, z = (int(round(v)) for v in self.middle)
        sentence = f"{self.count} of the region's points lie off the placed {role} model, around ({x}, {y}, {z}) mm " \
                   "in the scan"
        return f"{sentence}, {self.where}. {self.change}" if self.count else sentence


def off_model(points: np.ndarray, idx: np.ndarray, surface, found, role: str, platform=None,
              other=None) -> OffModel:
    """The points of the region ``idx`` (indices into ``points``, the scan in mm) that lie farther than
    its match's final gate from its model placed by ``found``, with where they lie in words.

    ``platform``: regions.Platform or None; ``other``: (role, SurfaceModel, MatchResult, region indices)
    of the other object, or None: what the points may be instead of the object."""
    idx = np.asarray(idx, dtype=np.int64)
    region = points[idx]
    gate = found.gate_mm if np.isfinite(found.gate_mm) else DEFAULT_GATE_MM
    off = ~near_points(region, surface, found.matrix, gate)
    if not off.any():
        return OffModel(idx[:0], region.mean(axis=0) if len(region) else np.zeros(3))
    off_points = region[off]
    belongs_to = _the_other_objects(off_points, idx[off], other)
    heights = np.abs(platform.height(off_points)) if platform is not None else None
    on_platform = not belongs_to and heights is not None and np.mean(heights <= NEAR_PLATFORM_MM) >= MOST
    # The platform's points lie at the region's foot: what tells where is on which side of the object.
    side = _side(region, off_points, platform.up if on_platform else None)
    if belongs_to:
        where = f"most of them on the {belongs_to}"
        change = (f"They belong to the {belongs_to}: draw the region tighter on its {side} side, so that it "
                  f"leaves the {belongs_to} out" if side else
                  f"They belong to the {belongs_to}: draw the region so that it leaves the {belongs_to} out")
    elif on_platform:
        within = int(np.ceil(np.quantile(heights[heights <= NEAR_PLATFORM_MM], SAID_SHARE)))
        where = f"most of them within {max(within, 1)} mm of the platform's plane"
        change = (f"Draw the region tighter on its {side} side, so that it leaves the platform out" if side else
                  "Draw the region so that it stops above the platform")
    else:
        where = ""
        change = (f"Draw the region tighter on its {side} side, or leave those points out" if side else
                  f"Leave out what is not the {role} (a clamp, a hand?), or check that the {role} model is the "
                  "object scanned")
    if side:
        toward = _toward_the_other(region, off_points, points, other, platform.up if on_platform else None)
        side_words = f"on the region's {side} side" + (f", {toward}" if toward else "")
        where = f"{where}, {side_words}" if where else side_words
    elif not where:
        where = "spread over the region"
    return OffModel(idx[off], off_points.mean(axis=0), where, change)


def _the_other_objects(off_points: np.ndarray, off_idx: np.ndarray, other) -> str:
    """The other object's role when most of the off-model points are its (in its region or near its
    placed model), else ""."""
    if other is None:
        return ""
    role, surface, found, region = other
    theirs = np.isin(off_idx, region)
    if found is not None and found.matrix is not None:
        gate = found.gate_mm if np.isfinite(found.gate_mm) else DEFAULT_GATE_MM
        theirs |= near_points(off_points, surface, found.matrix, max(NEAR_OTHER_MM, gate))
    return role if np.mean(theirs) >= MOST else ""


def _shift(region: np.ndarray, off_points: np.ndarray, across) -> np.ndarray:
    """From the middle of the region's box to the middle of the off-model points, ``across`` (a
    direction, or None) left out."""
    shift = off_points.mean(axis=0) - (region.min(axis=0) + region.max(axis=0)) / 2
    if across is None:
        return shift
    across = np.asarray(across, dtype=float) / np.linalg.norm(across)
    return shift - (shift @ across) * across


def _side(region: np.ndarray, off_points: np.ndarray, across=None) -> str:
    """The side of the region the off-model points lie on, as the scan's axis nearest to the way they
    lie from its middle ("+X", "-Z"), or "" when they are spread over it (their middle less than
    SIDE_SHARE of the region's half-width that way from its middle); ``across``: a direction left out."""
    shift = _shift(region, off_points, across)
    length = np.linalg.norm(shift)
    if length == 0:
        return ""
    way = shift / length
    along = region @ way
    if length < SIDE_SHARE * max((along.max() - along.min()) / 2, 1e-9):
        return ""
    axis = int(np.argmax(np.abs(way)))
    return f"{'+' if way[axis] > 0 else '-'}{AXES[axis]}"


def _toward_the_other(region: np.ndarray, off_points: np.ndarray, points: np.ndarray, other, across) -> str:
    """"toward the workpiece" or "away from the workpiece" when the off-model points lie that way from
    the region's middle (within TOWARD_DEG), else ""."""
    if other is None or len(other[3]) == 0:
        return ""
    shift = _shift(region, off_points, across)
    to_other = _shift(region, points[np.asarray(other[3], dtype=np.int64)], across)
    lengths = np.linalg.norm(shift) * np.linalg.norm(to_other)
    if lengths == 0:
        return ""
    cosine = float(shift @ to_other) / lengths
    if cosine >= np.cos(np.radians(TOWARD_DEG)):
        return f"toward the {other[0]}"
    if cosine <= -np.cos(np.radians(TOWARD_DEG)):
        return f"away from the {other[0]}"
    return ""
