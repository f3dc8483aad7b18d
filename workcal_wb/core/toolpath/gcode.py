"""G-code in and out: a reader that tracks the modal state, and a writer of complete blocks.

Read: G0/G1/G2/G3 in G17/G18/G19, modal axes, G90/G91, G90.1/G91.1 (arc centres), G20/G21, IJK or R
arcs, comments in ( ) or after ;.  A/B words are tool-axis angles in the writer's convention
(``orientation.gcode_ab_deg``) so WorkCal's own 5-axis output reads back.  Words that do not move the
tool (spindle, coolant, tool change, offsets listed in ``IGNORED_G``) are accepted and not carried over;
anything else is refused with its file and line rather than guessed at.

Axes not given before the first move that needs them take their first later value: a leading
``G0 Z16`` becomes a retract above the first XY point, not a move to X0 Y0.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..units import mm_per_unit
from . import arcs, orientation
from .model import ARC_CCW, ARC_CW, LINEAR, RAPID, Move, Toolpath
from .safety import number

MOTION = {0: RAPID, 1: LINEAR, 2: ARC_CW, 3: ARC_CCW}
MOTION_CODE = {kind: f"G{code}" for code, kind in MOTION.items()}
# plane code -> (index of its normal axis, the two centre-offset letters in the plane)
PLANES = {17: (2, "IJ"), 18: (1, "IK"), 19: (0, "JK")}
PLANE_OF_AXIS = {axis: code for code, (axis, _) in PLANES.items()}
IGNORED_G = {4, 40, 43, 49, 54, 55, 56, 57, 58, 59, 61, 61.1, 64, 80, 94}
IGNORED_LETTERS = set("NOMSTHD")  # line/program numbers, spindle, tool, offsets
AXES = "XYZ"
OFFSET_AXIS = {"I": 0, "J": 1, "K": 2}

# Start and end radius of an IJK arc may differ by this much (absolute or relative, the larger).
ARC_RADIUS_TOL_MM, ARC_RADIUS_TOL_REL = 0.005, 1e-3

_COMMENT = re.compile(r"\(([^()]*)\)|;(.*)$")
_WORD = re.compile(r"\s*([A-Za-z])\s*([+-]?(?:\d+\.?\d*|\.\d+))")


@dataclass
class _State:
    """The modal state of the machine while reading."""

    mm_per_unit: float
    motion: str | None = None
    plane: int = 17
    absolute: bool = True
    absolute_centres: bool = False
    feed: float | None = None
    position: list = field(default_factory=lambda: [None, None, None])
    ab_deg: list = field(default_factory=lambda: [0.0, 0.0])


def read_gcode(path, units: str = "mm") -> Toolpath:
    """Read a G-code file; ``units`` applies until the file says G20 or G21."""
    try:
        with open(path, encoding="utf-8", errors="replace") as fh:
            text = fh.read()
    except OSError as exc:
        raise InputError(f"{path}: cannot read G-code ({exc.strerror})") from exc
    return parse_gcode(text, source=str(path), units=units)


def parse_gcode(text: str, source: str = "G-code", units: str = "mm") -> Toolpath:
    """Read G-code text; ``source`` names it in every error message."""
    state = _State(mm_per_unit(units))
    moves, header, pending = [], [], []
    for line_number, raw in enumerate(text.splitlines(), start=1):
        where = f"{source}: line {line_number}"
        comments, words = _split(raw, where)
        pending += comments
        move = _execute(words, state, where, line_number)
        if move is None:
            continue
        if not moves:  # comment lines before the first move are the file's header
            header, pending = pending[:len(pending) - len(comments)], comments
        move.comment = "\n".join(pending)
        pending = []
        moves.append(move)
    _fill_leading_axes(moves, source)
    return Toolpath(moves, header=header if moves else pending, footer=pending if moves else [], source=source)


def _split(raw: str, where: str) -> tuple[list[str], dict]:
    """Comments (stripped texts) and words {letter: [values]} of one line."""
    comments = [(m.group(1) if m.group(1) is not None else m.group(2)).strip() for m in _COMMENT.finditer(raw)]
    rest = _COMMENT.sub(" ", raw).strip()
    if rest.startswith("%"):
        rest = rest[1:].strip()
    words: dict[str, list[float]] = {}
    pos = 0
    while pos < len(rest):
        m = _WORD.match(rest, pos)
        if not m:
            bad = rest[pos:].split()[0]
            raise InputError(f"{where}: cannot read {bad!r} "
                             "(expected a letter and a number, comments in ( ) or after ;)")
        letter, value = m.group(1).upper(), float(m.group(2))
        if letter not in "GM" and letter in words:
            raise InputError(f"{where}: {letter} given twice")
        words.setdefault(letter, []).append(value)
        pos = m.end()
    return [c for c in comments if c], words


def _execute(words: dict, state: _State, where: str, line: int) -> Move | None:
    """Apply one block to the state; the move it makes, if any."""
    codes = [round(g, 1) for g in words.pop("G", [])]
    for code in codes:
        _modal(code, state, where)
    for letter in list(words):
        if letter in IGNORED_LETTERS:
            del words[letter]
    if "P" in words or "Q" in words:
        if not {4, 64} & set(codes):
            raise InputError(f"{where}: P/Q words are only read with G4 or G64 (multi-turn arcs are not supported)")
        words.pop("P", None)
        words.pop("Q", None)
    unknown = sorted(set(words) - set("XYZIJKRFAB"))
    if unknown:
        raise InputError(f"{where}: unknown word {unknown[0]} (WorkCal reads G0-G3 toolpaths: X Y Z I J K R F A B)")
    if "F" in words:
        feed = words.pop("F")[0] * state.mm_per_unit
        if feed < 0:
            raise InputError(f"{where}: negative feed F")
        state.feed = feed
    if not words:
        return None
    if state.motion is None:
        raise InputError(f"{where}: coordinates without a motion mode (G0, G1, G2 or G3) in force")
    if (set(words) & set("IJKR")) and state.motion not in (ARC_CW, ARC_CCW):
        raise InputError(f"{where}: I/J/K/R given for a straight move ({MOTION_CODE[state.motion]})")
    start = list(state.position)
    _update_axes(words, state, where)
    if state.motion != RAPID and not state.feed:
        what = "missing feed (F) on the first" if state.feed is None else "feed F0 on a"
        raise InputError(f"{where}: {what} cutting move ({MOTION_CODE[state.motion]})")
    end = np.array([np.nan if v is None else v for v in state.position])
    common = dict(end=end, feed=None if state.motion == RAPID else state.feed, line=line,
                  tool_axis=orientation.tool_axis_from_ab(*state.ab_deg))
    if state.motion in (RAPID, LINEAR):
        return Move(state.motion, **common)
    if None in start:
        raise InputError(f"{where}: arc before the start position is known (give X, Y and Z first)")
    centre, normal = _arc_centre(words, state, np.array(start), end, where)
    return Move(state.motion, centre=centre, normal=normal, **common)


def _modal(code: float, state: _State, where: str) -> None:
    if code in MOTION:
        state.motion = MOTION[int(code)]
    elif code in PLANES:
        state.plane = int(code)
    elif code in (20, 21):
        state.mm_per_unit = 25.4 if code == 20 else 1.0
    elif code in (90, 91):
        state.absolute = code == 90
    elif code in (90.1, 91.1):
        state.absolute_centres = code == 90.1
    elif code not in IGNORED_G:
        raise InputError(f"{where}: G{code:g} is not supported (WorkCal reads G0-G3, G17-G21, G90/G91, G90.1/G91.1)")


def _update_axes(words: dict, state: _State, where: str) -> None:
    for i, axis in enumerate(AXES):
        if axis in words:
            value = words.pop(axis)[0] * state.mm_per_unit
            if state.absolute:
                state.position[i] = value
            elif state.position[i] is None:
                raise InputError(f"{where}: incremental (G91) {axis} before the {axis} position is known")
            else:
                state.position[i] += value
    for i, axis in enumerate("AB"):
        if axis in words:
            value = words.pop(axis)[0]
            state.ab_deg[i] = value if state.absolute else state.ab_deg[i] + value


def _arc_centre(words: dict, state: _State, start: np.ndarray, end: np.ndarray, where: str):
    """Centre (in the start's plane) and unit normal of a G2/G3 arc, checked for a consistent radius."""
    normal_axis, offset_letters = PLANES[state.plane]
    normal = np.zeros(3)
    normal[normal_axis] = 1.0
    if "R" in words:
        centre = _centre_from_radius(words["R"][0] * state.mm_per_unit, state.motion, start, end, normal, where)
    elif set(offset_letters) & set(words):
        centre = start.copy()
        for letter in offset_letters:
            value = words.get(letter, [0.0])[0] * state.mm_per_unit
            axis = OFFSET_AXIS[letter]
            centre[axis] = value if state.absolute_centres else start[axis] + value
    else:
        raise InputError(f"{where}: arc without centre ({' or '.join(offset_letters)} for G{state.plane}) or radius R")
    move = Move(state.motion, end, centre=centre, normal=normal)
    r_start, r_end = arcs.radius(start, move), arcs.radius(end, move)
    if r_start < ARC_RADIUS_TOL_MM:
        raise InputError(f"{where}: arc of zero radius")
    if abs(r_start - r_end) > max(ARC_RADIUS_TOL_MM, ARC_RADIUS_TOL_REL * r_start):
        raise InputError(f"{where}: arc radius mismatch: {r_start:.4f} mm from the centre to the start, "
                         f"{r_end:.4f} mm to the end")
    return centre, normal


def _centre_from_radius(r: float, kind: str, start, end, normal, where: str) -> np.ndarray:
    """R > 0: the short way (<= 180 degrees), R < 0: the long way."""
    chord = (end - start) - np.dot(end - start, normal) * normal
    half = np.linalg.norm(chord) / 2
    if half < arcs.FULL_CIRCLE_MM:
        raise InputError(f"{where}: an R arc cannot be a full circle; use I/J/K")
    if half > abs(r) + ARC_RADIUS_TOL_MM:
        raise InputError(f"{where}: arc radius mismatch: R {abs(r):.4f} mm is less than half the chord {half:.4f} mm")
    height = math.sqrt(max(r * r - half * half, 0.0))
    side = (1 if kind == ARC_CCW else -1) * (1 if r > 0 else -1)
    return start + chord / 2 + side * height * np.cross(normal, chord / (2 * half))


def _fill_leading_axes(moves: list[Move], source: str) -> None:
    for axis, name in enumerate(AXES):
        known = [m.end[axis] for m in moves if not math.isnan(m.end[axis])]
        if moves and not known:
            raise InputError(f"{source}: axis {name} is never given, so the path cannot be placed")
        for move in moves:
            if not math.isnan(move.end[axis]):
                break
            move.end[axis] = known[0]


# ---- writing -------------------------------------------------------------------------------------

@dataclass
class Block:
    """One G-code block: the code (G0..G3, G17..G19), its words in mm, mm/min, deg, and its comments."""

    code: str
    words: dict = field(default_factory=dict)
    comments: list = field(default_factory=list)


def blocks(toolpath: Toolpath) -> list[Block]:
    """Complete blocks for a toolpath whose arcs lie in the XY, ZX or YZ plane (see ``transform``).

    Every block repeats X Y Z; F is given when it changes; A B (tool-axis angles) on every block as
    soon as any tool axis leaves +Z."""
    five_axis = not all(orientation.is_vertical(m.tool_axis) for m in toolpath.moves)
    out, plane, feed = [], 17, None
    for start, move in zip(toolpath.starts(), toolpath.moves):
        kind, words = move.kind, dict(zip(AXES, move.end))
        if move.is_arc:
            axis = int(np.argmax(np.abs(move.normal)))
            if abs(move.normal[axis]) < 1 - 1e-9:
                raise ValueError(f"{toolpath.source}: arc normal {move.normal} is not along X, Y or Z; "
                                 "linearise it first")
            if move.normal[axis] < 0:
                kind = ARC_CW if kind == ARC_CCW else ARC_CCW
            if PLANE_OF_AXIS[axis] != plane:
                plane = PLANE_OF_AXIS[axis]
                out.append(Block(f"G{plane}"))
            offset = move.centre - start
            words.update({letter: offset[OFFSET_AXIS[letter]] for letter in PLANES[plane][1]})
        if five_axis:
            words.update(zip("AB", orientation.gcode_ab_deg(move.tool_axis)))
        if move.feed is not None and move.feed != feed:
            words["F"] = feed = move.feed
        out.append(Block(MOTION_CODE[kind], words, move.comment.split("\n") if move.comment else []))
    return out


def _comment(text: str) -> str:
    return "(" + text.replace("(", "[").replace(")", "]") + ")"


def format_gcode(toolpath: Toolpath, header: list[str] = ()) -> str:
    """G-code text in mm (G21), absolute (G90), incremental arc centres (the default everywhere)."""
    lines = [_comment(h) for h in list(header) + toolpath.header]
    lines.append("G21 G90 G17")
    for block in blocks(toolpath):
        words = [f"{k}{number(v, 2 if k == 'F' else 4)}" for k, v in block.words.items()]
        lines.append(" ".join([block.code] + words + [_comment(c) for c in block.comments]))
    lines += [_comment(f) for f in toolpath.footer]
    lines.append("M2")
    return "\n".join(lines) + "\n"
