"""Text point clouds (XYZ, ASC, PTS, CSV, TXT): x y z per line after any header lines."""
from __future__ import annotations

import re

import numpy as np

from ..errors import InputError
from .common import _INLINE_COMMENT, _Parsed, _numeric_table, _text, _trailing, _truncated

_FIELD_SEPARATORS = re.compile(r"[\s,;]+")
_NORMAL_HEADERS = (["nx", "ny", "nz"], ["normal_x", "normal_y", "normal_z"], ["normalx", "normaly", "normalz"])
_UNIT_NORMAL_TOLERANCE = 1e-3


def _parse_text_cloud(data: bytes, label: str) -> _Parsed:
    """x y z per line (whitespace, comma or semicolon), after any header lines; extra columns ignored."""
    lines = _text(data, label).splitlines()
    longest = max(range(len(lines)), key=lambda number: len(lines[number]), default=None)
    if longest is not None and len(lines[longest]) > MAX_TEXT_LINE_CHARS:
        raise InputError(f"{label}: line {longest + 1} is {len(lines[longest]):,} characters long (at most "
                         f"{MAX_TEXT_LINE_CHARS:,}): a point line holds x y z and a few more numbers, one point a line")
    first = next((number for number, line in enumerate(lines) if _is_point_line(line)), None)
    if first is None:
        raise InputError(f"{label}: no line with at least three numbers (x y z) found")
    delimiter = next((d for d in ";," if d in lines[first]), None)
    table = _numeric_table(lines[first:], first + 1, label, "point lines", delimiter)
    if table.shape[1] < 3:
        raise InputError(f"{label}: the point lines have {table.shape[1]} columns, x y z needs 3")
    header = next((line for line in reversed(lines[:first]) if line.strip()), "")
    if header.strip().isdigit():  # a point count (PTS, some XYZ writers): checked both ways
        _check_point_count(int(header), table, lines, first, label)
    names = [name.strip('"\'').lower() for name in _FIELD_SEPARATORS.split(header.strip().lstrip("#/").strip())]
    warnings = []
    normals = None
    if names[3:6] in _NORMAL_HEADERS and table.shape[1] >= 6:
        lengths = np.linalg.norm(table[:, 3:6], axis=1)
        if np.all(np.abs(lengths[np.isfinite(lengths)] - 1) < _UNIT_NORMAL_TOLERANCE):
            normals = table[:, 3:6]
        else:
            warnings.append(f"{label}: columns 4-6 are named {', '.join(names[3:6])} but are not unit "
                            "vectors; they were not used as normals")
    return _Parsed(table[:, :3], normals, warnings=tuple(warnings))


# The longest line a text cloud may have: a point with a hundred scalar fields fits; a whole cloud
# written on one line (slow to read, gigabytes in memory) does not.
MAX_TEXT_LINE_CHARS = 10_000


def _check_point_count(declared: int, table: np.ndarray, lines: list[str], first: int, label: str) -> None:
    if len(table) < declared:
        raise _truncated(label, declared, "points", len(table))
    if len(table) > declared:
        numbers = [number for number, line in enumerate(lines[first:], first + 1)
                   if _INLINE_COMMENT.split(line, 1)[0].strip()]
        raise _trailing(label, f"line {numbers[declared]}", declared, "points")


def _is_point_line(line: str) -> bool:
    fields = [field for field in _FIELD_SEPARATORS.split(line.strip()) if field]
    if len(fields) < 3:
        return False
    try:
        [float(field) for field in fields]
    except ValueError:
        return False
    return True
