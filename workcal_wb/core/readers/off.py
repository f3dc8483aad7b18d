"""OFF and its variants (COFF, NOFF, ...): counts, vertex lines, face lines."""
from __future__ import annotations

import re

import numpy as np

from ..errors import InputError
from .common import _Parsed, _fan_triangles, _numeric_table, _text, _trailing, _truncated

_OFF_KEYWORD = re.compile(r"(ST)?C?(N)?(4)?(n)?OFF")


def _parse_off(data: bytes, label: str) -> _Parsed:
    """OFF, COFF, NOFF (...): counts, vertex lines (normals for N), face lines 'k i1 .. ik [colour]'."""
    text_lines = _text(data, label).splitlines()
    lines = [(number, line.split("#", 1)[0].strip()) for number, line in enumerate(text_lines, 1)]
    lines = [(number, line) for number, line in lines if line]  # (line number, content) of data lines
    if not lines:
        raise InputError(f"{label}: not an OFF file (only comments)")
    keyword, *rest = lines[0][1].split()
    form = _OFF_KEYWORD.fullmatch(keyword)
    if form is None:
        raise InputError(f"{label}: not an OFF file (first word {keyword!r}, expected OFF, COFF, NOFF, ...)")
    if form.group(3) or form.group(4):
        raise InputError(f"{label}: {keyword} (points that are not 3D) is not supported")
    if not rest:
        if len(lines) < 2:
            raise InputError(f"{label}: the OFF file has no vertex and face counts")
        rest, lines = lines[1][1].split(), lines[1:]
    try:
        vertex_count, face_count = int(rest[0]), int(rest[1])
    except (IndexError, ValueError):
        vertex_count = face_count = -1
    if vertex_count < 0 or face_count < 0:
        raise InputError(f"{label}: the OFF counts line must start with two whole numbers "
                         "(vertices and faces)")
    vertex_lines = lines[1:1 + vertex_count]
    if len(vertex_lines) < vertex_count:
        raise _truncated(label, vertex_count, "vertices", len(vertex_lines))
    table = np.zeros((0, 3))
    if vertex_count:
        first, last = vertex_lines[0][0], vertex_lines[-1][0]
        table = _numeric_table(text_lines[first - 1:last], first, label, "vertex lines")
    columns = 6 if form.group(2) else 3
    if table.shape[1] < columns:
        raise InputError(f"{label}: vertex lines have {table.shape[1]} numbers, {keyword} needs {columns}")
    face_lines = lines[1 + vertex_count:1 + vertex_count + face_count]
    if len(face_lines) < face_count:
        raise _truncated(label, face_count, "faces", len(face_lines))
    after = lines[1 + vertex_count + face_count:]
    if after:
        raise _trailing(label, f"line {after[0][0]}", *((face_count, "faces") if face_count else
                                                          (vertex_count, "vertices")))
    normals = table[:, 3:6] if form.group(2) else None
    if not face_count:
        return _Parsed(table[:, :3], normals)
    corners, lengths = _off_faces(face_lines, label)
    warnings: list[str] = []
    return _Parsed(table[:, :3], normals, _fan_triangles(corners, lengths, label, warnings),
                   warnings=tuple(warnings))


def _off_faces(face_lines: list[tuple[int, str]], label: str):
    """Concatenated corner indices and corners per face from 'k i1 .. ik [colour]' lines."""
    corners, lengths = [], []
    for number, line in face_lines:
        words = line.split()
        try:
            length = int(words[0])
            indices = [int(word) for word in words[1:1 + length]]
        except ValueError:
            raise InputError(f"{label}: line {number}: face is not 'k i1 .. ik' whole numbers: {line!r}") from None
        if length < 0 or len(indices) < length:
            raise InputError(f"{label}: line {number}: face declares {length} corners, lists {len(indices)}")
        corners += indices
        lengths.append(length)
    return np.array(corners, dtype=np.int64), np.array(lengths, dtype=np.int64)
