"""G-code in: a streaming reader that tracks the modal state and keeps what the machine does between moves.

Read: G0-G3 in G17/G18/G19 (IJK or R arcs, never both), G90/G91, G90.1/G91.1, G20/G21, G4 dwell,
G28 (home, through its intermediate point) and G53 (machine coordinates), G43/G43.4/G49 length
offsets, M0/M1 stops, M3/M4/M5 with S, M6 with T, M7/M8/M9, M2/M30 (the end: nothing after is read),
rotary axes A/B/C as a tool axis (``orientation.ROTARY``), I/J/K tool vectors on G0/G1, N numbers,
``*`` checksums, ``%`` program boundaries, block delete ``/`` (the switch must be stated), comments
in ( ) or after ;.  Anything else (cutter compensation, canned cycles, two codes of one modal group
in a block, an unknown word) is refused with the file, the line and the word: WorkCal would rather
stop than guess at a toolpath.

The file is read line by line into columns (``model.Toolpath``), so a 2-million-line file needs
about 40 bytes a move, not the whole text.  Axes not known at a move (before they are first given,
after G28/G53) take their next given value and the move is marked partial: robots reach it with a
joint move, G-code writes only the axes its block gave.
"""
from __future__ import annotations

import math
import re
from array import array
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..units import mm_per_unit
from . import arcs, orientation
from .model import (ARC_CCW, ARC_CW, COOLANT, DWELL, LENGTH_OFFSET, LINEAR, MACHINE_MOVE, RAPID, SPINDLE, STOP,
                    TOOL_CHANGE, CODE, Event, Toolpath)

MOTION = {0: RAPID, 1: LINEAR, 2: ARC_CW, 3: ARC_CCW}
MOTION_CODE = {kind: f"G{code}" for code, kind in MOTION.items()}
# plane code -> (index of its normal axis, the two centre-offset letters in the plane)
PLANES = {17: (2, "IJ"), 18: (1, "IK"), 19: (0, "JK")}
PLANE_OF_AXIS = {axis: code for code, (axis, _) in PLANES.items()}
AXES = "XYZ"
OFFSET_AXIS = {"I": 0, "J": 1, "K": 2}

# Modal groups (Fanuc's, which Mastercam-style "G0 G17 G40 G49 G80 G90" lines follow): two codes of one
# group in one block are refused.
G_GROUPS = {"motion": {0, 1, 2, 3}, "canned cycle": {80}, "non-modal": {4, 28, 53}, "plane": {17, 18, 19}, "distance": {90, 91},
            "arc distance": {90.1, 91.1}, "units": {20, 21}, "tool length offset": {43, 43.4, 49},
            "cutter compensation": {40}, "work offset": {54, 55, 56, 57, 58, 59}, "path control": {61, 61.1, 64},
            "feed mode": {94}}
G_GROUP = {code: name for name, codes in G_GROUPS.items() for code in codes}
# What the reader refuses, and why (anything not in G_GROUP is refused as unsupported).
G_REFUSED = {41: "cutter radius compensation changes the path by the tool radius",
             42: "cutter radius compensation changes the path by the tool radius",
             93: "inverse-time feed", 95: "feed per revolution", 92: "a coordinate-system shift",
             10: "a coordinate-system or offset setting"}
M_GROUPS = {"stop": {0, 1, 2, 30}, "tool change": {6}, "spindle": {3, 4, 5}, "coolant": {7, 8, 9}}
M_GROUP = {code: name for name, codes in M_GROUPS.items() for code in codes}
SPINDLE_M = {3: "cw", 4: "ccw", 5: "off"}
COOLANT_M = {7: "mist", 8: "flood", 9: "off"}
BLOCK_DELETE = ("on", "off")  # the switch: "on" skips "/" blocks, "off" runs them
# The largest whole number a word such as T or H takes: eight digits, the most controls read, and exact
# as a float (T9007199254740993 would read as ...992).
MAX_WORD_INTEGER = 99_999_999
# The longest dwell taken (s): a program waiting longer has its P in the wrong unit, or is no program.
MAX_DWELL_S = 3600.0
DWELL_P = ("auto", "seconds", "ms")  # G4 P: "auto" = milliseconds without a decimal point (Fanuc, Haas), else seconds

# Start and end radius of an IJK arc may differ by this much (absolute or relative, the larger).
ARC_RADIUS_TOL_MM, ARC_RADIUS_TOL_REL = 0.005, 1e-3

_COMMENT = re.compile(r"\(([^()]*)\)|;(.*)$")
_NUMBER = r"[+-]?(?:\d+\.?\d*|\.\d+)"
_WORD = re.compile(r"([A-Z])\s*(" + _NUMBER + ")")
_BLOCK = re.compile(r"(?:\s*[A-Z]\s*" + _NUMBER + r")*\s*")
_CHECKSUM = re.compile(r"^(.*)\*\s*(\d+)\s*$")
# The block almost every line of a long file is: [N..] [G0/G1] [X..] [Y..] [Z..] [F..], read without the general path.
_FAST = re.compile(r"(?:N\d+\s*)?(?:G0*([01])(?![0-9.])\s*)?(?:X(" + _NUMBER + r")\s*)?(?:Y(" + _NUMBER
                   + r")\s*)?(?:Z(" + _NUMBER + r")\s*)?(?:F(" + _NUMBER + r")\s*)?")


@dataclass
class _State:
    """The modal state of the machine while reading, and the columns being filled."""

    mm_per_unit: float
    rotary: str
    block_delete: str | None
    dwell_p: str
    motion: str | None = None
    plane: int = 17
    absolute: bool = True
    absolute_centres: bool = False
    feed: float = math.nan
    position: list = field(default_factory=lambda: [math.nan, math.nan, math.nan])
    rotary_deg: dict = field(default_factory=lambda: {"A": 0.0, "B": 0.0, "C": 0.0})
    axis: tuple = (0.0, 0.0, 1.0)
    axis_source: str = ""  # "rotary" or "vector" once the file tilts the tool
    tool: int | None = None
    spindle: str = "off"
    speed: float | None = None
    # columns
    kind: array = field(default_factory=lambda: array("b"))
    end: array = field(default_factory=lambda: array("d"))
    feeds: array = field(default_factory=lambda: array("d"))
    lines: array = field(default_factory=lambda: array("i"))
    axes: array = field(default_factory=lambda: array("d"))
    centres: list = field(default_factory=list)
    normals: list = field(default_factory=list)
    tilted: bool = False
    comments: dict = field(default_factory=dict)
    events: list = field(default_factory=list)
    partial: dict = field(default_factory=dict)
    warnings: list = field(default_factory=list)

    @property
    def count(self) -> int:
        return len(self.kind)


def read_gcode(path, units: str = "mm", rotary: str = "ab", block_delete: str | None = None,
               dwell_p: str = "auto") -> Toolpath:
    """Read a G-code file line by line; ``units`` applies until the file says G20 or G21.

    ``rotary`` names the tool-axis convention of A/B/C words (``orientation.ROTARY``);
    ``block_delete`` ("on" skips "/" blocks, "off" runs them) must be given when the file has them."""
    try:
        with open(path, encoding="utf-8", errors="replace") as fh:
            return _read(fh, str(path), units, rotary, block_delete, dwell_p)
    except OSError as exc:
        raise InputError(f"{path}: cannot read G-code ({exc.strerror})") from exc


def parse_gcode(text: str, source: str = "G-code", units: str = "mm", rotary: str = "ab",
                block_delete: str | None = None, dwell_p: str = "auto") -> Toolpath:
    """Read G-code text; ``source`` names it in every error message."""
    return _read(text.splitlines(), source, units, rotary, block_delete, dwell_p)


def _read(lines, source: str, units: str, rotary: str, block_delete, dwell_p: str) -> Toolpath:
    if rotary not in orientation.ROTARY:
        raise InputError(f"unknown rotary-axis convention {rotary!r}; use one of {', '.join(orientation.ROTARY)}")
    if block_delete not in (None, *BLOCK_DELETE):
        raise InputError(f"block delete must be one of {', '.join(BLOCK_DELETE)}, not {block_delete!r}")
    if dwell_p not in DWELL_P:
        raise InputError(f"G4 P unit must be one of {', '.join(DWELL_P)}, not {dwell_p!r}")
    state = _State(mm_per_unit(units), rotary, block_delete, dwell_p)
    header, pending = [], []
    percent = ended = False
    number = 0
    for number, raw in enumerate(lines, start=1):
        text = raw.strip()
        if not text:
            continue
        if ended:
            if text == "%":
                continue
            state.warnings.append(f"{source}: line {number}: the program ended at {ended}; "
                                  "the lines after it were not read")
            break
        if not pending and _fast_move(text, state, number):  # most lines of a long file: nothing else in them
            continue
        if text[0] == "%":
            if percent and state.count + len(state.events):
                ended = f"the closing % (line {number})"
            percent = True
            text = text[1:].strip()
            if not text:
                continue
        comments = []
        if "(" in text or ";" in text or ")" in text:
            comments, text = _split_comments(text, source, number)
            if not state.count:
                header += comments
            else:
                pending += comments
            if not text:
                continue
        if text[0] == "/":
            if state.block_delete is None:
                raise InputError(f"{source}: line {number}: block delete '/': say whether the block-delete switch "
                                 "is on (skip these blocks) or off (run them), e.g. --block-delete on")
            if state.block_delete == "on":
                continue
            text = text[1:].lstrip()
        if "*" in text:
            text = _checked(text, source, number)
        upper = text.upper()
        if not pending and upper != text and _fast_move(upper, state, number):
            continue
        before = state.count
        end_code = _block(upper, state, source, number)
        if state.count > before:
            if before == 0:  # comments before the first move are the file's header
                header, pending = header[:len(header) - len(comments)], comments
            if pending:
                state.comments[before] = "\n".join(pending)
                pending = []
        if end_code:
            ended = f"{end_code} (line {number})"
    return _finish(state, source, header, pending)


def _fast_move(text: str, state: _State, number: int) -> bool:
    """Read a plain straight move in absolute mode with every axis known; False leaves it to ``_block``."""
    m = _FAST.fullmatch(text)
    if m is None or not state.absolute or not state.kind or math.isnan(sum(state.position)):  # kind: any move yet
        return False
    code, x, y, z, f = m.groups()
    motion = MOTION[int(code)] if code else state.motion
    if motion not in (RAPID, LINEAR) or (x is None and y is None and z is None):
        return False
    unit = state.mm_per_unit
    if f is not None:
        state.feed = float(f) * unit
    if motion == LINEAR and not state.feed > 0:
        return False
    state.motion = motion
    position = state.position
    if x is not None:
        position[0] = float(x) * unit
    if y is not None:
        position[1] = float(y) * unit
    if z is not None:
        position[2] = float(z) * unit
    state.kind.append(CODE[motion])
    state.end.extend(position)
    state.feeds.append(math.nan if motion == RAPID else state.feed)
    state.lines.append(number)
    if state.tilted:
        state.axes.extend(state.axis)
    return True


def gcode_comment(text: str) -> str:
    """``text`` (one line) as a G-code comment: its parentheses as brackets, ';' (a comment start) as ',',
    '%' (a program boundary) as ' pct'."""
    return "(" + text.replace("(", "[").replace(")", "]").replace(";", ",").replace("%", " pct") + ")"


def _split_comments(text: str, source: str, number: int) -> tuple[list[str], str]:
    comments = [(m.group(1) if m.group(1) is not None else m.group(2)).strip() for m in _COMMENT.finditer(text)]
    rest = _COMMENT.sub(" ", text).strip()
    if "(" in rest or ")" in rest:
        raise InputError(f"{source}: line {number}: unbalanced parenthesis in a comment")
    return [c for c in comments if c], rest


def _checked(text: str, source: str, number: int) -> str:
    """The block without its ``*nn`` checksum, which must be the XOR of the bytes before the ``*``."""
    m = _CHECKSUM.match(text)
    if not m:
        raise InputError(f"{source}: line {number}: '*' is only read as a checksum at the end of a block (*nn)")
    body, given = m.group(1), int(m.group(2))
    actual = 0
    for byte in body.encode("utf-8"):
        actual ^= byte
    if actual != given:
        raise InputError(f"{source}: line {number}: checksum *{given} does not match the block (it is *{actual})")
    return body.strip()


def _words(text: str, source: str, number: int):
    """G codes, M codes and the other words {letter: value} of one block (N and O numbers dropped)."""
    if not _BLOCK.fullmatch(text):
        pos = 0
        for m in _WORD.finditer(text):
            if text[pos:m.start()].strip():
                break
            pos = m.end()
        bad = text[pos:].split()[0]
        raise InputError(f"{source}: line {number}: cannot read {bad!r} "
                         "(expected a letter and a number, comments in ( ) or after ;)")
    g, m, values = [], [], {}
    for i, (letter, value) in enumerate(_WORD.findall(text)):
        if letter == "P" and "." not in value:
            values["P."] = False  # G4 P without a decimal point: milliseconds on Fanuc-family controls
        if letter == "G":
            g.append(round(float(value), 1))
        elif letter == "M":
            m.append(float(value))
        elif letter in "NO" and i == 0:
            continue
        elif letter in values:
            raise InputError(f"{source}: line {number}: {letter} given twice")
        else:
            values[letter] = float(value)
    return g, m, values


def _group_check(codes, groups: dict, letter: str, source: str, number: int) -> None:
    seen = {}
    for code in codes:
        name = groups.get(code)
        if name is None:
            continue
        if name in seen:
            raise InputError(f"{source}: line {number}: {letter}{seen[name]:g} and {letter}{code:g} are both in the "
                             f"{name} group; one block can hold only one of them")
        seen[name] = code


def _block(text: str, state: _State, source: str, number: int) -> str | None:
    """Execute one block in RS274/NGC order; returns "M2"/"M30" when it ends the program."""
    g, m, words = _words(text, source, number)
    if g:
        _group_check(g, G_GROUP, "G", source, number)
        for code in g:
            if code not in G_GROUP:
                why = G_REFUSED.get(code, "not a code WorkCal reads")
                raise InputError(f"{source}: line {number}: G{code:g} is not supported ({why})")
    if m:
        _group_check(m, M_GROUP, "M", source, number)
        for code in m:
            if code not in M_GROUP:
                raise InputError(f"{source}: line {number}: M{code:g} is not supported (WorkCal reads M0-M9 and M30)")
    event = _event_maker(state, number)
    if "F" in words:
        feed = words.pop("F") * state.mm_per_unit
        if feed < 0:
            raise InputError(f"{source}: line {number}: negative feed F")
        state.feed = feed
    speed = words.pop("S", None)
    if speed is not None:
        if speed < 0:
            raise InputError(f"{source}: line {number}: negative spindle speed S")
        changed = speed != state.speed
        state.speed = speed
        if changed and state.spindle != "off" and not {3, 4, 5} & set(m):
            event(SPINDLE, state.spindle, speed)
    if "T" in words:
        state.tool = _integer(words.pop("T"), "T", source, number)
    if 6 in m:
        if state.tool is None:
            raise InputError(f"{source}: line {number}: tool change M6 without a tool number T")
        if state.tool == 0:
            raise InputError(f"{source}: line {number}: tool change M6 to T0, which is no tool (an empty spindle, "
                             "a robot's bare flange)")
        event(TOOL_CHANGE, f"T{state.tool}", state.tool)
    for code in m:
        if code in SPINDLE_M:
            state.spindle = SPINDLE_M[code]
            event(SPINDLE, state.spindle, state.speed)
        elif code in COOLANT_M:
            event(COOLANT, COOLANT_M[code])
    if 4 in g:
        _dwell(words, state, event, source, number)
    elif "P" in words and 64 in g:
        words.pop("P")  # G64 P: the path-blending tolerance of LinuxCNC, not a position
    words.pop("P.", None)
    for code in g:
        _modal(code, state)
    _length_offset(g, words, event, source, number)
    if 28 in g or 53 in g:
        _machine_move(g, words, state, event, source, number)
    elif words:
        _motion(g, words, state, source, number)
    for code in m:
        if code in (0, 1):
            event(STOP, f"M{code:g}")
    end = [f"M{code:g}" for code in m if code in (2, 30)]
    return end[0] if end else None


def _event_maker(state: _State, number: int):
    def event(kind, code="", value=None):
        state.events.append(Event(kind, state.count, number, code, value))
    return event


def _integer(value: float, letter: str, source: str, number: int) -> int:
    if value < 0:
        raise InputError(f"{source}: line {number}: {letter}{value:g} is negative")
    if value != int(value):
        raise InputError(f"{source}: line {number}: {letter}{value:g} is not a whole number")
    if value > MAX_WORD_INTEGER:
        raise InputError(f"{source}: line {number}: {letter}{value:.0f} is more than {MAX_WORD_INTEGER:,}, the "
                         "largest number such a word takes")
    return int(value)


def _dwell(words: dict, state: _State, event, source: str, number: int) -> None:
    if "P" in words:
        value = words.pop("P")
        integer = not words.pop("P.", True)
        seconds = value / 1000.0 if state.dwell_p == "ms" or (state.dwell_p == "auto" and integer) else value
    elif "X" in words:
        seconds = words.pop("X")  # Fanuc: G4 X in seconds
    else:
        raise InputError(f"{source}: line {number}: G4 dwell without its time (P or X)")
    if seconds < 0:
        raise InputError(f"{source}: line {number}: negative dwell time")
    if seconds > MAX_DWELL_S:
        raise InputError(f"{source}: line {number}: a dwell of {seconds:g} s, more than {MAX_DWELL_S:g} s: a "
                         "program that waits that long is a mistake (P in seconds where milliseconds were meant? "
                         "see --dwell-p)")
    event(DWELL, "", seconds)
    if words:
        raise InputError(f"{source}: line {number}: G4 dwell with {' '.join(sorted(words))}: "
                         "a dwell block holds only its time")


def _modal(code: float, state: _State) -> None:
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


def _length_offset(g, words: dict, event, source: str, number: int) -> None:
    if 43 in g or 43.4 in g:
        if "H" not in words:
            raise InputError(f"{source}: line {number}: G43 without its length-offset register H")
        h = _integer(words.pop("H"), "H", source, number)
        event(LENGTH_OFFSET, "G43.4" if 43.4 in g else "G43", h)
    elif 49 in g:
        event(LENGTH_OFFSET, "G49", None)
    if "H" in words:
        raise InputError(f"{source}: line {number}: H without G43 (a length-offset register needs G43)")
    words.pop("D", None)  # cutter-radius register: read only with G41/G42, which are refused


def _machine_move(g, words: dict, state: _State, event, source: str, number: int) -> None:
    """G28: to the intermediate point (work coordinates), then home; G53: a move in machine coordinates."""
    if 28 in g and 53 in g:
        raise InputError(f"{source}: line {number}: G28 and G53 in one block")
    motion = [c for c in g if c in MOTION]
    extra = sorted(set(words) - set(AXES))
    if extra:
        raise InputError(f"{source}: line {number}: {extra[0]} with G{28 if 28 in g else 53} "
                         "(a machine move takes only X, Y, Z)")
    axes = [a for a in AXES if a in words]
    if 28 in g:
        if motion:
            raise InputError(f"{source}: line {number}: G28 and G{motion[0]:g} in one block both use the axis words")
        target, moved = list(state.position), False
        for a in axes:
            i, value = AXES.index(a), words.pop(a) * state.mm_per_unit
            if state.absolute:
                moved |= not value == state.position[i]
                target[i] = value
            elif value:
                if math.isnan(state.position[i]):
                    raise InputError(f"{source}: line {number}: incremental G28 {a} before the {a} position is known")
                target[i], moved = state.position[i] + value, True
        if moved:  # to the intermediate point first, in work coordinates
            _append(state, RAPID, target, math.nan, number)
        event(MACHINE_MOVE, "G28 " + " ".join(axes or AXES), None)
        homed = axes or AXES
    else:
        kind = MOTION[int(motion[0])] if motion else state.motion
        if kind not in (RAPID, LINEAR):
            raise InputError(f"{source}: line {number}: G53 needs G0 or G1 (machine coordinates are never arcs)")
        text = " ".join(f"{a}{words.pop(a) * state.mm_per_unit:.4f}" for a in axes)
        event(MACHINE_MOVE, f"G53 {MOTION_CODE[kind]} {text}".strip(), None)
        homed = axes
    for a in homed:
        state.position[AXES.index(a)] = math.nan


def _motion(g, words: dict, state: _State, source: str, number: int) -> None:
    unknown = sorted(set(words) - set("XYZIJKRABC"))
    if unknown:
        raise InputError(f"{source}: line {number}: unknown word {unknown[0]} "
                         "(WorkCal reads G0-G3 toolpaths: X Y Z I J K R F A B C)")
    kind = state.motion
    if kind is None:
        raise InputError(f"{source}: line {number}: coordinates without a motion mode (G0, G1, G2 or G3) in force")
    arc = kind in (ARC_CW, ARC_CCW)
    if "R" in words and not arc:
        raise InputError(f"{source}: line {number}: R given for a straight move ({MOTION_CODE[kind]})")
    start = list(state.position)
    for i, axis in enumerate(AXES):
        if axis in words:
            value = words.pop(axis) * state.mm_per_unit
            if state.absolute:
                state.position[i] = value
            elif math.isnan(state.position[i]):
                raise InputError(f"{source}: line {number}: incremental (G91) {axis} before the {axis} position is known")
            else:
                state.position[i] += value
    _tool_axis(words, state, arc, source, number)
    if kind != RAPID and not state.feed > 0:
        what = "missing feed (F) on the first" if math.isnan(state.feed) else "feed F0 on a"
        raise InputError(f"{source}: line {number}: {what} cutting move ({MOTION_CODE[kind]})")
    if arc:
        if any(map(math.isnan, start)):
            raise InputError(f"{source}: line {number}: arc before the start position is known (give X, Y and Z first)")
        centre, normal = _arc_centre(words, state, start, list(state.position), source, number)
        state.centres.append(centre)
        state.normals.append(normal)
    _append(state, kind, state.position, math.nan if kind == RAPID else state.feed, number)


def _tool_axis(words: dict, state: _State, arc: bool, source: str, number: int) -> None:
    rotary = [a for a in "ABC" if a in words]
    vector = [] if arc else [a for a in "IJK" if a in words]
    if rotary:
        allowed = orientation.ROTARY[state.rotary].letters
        bad = [a for a in rotary if a not in allowed]
        if bad:
            raise InputError(f"{source}: line {number}: rotary axis {bad[0]} is not one of the {state.rotary.upper()} "
                             f"convention's axes (say --rotary with the machine's two rotary axes)")
        for a in rotary:
            value = words.pop(a)
            state.rotary_deg[a] = value if state.absolute else state.rotary_deg[a] + value
        state.axis = tuple(orientation.tool_axis_from_rotary(state.rotary, *(state.rotary_deg[a] for a in allowed)))
    if vector:
        ijk = np.array([words.pop(a, 0.0) for a in "IJK"])
        length = float(np.linalg.norm(ijk))
        if length < 1e-9:
            raise InputError(f"{source}: line {number}: tool vector I J K of zero length")
        state.axis = tuple(ijk / length)
    for used, name in ((rotary, "rotary"), (vector, "vector")):
        if used:
            if state.axis_source and state.axis_source != name:
                raise InputError(f"{source}: line {number}: both rotary axes and I/J/K tool vectors in one file")
            state.axis_source = name


def _arc_centre(words: dict, state: _State, start: list, end: list, source: str, number: int):
    """Centre (in the start's plane) and unit normal of a G2/G3 arc, checked for a consistent radius.
    In plain floats: numpy's calls on 3-vectors made an arc cost as much as a hundred straight moves."""
    normal_axis, offset_letters = PLANES[state.plane]
    normal = [0.0, 0.0, 0.0]
    normal[normal_axis] = 1.0
    for letter in "IJK":  # an off-plane offset of zero says nothing (FreeCAD's posts write K0 in G17 arcs)
        if letter not in offset_letters and words.get(letter) == 0:
            del words[letter]
    offsets = [a for a in "IJK" if a in words]
    wrong = [a for a in offsets if a not in offset_letters]
    if wrong:
        raise InputError(f"{source}: line {number}: {wrong[0]} in a G{state.plane} arc (its centre is given by "
                         f"{' and '.join(offset_letters)}; a helix rises by the axis word, not by {wrong[0]})")
    if "R" in words and offsets:
        raise InputError(f"{source}: line {number}: R and {'/'.join(offsets)} in one arc: give the radius or the "
                         "centre, not both (they may describe different arcs)")
    if "R" in words:
        centre = _centre_from_radius(words.pop("R") * state.mm_per_unit, state.motion, start, end, normal_axis,
                                     source, number)
    elif offsets:
        centre = list(start)
        for letter in offset_letters:
            value = words.pop(letter, 0.0) * state.mm_per_unit
            axis = OFFSET_AXIS[letter]
            centre[axis] = value if state.absolute_centres else start[axis] + value
    else:
        raise InputError(f"{source}: line {number}: arc without centre ({' or '.join(offset_letters)} "
                         f"for G{state.plane}) or radius R")
    r_start, r_end = _radius(start, centre, normal_axis), _radius(end, centre, normal_axis)
    if r_start < ARC_RADIUS_TOL_MM:
        raise InputError(f"{source}: line {number}: arc of zero radius")
    if abs(r_start - r_end) > max(ARC_RADIUS_TOL_MM, ARC_RADIUS_TOL_REL * r_start):
        raise InputError(f"{source}: line {number}: arc radius mismatch: {r_start:.4f} mm from the centre to the "
                         f"start, {r_end:.4f} mm to the end")
    return centre, normal


def _in_plane(normal_axis: int) -> tuple[int, int]:
    """The two axes of the arc plane square to ``normal_axis``, in turn after it (normal x first = second)."""
    return (normal_axis + 1) % 3, (normal_axis + 2) % 3


def _radius(point: list, centre: list, normal_axis: int) -> float:
    """Distance from ``centre`` to ``point`` in the arc plane (square to axis ``normal_axis``)."""
    i, j = _in_plane(normal_axis)
    return math.sqrt((point[i] - centre[i]) ** 2 + (point[j] - centre[j]) ** 2)


def _centre_from_radius(r: float, kind: str, start: list, end: list, normal_axis: int, source: str,
                        number: int) -> list:
    """R > 0: the short way (<= 180 degrees), R < 0: the long way."""
    chord = [0.0 if k == normal_axis else e - s for k, (s, e) in enumerate(zip(start, end))]
    half = math.sqrt(sum(c * c for c in chord)) / 2
    if half < arcs.FULL_CIRCLE_MM:
        raise InputError(f"{source}: line {number}: an R arc cannot be a full circle; use I/J/K")
    if half > abs(r) + ARC_RADIUS_TOL_MM:
        raise InputError(f"{source}: line {number}: arc radius mismatch: R {abs(r):.4f} mm is less than half the "
                         f"chord {half:.4f} mm")
    height = math.sqrt(max(r * r - half * half, 0.0))
    side = (1 if kind == ARC_CCW else -1) * (1 if r > 0 else -1)
    i, j = _in_plane(normal_axis)  # normal x chord turns the chord a quarter in the plane
    across = [0.0, 0.0, 0.0]
    across[i], across[j] = -chord[j] / (2 * half), chord[i] / (2 * half)
    return [s + c / 2 + side * height * a for s, c, a in zip(start, chord, across)]


def _append(state: _State, kind: str, position, feed: float, number: int) -> None:
    index = state.count
    known = "".join(a for a, v in zip(AXES, position) if not math.isnan(v))
    if len(known) < 3:
        state.partial[index] = known
    state.kind.append(CODE[kind])
    state.end.extend(position)
    state.feeds.append(feed)
    state.lines.append(number)
    if state.axis != (0.0, 0.0, 1.0) and not state.tilted:
        state.tilted = True
        state.axes.extend([0.0, 0.0, 1.0] * index)
    if state.tilted:
        state.axes.extend(state.axis)


def _finish(state: _State, source: str, header: list, pending: list) -> Toolpath:
    n = state.count
    end = np.frombuffer(state.end, dtype=float).reshape(n, 3).copy()
    _fill_unknown_axes(end, np.frombuffer(state.lines, dtype=np.int32), source)
    return Toolpath(kind=np.frombuffer(state.kind, dtype=np.int8), end=end,
                    feed=np.frombuffer(state.feeds, dtype=float), line=np.frombuffer(state.lines, dtype=np.int32),
                    tool_axis=np.frombuffer(state.axes, dtype=float).reshape(n, 3) if state.tilted else None,
                    arc_centre=np.array(state.centres).reshape(-1, 3), arc_normal=np.array(state.normals).reshape(-1, 3),
                    comments=state.comments, events=state.events, partial=state.partial,
                    header=header if n else [], footer=pending if n else header + pending,
                    warnings=state.warnings, source=source)


def _fill_unknown_axes(end: np.ndarray, lines: np.ndarray, source: str) -> None:
    """An axis not known at a move (not yet given, or after G28/G53) takes its next given value."""
    n = len(end)
    for axis, name in enumerate(AXES):
        column = end[:, axis]
        unknown = np.isnan(column)
        if not unknown.any():
            continue
        index = np.where(unknown, n, np.arange(n))
        following = np.minimum.accumulate(index[::-1])[::-1]
        stuck = unknown & (following == n)
        if stuck.any():
            first = int(np.flatnonzero(stuck)[0])
            if unknown.all():
                raise InputError(f"{source}: axis {name} is never given, so the path cannot be placed")
            raise InputError(f"{source}: line {lines[first]}: {name} is not known here (after G28/G53 or never "
                             f"given) and never given again, so the move cannot be placed")
        column[unknown] = column[following[unknown]]
