"""PLY: ASCII and binary, any elements and list properties; ``comment units`` and ``comment viewpoint``."""
from __future__ import annotations

import re
import struct
from functools import cached_property
from typing import NamedTuple

import numpy as np

from ..errors import InputError
from .common import (_MAX_HEADER_BYTES, _Parsed, _check_binary_end, _fan_triangles, _floats,
                     _integer_indices, _line_of_token, _numbers, _points_and_normals, _trailing, _truncated,
                     _viewpoint)

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
