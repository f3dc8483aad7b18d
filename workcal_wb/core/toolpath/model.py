"""A toolpath as WorkCal holds it: moves in columns (numpy arrays), and the machine events between them.

Every move is complete (absolute end point in mm, no modal gaps) so that a rigid transform acts on
whole columns at once; the modal bookkeeping of G-code lives only in the reader and the writers.
Columns keep a 2-million-move file within about 40 bytes a move (plus 24 when the tool tilts and
48 per arc), where one Python object per move would take ten times that.

``Move`` is a view of one move (tests, small paths, messages); ``Toolpath.from_moves`` builds a path
from such views.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

RAPID, LINEAR, ARC_CW, ARC_CCW = "rapid", "linear", "arc_cw", "arc_ccw"
KINDS = (RAPID, LINEAR, ARC_CW, ARC_CCW)  # a move's kind code is its index here
ARC_KINDS = (ARC_CW, ARC_CCW)
CODE = {kind: code for code, kind in enumerate(KINDS)}
FIRST_ARC_CODE = CODE[ARC_CW]

# A 3-axis toolpath has its tool along +Z of its own frame (pointing from the tip up the spindle).
DEFAULT_TOOL_AXIS = (0.0, 0.0, 1.0)

# Machine events between moves (``Event.kind``), each kept in every output format that has it.
STOP = "stop"  # M0 (code "M0") or optional stop M1 (code "M1")
TOOL_CHANGE = "tool_change"  # number = the new tool T
LENGTH_OFFSET = "length_offset"  # number = H register (G43 / G43.4), None = cancelled (G49)
SPINDLE = "spindle"  # code "cw" (M3), "ccw" (M4) or "off" (M5); number = speed S in rpm
COOLANT = "coolant"  # code "mist" (M7), "flood" (M8) or "off" (M9)
DWELL = "dwell"  # number = seconds (G4)
MACHINE_MOVE = "machine_move"  # G28 (home) or G53 (machine coordinates): code = the block as G-code
EVENT_KINDS = (STOP, TOOL_CHANGE, LENGTH_OFFSET, SPINDLE, COOLANT, DWELL, MACHINE_MOVE)


def _vector(value, name: str) -> np.ndarray:
    v = np.asarray(value, dtype=float).reshape(-1)
    if v.shape != (3,):
        raise ValueError(f"{name} must have 3 components, got {v.shape}")
    return v


@dataclass(frozen=True)
class Event:
    """Something the machine does between two moves: it comes before move ``before`` (len = at the end)."""

    kind: str
    before: int
    line: int | None = None
    code: str = ""
    number: float | None = None

    def __post_init__(self):
        if self.kind not in EVENT_KINDS:
            raise ValueError(f"event kind must be one of {EVENT_KINDS}, not {self.kind!r}")


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
    """Moves in columns, in order; the first move starts wherever the machine is, so it is never an arc.

    ``tool_axis`` is None (every axis +Z), one row (the same axis for every move) or one row per
    move.  Arc centres and normals have one row per arc, in the order of the arcs among the moves.
    ``partial`` maps a move made while an axis was unknown (before it was first given, or after
    G28/G53 sent it home) to the axes that were known; the others hold their next given value.
    Robots reach the first move after the start or a machine move with a joint move; G-code writes
    only the known axes of a partial move."""

    kind: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int8))
    end: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    feed: np.ndarray = field(default_factory=lambda: np.zeros(0))  # mm/min, NaN for rapids
    line: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int32))  # 0 = unknown
    tool_axis: np.ndarray | None = None
    arc_centre: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    arc_normal: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    comments: dict = field(default_factory=dict)  # move index -> comment lines joined by "\n"
    events: list = field(default_factory=list)  # Event, in order
    partial: dict = field(default_factory=dict)  # move index -> the axes known there ("XY", "Z", ...)
    header: list = field(default_factory=list)  # comments before the first move
    footer: list = field(default_factory=list)  # comments after the last move
    warnings: list = field(default_factory=list)
    source: str = "toolpath"  # file or object name, for messages

    def __post_init__(self):
        self.kind = np.asarray(self.kind, dtype=np.int8).reshape(-1)
        n = len(self.kind)
        self.end = np.asarray(self.end, dtype=float).reshape(n, 3)
        self.feed = np.asarray(self.feed, dtype=float).reshape(n)
        self.line = np.asarray(self.line, dtype=np.int32).reshape(n)
        self.arc_centre = np.asarray(self.arc_centre, dtype=float).reshape(-1, 3)
        self.arc_normal = np.asarray(self.arc_normal, dtype=float).reshape(-1, 3)
        if self.tool_axis is not None:
            self.tool_axis = np.asarray(self.tool_axis, dtype=float).reshape(-1, 3)
            if len(self.tool_axis) not in (1, n):
                raise ValueError(f"{self.source}: {len(self.tool_axis)} tool axes for {n} moves")
        if not len(self.arc_centre) == len(self.arc_normal) == int(np.count_nonzero(self.arc_mask)):
            raise ValueError(f"{self.source}: arc centres and normals do not match the arc moves")
        if n and self.kind[0] >= FIRST_ARC_CODE:
            raise ValueError(f"{self.source}: the first move is an arc but its start point is unknown")

    # ---- building and viewing ------------------------------------------------------------------

    @classmethod
    def from_moves(cls, moves, **kw) -> "Toolpath":
        """A toolpath from ``Move`` views (tests, small generated paths)."""
        moves = list(moves)
        arcs = [m for m in moves if m.is_arc]
        axes = np.array([m.tool_axis for m in moves]).reshape(-1, 3)
        return cls(kind=[CODE[m.kind] for m in moves], end=[m.end for m in moves],
                   feed=[np.nan if m.feed is None else m.feed for m in moves],
                   line=[m.line or 0 for m in moves],
                   tool_axis=None if np.all(axes == DEFAULT_TOOL_AXIS) else axes,
                   arc_centre=[m.centre for m in arcs], arc_normal=[m.normal for m in arcs],
                   comments={i: m.comment for i, m in enumerate(moves) if m.comment}, **kw)

    def __len__(self) -> int:
        return len(self.kind)

    @property
    def arc_mask(self) -> np.ndarray:
        return self.kind >= FIRST_ARC_CODE

    def axes(self) -> np.ndarray:
        """(N, 3) tool axes (a broadcast view when they are all the same)."""
        axis = np.array([DEFAULT_TOOL_AXIS]) if self.tool_axis is None else self.tool_axis
        return np.broadcast_to(axis, (len(self), 3))

    def starts(self) -> np.ndarray:
        """(N, 3) start point of every move (the first move starts at its own end: the entry point)."""
        return np.concatenate([self.end[:1], self.end[:-1]])

    def points(self) -> np.ndarray:
        """(N, 3) end points."""
        return self.end

    def move(self, i: int) -> Move:
        """Move ``i`` as a ``Move`` view."""
        arc = int(np.count_nonzero(self.arc_mask[:i])) if self.kind[i] >= FIRST_ARC_CODE else None
        feed = float(self.feed[i])
        return Move(KINDS[self.kind[i]], self.end[i].copy(), feed=None if np.isnan(feed) else feed,
                    tool_axis=self.axes()[i].copy(), line=int(self.line[i]) or None,
                    centre=None if arc is None else self.arc_centre[arc].copy(),
                    normal=None if arc is None else self.arc_normal[arc].copy(),
                    comment=self.comments.get(i, ""))

    @property
    def moves(self) -> list[Move]:
        """Every move as a ``Move`` view (for small paths: each view costs a few hundred bytes)."""
        return [self.move(i) for i in range(len(self))]

    def where(self, i: int) -> str:
        """"move 5 (line 12)": how messages name move ``i``."""
        line = int(self.line[i])
        return f"move {i + 1}" + (f" (line {line})" if line else "")

    def with_columns(self, **columns) -> "Toolpath":
        """The same path with some columns replaced (move count unchanged)."""
        return replace(self, **columns)


@dataclass
class RotaryTable:
    """The platform's rotary table (the paper's 7th axis): its frame ^B Q, and the angle to export at.

    The calibration W = ^B X was measured at table angle 0, so ^Q X = ^B Q^-1 W is fixed to the
    table and one calibration serves every angle."""

    frame: np.ndarray  # ^B Q: the table frame (Z = table axis) in the robot base frame, mm
    angle_deg: float = 0.0
    source: str = "table frame"
