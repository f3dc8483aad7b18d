"""What the format readers share: the parsed result, text and number helpers, count errors."""
from __future__ import annotations

import re
import warnings
from typing import NamedTuple

import numpy as np

from ..errors import InputError

# Headers are small; searching further would only scan binary data of a file without one.
_MAX_HEADER_BYTES = 1 << 20
_COMMENT_PREFIXES = ("#", "//")
_INLINE_COMMENT = re.compile("#|//")


class _Parsed(NamedTuple):
    """What a format parser found, before unit scaling and checks."""

    points: np.ndarray
    normals: np.ndarray | None = None
    triangles: np.ndarray | None = None
    units: str | None = None  # the unit the file declares itself (PLY ``comment units``)
    warnings: tuple[str, ...] = ()
    sensors: np.ndarray | None = None  # scanner positions the file states (k x 3, the file's unit)
    sensor_of: np.ndarray | None = None  # which of them saw each point



def _text(data: bytes, label: str) -> str:
    """The file as text; binary data under a text extension is refused instead of misread."""
    if b"\0" in data:
        raise InputError(f"{label}: contains binary data where text was expected "
                         "(a binary file with the wrong extension?)")
    return data.decode("utf-8", errors="replace")


def _truncated(label: str, declared: int, noun: str, found: int) -> InputError:
    return InputError(f"{label}: header declares {declared} {noun}, data ends after {found}")


def _trailing(label: str, where: str, declared: int, noun: str) -> InputError:
    """Data after everything the header declares: a count that is too small, or a corrupt file."""
    return InputError(f"{label}: {where}: data continues after the {declared} {noun} the header declares; "
                      "the header's count is wrong or the file is corrupt")


def _binary_tail(data: bytes, end: int) -> str | None:
    """Where data continues after binary data that should end at ``end`` ("byte N (k bytes)"), or None.
    One line ending after the data (some writers add one) is not a record."""
    if data[end:] in (b"", b"\n", b"\r\n"):
        return None
    return f"byte {end} ({len(data) - end} bytes more)"


def _check_binary_end(data: bytes, end: int, label: str, declared: int, noun: str) -> None:
    where = _binary_tail(data, end)
    if where:
        raise _trailing(label, where, declared, noun)


def _numbers(text: bytes, count: int) -> np.ndarray | None:
    """The ``count`` whitespace-separated numbers of ``text`` parsed at once, or None when they are
    not that many numbers (some token is not one: the caller names it)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # numpy warns, and will raise, when a token is not a number
        try:
            values = np.fromstring(text, dtype=np.float64, sep=" ")
        except ValueError:
            return None
    return values if len(values) == count else None


def _line_of_token(text: bytes, index: int) -> int:
    """1-based line (within ``text``) of whitespace-separated token number ``index`` (error paths only)."""
    seen = 0
    for number, line in enumerate(text.split(b"\n"), 1):
        seen += len(line.split())
        if seen > index:
            return number
    return number


def _floats(tokens, label: str, what: str) -> np.ndarray:
    """Text tokens as float64 in one numpy conversion; the error names the first bad token."""
    tokens = np.asarray(tokens)
    try:
        return tokens.astype(np.float64)
    except ValueError:
        for token in tokens.ravel():
            try:
                float(token)
            except ValueError:
                shown = token.decode("latin-1") if isinstance(token, bytes) else token
                raise InputError(f"{label}: non-numeric value {shown!r} in the {what}") from None
        raise


def _numeric_table(lines: list[str], first_number: int, label: str, what: str,
                   delimiter: str | None = None) -> np.ndarray:
    """Consecutive lines of numbers (the first is line ``first_number`` of the file) as an
    (N, columns) float array; blank lines and # or // comments are skipped, errors say the line."""
    try:
        return np.loadtxt(lines, delimiter=delimiter, comments=_COMMENT_PREFIXES, ndmin=2, dtype=np.float64)
    except ValueError:
        pass
    columns = None
    for number, text in enumerate(lines, first_number):
        values = _INLINE_COMMENT.split(text, 1)[0]
        if not values.strip():
            continue
        fields = values.split(delimiter)
        try:
            [float(field) for field in fields]
        except ValueError:
            raise InputError(f"{label}: line {number}: non-numeric value in the {what}: "
                             f"{text.strip()[:80]!r}") from None
        if columns is not None and len(fields) != columns:
            raise InputError(f"{label}: line {number} has {len(fields)} values, "
                             f"the {what} before it have {columns}")
        columns = len(fields)
    raise InputError(f"{label}: the {what} cannot be read as a table of numbers")


def _integer_indices(values: np.ndarray, label: str) -> np.ndarray:
    """Vertex indices as int64; text formats give floats, which must be whole numbers."""
    whole = np.all(np.abs(values) < 2**62) and np.array_equal(values, np.round(values))  # NaN, inf, 1e20: not
    if values.dtype.kind == "f" and not whole:
        raise InputError(f"{label}: a face has a vertex index that is not a whole number")
    return values.astype(np.int64)


def _fan_triangles(corners: np.ndarray, lengths: np.ndarray, label: str,
                   warnings: list[str]) -> np.ndarray | None:
    """Fan-triangulate polygons given as concatenated corner indices and corners per polygon.

    Polygons with fewer than three corners are not surfaces; they are dropped with a warning.
    """
    lengths = np.asarray(lengths, dtype=np.int64)
    starts = np.cumsum(lengths) - lengths
    usable = lengths >= 3
    if not usable.all():
        warnings.append(f"{label}: ignored {int((~usable).sum())} faces with fewer than 3 corners")
    starts, lengths = starts[usable], lengths[usable]
    if len(lengths) == 0:
        return None
    per_polygon = lengths - 2
    polygon = np.repeat(np.arange(len(lengths)), per_polygon)
    step = np.arange(len(polygon)) - np.repeat(np.cumsum(per_polygon) - per_polygon, per_polygon) + 1
    first = starts[polygon]
    return corners[np.stack([first, first + step, first + step + 1], axis=1)]


def _points_and_normals(columns: dict, point_names, normal_names, label: str, owner: str):
    """(points, normals or None) from named per-point value arrays."""
    missing = [axis for axis in point_names if axis not in columns]
    if missing:
        raise InputError(f"{label}: the {owner} have no {', '.join(missing)} "
                         f"(found: {', '.join(columns) or 'nothing'})")
    for axis in (*point_names, *normal_names):
        if axis in columns and np.ndim(columns[axis]) != 1:
            raise InputError(f"{label}: {axis} must be one number per point")
    points = np.column_stack([columns[axis] for axis in point_names]).astype(np.float64)
    if all(axis in columns for axis in normal_names):
        return points, np.column_stack([columns[axis] for axis in normal_names]).astype(np.float64)
    return points, None


def _viewpoint(words: list, count: int, what: str) -> np.ndarray:
    """``count`` finite numbers from header words, or an error naming ``what``."""
    try:
        values = np.array([float(word) for word in words])
    except ValueError:
        values = np.zeros(0)
    if len(values) != count or not np.isfinite(values).all():
        raise InputError(f"{what} must be {count} finite numbers, found {' '.join(words)[:80]!r}")
    return values
