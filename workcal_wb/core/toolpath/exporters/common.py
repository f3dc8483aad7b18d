"""What every exporter shares: the job, the header (source, W, quality, conventions, placeholders),
robot targets as columns, events in words, program parts and names."""
from __future__ import annotations

import itertools
import re
import textwrap
import unicodedata
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from workcal_wb import __version__

from ...errors import InputError
from ...result import CHOSEN, CalibrationResult, choice_words, result_fingerprint, status_gate_code
from ..model import (COOLANT, DWELL, LENGTH_OFFSET, MACHINE_MOVE, SPINDLE, STOP, TOOL_CHANGE, Event, Toolpath)
from ..orientation import tool_rotations
from ..safety import ExportOptions, check_positions, forced_banner, gate_text, number, value_text
from ..transform import linearised

# Corner blending for robot moves (KRL $APO.CDIS, RAPID zone, UR blend radius): well inside a 0.3 mm
# calibration tolerance.
BLEND_MM = 0.1
ORIENTATION_NOTE = ("tool orientation: tool Z = -tool axis, along the approach into the part; tool X = workpiece +X "
                    "projected perpendicular to tool Z, or workpiece +Y when the tool axis lies along X")
DEFAULT_RAPID_FEED_MM_MIN = 6000.0  # robots have no G0: rapids are linear moves at this speed


@dataclass
class ExportJob:
    """Everything an exporter renders from; every check has passed before one is made."""

    toolpath: Toolpath  # in the workpiece frame X, mm
    calibration: CalibrationResult
    transform: np.ndarray  # X -> B actually used (W, or the rotary-table chain)
    forced: bool
    out: Path
    options: ExportOptions
    machine: str
    notes: list = field(default_factory=list)  # facts found while rendering, for the header
    banner: list = field(default_factory=list)  # why the export was forced (safety.Placement.banner)
    reach: object = None  # robots.reach.ReachReport of options.robot, None when not checked

    @property
    def solved(self):
        """The reach check's report when the robot follows the program: its configuration at every target
        is then written into the program; None otherwise (no robot, or a forced export it cannot follow)."""
        return self.reach if self.reach is not None and self.reach.reachable else None

    @property
    def chord_tol_mm(self) -> float:
        return self.options.chord_tol_mm

    @property
    def table(self):
        return self.options.table


# ---- header ------------------------------------------------------------------------------------

def matrix_rows(T: np.ndarray, indent: str = "  ") -> list[str]:
    return [indent + " ".join(f"{number(v, 6):>12}" for v in row) for row in np.asarray(T)]


def _uncertainty_line(calibration: CalibrationResult) -> str:
    u = calibration.uncertainty if isinstance(calibration.uncertainty, dict) else {}
    for key, where in (("toolpath", "toolpath"), ("surface", "workpiece surface")):
        bound = u.get(f"{key}_bound_mm")
        if isinstance(bound, (int, float)):
            median = u.get(f"{key}_median_mm")
            extra = f", median {value_text(float(median))} mm" if isinstance(median, (int, float)) else ""
            return f"displacement uncertainty at the {where}: bound {value_text(float(bound))} mm{extra}"
    return "displacement uncertainty: not estimated"


def _calibration_lines(job: ExportJob) -> list[str]:
    c = job.calibration
    lines = [f"calibration: {job.options.calibration_source}, result sha256 {result_fingerprint(c)}",
             f"calibration status {c.status}, tolerance {value_text(c.tolerance_mm)} mm, {_uncertainty_line(c)}"]
    resolved = status_gate_code(c.choice.role) if c.status == CHOSEN else None  # the gate a person's choice settles
    lines += [f"{gate_text(g)}: {'passed' if g.get('passed') else 'FAILED'}"
              + (" (resolved by the person's choice below)" if not g.get("passed") and g.get("code") == resolved
                 else "") for g in c.quality_gates]
    lines += [choice_words(c.choice)] if c.choice is not None else []
    return lines + [f"reason: {r}" for r in c.reasons]


def placement_name(job: ExportJob) -> str:
    """How the header names the transform used: W, or the rotary-table chain."""
    return "W" if job.table is None else "^B Q Rz(angle) ^B Q^-1 W"


def header_lines(job: ExportJob, format_name: str, notes: list[str]) -> list[str]:
    """The comment lines every exported file starts with (FORCED banner first when forced)."""
    lines = list(job.banner) or (forced_banner(job.calibration) if job.forced else [])
    lines += [f"WorkCal {__version__} toolpath export to {format_name}: {job.out.name}",
              f"toolpath: {job.toolpath.source}, {len(job.toolpath)} moves, machine {job.machine}", *notes,
              *job.notes, "W = ^B X, the workpiece frame X in the robot base frame B, 4x4, mm:",
              *matrix_rows(job.calibration.W)]
    if job.table is not None:
        lines += [f"rotary table at {number(job.table.angle_deg, 4)} deg; table frame ^B Q, 4x4, mm:",
                  *matrix_rows(job.table.frame),
                  f"transform used = {placement_name(job)}, 4x4, mm:", *matrix_rows(job.transform)]
    lines += _calibration_lines(job)
    lines += [f"source: {h}" for h in job.toolpath.header]
    lines += [f"reader: {w}" for w in job.toolpath.warnings]
    return lines


def wrapped(lines, width: int) -> list[str]:
    """Comment lines cut at ``width`` characters (at spaces where possible), none empty, each one line
    of plain text (comment_text)."""
    out = []
    for line in lines:
        out += textwrap.wrap(comment_text(line), width, break_long_words=True, break_on_hyphens=False) or ["-"]
    return out


def comment_text(text) -> str:
    """``text`` as one line of plain ASCII (ascii_text), each control character a space: a line break,
    NUL, a form feed or a separator (which str.splitlines breaks at) would end a comment and let the
    rest be read as code.  Every text from outside (file names, the CAM file's comments and words,
    result.json's text) reaches a program through this, then through its format's comment or string."""
    return _CONTROL.sub(" ", ascii_text(str(text)))


# The ASCII control characters (ascii_text has made every other character printable ASCII or '?').
_CONTROL = re.compile(r"[\x00-\x1f\x7f]")


def robot_notes(job: ExportJob, speed_unit: str) -> list[str]:
    """The conventions all robot formats share."""
    return [ORIENTATION_NOTE,
            f"arcs: linearised into chords within {job.chord_tol_mm} mm",
            f"rapids (G0): linear moves at {number(job.options.rapid_feed_mm_min, 1)} mm/min; speeds in {speed_unit}",
            "first move: a joint move to the first point of the CAM file (its approach), then its moves as written",
            "G28/G53 (machine home): a straight retract to the program's top Z (the robot has no machine home)"]


# ---- robot targets -----------------------------------------------------------------------------

@dataclass
class RobotPath:
    """Robot targets in columns: position (N, 3), rotation (N, 3, 3) in the output frame, speed mm/min."""

    position: np.ndarray
    rotation: np.ndarray
    feed: np.ndarray
    rapid: np.ndarray
    line: np.ndarray
    comments: dict
    events: list

    def __len__(self) -> int:
        return len(self.position)

    def matrix(self, i: int) -> np.ndarray:
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = self.rotation[i], self.position[i]
        return T


def _with_retracts(path: Toolpath) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict, list]:
    """End points, feeds, lines and tool axes with a retract to the top Z inserted for every machine move
    that homes Z, and unknown Z of partial moves at that top; comments and events re-indexed."""
    top = float(path.end[:, 2].max())
    end = path.end.copy()
    for i, known in path.partial.items():
        if "Z" not in known:
            end[i, 2] = top
    homes = [e for e in path.events if e.kind == MACHINE_MOVE and 0 < e.before
             and any(word.startswith("Z") for word in e.code.split()[1:])]
    home_ids = {id(e) for e in homes}
    at = np.array([e.before for e in homes], dtype=np.int64)
    retract = end[at - 1].copy() if len(at) else np.zeros((0, 3))
    retract[:, 2] = top
    axes = path.axes()
    end = np.insert(end, at, retract, axis=0)
    feed = np.insert(path.feed, at, np.nan)
    line = np.insert(path.line, at, [e.line or 0 for e in homes])
    axes = np.insert(axes, at, axes[at - 1] if len(at) else np.zeros((0, 3)), axis=0)
    shift = np.searchsorted(at, np.arange(len(path) + 1), side="right")
    comments = {int(i + shift[i]): c for i, c in path.comments.items()}
    events = []
    for e in path.events:
        before = int(e.before + shift[e.before])
        if id(e) in home_ids:
            before -= 1  # the retract comes after the event's message
        events.append(Event(e.kind, before, e.line, e.code, e.number))
    return end, feed, line, axes, comments, events


def robot_path(job: ExportJob, in_base_frame: bool, max_speed_mm_s: float) -> RobotPath:
    """The job's robot targets along the linearised path, in B or (``in_base_frame=False``) in X.

    The orientation is built in the workpiece frame and then carried by T, so a program in workpiece
    coordinates and one in B describe the same physical tool pose.  Speeds above the controller's
    ``max_speed_mm_s`` are limited to it (the header says where)."""
    path = linearised(job.toolpath, job.chord_tol_mm)
    end, feed, line, axes, comments, events = _with_retracts(path)
    T = job.transform
    check_positions(end @ T[:3, :3].T + T[:3, 3], lambda k: f"robot target {k + 1} (line {line[k]})",
                    path.source, job.options.envelope)
    rapid = np.isnan(feed)
    speed = np.where(rapid, job.options.rapid_feed_mm_min, feed)
    limit = max_speed_mm_s * 60.0
    over = np.flatnonzero(speed > limit)
    if over.size:
        first = int(line[over[0]])
        job.notes.append(f"speed limited: {over.size} moves asked for more than the controller's "
                         f"{max_speed_mm_s:g} mm/s (first at line {first}); they run at {max_speed_mm_s:g} mm/s")
        speed = np.minimum(speed, limit)
    unique, inverse = np.unique(axes, axis=0, return_inverse=True)
    rotation = tool_rotations(unique)[np.asarray(inverse).reshape(-1)]
    position = end
    if in_base_frame:
        rotation = T[:3, :3] @ rotation
        position = end @ T[:3, :3].T + T[:3, 3]
    return RobotPath(position, rotation, speed, rapid, line, comments, events)


def events_by_move(events: list, count: int) -> dict:
    """{move index: [events before it]}, the events after the last move under ``count``."""
    out: dict = {}
    for e in events:
        out.setdefault(min(e.before, count), []).append(e)
    return out


def tools_by_move(path: RobotPath, first: int) -> list[int]:
    """The CAM tool in use at each target (changed by the tool-change events before it)."""
    changes = {e.before: int(e.number) for e in path.events if e.kind == TOOL_CHANGE}
    tools, tool = [], first
    for i in range(len(path)):
        tool = changes.get(i, tool)
        tools.append(tool)
    return tools


def first_tool(path: RobotPath) -> int:
    """The tool of the first move: the one changed to before it, else 1."""
    return next((int(e.number) for e in path.events if e.kind == TOOL_CHANGE and e.before == 0), 1)


def move_groups(path: RobotPath, event_lines, comment_line, move_line):
    """Line groups in order, one per target (its events, its comments, then ``move_line(i, stops)``,
    where ``stops(i)`` says whether the robot must stop at target i) and one for the events after the
    last target: the body every robot language packs into program parts."""
    events = events_by_move(path.events, len(path))

    def stops(i: int) -> bool:
        return i + 1 == len(path) or i + 1 in events

    for i in range(len(path)):
        lines = []
        for e in events.get(i, ()):
            lines += event_lines(e)
        lines += [comment_line(comment_text(c)) for c in path.comments.get(i, "").split("\n") if c]
        yield lines + move_line(i, stops)
    tail = []
    for e in events.get(len(path), ()):
        tail += event_lines(e)
    yield tail


@dataclass
class Action:
    """What a robot program does for one G-code event: a message, and whether the robot must stop."""

    message: str
    stop: bool
    tool: int | None = None
    dwell_s: float | None = None


def action(event: Event) -> Action:
    """An event in words, the same for every robot language (each writes it its own way), its message
    one line of plain text (comment_text)."""
    act = _action(event)
    act.message = comment_text(act.message)
    return act


def _action(event: Event) -> Action:
    n = event.number
    if event.kind == STOP:
        optional = event.code == "M1"
        return Action("optional stop (M1), kept as a stop" if optional else "program stop (M0)", True)
    if event.kind == TOOL_CHANGE:
        return Action(f"tool change (M6): fit tool T{n}, then continue", True, tool=int(n))
    if event.kind == LENGTH_OFFSET:
        what = "cancelled (G49)" if n is None else f"H{n} ({event.code})"
        return Action(f"tool length offset {what}: held in the robot's tool data", False)
    if event.kind == SPINDLE:
        speed = "" if n is None else f" at {n:g} rpm"
        words = {"cw": "on clockwise (M3)", "ccw": "on counter-clockwise (M4)", "off": "off (M5)"}[event.code]
        return Action(f"spindle {words}{speed}: set it, then continue", True)
    if event.kind == COOLANT:
        words = {"mist": "mist on (M7)", "flood": "flood on (M8)", "off": "off (M9)"}[event.code]
        return Action(f"coolant {words}: set it, then continue", True)
    if event.kind == DWELL:
        return Action(f"dwell (G4) {n:g} s", False, dwell_s=float(n))
    return Action(f"machine move {event.code}: retract to the program's top Z", False)


def ascii_text(text: str) -> str:
    """``text`` in plain ASCII, one character for one: a letter's base letter (é -> e), else '?'.

    Controllers read ASCII (UR's script interface takes only ASCII text; Fanuc TP and CNC posts write
    ASCII), and the CAM file's own words reach the program in comments and messages."""
    if text.isascii():
        return text
    return "".join(c if c.isascii() else _ascii_char(c) for c in text)


def _ascii_char(c: str) -> str:
    base = unicodedata.normalize("NFKD", c).encode("ascii", "ignore").decode()
    return base if len(base) == 1 else "?"


# ---- parts and names ---------------------------------------------------------------------------

def part_ranges(count: int, per_part: int) -> list[tuple[int, int]]:
    """[start, stop) move ranges of the program parts (one part when everything fits)."""
    return [(a, min(a + per_part, count)) for a in range(0, count, per_part)] or [(0, 0)]


def program_name(job: ExportJob, max_len: int, must_match_file: bool = False, reserved=()) -> str:
    """A controller-safe program name from the output file name (letters, digits, _; starts with a letter).

    KRL and Fanuc load a program only under its own file name, so there a mismatch is an error.
    ``max_len`` leaves room for the "_001" of program parts."""
    stem = job.out.stem
    name = re.sub(r"\W", "_", stem, flags=re.ASCII)[:max_len]
    if not name[:1].isalpha():
        name = ("P" + name)[:max_len]
    if must_match_file and name.lower() != stem.lower():
        raise InputError(f"{job.out}: the file name must be a valid program name (a letter, then letters, digits or _, "
                         f"at most {max_len} characters), e.g. {name}{job.out.suffix}")
    if name.upper() in reserved:
        raise InputError(f"{job.out}: {name} is a reserved word of the robot language or a name the program "
                         "declares itself; choose another file name")
    return name


def part_name(name: str, index: int) -> str:
    return f"{name}_{index:03d}"


def part_path(job: ExportJob, index: int) -> Path:
    """Where part ``index`` of the program goes: beside it, named after its file."""
    return job.out.with_name(f"{job.out.stem}_{index:03d}{job.out.suffix}")


def fingerprint(job: ExportJob) -> str:
    return result_fingerprint(job.calibration)


def packed(groups, limit: int):
    """Line groups (one per move) packed in order into parts of at most ``limit`` lines."""
    part = []
    for lines in groups:
        if part and len(part) + len(lines) > limit:
            yield part
            part = []
        part += lines
    yield part


def program_files(job: ExportJob, groups, limit: int, single, part, main):
    """The files of a program: ``single(body)`` when it fits in ``limit`` lines, otherwise each
    ``part(index, body)`` -> (path, chunks) in order and then ``main(count)``, the text that calls them."""
    parts = packed(groups, limit)
    first = next(parts)
    second = next(parts, None)
    if second is None:
        yield job.out, [single(first)]
        return
    count = 0
    for count, body in enumerate(itertools.chain([first, second], parts), start=1):
        yield part(count, body)
    yield job.out, [main(count)]
