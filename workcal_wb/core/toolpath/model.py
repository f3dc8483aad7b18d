"""A toolpath as WorkCal holds it: a list of moves with absolute end points in mm.

Every move is complete (no modal gaps) so that a rigid transform can act on it directly; the modal
bookkeeping of G-code lives only in the reader and the writer.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

RAPID, LINEAR, ARC_CW, ARC_CCW = "rapid", "linear", "arc_cw", "arc_ccw"
KINDS = (RAPID, LINEAR, ARC_CW, ARC_CCW)
ARC_KINDS = (ARC_CW, ARC_CCW)

# A 3-axis toolpath has its tool along +Z of its own frame (pointing from the tip up the spindle).
DEFAULT_TOOL_AXIS = (0.0, 0.0, 1.0)


def _vector(value, name: str) -> np.ndarray:
    v = np.asarray(value, dtype=float).reshape(-1)
    if v.shape != (3,):
        raise ValueError(f"{name} must have 3 components, got {v.shape}")
    return v


@dataclass
class Move:
    """One motion to ``end``.  An arc turns about ``normal`` through ``centre``: ``arc_ccw`` is
    counter-clockwise seen from the tip of the normal (right-hand rule), ``arc_cw`` the other way.
    ``centre`` lies in the plane of the arc's start point; a helix rises along the normal."""

    kind: str
    end: np.ndarray
    feed: float | None = None  # mm/min; None for rapids (the machine's own rapid rate)
    tool_axis: np.ndarray = field(default_factory=lambda: np.array(DEFAULT_TOOL_AXIS))
    centre: np.ndarray | None = None
    normal: np.ndarray | None = None
    line: int | None = None  # line (G-code) or command number (FreeCAD Path) it came from
    comment: str = ""  # comments on or just before that line, one per text line

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"move kind must be one of {KINDS}, not {self.kind!r}")
        self.end = _vector(self.end, "end")
        self.tool_axis = _vector(self.tool_axis, "tool_axis")
        if self.is_arc:
            if self.centre is None or self.normal is None:
                raise ValueError("an arc needs a centre and a plane normal")
            self.centre = _vector(self.centre, "centre")
            self.normal = _vector(self.normal, "normal")

    @property
    def is_arc(self) -> bool:
        return self.kind in ARC_KINDS


@dataclass
class Toolpath:
    """Moves in order; the first move starts wherever the machine is, so it is never an arc."""

    moves: list[Move] = field(default_factory=list)
    header: list[str] = field(default_factory=list)  # comments before the first move
    footer: list[str] = field(default_factory=list)  # comments after the last move
    source: str = "toolpath"  # file or object name, for messages

    def __post_init__(self):
        if self.moves and self.moves[0].is_arc:
            raise ValueError(f"{self.source}: the first move is an arc but its start point is unknown")

    def __len__(self) -> int:
        return len(self.moves)

    def starts(self) -> list[np.ndarray]:
        """Start point of every move (the first move starts at its own end: the entry point)."""
        if not self.moves:
            return []
        return [self.moves[0].end] + [m.end for m in self.moves[:-1]]

    def points(self) -> np.ndarray:
        """(N, 3) end points."""
        return np.array([m.end for m in self.moves]).reshape(-1, 3)


@dataclass
class RotaryTable:
    """The platform's rotary table (the paper's 7th axis): its frame ^B Q, and the angle to export at.

    The calibration W = ^B X was measured at table angle 0, so ^Q X = ^B Q^-1 W is fixed to the
    table and one calibration serves every angle."""

    frame: np.ndarray  # ^B Q: the table frame (Z = table axis) in the robot base frame, mm
    angle_deg: float = 0.0
    source: str = "table frame"
