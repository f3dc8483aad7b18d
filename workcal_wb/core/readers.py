"""Read scans and models (PLY, PCD, E57, XYZ-like text, STL, OBJ, OFF) into a checked ``Cloud`` in mm.

Where a scan file says where its scanner stood (PCD ``VIEWPOINT``, the pose of each E57 scan, a PLY
``comment viewpoint X Y Z`` line), the Cloud keeps it as ``sensors``.

A silently misread file would place the workpiece wrongly, so every problem with a file becomes an
``InputError`` that names the file and says what is wrong.  Point data is parsed with numpy in bulk;
Python loops only walk records whose length varies (mixed polygons, Cyberware ``range_grid``).
"""
from __future__ import annotations

import os
import re
import struct
import warnings
from functools import cached_property
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .errors import InputError
from .files import checked_input, read_bytes
from .geometry import Cloud, checked
from .units import extent_warnings, mm_per_unit

# Headers are small; searching further would only scan binary data of a file without one.
_MAX_HEADER_BYTES = 1 << 20
_COMMENT_PREFIXES = ("#", "//")
_INLINE_COMMENT = re.compile("#|//")
_UNIT_NORMAL_TOLERANCE = 1e-3


class _Parsed(NamedTuple):
    """What a format parser found, before unit scaling and checks."""

    points: np.ndarray
    normals: np.ndarray | None = None
    triangles: np.ndarray | None = None
    units: str | None = None  # the unit the file declares itself (PLY ``comment units``)
    warnings: tuple[str, ...] = ()
    sensors: np.ndarray | None = None  # scanner positions the file states (k x 3, the file's unit)
    sensor_of: np.ndarray | None = None  # which of them saw each point


def read_cloud(path, units: str | None = "mm", name: str | None = None, unit_option: str = "unit",
               max_points: int | None = None) -> Cloud:
    """Read a point cloud or mesh file into a checked ``Cloud`` in mm.

    ``units`` is the file's length unit; ``None`` uses the ``comment units`` line of a PLY written by
    WorkCal (mm when there is none).  ``name`` defaults to the file name.  ``unit_option`` is how the
    caller's user sets the unit (e.g. "--model-units"), named in a warning about a suspect size.
    ``max_points``: a binary PLY point cloud holding more points is read in chunks and thinned as it
    is read (``_thinned_ply``), so it is never in memory whole; a warning says so.
    """
    path = Path(path)
    parse = _PARSERS.get(path.suffix.lower())
    if parse is None:
        raise InputError(f"{path}: unknown file type {path.suffix or '(no extension)'!r}; "
                         f"WorkCal reads {', '.join(_PARSERS)}")
    scale = None if units is None else mm_per_unit(units)  # a bad unit is refused before reading
    label = str(path)
    if parse is _read_e57:  # pye57 reads the file itself; E57 coordinates are metres by the standard
        checked_input(path)
        parsed, units = _read_e57(path, label), "m"
        scale = mm_per_unit(units)
    else:
        parsed = _thinned_ply(path, label, max_points) if max_points and parse is _parse_ply else None
        if parsed is None:
            parsed = _parsed(parse, read_bytes(path), label)
    if scale is None:
        units = parsed.units or "mm"
        try:
            scale = mm_per_unit(units)
        except InputError as exc:
            raise InputError(f"{label}: the file declares {exc}") from None
    with np.errstate(over="ignore"):  # a value too large in mm becomes inf: refused or dropped by checked
        points = parsed.points if scale == 1 else parsed.points * scale  # (no copy of millions of points in mm)
    sensors = None if parsed.sensors is None else parsed.sensors * scale
    cloud = checked(Cloud(points, parsed.normals, parsed.triangles, path.name, list(parsed.warnings), sensors,
                          parsed.sensor_of))
    cloud.name = name or path.name
    cloud.warnings += extent_warnings(cloud.points, path.name, units, unit_option)
    return cloud


def _parsed(parse, data: bytes, label: str) -> _Parsed:
    try:
        return parse(data, label)
    except (ValueError, IndexError, struct.error, OverflowError) as exc:
        # Parsers report every problem they know of; this keeps an unforeseen one an InputError.
        raise InputError(f"{label}: cannot be read as a {label.rsplit('.', 1)[-1]} file ({exc})") from None


# --- shared steps ------------------------------------------------------------------------------

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


# --- PLY ----------------------------------------------------------------------------------------

_PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
              "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
              "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}
_PLY_BYTE_ORDERS = {"ascii": None, "binary_little_endian": "<", "binary_big_endian": ">"}
_STRUCT_CODES = {"i1": "b", "u1": "B", "i2": "h", "u2": "H", "i4": "i", "u4": "I", "f4": "f", "f8": "d"}
_PLY_FACE_LISTS = ("vertex_indices", "vertex_index")
_PLY_PLURALS = {"vertex": "vertices", "face": "faces"}


class _PlyProperty(NamedTuple):
    name: str
    type: str  # numpy code of the value, or of a list's items
    length_type: str | None = None  # numpy code of a list's length; None for a single value


class _PlyElement(NamedTuple):
    name: str
    count: int
    properties: list

    @property
    def noun(self) -> str:
        return _PLY_PLURALS.get(self.name, f"{self.name} elements")


class _PlyHeader(NamedTuple):
    byte_order: str | None  # None for ascii
    elements: list
    units: str | None
    body_start: int
    viewpoint: np.ndarray | None = None  # ``comment viewpoint X Y Z``: the scanner's position


def _parse_ply(data: bytes, label: str) -> _Parsed:
    header = _ply_header(data, label)
    elements = {element.name: element for element in header.elements}
    if "vertex" not in elements:
        raise InputError(f"{label}: the PLY header declares no vertex element")
    face = elements.get("face")
    face_list = face and next((p for p in face.properties
                               if p.name in _PLY_FACE_LISTS and p.length_type), None)
    wanted = {"vertex"} | ({"face"} if face_list else set())
    if header.byte_order is None:
        body = _AsciiPlyBody(data[header.body_start:], label)
    else:
        body = _BinaryPlyBody(data, header.byte_order, label)
    values, pos = {}, header.body_start if header.byte_order else 0
    for element in header.elements:  # all of them, also those not needed (range_grid): the end is checked
        element_values, pos = _ply_element(body, element, pos, element.name in wanted)
        if element.name in wanted:
            values[element.name] = element_values
    last = header.elements[-1]
    if header.byte_order:
        _check_binary_end(data, pos, label, last.count, last.noun)
    elif pos < body.end:
        line = data[:header.body_start].count(b"\n") + _line_of_token(data[header.body_start:], pos)
        raise _trailing(label, f"line {line}", last.count, last.noun)
    points, normals = _points_and_normals(values["vertex"], "xyz", ("nx", "ny", "nz"), label, "vertices")
    warnings: list[str] = []
    triangles = None
    if face_list and face.count:
        corners, lengths = values["face"][face_list.name]
        triangles = _fan_triangles(_integer_indices(corners, label), lengths, label, warnings)
    return _Parsed(points, normals, triangles, header.units, tuple(warnings),
                   None if header.viewpoint is None else header.viewpoint[None])


def _ply_header(data: bytes, label: str) -> _PlyHeader:
    if not re.match(rb"ply\r?\n", data):
        raise InputError(f"{label}: not a PLY file (it does not start with a 'ply' line)")
    end = re.search(rb"^end_header[ \t]*(?:\r?\n|\Z)", data[:_MAX_HEADER_BYTES], re.M)
    if end is None and len(data) > _MAX_HEADER_BYTES:
        raise InputError(f"{label}: the PLY header goes on past {_MAX_HEADER_BYTES:,} bytes without an end_header "
                         "line (a point cloud's header takes a few hundred)")
    if end is None:
        raise InputError(f"{label}: the PLY header has no end_header line")
    byte_order, units, elements, have_format, viewpoint = None, None, [], False, None
    for number, line in enumerate(data[:end.start()].decode("latin-1").splitlines()[1:], 2):
        words = line.split()
        if not words or words[0] in ("comment", "obj_info"):
            if words[:2] == ["comment", "units"] and len(words) == 3:
                units = words[2]
            if words[:2] == ["comment", "viewpoint"]:
                viewpoint = _viewpoint(words[2:], 3, f"{label}: PLY header line {number}: comment viewpoint")
            continue
        if words[0] == "format" and len(words) == 3 and words[1] in _PLY_BYTE_ORDERS:
            byte_order, have_format = _PLY_BYTE_ORDERS[words[1]], True
        elif words[0] == "element" and len(words) == 3 and words[2].isascii() and words[2].isdigit():
            elements.append(_PlyElement(words[1], int(words[2]), []))
        elif words[0] == "property" and elements:
            elements[-1].properties.append(_ply_property(words, number, line, label))
        else:
            raise InputError(f"{label}: PLY header line {number} is not valid or not supported: {line!r}")
    if not have_format:
        raise InputError(f"{label}: the PLY header has no 'format ascii|binary_little_endian|"
                         "binary_big_endian 1.0' line")
    if len({element.name for element in elements}) < len(elements):
        raise InputError(f"{label}: the PLY header declares an element twice")
    for element in elements:
        names = [p.name for p in element.properties]
        if len(set(names)) < len(names):
            raise InputError(f"{label}: the PLY element {element.name!r} repeats a property name")
    return _PlyHeader(byte_order, elements, units, end.end(), viewpoint)


def _ply_property(words: list[str], number: int, line: str, label: str) -> _PlyProperty:
    if len(words) == 3 and words[1] in _PLY_TYPES:
        return _PlyProperty(words[2], _PLY_TYPES[words[1]])
    if (len(words) == 5 and words[1] == "list" and words[3] in _PLY_TYPES
            and _PLY_TYPES.get(words[2], "f")[0] in "iu"):
        return _PlyProperty(words[4], _PLY_TYPES[words[3]], _PLY_TYPES[words[2]])
    raise InputError(f"{label}: PLY header line {number} has an unknown property type: {line!r}")


def _ply_element(body, element: _PlyElement, pos: int, keep: bool):
    """The element's values ({name: array}, a list as (items, lengths)) and where the next one starts.

    Records are fixed-size while no list changes length, so the first record's list lengths are
    tried for all records in one vectorised read (all-triangle faces, plain vertices); a
    record-by-record walk is the fallback (mixed polygons, Cyberware range_grid).
    """
    if element.count == 0:
        empty = np.zeros(0, dtype=np.int64)
        return {prop.name: empty if prop.length_type is None else (empty, empty)
                for prop in element.properties}, pos
    first_lengths = _walk_list_lengths(body, element, pos, 1)[0]
    fixed = body.fixed_records(element, pos, first_lengths, keep)
    if fixed is not None:
        return fixed
    lengths = _walk_list_lengths(body, element, pos, element.count)
    return body.gathered_records(element, pos, lengths, keep)


def _walk_list_lengths(body, element: _PlyElement, pos: int, count: int) -> np.ndarray:
    """(count, number of lists) list lengths, read record by record (the only way through them, but
    for ASCII records one per line)."""
    by_lines = body.line_list_lengths(element, pos, count)
    if by_lines is not None:
        return by_lines
    if not any(prop.length_type for prop in element.properties):  # fixed size: no walk needed
        size = sum(body.width(prop.type) for prop in element.properties)
        if size * count > body.end - pos:
            raise _truncated(body.label, element.count, element.noun, (body.end - pos) // size)
        return np.zeros((count, 0), dtype=np.int64)
    lengths = []  # grown record by record: a corrupt count must not allocate before the data ends
    try:
        while len(lengths) < count:
            record = []
            for prop in element.properties:
                if prop.length_type is None:
                    pos += body.width(prop.type)
                    continue
                record.append(body.length_at(pos, prop.length_type))
                pos += body.width(prop.length_type) + record[-1] * body.width(prop.type)
            if pos > body.end:
                break
            lengths.append(record)
    except (IndexError, struct.error):
        pass  # a list length lies beyond the end of the data
    if len(lengths) < count:
        raise _truncated(body.label, element.count, element.noun, len(lengths))
    return np.array(lengths, dtype=np.int64).reshape(count, -1)


def _record_offsets(body, element: _PlyElement, pos: int, lengths: np.ndarray):
    """Where each property of each record starts, given every record's list lengths.

    Returns ({name: offsets}, end); a list's offsets point at its first item.
    """
    within = np.zeros(len(lengths), dtype=np.int64)  # grows to each record's size
    relative = {}
    for prop, column in _with_list_columns(element):
        if column is not None:
            within += body.width(prop.length_type)
        relative[prop.name] = within.copy()
        within += body.width(prop.type) * (1 if column is None else lengths[:, column])
    starts = pos + np.cumsum(within) - within
    return {name: starts + offset for name, offset in relative.items()}, pos + int(within.sum())


def _with_list_columns(element: _PlyElement):
    """Each property with its column in the list-lengths array (None for a single value)."""
    column = 0
    for prop in element.properties:
        if prop.length_type is None:
            yield prop, None
        else:
            yield prop, column
            column += 1


def _ragged_positions(starts: np.ndarray, lengths: np.ndarray, step: int) -> np.ndarray:
    """Positions of every item of lists that start at ``starts`` with ``step`` between items."""
    within = np.arange(int(lengths.sum())) - np.repeat(np.cumsum(lengths) - lengths, lengths)
    return np.repeat(starts, lengths) + within * step


_WHITESPACE = np.zeros(256, bool)
_WHITESPACE[list(b" \t\n\r\x0b\x0c")] = True  # what bytes.split() splits on


class _AsciiPlyBody:
    """ASCII PLY data as one token stream (records may wrap lines, as rply allows).

    Tokens are located with numpy and a run of them is parsed as numbers at once (``numbers``); their
    text is split out only when one is not a number, to name it.  Where every record of an element
    with one list is one line, the usual layout, its list lengths are read from the lines' lengths
    at once instead of record by record (a Cyberware range_grid has 200k records).
    """

    def __init__(self, body: bytes, label: str):
        self.body, self.label = body, label
        self.raw = np.frombuffer(body, np.uint8)
        edges = np.diff(np.concatenate([[1], _WHITESPACE[self.raw], [1]]).astype(np.int8))
        self.starts, self.ends = np.flatnonzero(edges == -1), np.flatnonzero(edges == 1)  # each token's bytes
        self.end = len(self.starts)
        self._by_lines = {}

    @cached_property
    def tokens(self) -> list[bytes]:
        return self.body.split()

    @cached_property
    def _line_firsts(self) -> np.ndarray:
        """The index of each token that is the first on its line."""
        newlines = np.cumsum(self.raw == 10, dtype=np.int64)
        after_newline = newlines[self.starts[1:] - 1] > newlines[self.ends[:-1] - 1]
        return np.flatnonzero(np.r_[True, after_newline])

    def numbers(self, pos: int, end: int) -> np.ndarray | None:
        """Tokens ``pos`` to ``end`` as float64, parsed at once; None when one is not a number."""
        if end <= pos:
            return np.zeros(0)
        return _numbers(self.body[self.starts[pos]:self.ends[end - 1]], end - pos)

    @staticmethod
    def width(_type: str) -> int:
        return 1

    def length_at(self, pos: int, _type: str) -> int:
        token = self.tokens[pos]
        if not token.isdigit():
            raise InputError(f"{self.label}: list length {token.decode('latin-1')!r} is not a whole number")
        return int(token)

    def line_list_lengths(self, element, pos: int, count: int) -> np.ndarray | None:
        """(count, 1) list lengths of an element with one list whose ``count`` records from token ``pos``
        are one line each (each line as long as its list length, written plainly, says), or None
        when they are not: then the records are walked one by one."""
        key = (element.name, pos, count)
        if key not in self._by_lines:
            self._by_lines[key] = self._line_list_lengths(element, pos, count)
        return self._by_lines[key]

    def _line_list_lengths(self, element, pos: int, count: int) -> np.ndarray | None:
        columns = list(_with_list_columns(element))
        listed = [i for i, (_, column) in enumerate(columns) if column is not None]
        if len(listed) != 1 or count == 0:
            return None
        firsts = self._line_firsts
        k = int(np.searchsorted(firsts, pos))
        if k + count > len(firsts) or firsts[k] != pos:
            return None
        starts = firsts[k:k + count]
        lengths = np.append(firsts[k + 1:k + count], firsts[k + count] if k + count < len(firsts) else self.end)
        lengths -= starts + len(columns)
        at = starts + listed[0]
        short = lengths < 10
        if (lengths < 0).any() or not np.array_equal(self.raw[self.starts[at[short]]], 48 + lengths[short]) \
                or not (self.ends[at[short]] - self.starts[at[short]] == 1).all():
            return None
        for token, length in zip(at[~short].tolist(), lengths[~short].tolist()):
            if self.body[self.starts[token]:self.ends[token]] != str(length).encode():
                return None
        return lengths[:, None]

    def fixed_records(self, element, pos, first_lengths, keep):
        width = sum(1 if column is None else 1 + first_lengths[column]
                    for _, column in _with_list_columns(element))
        end = pos + element.count * width
        if end > self.end:
            return None
        if first_lengths.size:  # one length for all records?  The lines may tell without parsing them.
            by_lines = self.line_list_lengths(element, pos, element.count)
            if by_lines is not None and not (by_lines == first_lengths).all():
                return None
            if by_lines is not None and not keep:
                return None, end
        table = self.numbers(pos, end)
        table = (np.array(self.tokens[pos:end]) if table is None else table).reshape(element.count, width)
        values, column_start = {}, 0
        for prop, column in _with_list_columns(element):
            if column is None:
                if keep:
                    values[prop.name] = _floats(table[:, column_start], self.label, f"{element.name} data")
                column_start += 1
                continue
            length = first_lengths[column]
            if not np.all(_floats(table[:, column_start], self.label, "list lengths") == length):
                return None
            if keep:
                items = _floats(table[:, column_start + 1:column_start + 1 + length], self.label,
                                f"{element.name} data")
                values[prop.name] = (items.ravel(), np.full(element.count, length))
            column_start += 1 + length
        return (values if keep else None), end

    def gathered_records(self, element, pos, lengths, keep):
        offsets, end = _record_offsets(self, element, pos, lengths)
        if not keep:
            return None, end
        tokens = self.numbers(pos, end)
        tokens = np.array(self.tokens[pos:end]) if tokens is None else tokens
        values = {}
        for prop, column in _with_list_columns(element):
            where = offsets[prop.name] - pos
            if column is not None:
                where = _ragged_positions(where, lengths[:, column], 1)
            read = _floats(tokens[where], self.label, f"{element.name} data")
            values[prop.name] = read if column is None else (read, lengths[:, column])
        return values, end


class _BinaryPlyBody:
    """Binary PLY data, read with numpy structured dtypes when records have a fixed size."""

    def __init__(self, data: bytes, byte_order: str, label: str):
        self.data, self.byte_order, self.label, self.end = data, byte_order, label, len(data)

    @staticmethod
    def width(type_code: str) -> int:
        return int(type_code[1])

    @staticmethod
    def line_list_lengths(element, pos: int, count: int) -> None:
        return None  # binary records have no lines

    def length_at(self, pos: int, type_code: str) -> int:
        (value,) = struct.unpack_from(self.byte_order + _STRUCT_CODES[type_code], self.data, pos)
        if value < 0:
            raise InputError(f"{self.label}: negative list length {value} in the data")
        return value

    def fixed_records(self, element, pos, first_lengths, keep):
        fields = []
        for prop, column in _with_list_columns(element):
            if column is None:
                fields.append((prop.name, self.byte_order + prop.type))
            else:
                fields.append((f"{prop.name}#length", self.byte_order + prop.length_type))
                fields.append((prop.name, self.byte_order + prop.type, (int(first_lengths[column]),)))
        record = np.dtype(fields)
        end = pos + element.count * record.itemsize
        if end > self.end:
            return None
        table = np.frombuffer(self.data, record, element.count, pos)
        for prop, column in _with_list_columns(element):
            if column is not None and not np.all(table[f"{prop.name}#length"] == first_lengths[column]):
                return None
        if not keep:
            return None, end
        values = {}
        for prop, column in _with_list_columns(element):
            if column is None:
                values[prop.name] = table[prop.name]
            else:
                values[prop.name] = (table[prop.name].ravel(), np.full(element.count, first_lengths[column]))
        return values, end

    def gathered_records(self, element, pos, lengths, keep):
        offsets, end = _record_offsets(self, element, pos, lengths)
        if not keep:
            return None, end
        raw = np.frombuffer(self.data, np.uint8, end - pos, pos)
        values = {}
        for prop, column in _with_list_columns(element):
            starts = offsets[prop.name] - pos
            size = self.width(prop.type)
            if column is not None:
                starts = _ragged_positions(starts, lengths[:, column], size)
            read = raw[starts[:, None] + np.arange(size)].view(self.byte_order + prop.type).ravel()
            values[prop.name] = read if column is None else (read, lengths[:, column])
        return values, end


# --- PCD ----------------------------------------------------------------------------------------

_PCD_TYPES = {("F", "4"): "f4", ("F", "8"): "f8", ("I", "1"): "i1", ("I", "2"): "i2", ("I", "4"): "i4",
              ("I", "8"): "i8", ("U", "1"): "u1", ("U", "2"): "u2", ("U", "4"): "u4", ("U", "8"): "u8"}
_PCD_ENCODINGS = ("ascii", "binary", "binary_compressed")


def _parse_pcd(data: bytes, label: str) -> _Parsed:
    fields, count, encoding, start, viewpoint = _pcd_header(data, label)
    if encoding == "ascii":
        width = sum(size for _, _, size in fields)
        tokens = data[start:].split()
        if len(tokens) < count * width:
            raise _truncated(label, count, "points", len(tokens) // width)
        if len(tokens) > count * width:
            line = data[:start].count(b"\n") + _line_of_token(data[start:], count * width)
            raise _trailing(label, f"line {line}", count, "points")
        table = _floats(tokens[:count * width], label, "point data").reshape(count, width)
        offsets = np.cumsum([0] + [size for _, _, size in fields])
        columns = {name: table[:, offset:offset + size] for (name, _, size), offset in zip(fields, offsets)}
    else:
        record = np.dtype([(name, "<" + code, (size,)) for name, code, size in fields])
        if encoding == "binary":
            if len(data) - start < count * record.itemsize:
                raise _truncated(label, count, "points", (len(data) - start) // record.itemsize)
            _check_binary_end(data, start + count * record.itemsize, label, count, "points")
            table = np.frombuffer(data, record, count, start)
            columns = {name: table[name] for name, _, _ in fields}
        else:
            raw = _pcd_decompressed(data, start, count * record.itemsize, label)
            columns, offset = {}, 0
            for name, code, size in fields:  # compressed data is stored field by field
                columns[name] = np.frombuffer(raw, "<" + code, count * size, offset).reshape(count, size)
                offset += count * size * int(code[1])
    single = {name: values[:, 0] if values.shape[1] == 1 else values for name, values in columns.items()}
    points, normals = _points_and_normals(single, "xyz", ("normal_x", "normal_y", "normal_z"), label, "points")
    return _Parsed(points, normals, sensors=viewpoint)


def _pcd_header(data: bytes, label: str):
    """([(field name, numpy code, values per point)], points, encoding, offset of the data, the scanner's
    position as a 1 x 3 array or None).  ``VIEWPOINT tx ty tz qw qx qy qz`` gives the position; PCL writes
    ``0 0 0 1 0 0 0`` whether or not the scanner stood there, so that one says nothing."""
    entries, pos = {}, 0
    while "DATA" not in entries:
        newline = data.find(b"\n", pos)
        if newline < 0 or pos > _MAX_HEADER_BYTES:
            raise InputError(f"{label}: not a PCD file (no 'DATA' line in the header)")
        words = data[pos:newline].decode("latin-1").split()
        pos = newline + 1
        if words and not words[0].startswith("#"):
            entries[words[0].upper()] = words[1:]
    names = entries.get("FIELDS") or []
    sizes, types = entries.get("SIZE") or [], entries.get("TYPE") or []
    counts = entries.get("COUNT") or ["1"] * len(names)
    if not names or not len(names) == len(sizes) == len(types) == len(counts):
        raise InputError(f"{label}: the PCD header needs FIELDS, SIZE, TYPE (and COUNT) with one "
                         "entry per field")
    encoding = entries["DATA"][0].lower() if entries["DATA"] else ""
    if encoding not in _PCD_ENCODINGS:
        raise InputError(f"{label}: unsupported PCD DATA {encoding!r}; expected one of {', '.join(_PCD_ENCODINGS)}")
    try:
        fields = []
        for index, (name, size, kind, count) in enumerate(zip(names, sizes, types, counts)):
            unique = name if name not in {field[0] for field in fields} else f"{name}#{index}"  # "_" padding
            fields.append((unique, _PCD_TYPES[kind.upper(), size], int(count)))
        grid = (int(entries["WIDTH"][0]), int(entries["HEIGHT"][0])) if "WIDTH" in entries else None
        points = int(entries["POINTS"][0]) if "POINTS" in entries else grid[0] * grid[1]
    except (KeyError, IndexError, ValueError, TypeError):
        raise InputError(f"{label}: the PCD header has an invalid or missing SIZE/TYPE/COUNT/"
                         "POINTS/WIDTH/HEIGHT entry") from None
    if grid is not None and grid[0] * grid[1] != points:
        raise InputError(f"{label}: the PCD header declares POINTS {points} but WIDTH {grid[0]} x HEIGHT "
                         f"{grid[1]} = {grid[0] * grid[1]}")
    if points < 0 or any(count < 1 for _, _, count in fields):
        raise InputError(f"{label}: the PCD header declares a negative POINTS or a COUNT below 1")
    viewpoint = None
    if "VIEWPOINT" in entries:
        pose = _viewpoint(entries["VIEWPOINT"], 7, f"{label}: the PCD VIEWPOINT")
        if not np.array_equal(pose, [0, 0, 0, 1, 0, 0, 0]):
            viewpoint = pose[None, :3]
    return fields, points, encoding, pos, viewpoint


def _viewpoint(words: list, count: int, what: str) -> np.ndarray:
    """``count`` finite numbers from header words, or an error naming ``what``."""
    try:
        values = np.array([float(word) for word in words])
    except ValueError:
        values = np.zeros(0)
    if len(values) != count or not np.isfinite(values).all():
        raise InputError(f"{what} must be {count} finite numbers, found {' '.join(words)[:80]!r}")
    return values


# --- E57 ----------------------------------------------------------------------------------------

def _read_e57(path: Path, label: str) -> _Parsed:
    """Every scan of an E57 file in the file's common frame, each moved by its stored pose, with each
    scan's scanner position (the pose's translation) kept for the free-space test.  Points a scan marks
    invalid are dropped; each scan's point count is checked against its header."""
    try:
        import pye57
    except ImportError:
        from .errors import MissingDependency

        raise MissingDependency(f"{label}: E57 files are read with the Python package pye57, which is not installed; "
                                "install it with: python3 -m pip install pye57 (in FreeCAD: the Addon Manager "
                                "installs it with WorkCal, or see the README)") from None
    from .frames import from_quaternion_wxyz

    try:
        e57 = pye57.E57(str(path))
    except Exception as exc:  # libE57Format reports a broken file as its own exception types
        raise InputError(f"{label}: cannot be read as an E57 file ({exc})") from None
    points, sensors, sensor_of = [], [], []
    for index in range(e57.scan_count):
        try:
            header = e57.get_header(index)
            data = e57.read_scan_raw(index)
        except Exception as exc:
            raise InputError(f"{label}: scan {index} cannot be read ({exc})") from None
        if not all(f"cartesian{axis}" in data for axis in "XYZ"):
            raise InputError(f"{label}: scan {index} has no cartesian coordinates (cartesianX, Y, Z); WorkCal reads "
                             "E57 scans stored as x, y, z")
        xyz = np.column_stack([np.asarray(data[f"cartesian{axis}"], dtype=float) for axis in "XYZ"])
        if len(xyz) != header.point_count:
            raise _truncated(label, header.point_count, f"points in scan {index}", len(xyz))
        if "cartesianInvalidState" in data:
            xyz = xyz[np.asarray(data["cartesianInvalidState"]) == 0]
        pose = from_quaternion_wxyz(np.asarray(header.rotation, dtype=float), np.asarray(header.translation, float))
        points.append(xyz @ pose[:3, :3].T + pose[:3, 3])
        sensors.append(pose[:3, 3])
        sensor_of.append(np.full(len(xyz), index, dtype=np.int64))
    if not points:
        raise InputError(f"{label}: the E57 file holds no scans")
    return _Parsed(np.vstack(points), sensors=np.array(sensors), sensor_of=np.concatenate(sensor_of))


def _pcd_decompressed(data: bytes, start: int, expected: int, label: str) -> bytes:
    if len(data) < start + 8:
        raise InputError(f"{label}: the binary_compressed data ends before its size fields")
    compressed_size, raw_size = struct.unpack_from("<II", data, start)
    if raw_size != expected:
        raise InputError(f"{label}: the header declares {expected} bytes of point data, "
                         f"the compressed block holds {raw_size}")
    block = data[start + 8:start + 8 + compressed_size]
    if len(block) < compressed_size:
        raise InputError(f"{label}: compressed data ends after {len(block)} of {compressed_size} bytes")
    where = _binary_tail(data, start + 8 + compressed_size)
    if where:
        raise InputError(f"{label}: {where}: data continues after the compressed data; the file is corrupt")
    return _lzf_decompress(block, expected, label)


def _lzf_decompress(block: bytes, expected: int, label: str) -> bytes:
    """LZF (as written by PCL): literal runs and back-references into the output so far."""
    out = bytearray()
    pos = 0
    try:
        while pos < len(block):
            control = block[pos]
            pos += 1
            if control < 32:  # a run of control + 1 literal bytes
                if pos + control + 1 > len(block):
                    break
                out += block[pos:pos + control + 1]
                pos += control + 1
                continue
            length = (control >> 5) + 2
            if length == 9:  # a longer copy: its extra length follows
                length += block[pos]
                pos += 1
            distance = ((control & 0x1F) << 8) + block[pos] + 1
            pos += 1
            if distance > len(out):
                break
            source = out[len(out) - distance:len(out) - distance + length]
            out += (source * (length // len(source) + 1))[:length]  # an overlapping copy repeats
    except IndexError:  # the stream ends inside a back-reference
        pass
    if pos != len(block) or len(out) != expected:
        raise InputError(f"{label}: the binary_compressed (LZF) data is corrupt")
    return bytes(out)


# --- large scans: thinned while they are read -------------------------------------------------

# A scan with more points than this is thinned on reading by the commands (a few million points fix a
# pose as well as tens of millions, and memory stays bounded); thinning keeps at most half of it.
LARGE_SCAN_POINTS = 6_000_000
THIN_CHUNK = 1 << 20  # records read at a time
GRID_SAMPLE = 1 << 16  # the first finite points, whose spacing sizes the thinning grid
_KEY_BITS = 21  # voxel index bits per axis


def _thinned_ply(path: Path, label: str, max_points: int) -> _Parsed | None:
    """A binary PLY holding only vertices, more than ``max_points`` of them, read in chunks of
    THIN_CHUNK records and thinned as it is read: one point per voxel (the first in the file, a real
    measurement with its normal), the voxel doubled whenever more than max_points / 2 are kept, so
    memory stays bounded whatever the file holds.  Doubled voxels nest, so the points kept are those
    of the final grid over the whole file, whatever the chunk size.  None for any other file (read
    whole as usual).  The counts are checked both ways as for any PLY."""
    if checked_input(path).stat().st_size < max_points * 12:  # under max_points vertices of 3 floats
        return None
    with open(path, "rb") as fh:
        header = _ply_header(fh.read(_MAX_HEADER_BYTES), label)
        (vertex, *others) = header.elements
        names = [p.name for p in vertex.properties]
        if (header.byte_order is None or others or vertex.name != "vertex" or vertex.count <= max_points
                or any(p.length_type for p in vertex.properties) or not {"x", "y", "z"} <= set(names)):
            return None  # (the whole-file reader names what is missing or wrong)
        record = np.dtype([(p.name, header.byte_order + p.type) for p in vertex.properties])
        size = os.fstat(fh.fileno()).st_size
        end = header.body_start + vertex.count * record.itemsize
        if size < end:
            raise _truncated(label, vertex.count, "vertices", (size - header.body_start) // record.itemsize)
        fh.seek(end)
        if fh.read(3) not in (b"", b"\n", b"\r\n"):
            raise _trailing(label, f"byte {end} ({size - end} bytes more)", vertex.count, "vertices")
        fh.seek(header.body_start)
        columns = ["x", "y", "z"] + (["nx", "ny", "nz"] if {"nx", "ny", "nz"} <= set(names) else [])
        thinning = _Thinning(vertex.count, max_points // 2, len(columns))
        for start in range(0, vertex.count, THIN_CHUNK):
            chunk = np.fromfile(fh, record, min(THIN_CHUNK, vertex.count - start))
            values = np.empty((len(chunk), len(columns)))
            for k, name in enumerate(columns):  # one column at a time: no second copy of the chunk
                values[:, k] = chunk[name]
            del chunk
            thinning.add(values, start)
    values, kept = thinning.result()
    grid = thinning.grid
    warnings = [f"{label}: {vertex.count:,} points, more than the {max_points:,} read whole: thinned while "
                f"reading to {kept:,}, one point kept per voxel of "
                f"{grid.voxel if grid is not None else 0:.3g} (the file's units)"]
    if thinning.dropped:
        warnings.append(f"{label}: ignored {thinning.dropped} points with NaN or infinite coordinates")
    return _Parsed(values[:, :3], values[:, 3:] if values.shape[1] == 6 else None, None, header.units,
                   tuple(warnings), None if header.viewpoint is None else header.viewpoint[None])


class _Thinning:
    """The points kept so far (file order) and the sorted keys of their voxels: a chunk adds the first
    point of each voxel no earlier point reached; past ``target`` points the voxel doubles."""

    def __init__(self, total: int, target: int, width: int):
        self.total, self.target = total, target
        self.grid: _ThinningGrid | None = None
        self.parts = [(np.zeros((0, width)), np.zeros(0, np.int64))]  # (values, file index)
        self.count = 0  # points in parts
        self.seen = np.zeros(0, np.int64)  # sorted keys of the voxels kept
        self.dropped = 0  # non-finite points

    def add(self, values: np.ndarray, start: int) -> None:
        finite = np.isfinite(values[:, :3]).all(axis=1)  # a bad normal is for checked() to judge
        self.dropped += len(values) - int(finite.sum())
        values, index = values[finite], start + np.flatnonzero(finite)
        if self.grid is None:  # kept whole until GRID_SAMPLE finite points (or the file's end) size the grid
            self.parts.append((values, index))
            self.count += len(index)
            if self.count and self.count >= min(GRID_SAMPLE, self.total - self.dropped):
                values, index = self._joined()
                self.grid, self.count = _ThinningGrid(values[:GRID_SAMPLE, :3], self.total, self.target), 0
            else:
                return
        keys, first = np.unique(self.grid.keys(values[:, :3], index), return_index=True)
        new = ~_sorted_holds(self.seen, keys)
        first = np.sort(first[new])
        self.seen = np.insert(self.seen, np.searchsorted(self.seen, keys[new]), keys[new])
        self.parts.append((values[first], index[first]))
        self.count += len(first)
        if self.count > self.target:
            values, index = self._joined()
            while len(index) > self.target:  # a doubled voxel holds whole voxels of the last grid
                self.grid.voxel *= 2.0
                self.seen, first = np.unique(self.grid.keys(values[:, :3], index), return_index=True)
                first = np.sort(first)
                values, index = values[first], index[first]
            self.parts, self.count = [(values, index)], len(index)

    def _joined(self):
        values, index = (np.concatenate(column) for column in zip(*self.parts))
        self.parts = []
        return values, index

    def result(self) -> tuple[np.ndarray, int]:
        """The values kept (file order) and how many."""
        values, index = self._joined()
        return values, len(index)


def _sorted_holds(sorted_keys: np.ndarray, keys: np.ndarray) -> np.ndarray:
    """Which of ``keys`` are in ``sorted_keys`` (ascending)."""
    at = np.minimum(np.searchsorted(sorted_keys, keys), max(len(sorted_keys) - 1, 0))
    return sorted_keys[at] == keys if len(sorted_keys) else np.zeros(len(keys), bool)


class _ThinningGrid:
    """Voxels fixed to the sample's corner, sized so that a surface sampled like it keeps about
    ``target`` points of ``total`` (points on a surface thin as the square of the voxel)."""

    def __init__(self, points: np.ndarray, total: int, target: int):
        from .pointops import median_spacing

        self.corner = points.min(axis=0)
        self.voxel = max(median_spacing(points) * np.sqrt(total / target), 1e-9)

    def keys(self, points: np.ndarray, index: np.ndarray) -> np.ndarray:
        """Each point's voxel as one int64; a point beyond the grid's reach (a stray point far away)
        gets a key of its own (-1 - its file index), so it is always kept."""
        cells = np.floor((points - self.corner) / self.voxel) + (1 << (_KEY_BITS - 1))
        inside = ((cells >= 0) & (cells < 1 << _KEY_BITS)).all(axis=1)
        cells = np.where(inside[:, None], cells, 0).astype(np.int64)
        return np.where(inside, (cells[:, 0] << 2 * _KEY_BITS) | (cells[:, 1] << _KEY_BITS) | cells[:, 2], -1 - index)


# --- text point clouds --------------------------------------------------------------------------

_FIELD_SEPARATORS = re.compile(r"[\s,;]+")
_NORMAL_HEADERS = (["nx", "ny", "nz"], ["normal_x", "normal_y", "normal_z"], ["normalx", "normaly", "normalz"])


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


# --- meshes -------------------------------------------------------------------------------------

# The 50-byte triangle record of binary STL (the writer uses it too).
STL_RECORD = np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attribute", "<u2")])
_STL_FACET = re.compile(r"\bfacet\b")
_STL_VERTEX_KEYWORD = re.compile(r"\bvertex\b")
_STL_VERTEX = re.compile(r"\bvertex\s+(\S+)\s+(\S+)\s+(\S+)")


def _parse_stl(data: bytes, label: str) -> _Parsed:
    declared = struct.unpack_from("<I", data, 80)[0] if len(data) >= 84 else None
    size = None if declared is None else 84 + declared * STL_RECORD.itemsize
    ascii = data.lstrip()[:5].lower() == b"solid" and b"\0" not in data
    if size is not None and (len(data) == size or (len(data) > size and not ascii)):
        _check_binary_end(data, size, label, declared, "triangles")
        corners = np.frombuffer(data, STL_RECORD, declared, 84)["corners"].reshape(-1, 3)
    elif ascii:
        corners = _ascii_stl_corners(data, label)
    elif declared is not None:
        raise _truncated(label, declared, "triangles", (len(data) - 84) // STL_RECORD.itemsize)
    else:
        raise InputError(f"{label}: not an STL file (too short for binary STL, does not start with 'solid')")
    points, inverse = _merged_vertices(corners.astype(np.float64))
    return _Parsed(points, triangles=inverse.reshape(-1, 3))


def _ascii_stl_corners(data: bytes, label: str) -> np.ndarray:
    text = _text(data, label).lower()
    facets, closed = len(_STL_FACET.findall(text)), text.count("endfacet")
    if facets != closed:
        raise InputError(f"{label}: the ASCII STL ends inside a facet (after {closed} complete ones)")
    last = text.rfind("endsolid")
    if last < 0:
        raise InputError(f"{label}: the ASCII STL has no 'endsolid' line (the file is cut short after "
                         f"{closed} facets?)")
    after = text.find("\n", last)
    tail = text[after:] if after >= 0 else ""
    if tail.strip():
        line = text.count("\n", 0, after + len(tail) - len(tail.lstrip())) + 1
        raise InputError(f"{label}: line {line}: text after endsolid, the end of the last solid")
    corners = _STL_VERTEX.findall(text)
    if len(corners) != len(_STL_VERTEX_KEYWORD.findall(text)):
        raise InputError(f"{label}: a vertex line has fewer than three coordinates")
    if len(corners) != 3 * facets:
        raise InputError(f"{label}: {len(corners)} vertex lines for {facets} facets; every facet "
                         "needs exactly 3")
    return _floats(corners, label, "vertex lines").reshape(-1, 3)


def _merged_vertices(corners: np.ndarray):
    """Identical corners merged into one vertex (in first-seen order), so STL becomes an indexed mesh.

    Rows are compared as raw bytes, 2x faster than np.unique(axis=0); adding 0.0 first turns
    -0.0 into 0.0 so that equal coordinates have equal bytes.
    """
    corners = np.ascontiguousarray(corners + 0.0)
    rows = corners.view(np.dtype((np.void, 3 * corners.itemsize))).ravel()
    _, first, inverse = np.unique(rows, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return corners[first[order]], rank[inverse]


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


_PARSERS = {".ply": _parse_ply, ".pcd": _parse_pcd, ".e57": _read_e57, ".xyz": _parse_text_cloud, ".asc": _parse_text_cloud,
            ".pts": _parse_text_cloud, ".csv": _parse_text_cloud, ".txt": _parse_text_cloud,
            ".stl": _parse_stl, ".obj": _parse_obj, ".off": _parse_off}
