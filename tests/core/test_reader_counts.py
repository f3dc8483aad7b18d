"""Readers never drop data silently: counts are checked against the header both ways, and data after
what the header declares is an error naming the file and the line or byte where it starts."""
import struct

import numpy as np
import pytest
from test_readers import POINTS, TRIANGLES, lzf_literals, pcd_header, ply_bytes, write

from workcal_wb.core.errors import InputError
from workcal_wb.core.readers import read_cloud

XYZ = ["float x", "float y", "float z"]
FACES = ["list uchar int vertex_indices"]


def declared_fewer(encoding: str, declared: int, held: int) -> bytes:
    """A PLY whose header declares ``declared`` vertices while the data holds ``held``."""
    rows = [(float(i), float(i % 7), float(i % 5)) for i in range(held)]
    data = ply_bytes(encoding, [("vertex", XYZ, rows)])
    return data.replace(f"element vertex {held}".encode(), f"element vertex {declared}".encode(), 1)


@pytest.mark.parametrize("encoding", ["binary_little_endian", "binary_big_endian"])
def test_binary_ply_with_more_vertices_than_declared_names_the_byte(tmp_path, encoding):
    # The finding: half the scan was used and the calibration said "ok".
    data = declared_fewer(encoding, 500, 1000)
    body = data.index(b"end_header\n") + len(b"end_header\n")
    with pytest.raises(InputError) as error:
        read_cloud(write(tmp_path, "half.ply", data))
    text = str(error.value)
    assert "half.ply" in text and "500 vertices" in text and f"byte {body + 500 * 12}" in text, text


def test_ascii_ply_with_more_vertices_than_declared_names_the_line(tmp_path):
    data = declared_fewer("ascii", 500, 1000)
    first_data_line = data[:data.index(b"end_header")].count(b"\n") + 2
    with pytest.raises(InputError) as error:
        read_cloud(write(tmp_path, "half.ply", data))
    text = str(error.value)
    assert "half.ply" in text and "500 vertices" in text and f"line {first_data_line + 500}" in text, text


@pytest.mark.parametrize("encoding", ["ascii", "binary_little_endian", "binary_big_endian"])
def test_ply_with_data_after_the_faces_is_refused(tmp_path, encoding):
    data = ply_bytes(encoding, [("vertex", XYZ, POINTS), ("face", FACES, [(t,) for t in TRIANGLES])])
    extra = b"3 0 1 2\n" if encoding == "ascii" else struct.pack("<B3i", 3, 0, 1, 2)
    with pytest.raises(InputError, match=r"mesh.ply: .*2 faces"):
        read_cloud(write(tmp_path, "mesh.ply", data + extra))


@pytest.mark.parametrize("encoding", ["ascii", "binary_little_endian"])
def test_ply_trailing_data_after_an_element_that_is_not_read_is_refused(tmp_path, encoding):
    """Elements WorkCal does not use (Cyberware range_grid) are still walked to the end of the file."""
    grid = [([0],), ([],), ([1],)]
    data = ply_bytes(encoding, [("vertex", XYZ, POINTS), ("range_grid", FACES, grid)])
    assert len(read_cloud(write(tmp_path, "ok.ply", data))) == len(POINTS)
    extra = b"1 2\n" if encoding == "ascii" else struct.pack("<Bi", 1, 2)
    with pytest.raises(InputError, match=r"grid.ply: .*3 range_grid elements"):
        read_cloud(write(tmp_path, "grid.ply", data + extra))


def test_ply_declaring_an_element_twice_is_refused(tmp_path):
    """Found by the fuzz test: a second face element was read as the first one's (a KeyError)."""
    data = ply_bytes("binary_little_endian", [("vertex", XYZ, POINTS), ("face", FACES, [(t,) for t in TRIANGLES]),
                                              ("face", ["uchar flags"], [(1,), (2,)])])
    with pytest.raises(InputError, match="twice.ply: the PLY header declares an element twice"):
        read_cloud(write(tmp_path, "twice.ply", data))


def test_ply_line_ending_after_binary_data_is_accepted(tmp_path):
    """A newline some writers add after the binary data is not a record (shorter than one)."""
    data = ply_bytes("binary_little_endian", [("vertex", XYZ, POINTS)])
    assert len(read_cloud(write(tmp_path, "nl.ply", data + b"\n"))) == len(POINTS)


# --- PCD -------------------------------------------------------------------------------------

def pcd(encoding: str, declared: int, body: bytes, width=None, height=1) -> bytes:
    header = pcd_header("x y z", "4 4 4", "F F F", "1 1 1", width or declared, height, encoding)
    return header.replace(f"POINTS {(width or declared) * height}".encode(), f"POINTS {declared}".encode()) + body


def test_pcd_ascii_with_more_points_than_declared_names_the_line(tmp_path):
    body = b"".join(f"{i} 0 0\n".encode() for i in range(5))
    with pytest.raises(InputError, match=r"more.pcd: line 15: .*3 points"):
        read_cloud(write(tmp_path, "more.pcd", pcd("ascii", 3, body)))


def test_pcd_binary_with_more_points_than_declared_names_the_byte(tmp_path):
    data = pcd("binary", 3, np.arange(15, dtype="<f4").tobytes())
    start = data.index(b"DATA binary\n") + len(b"DATA binary\n")
    with pytest.raises(InputError, match=rf"more.pcd: byte {start + 36} .*3 points"):
        read_cloud(write(tmp_path, "more.pcd", data))


def test_pcd_binary_compressed_with_bytes_after_the_block_is_refused(tmp_path):
    raw = np.zeros(6, "<f4").tobytes()
    block = lzf_literals(raw)
    data = pcd("binary_compressed", 2, struct.pack("<II", len(block), len(raw)) + block + b"junk")
    with pytest.raises(InputError, match=r"more.pcd: byte \d+ .*after the compressed data"):
        read_cloud(write(tmp_path, "more.pcd", data))


def test_pcd_points_must_agree_with_width_times_height(tmp_path):
    data = pcd("ascii", 2, b"1 2 3\n4 5 6\n", width=3, height=1)
    with pytest.raises(InputError, match=r"wh.pcd: .*POINTS 2.*WIDTH 3 x HEIGHT 1"):
        read_cloud(write(tmp_path, "wh.pcd", data))


# --- STL, OBJ, OFF, text ---------------------------------------------------------------------

def test_binary_stl_with_bytes_after_the_declared_triangles_names_the_byte(tmp_path):
    record = struct.pack("<12fH", 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0)
    data = b"\0" * 80 + struct.pack("<I", 1) + record * 3
    with pytest.raises(InputError, match=r"three.stl: byte 134 .*1 triangles"):
        read_cloud(write(tmp_path, "three.stl", data))


def test_ascii_stl_with_text_after_endsolid_names_the_line(tmp_path):
    facet = "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n"
    text = f"solid a\n{facet}endsolid a\n0 1 2\n"
    with pytest.raises(InputError, match=r"tail.stl: line 10: .*after endsolid"):
        read_cloud(write(tmp_path, "tail.stl", text))


def test_off_with_lines_after_the_declared_faces_names_the_line(tmp_path):
    text = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 2 1 0\n"
    with pytest.raises(InputError, match=r"tail.off: line 7: .*1 faces"):
        read_cloud(write(tmp_path, "tail.off", text))


def test_obj_line_that_is_no_obj_statement_names_the_line(tmp_path):
    text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n0.5 0.5 0.5\n"
    with pytest.raises(InputError, match=r"junk.obj: line 5: .*not an OBJ statement"):
        read_cloud(write(tmp_path, "junk.obj", text))


def test_text_cloud_with_a_trailing_line_that_is_not_a_point_names_the_line(tmp_path):
    with pytest.raises(InputError, match=r"tail.xyz: line 3"):
        read_cloud(write(tmp_path, "tail.xyz", "1 2 3\n4 5 6\nend of scan\n"))


def test_pts_count_line_is_checked_both_ways(tmp_path):
    points = "".join(f"{i} 0 0 10 20 30 40\n" for i in range(4))
    assert len(read_cloud(write(tmp_path, "ok.pts", "4\n" + points))) == 4
    with pytest.raises(InputError, match=r"few.pts: header declares 6 points, data ends after 4"):
        read_cloud(write(tmp_path, "few.pts", "6\n" + points))
    with pytest.raises(InputError, match=r"many.pts: line 4: data continues after the 2 points"):
        read_cloud(write(tmp_path, "many.pts", "2\n" + points))


def test_a_scan_larger_than_the_limit_is_thinned_while_read(tmp_path):
    """A binary PLY scan with more points than ``max_points`` is read in chunks and thinned (one real
    point per voxel, with its normal), saying so; its counts are still checked both ways."""
    from workcal_wb.core import readers
    from workcal_wb.core.geometry import Cloud
    from workcal_wb.core.readers import thinning
    from workcal_wb.core.writers import write_ply

    rng = np.random.default_rng(3)
    u, v = rng.random((2, 60000)) * 100
    points = np.column_stack([u, v, 5 * np.sin(u / 10) + rng.normal(0, 0.05, len(u))])
    normals = np.tile([0.0, 0.0, 1.0], (len(u), 1))
    path = tmp_path / "dense.ply"
    write_ply(path, Cloud(points, normals))
    whole = readers.read_cloud(path)
    assert len(whole) == 60000 and not any("thinned" in w for w in whole.warnings)
    readers_chunk = thinning.THIN_CHUNK
    try:
        thinning.THIN_CHUNK = 7000  # several chunks, the grid coarsened on the way
        thinned = readers.read_cloud(path, max_points=10000)
    finally:
        thinning.THIN_CHUNK = readers_chunk
    assert 1000 < len(thinned) <= 5000
    assert any("60,000 points" in w and f"to {len(thinned):,}" in w for w in thinned.warnings)
    rows = {tuple(p) for p in points}
    assert all(tuple(p) in rows for p in thinned.points)  # real points, not averages
    assert np.array_equal(thinned.normals, np.tile([0.0, 0.0, 1.0], (len(thinned), 1)))
    # spread over the whole surface: every 10 x 10 mm cell of it keeps points
    cells = np.unique(np.floor(thinned.points[:, :2] / 10).astype(int), axis=0)
    assert len(cells) == 100
    data = path.read_bytes()
    (tmp_path / "cut.ply").write_bytes(data[:-240])
    with pytest.raises(InputError, match="declares 60000 vertices, data ends after 59995"):
        readers.read_cloud(tmp_path / "cut.ply", max_points=10000)
    (tmp_path / "long.ply").write_bytes(data + b"\0" * 48)
    with pytest.raises(InputError, match="data continues after the 60000 vertices"):
        readers.read_cloud(tmp_path / "long.ply", max_points=10000)
    # The scanner's position a PLY states survives the thinning, in mm as the points.
    (tmp_path / "seen.ply").write_bytes(data.replace(b"comment written by WorkCal", b"comment viewpoint 1 2 3", 1))
    seen = readers.read_cloud(tmp_path / "seen.ply", units="cm", max_points=10000)
    assert np.array_equal(seen.sensors, [[10.0, 20.0, 30.0]]) and len(seen) < 60000


def test_a_large_scan_whose_normals_are_nan_is_thinned_not_emptied(tmp_path):
    """Points with good coordinates but NaN normals are kept while thinning; the normals are dropped."""
    from workcal_wb.core import readers

    u, v = np.random.default_rng(4).random((2, 12000)) * 100
    rows = np.zeros(len(u), [(name, "<f4") for name in ("x", "y", "z", "nx", "ny", "nz")])
    rows["x"], rows["y"], rows["z"] = u, v, 5 * np.sin(u / 10)
    rows["nx"] = rows["ny"] = rows["nz"] = np.nan
    header = "ply\nformat binary_little_endian 1.0\nelement vertex 12000\n" + "".join(
        f"property float {name}\n" for name in rows.dtype.names) + "end_header\n"
    (tmp_path / "nan.ply").write_bytes(header.encode() + rows.tobytes())
    thinned = readers.read_cloud(tmp_path / "nan.ply", max_points=10000)
    assert 1000 < len(thinned) <= 5000 and thinned.normals is None
    assert any("points have NaN or infinite normals" in w for w in thinned.warnings), thinned.warnings
    assert not any("coordinates" in w for w in thinned.warnings), thinned.warnings


def test_thinning_while_reading_does_not_depend_on_the_chunk_size(tmp_path):
    """Read in chunks of a few hundred records or in one, a large scan thins to the very same points
    (the first of each voxel of one grid over the whole file), with non-finite points and a stray point
    far away, and each read says so.  (The grid was sized from the first chunk and grown by sqrt(2),
    so what was kept depended on how the file was cut.)"""
    from workcal_wb.core import readers
    from workcal_wb.core.geometry import Cloud
    from workcal_wb.core.readers import thinning

    rng = np.random.default_rng(5)
    u, v = rng.random((2, 40000)) * 80
    points = np.column_stack([u, v, 4 * np.cos(v / 9) + rng.normal(0, 0.05, len(u))])
    points[::997] = np.nan
    points[12345] = [5e4, 0.0, 0.0]  # beyond the grid's reach: kept as it is
    path = tmp_path / "scan.ply"
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(points)}\nproperty float x\n"
              "property float y\nproperty float z\nend_header\n").encode()
    path.write_bytes(header + points.astype("<f4").tobytes())
    reads = []
    for chunk in (333, 1 << 20):
        kept_chunk = thinning.THIN_CHUNK
        try:
            thinning.THIN_CHUNK = chunk
            reads.append(readers.read_cloud(path, max_points=8000))
        finally:
            thinning.THIN_CHUNK = kept_chunk
    small, whole = reads
    assert np.array_equal(small.points, whole.points) and small.warnings == whole.warnings
    assert 1000 < len(whole) <= 4000 and [5e4, 0.0, 0.0] in whole.points.tolist()
    assert any(f"40,000 points, more than the 8,000 read whole: thinned while reading to {len(whole):,}" in w
               for w in whole.warnings), whole.warnings
    assert any("ignored 41 points with NaN" in w for w in whole.warnings), whole.warnings
    assert np.isin(whole.points.astype("<f4").view("<V12"), points.astype("<f4").view("<V12")).all()
