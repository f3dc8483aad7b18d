"""PCD: ascii, binary and binary_compressed (LZF) data; ``VIEWPOINT``."""
from __future__ import annotations

import struct

import numpy as np

from ..errors import InputError
from .common import (_MAX_HEADER_BYTES, _Parsed, _binary_tail, _check_binary_end, _floats, _line_of_token,
                     _points_and_normals, _trailing, _truncated, _viewpoint)

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
