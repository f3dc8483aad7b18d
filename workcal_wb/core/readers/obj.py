"""Wavefront OBJ: v and f lines; every other statement of the specification is skipped."""
from __future__ import annotations

import re

import numpy as np

from ..errors import InputError
from .common import _Parsed, _fan_triangles, _floats, _text

_OBJ_VERTEX = re.compile(r"^[ \t]*v[ \t]+(\S+)[ \t]+(\S+)[ \t]+(\S+)", re.M)
_OBJ_VERTEX_KEYWORD = re.compile(r"^[ \t]*v[ \t]", re.M)
_OBJ_FACE = re.compile(r"^[ \t]*f[ \t]+([^\r\n#]*)", re.M)
_OBJ_STATEMENT = re.compile(r"^[ \t]*([^\s#]\S*)", re.M)
# Every statement of the OBJ specification; what WorkCal does not use (texture, groups, curves) is skipped.
_OBJ_KEYWORDS = frozenset("v vt vn vp f l p g o s mg mtllib usemtl usemap maplib lod bevel c_interp d_interp "
                          "shadow_obj trace_obj ctech stech cstype deg bmat step curv curv2 surf parm trim hole "
                          "scrv sp end con call csh".split())


def _parse_obj(data: bytes, label: str) -> _Parsed:
    """v lines and f lines (v, v/vt, v//vn, v/vt/vn; negative = relative); all else is ignored."""
    text = _text(data, label)
    _check_obj_statements(text, label)
    vertex_lines = list(_OBJ_VERTEX.finditer(text))
    if len(vertex_lines) != len(_OBJ_VERTEX_KEYWORD.findall(text)):
        raise InputError(f"{label}: a 'v' line has fewer than three coordinates")
    points = _floats([match.groups() for match in vertex_lines], label, "v lines").reshape(-1, 3)
    face_lines = list(_OBJ_FACE.finditer(text))
    if not face_lines:
        return _Parsed(points)
    corners_per_face = [line.group(1).split() for line in face_lines]
    lengths = np.array([len(corners) for corners in corners_per_face], dtype=np.int64)
    references = [corner.split("/", 1)[0] for corners in corners_per_face for corner in corners]
    face_of = np.repeat(np.arange(len(face_lines)), lengths)

    def where(corner: int) -> str:
        return f"{label}: line {text.count(chr(10), 0, face_lines[face_of[corner]].start()) + 1}"

    try:
        indices = np.array(references, dtype=np.int64)
    except ValueError:
        bad = next(k for k, reference in enumerate(references) if not re.fullmatch(r"[+-]?\d+", reference))
        raise InputError(f"{where(bad)}: 'f' refers to vertex {references[bad][:40]!r}, not a whole number") from None
    if np.any(indices == 0):
        raise InputError(f"{where(int(np.argmax(indices == 0)))}: 'f' refers to vertex 0; OBJ vertices count from 1")
    defined_before = np.repeat(np.searchsorted([match.start() for match in vertex_lines],
                                               [match.start() for match in face_lines]), lengths)
    outside = (indices > len(points)) | (indices < -defined_before)
    if outside.any():
        bad = int(np.argmax(outside))
        raise InputError(f"{where(bad)}: 'f' refers to vertex {indices[bad]}, and the file has "
                         f"{len(points) if indices[bad] > 0 else defined_before[bad]} vertices "
                         f"{'in all' if indices[bad] > 0 else 'before that line'}")
    indices = np.where(indices > 0, indices - 1, indices + defined_before)
    warnings: list[str] = []
    triangles = _fan_triangles(indices, lengths, label, warnings)
    return _Parsed(points, triangles=triangles, warnings=tuple(warnings))


def _check_obj_statements(text: str, label: str) -> None:
    """Refuse a line that is no OBJ statement (numbers without a keyword, binary junk, another format)."""
    unknown = set(_OBJ_STATEMENT.findall(text)) - _OBJ_KEYWORDS
    if unknown:
        first = next(m for m in _OBJ_STATEMENT.finditer(text) if m.group(1) in unknown)
        line = text.count("\n", 0, first.start()) + 1
        raise InputError(f"{label}: line {line}: {first.group(1)[:40]!r} is not an OBJ statement "
                         "(v, vn, f, g, ...)")
