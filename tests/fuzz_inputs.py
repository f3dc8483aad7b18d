"""Hostile files for the fuzz tests (tests/core/test_fuzz.py) and the FreeCAD bad-input tests: a small valid
file of every format WorkCal reads, and seeded mutations of it (truncated, bytes flipped, inserted,
deleted or repeated, numbers and header counts replaced by absurd ones).

A mutation is plain data (see ``apply``): hypothesis draws and shrinks them in tests/core/test_fuzz.py,
``random_mutations`` draws a fixed sample from a seed for the FreeCAD tests.
"""
from __future__ import annotations

import io
import json
import re
import struct

import numpy as np

# A small closed mesh (an octahedron) and a point cloud with normals: every value exact in float32.
VERTICES = np.array([[10, 0, 0], [-10, 0, 0], [0, 10, 0], [0, -10, 0], [0, 0, 10], [0, 0, -10]], dtype=float)
FACES = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
POINTS = np.array([[x, y, 0.25 * x - 0.5 * y] for x in range(-4, 5) for y in range(-3, 4)], dtype=float)


def _ply_header(encoding: str, faces: bool) -> str:
    lines = ["ply", f"format {encoding} 1.0", "comment units mm", f"element vertex {len(VERTICES)}",
             "property float x", "property float y", "property float z"]
    if faces:
        lines += [f"element face {len(FACES)}", "property list uchar int vertex_indices"]
    return "\n".join(lines + ["end_header"]) + "\n"


def ply(encoding: str) -> bytes:
    header = _ply_header(encoding, True).encode()
    if encoding == "ascii":
        body = "".join(f"{x:g} {y:g} {z:g}\n" for x, y, z in VERTICES)
        body += "".join(f"3 {a} {b} {c}\n" for a, b, c in FACES)
        return header + body.encode()
    order = "<" if encoding == "binary_little_endian" else ">"
    body = VERTICES.astype(order + "f4").tobytes()
    body += b"".join(struct.pack(order + "B3i", 3, *face) for face in FACES)
    return header + body


def _pcd_header(encoding: str) -> bytes:
    n = len(POINTS)
    return (f"# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\n"
            f"VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {encoding}\n").encode()


def pcd(encoding: str) -> bytes:
    if encoding == "ascii":
        return _pcd_header(encoding) + "".join(f"{x:g} {y:g} {z:g}\n" for x, y, z in POINTS).encode()
    if encoding == "binary":
        return _pcd_header(encoding) + POINTS.astype("<f4").tobytes()
    raw = np.ascontiguousarray(POINTS.astype("<f4").T).tobytes()  # field by field
    block = b"".join(bytes([len(raw[i:i + 32]) - 1]) + raw[i:i + 32] for i in range(0, len(raw), 32))  # LZF literals
    return _pcd_header(encoding) + struct.pack("<II", len(block), len(raw)) + block


def stl(binary: bool) -> bytes:
    corners = VERTICES[FACES]
    if binary:
        records = b"".join(struct.pack("<12fH", 0, 0, 1, *c.ravel(), 0) for c in corners)
        return b"fuzz".ljust(80) + struct.pack("<I", len(corners)) + records
    facets = "".join("facet normal 0 0 1\n outer loop\n" + "".join(f"  vertex {x:g} {y:g} {z:g}\n" for x, y, z in c)
                     + " endloop\nendfacet\n" for c in corners)
    return f"solid fuzz\n{facets}endsolid fuzz\n".encode()


def obj() -> bytes:
    return ("# fuzz\no octahedron\n" + "".join(f"v {x:g} {y:g} {z:g}\n" for x, y, z in VERTICES)
            + "vn 0 0 1\n" + "".join(f"f {a + 1}//1 {b + 1}//1 {c + 1}//1\n" for a, b, c in FACES)).encode()


def off() -> bytes:
    return (f"OFF\n# fuzz\n{len(VERTICES)} {len(FACES)} 0\n" + "".join(f"{x:g} {y:g} {z:g}\n" for x, y, z in VERTICES)
            + "".join(f"3 {a} {b} {c}\n" for a, b, c in FACES)).encode()


def text_cloud(separator: str, header: str = "") -> bytes:
    return (header + "".join(separator.join(f"{v:g}" for v in p) + "\n" for p in POINTS)).encode()


def result_json() -> bytes:
    from workcal_wb.core import frames
    from workcal_wb.core.result import RIVAL, CalibrationResult, Candidate, MatchResult, Reason

    W = frames.rigid(frames.from_rotvec([0.1, 0.2, -0.3])[:3, :3], [800.0, 100.0, 50.0])
    match = MatchResult("ok", "robust", W, rms_mm=0.07, n_inliers=900, percentiles_mm={"50": 0.05},
                        candidates=[Candidate(W, score=1.0)], warnings=["a warning"],
                        ties=[Reason(RIVAL, "a rival")])
    result = CalibrationResult("ok", W, U=W, V=np.eye(4), workpiece=match, reference=match,
                               uncertainty={"toolpath_bound_mm": 0.03, "surface_bound_mm": 0.02, "method": "bootstrap"},
                               quality_gates=[{"name": "workpiece RMS", "value": 0.07, "limit": 0.3, "passed": True,
                                               "unit": "mm"}],
                               regions={"workpiece": np.arange(5), "reference": np.arange(5, 9), "source": "user"},
                               inputs={"scan": "scan.ply", "scan_points": 20}, reasons=[], warnings=[])
    return json.dumps(result.to_dict(), indent=1).encode()


def regions_npz() -> bytes:
    buffer = io.BytesIO()
    np.savez_compressed(buffer, workpiece=np.arange(5, dtype=np.int32), reference=np.arange(5, 9, dtype=np.int32))
    return buffer.getvalue()


GCODE = (b"(fuzz)\nG21 G90 G17\nG0 X0 Y0 Z10\nG1 Z0 F500\nG1 X20 Y0\nG2 X30 Y10 I0 J10\nG3 X20 Y20 R10\n"
         b"G91 G1 X-5 Y-5\nG90 G0 Z10\nM30\n")

# file name -> valid content; the extension picks the reader.
SEEDS = {
    "ascii.ply": ply("ascii"), "little.ply": ply("binary_little_endian"), "big.ply": ply("binary_big_endian"),
    "ascii.pcd": pcd("ascii"), "binary.pcd": pcd("binary"), "compressed.pcd": pcd("binary_compressed"),
    "cloud.xyz": text_cloud(" "), "cloud.csv": text_cloud(",", "x,y,z\n"), "cloud.pts": text_cloud(" ", f"{len(POINTS)}\n"),
    "ascii.stl": stl(False), "binary.stl": stl(True), "mesh.obj": obj(), "mesh.off": off(),
}
SPECIAL = [b"nan", b"inf", b"-inf", b"-1", b"0", b"1e308", b"-1e308", b"4294967295", b"99999999999999999999",
           b"1.5", b"", b"\x00", b"\xff\xfe", b"1e-320", b"+", b"."]
NUMBER = re.compile(rb"[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?")

# A mutation is a tuple (kind, where, *what): ``where`` in [0, 1] is a position as a fraction of the data
# (of the number tokens for "number"), so that one mutation means the same on any file.
KINDS = ("truncate", "flip", "insert", "delete", "repeat", "number")


def apply(data: bytes, mutations) -> bytes:
    for kind, where, *what in mutations:
        data = _APPLY[kind](data, where, *what)
    return data


def random_mutations(rng: np.random.Generator, count: int = 3) -> list:
    """Up to ``count`` mutations drawn with ``rng`` (the FreeCAD tests' fixed sample)."""
    out = []
    for _ in range(int(rng.integers(1, count + 1))):
        kind, where = KINDS[int(rng.integers(len(KINDS)))], float(rng.random())
        what = {"truncate": (), "flip": (int(rng.integers(256)),), "insert": (rng.bytes(int(rng.integers(1, 64))),),
                "delete": (int(rng.integers(1, 64)),), "repeat": (int(rng.integers(1, 200)), int(rng.integers(2, 5))),
                "number": (SPECIAL[int(rng.integers(len(SPECIAL)))],)}[kind]
        out.append((kind, where, *what))
    return out


def _at(data: bytes, where: float) -> int:
    return min(len(data), int(where * (len(data) + 1)))


def _truncate(data, where):
    return data[:_at(data, where)]


def _flip(data, where, value):
    at = min(_at(data, where), len(data) - 1)
    return data if not data else data[:at] + bytes([value]) + data[at + 1:]


def _insert(data, where, piece):
    at = _at(data, where)
    return data[:at] + piece + data[at:]


def _delete(data, where, length):
    at = _at(data, where)
    return data[:at] + data[at + length:]


def _repeat(data, where, length, times):
    at = _at(data, where)
    return data[:at] + data[at:at + length] * times + data[at:]


def _number(data, where, value):
    """A number token (a coordinate, an index, a header count) replaced by ``value``."""
    numbers = list(NUMBER.finditer(data))
    if not numbers:
        return data
    token = numbers[min(int(where * len(numbers)), len(numbers) - 1)]
    return data[:token.start()] + value + data[token.end():]


_APPLY = {"truncate": _truncate, "flip": _flip, "insert": _insert, "delete": _delete, "repeat": _repeat,
          "number": _number}
