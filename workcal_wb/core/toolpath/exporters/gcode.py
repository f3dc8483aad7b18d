"""G-code (.nc) in the machine's frame B for a 3-axis machine or a 5-axis one in tool-centre-point mode.

Structure: ``%``, comment lines, a safe-start block (mm, absolute, XY plane, no compensation or
cycle, feed per minute), the CAM file's own events (tool change, spindle, coolant, dwell, stops,
G28/G53) where it had them, tool-length compensation (``G43 H`` on a 3-axis machine, ``G43.4 H``
tool-centre-point control on a 5-axis one, so XYZ is the tool tip) in the block of the first move
that gives Z after the CAM file's G43 (or after the start when it has none: the offset itself moves
Z on Fanuc-family controls, so it never stands alone), every move with its motion code and full
position (a move made after G28/G53 only with the axes its block gave, 3-axis), ``G49``, ``M30``,
``%``.  Comments never hold ``(``, ``)``, ``;`` or ``%``.

The text is produced in chunks of moves, so a 2-million-move program is never one string in memory.
"""
from __future__ import annotations

import numpy as np

from .. import orientation
from ..gcode import AXES, MOTION_CODE, OFFSET_AXIS, PLANE_OF_AXIS, PLANES, gcode_comment
from ..model import (ARC_CCW, ARC_CW, COOLANT, DWELL, FIRST_ARC_CODE, KINDS, LENGTH_OFFSET, SPINDLE, STOP,
                     TOOL_CHANGE)
from ..safety import check_vertical, number, numbers, writable
from ..transform import transformed
from . import common

NAME, EXTENSION = "G-code", ".nc"
MACHINES = ("3axis", "5axis-tcp")
CONTROLLERS = ()  # machine tools: no robot runs G-code
CHUNK_MOVES = 20_000
COMMENT_WIDTH = 72
SAFE_START = "G21 G90 G17 G40 G80 G94"
TCP_ON = "G43.4"  # Fanuc 30i-family tool-centre-point control; Siemens TRAORI, Heidenhain M128, Haas G234


def comment(text: str) -> str:
    """A G-code comment on one line (common.comment_text): no nested parentheses, no ';' (a comment
    start) and no '%' (a program boundary)."""
    return gcode_comment(common.comment_text(text))


def _event_blocks(event, machine: str) -> list[str]:
    n = event.number
    if event.kind == STOP:
        return [event.code]
    if event.kind == TOOL_CHANGE:
        return [f"T{n} M6"]
    if event.kind == LENGTH_OFFSET:
        return ["G49"] if n is None else []  # G43 H goes into a Z move: _length_offsets
    if event.kind == SPINDLE:
        code = {"cw": "M3", "ccw": "M4", "off": "M5"}[event.code]
        return [code if n is None or code == "M5" else f"S{number(n, 3).rstrip('0').rstrip('.')} {code}"]
    if event.kind == COOLANT:
        return [{"mist": "M7", "flood": "M8", "off": "M9"}[event.code]]
    if event.kind == DWELL:
        return [f"G4 P{n:.3f}"]
    if event.code.startswith("G28"):
        return ["G91 G28 " + " ".join(f"{a}0" for a in event.code.split()[1:]), "G90"]
    return [event.code]  # G53: machine coordinates, the same machine whatever W is


def _notes(job: common.ExportJob) -> list[str]:
    notes = ["units: mm G21, feed F in mm/min, absolute positions G90, arc centres I J K incremental, "
             "dwell G4 P in seconds",
             "positions: tool tip in the machine's frame B (make B the active work offset)",
             f"arcs: kept where their plane stays XY, ZX or YZ within {job.chord_tol_mm} mm, otherwise chords "
             f"within {job.chord_tol_mm} mm"]
    if job.machine == "3axis":
        tilt = check_vertical(job.toolpath, job.transform, job.options.vertical_tol_deg)
        notes += [f"3-axis: the tool stays along the machine's Z; W tilts the tool axis {tilt:.4f} deg, within the "
                  f"tolerance {job.options.vertical_tol_deg:g} deg",
                  "tool length: G43 H with the first Z move (H of the tool in use, H1 when the file names none)",
                  "after G28/G53 a move carries only the axes its block gave"]
    else:
        rotary = orientation.ROTARY[job.options.rotary]
        notes += [f"5-axis, tool-centre-point control {TCP_ON} H (Fanuc 30i family; on Siemens use TRAORI, on "
                  "Heidenhain M128, on Haas G234): XYZ is the tool tip, the control moves the rotary axes",
                  f"rotary axes {rotary.letters[0]} {rotary.letters[1]} in degrees, the tool's turn relative to the "
                  f"workpiece (ISO 841 sense): {rotary.formula}; {rotary.letters[1]} is kept continuous",
                  "after G28/G53 a move carries its full position"]
    return notes


def _length_offsets(path, machine: str, add_missing: bool = True) -> dict:
    """{move index: (G43 or G43.4, H word)}: each G43 H of the CAM file (and, ``add_missing``, G43 H1 or
    H of the first tool when it has none) in the first move from there on whose block gives Z; a G49
    drops the ones not yet written."""
    code = TCP_ON if machine == "5axis-tcp" else "G43"

    def z_move(i: int):
        while machine == "3axis" and i < len(path) and "Z" not in path.partial.get(i, "Z"):
            i += 1
        return i if i < len(path) else None

    offsets = [e for e in path.events if e.kind == LENGTH_OFFSET]
    if not offsets and add_missing:
        tools = [e.number for e in path.events if e.before == 0 and e.kind == TOOL_CHANGE]
        first = z_move(0)
        return {} if first is None else {first: (code, f"H{int(tools[-1]) if tools else 1}")}
    out = {}
    for e in offsets:
        if e.number is None:
            out = {i: words for i, words in out.items() if i < e.before}
        elif (i := z_move(e.before)) is not None:
            out[i] = (code, f"H{e.number}")
    return out


def render(job: common.ExportJob) -> list:
    path = transformed(job.toolpath, job.transform, job.chord_tol_mm)
    header = [comment(h) for h in common.wrapped(common.header_lines(job, NAME, _notes(job)), COMMENT_WIDTH)]
    return [(job.out, _chunks(path, header, job.machine, job.options.rotary, _length_offsets(path, job.machine)))]


def format_gcode(toolpath, header=()) -> str:
    """G-code of a toolpath in its own frame, with no calibration (the simulator's sample, test files):
    3-axis when every tool axis is +Z, 5-axis A/B otherwise."""
    vertical = toolpath.tool_axis is None or np.allclose(toolpath.tool_axis, orientation.VERTICAL, atol=1e-12)
    lines = [comment(h) for h in list(header) + toolpath.header]
    machine = "3axis" if vertical else "5axis-tcp"
    return "".join(_chunks(toolpath, lines, machine, "ab", _length_offsets(toolpath, machine, add_missing=False)))


def _feed_words(feed: np.ndarray) -> np.ndarray:
    """" F..." where a move's feed differs from the last one written, "" elsewhere (rapids write none)."""
    known = ~np.isnan(feed)
    index = np.where(known, np.arange(len(feed)), -1)
    last = np.maximum.accumulate(np.concatenate([[-1], index[:-1]]))
    previous = np.where(last >= 0, feed[np.maximum(last, 0)], np.nan)
    write = known & ~(feed == previous)
    words = np.full(len(feed), "", dtype=object)
    words[write] = [f" F{v}" for v in numbers(feed[write], 2)]
    return words


def _chunks(path, header: list[str], machine: str, rotary_name: str, offsets: dict):
    """The program text, CHUNK_MOVES moves at a time: plain moves formatted in bulk, the others
    (arcs, events, comments, partial moves) one by one."""
    five_axis = machine == "5axis-tcp"
    rotary = orientation.ROTARY[rotary_name].letters
    angles = orientation.rotary_from_tool_axes(rotary_name, path.axes()) if five_axis else None
    events = common.events_by_move(path.events, len(path))
    special = path.arc_mask.copy()
    special[[i for i in set(events) | set(path.comments) | set(path.partial) | set(offsets) if i < len(path)]] = True
    special[:1] = True
    arc_rows = np.cumsum(path.arc_mask) - 1
    starts = path.starts()
    feed_words = _feed_words(path.feed)
    codes = np.array([MOTION_CODE[k] for k in KINDS], dtype=object)[path.kind]
    yield "%\n" + "\n".join(header) + "\n" + SAFE_START + "\n"
    plane = 17
    for a in range(0, len(path), CHUNK_MOVES):
        b = min(a + CHUNK_MOVES, len(path))
        rot = None if angles is None else np.array(numbers(angles[a:b], 4), dtype=object).reshape(-1, 2)
        tail = ([f" {rotary[0]}{u} {rotary[1]}{v}" for u, v in rot] if rot is not None else [""] * (b - a))
        # A whole line formatted at once (numbers' rule, by writable): half the time of a word at a time.
        lines = [f"{c} X{x:.4f} Y{y:.4f} Z{z:.4f}{t}{f}" for c, (x, y, z), t, f in
                 zip(codes[a:b].tolist(), writable(path.end[a:b], 4).tolist(), tail, feed_words[a:b].tolist())]
        # The others' numbers, and their arcs' planes, for the whole chunk at once.
        here = np.flatnonzero(special[a:b]) + a
        row_words = np.array(numbers(path.end[here], 4), dtype=object).reshape(-1, 3)
        arcs_here = here[path.arc_mask[here]]
        normals = path.arc_normal[arc_rows[arcs_here]]
        normal_axes = np.abs(normals).argmax(axis=1)
        arc_words = iter(zip(np.array(numbers(path.arc_centre[arc_rows[arcs_here]] - starts[arcs_here], 4),
                                      dtype=object).reshape(-1, 3),
                             normal_axes.tolist(), (normals[np.arange(len(normals)), normal_axes] < 0).tolist()))
        for i, row in zip(here.tolist(), row_words):
            block = []
            for e in events.get(i, ()):
                block += _event_blocks(e, machine)
            k = int(path.kind[i])
            known = path.partial.get(i, AXES) if not five_axis else AXES
            words = [f"{axis}{row[j]}" for j, axis in enumerate(AXES) if axis in known]
            code = MOTION_CODE[KINDS[k]]
            g43, h = offsets.get(i, ("", ""))
            if k >= FIRST_ARC_CODE:
                offset, axis, reversed_normal = next(arc_words)
                if reversed_normal:
                    code = MOTION_CODE[ARC_CW if KINDS[k] == ARC_CCW else ARC_CCW]
                if PLANE_OF_AXIS[axis] != plane:
                    plane = PLANE_OF_AXIS[axis]
                    block.append(f"G{plane}")
                words += [f"{letter}{offset[OFFSET_AXIS[letter]]}" for letter in PLANES[plane][1]]
            notes = [comment(c) for c in path.comments.get(i, "").split("\n") if c]  # on the line: they stay its own
            block.append(" ".join(w for w in [code, g43, *words, h] if w) + tail[i - a] + feed_words[i]
                         + "".join(" " + n for n in notes))
            lines[i - a] = "\n".join(block)
        yield "\n".join(lines) + "\n"
    lines = []
    for e in events.get(len(path), ()):
        lines += _event_blocks(e, machine)
    offsets = [e for e in path.events if e.kind == LENGTH_OFFSET]
    cancel = [] if offsets and offsets[-1].number is None else ["G49"]
    lines += [comment(f) for f in path.footer] + cancel + ["M30", "%"]
    yield "\n".join(lines) + "\n"
