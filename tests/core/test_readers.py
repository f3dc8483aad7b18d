"""Readers and writers: every format and encoding, written by hand here and read back exactly."""
import struct

import numpy as np
import pytest

from workcal_wb.core.errors import InputError
from workcal_wb.core.geometry import Cloud
from workcal_wb.core.readers import read_cloud
from workcal_wb.core.writers import write_ply, write_stl, write_xyz


def f32(values):
    """Values as a file with float32 fields holds them."""
    return np.asarray(values, dtype=np.float32).astype(np.float64)


# A quad (0.5 mm below plane at one corner) with unit normals; all values exact in float32.
POINTS = [(0.0, 0.0, 0.0), (1.5, 0.0, 0.0), (1.5, 2.25, 0.0), (0.0, 2.25, -0.5)]
NORMALS = [(0.0, 0.0, 1.0), (0.0, 0.0, 1.0), (0.0, 0.6, 0.8), (0.6, 0.0, -0.8)]
TRIANGLES = [(0, 1, 2), (0, 2, 3)]


def write(folder, name, content):
    path = folder / name
    path.write_bytes(content.encode() if isinstance(content, str) else content)
    return path


# --- PLY --------------------------------------------------------------------------------------

PLY_STRUCT = {"char": "b", "int8": "b", "uchar": "B", "uint8": "B", "short": "h", "int16": "h",
              "ushort": "H", "uint16": "H", "int": "i", "int32": "i", "uint": "I", "uint32": "I",
              "float": "f", "float32": "f", "double": "d", "float64": "d"}


def ply_bytes(encoding, elements, comments=("comment hand-made", "obj_info is_cyberware_data 1")):
    """A PLY file built value by value, independently of the reader.

    ``elements``: (name, properties, rows); a property is 'type name' or 'list count_type item_type
    name'; a row holds one value per scalar property and a sequence per list property.
    """
    header = ["ply", f"format {encoding} 1.0", *comments]
    for name, properties, rows in elements:
        header += [f"element {name} {len(rows)}"] + [f"property {p}" for p in properties]
    out = ("\n".join(header + ["end_header"]) + "\n").encode()
    order = {"binary_little_endian": "<", "binary_big_endian": ">"}.get(encoding)
    for _, properties, rows in elements:
        for row in rows:
            words = []
            for prop, value in zip(properties, row):
                kind = prop.split()
                if kind[0] == "list":
                    words += [len(value), *value]
                    if order:
                        out += struct.pack(order + PLY_STRUCT[kind[1]], len(value))
                        out += struct.pack(order + PLY_STRUCT[kind[2]] * len(value), *value)
                else:
                    words.append(value)
                    if order:
                        out += struct.pack(order + PLY_STRUCT[kind[0]], value)
            if not order:
                out += (" ".join(map(str, words)) + "\n").encode()
    return out


# Vertex properties in an odd order with extras; Cyberware-style list elements before and after.
VERTEX_PROPERTIES = ["float intensity", "double z", "float nx", "float x", "uchar confidence",
                     "float y", "float ny", "float nz"]
VERTEX_ROWS = [(0.25, p[2], n[0], p[0], 200, p[1], n[1], n[2]) for p, n in zip(POINTS, NORMALS)]
RANGE_GRID = ("range_grid", ["list uchar int vertex_indices"], [([0],), ([],), ([1, 2],)])
EDGES = ("edge", ["int vertex1", "int vertex2"], [(0, 1), (1, 2)])
MATERIAL = ("material", ["list uchar float shininess", "uchar red"], [([0.5, 0.25], 3), ([], 4)])
FACE_VARIANTS = {  # (face list property, polygons, expected triangles)
    "triangles": ("list uchar int vertex_indices", [[0, 1, 2], [0, 2, 3]], TRIANGLES),
    "mixed polygons": ("list uint8 uint32 vertex_index", [[0, 1, 2, 3], [1, 2, 3]],
                       [(0, 1, 2), (0, 2, 3), (1, 2, 3)]),
}
ENCODINGS = ["ascii", "binary_little_endian", "binary_big_endian"]


def scanner_ply(encoding, faces="triangles"):
    face_list, polygons, _ = FACE_VARIANTS[faces]
    face = ("face", ["uchar flags", face_list, "float quality"], [(1, p, 0.5) for p in polygons])
    return ply_bytes(encoding, [RANGE_GRID, ("vertex", VERTEX_PROPERTIES, VERTEX_ROWS), EDGES, face, MATERIAL])


@pytest.mark.parametrize("faces", FACE_VARIANTS)
@pytest.mark.parametrize("encoding", ENCODINGS)
def test_ply_with_extra_properties_and_elements(tmp_path, encoding, faces):
    cloud = read_cloud(write(tmp_path, "part.PLY", scanner_ply(encoding, faces)))
    np.testing.assert_array_equal(cloud.points, POINTS)
    np.testing.assert_array_equal(cloud.normals, NORMALS if encoding == "ascii" else f32(NORMALS))
    np.testing.assert_array_equal(cloud.triangles, FACE_VARIANTS[faces][2])
    assert cloud.name == "part.PLY" and cloud.warnings == []


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_ply_type_aliases_and_a_point_cloud_without_faces(tmp_path, encoding):
    rows = [(int(x * 2), y, -1, 7, z, 300, 1 << 20, 9) for x, y, z in POINTS]
    properties = ["int16 x", "float64 y", "int8 a", "uint8 b", "float32 z", "uint16 c", "uint32 d", "int32 e"]
    path = write(tmp_path, "aliases.ply", ply_bytes(encoding, [("vertex", properties, rows)]))
    cloud = read_cloud(path)
    np.testing.assert_array_equal(cloud.points, [(2 * x, y, z) for x, y, z in POINTS])
    assert cloud.normals is None and cloud.triangles is None


def test_ply_hand_written_ascii_with_crlf_and_a_record_wrapped_over_two_lines(tmp_path):
    text = ("ply\r\nformat ascii 1.0\r\nobj_info num_cols 512\r\nelement vertex 3\r\n"
            "property float x\r\nproperty float y\r\nproperty float z\r\nend_header\r\n"
            "1 2 3\r\n4 5\r\n6\r\n7 8 9 \r\n")
    cloud = read_cloud(write(tmp_path, "crlf.ply", text))
    np.testing.assert_array_equal(cloud.points, [(1, 2, 3), (4, 5, 6), (7, 8, 9)])


def test_ply_binary_faces_with_variable_lists_next_to_a_fixed_triangle_fast_path(tmp_path):
    """Many mixed polygons after many vertices: the record walk must agree with the vectorised read."""
    rng = np.random.default_rng(1)
    vertices = [tuple(row) for row in f32(rng.uniform(-50, 50, (500, 3)))]
    polygons = [list(rng.choice(500, size, replace=False)) for size in rng.integers(3, 7, 300)]
    data = ply_bytes("binary_big_endian", [("vertex", ["float x", "float y", "float z"], vertices),
                                           ("face", ["list uchar int vertex_indices"], [(p,) for p in polygons])])
    cloud = read_cloud(write(tmp_path, "mixed.ply", data))
    expected = [(p[0], p[k], p[k + 1]) for p in polygons for k in range(1, len(p) - 1)]
    np.testing.assert_array_equal(cloud.points, vertices)
    np.testing.assert_array_equal(cloud.triangles, expected)


# --- PCD --------------------------------------------------------------------------------------

def pcd_header(fields, sizes, types, counts, width, height, data):
    return (f"# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS {fields}\nSIZE {sizes}\n"
            f"TYPE {types}\nCOUNT {counts}\nWIDTH {width}\nHEIGHT {height}\nVIEWPOINT 0 0 0 1 0 0 0\n"
            f"POINTS {width * height}\nDATA {data}\n").encode()


def lzf_literals(raw):
    """An LZF stream of literal runs only (the simplest valid compressor output)."""
    return b"".join(bytes([len(raw[i:i + 32]) - 1]) + raw[i:i + 32] for i in range(0, len(raw), 32))


PCD_FIELDS = ("x y z normal_x normal_y normal_z rgb hist", "4 4 8 4 4 4 4 2", "F F F F F F U I", "1 1 1 1 1 1 1 3")
PCD_DTYPE = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f8"), ("normal", "<f4", 3), ("rgb", "<u4"),
                      ("hist", "<i2", 3)])


def pcd_records():
    records = np.zeros(len(POINTS), dtype=PCD_DTYPE)
    for axis, name in enumerate("xyz"):
        records[name] = [p[axis] for p in POINTS]
    records["normal"], records["rgb"], records["hist"] = NORMALS, 0xFF8000, (1, -2, 3)
    return records


def test_pcd_ascii(tmp_path):
    lines = "".join(f"{p[0]} {p[1]} {p[2]} {n[0]} {n[1]} {n[2]} 4286611584 1 -2 3\n" for p, n in zip(POINTS, NORMALS))
    cloud = read_cloud(write(tmp_path, "scan.pcd", pcd_header(*PCD_FIELDS, 4, 1, "ascii") + lines.encode()))
    np.testing.assert_array_equal(cloud.points, POINTS)
    np.testing.assert_array_equal(cloud.normals, NORMALS)


def test_pcd_binary(tmp_path):
    data = pcd_header(*PCD_FIELDS, 2, 2, "binary") + pcd_records().tobytes()
    cloud = read_cloud(write(tmp_path, "scan.pcd", data))
    np.testing.assert_array_equal(cloud.points, f32(POINTS))
    np.testing.assert_array_equal(cloud.normals, f32(NORMALS))


def test_pcd_binary_compressed_field_by_field(tmp_path):
    records = pcd_records()
    fields = [records["x"], records["y"], records["z"], *records["normal"].T, records["rgb"], records["hist"]]
    raw = b"".join(np.ascontiguousarray(field).tobytes() for field in fields)
    block = lzf_literals(raw)
    data = pcd_header(*PCD_FIELDS, 4, 1, "binary_compressed") + struct.pack("<II", len(block), len(raw)) + block
    cloud = read_cloud(write(tmp_path, "scan.pcd", data))
    np.testing.assert_array_equal(cloud.points, f32(POINTS))
    np.testing.assert_array_equal(cloud.normals, f32(NORMALS))


def test_pcd_lzf_back_references_short_long_and_overlapping(tmp_path):
    """Two points stored field by field: x = y = [1, 1], 20 padding zeros, z = [2, 3]."""
    one = struct.pack("<f", 1.0)
    block = (bytes([3]) + one               # literal 1.0
             + bytes([6 << 5, 3])           # copy 8 bytes from 4 back (overlaps what it writes)
             + bytes([2 << 5, 3])           # copy 4 bytes from 4 back
             + bytes([0, 0])                # literal zero byte
             + bytes([7 << 5, 19 - 9, 0])   # long form: copy 19 bytes from 1 back
             + bytes([7]) + struct.pack("<2f", 2.0, 3.0))
    header = pcd_header("x y _ z", "4 4 1 4", "F F U F", "1 1 10 1", 2, 1, "binary_compressed")
    data = header + struct.pack("<II", len(block), 44) + block
    cloud = read_cloud(write(tmp_path, "lzf.pcd", data))
    np.testing.assert_array_equal(cloud.points, [(1, 1, 2), (1, 1, 3)])


def test_pcd_written_by_open3d_binary_compressed(tmp_path):
    o3d = pytest.importorskip("open3d")
    grid = np.stack(np.meshgrid(np.arange(40.0), np.arange(30.0), [5.0]), -1).reshape(-1, 3)  # compresses well
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(grid))
    path = tmp_path / "grid.pcd"
    assert o3d.io.write_point_cloud(str(path), pcd, compressed=True)
    assert b"DATA binary_compressed" in path.read_bytes()
    np.testing.assert_array_equal(read_cloud(path).points, grid)


def test_pcd_organised_with_nan_drops_them_with_a_warning(tmp_path):
    rows = np.array([(0, 0, 1), (np.nan, np.nan, np.nan), (1, 0, 1), (1, 1, 1), (np.nan,) * 3, (0, 1, 1)], "<f4")
    data = pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 3, 2, "binary") + rows.tobytes()
    cloud = read_cloud(write(tmp_path, "organised.pcd", data))
    np.testing.assert_array_equal(cloud.points, rows[[0, 2, 3, 5]])
    assert any("2 points with NaN" in w for w in cloud.warnings)
    ascii_rows = "0 0 1\nnan nan nan\n1 0 1\n1 1 1\nnan nan nan\n0 1 1\n"
    data = pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 3, 2, "ascii") + ascii_rows.encode()
    assert len(read_cloud(write(tmp_path, "organised_ascii.pcd", data))) == 4


# --- text point clouds ------------------------------------------------------------------------

def rows_text(rows, separator=" "):
    return "".join(separator.join(str(v) for v in row) + "\n" for row in rows)


@pytest.mark.parametrize("name", ["scan.xyz", "scan.asc", "scan.txt"])
def test_text_whitespace_with_blank_and_comment_lines(tmp_path, name):
    text = "# exported\n\n" + rows_text(POINTS[:2], "\t") + "\n// note\n" + rows_text(POINTS[2:], "  ")
    cloud = read_cloud(write(tmp_path, name, text))
    np.testing.assert_array_equal(cloud.points, POINTS)
    assert cloud.normals is None


def test_pts_with_count_line_and_intensity_rgb(tmp_path):
    text = f"{len(POINTS)}\n" + rows_text([(*p, -1200, 255, 128, 0) for p in POINTS])
    cloud = read_cloud(write(tmp_path, "scan.pts", text))
    np.testing.assert_array_equal(cloud.points, POINTS)
    assert cloud.normals is None


@pytest.mark.parametrize("separator, header", [(",", "x,y,z,nx,ny,nz,intensity"),
                                               (";", "//X;Y;Z;Nx;Ny;Nz;Intensity"),
                                               (" ", "# x y z normal_x normal_y normal_z i")])
def test_csv_header_naming_normals_gives_normals(tmp_path, separator, header):
    text = header + "\n" + rows_text([(*p, *n, 7) for p, n in zip(POINTS, NORMALS)], separator)
    cloud = read_cloud(write(tmp_path, "scan.csv", text))
    np.testing.assert_array_equal(cloud.points, POINTS)
    np.testing.assert_array_equal(cloud.normals, NORMALS)


def test_text_columns_that_are_not_named_or_not_unit_are_no_normals(tmp_path):
    rows = [(*p, *n) for p, n in zip(POINTS, NORMALS)]
    assert read_cloud(write(tmp_path, "six.xyz", rows_text(rows))).normals is None
    rgb = [(*p, 255, 0, 0) for p in POINTS]
    cloud = read_cloud(write(tmp_path, "rgb.csv", "x,y,z,nx,ny,nz\n" + rows_text(rgb, ",")))
    assert cloud.normals is None and any("not unit vectors" in w for w in cloud.warnings)


@pytest.mark.parametrize("bad", [[1], [0, 1, 2, 3]])
def test_nan_normals_on_good_points_drop_the_normals_not_the_points(tmp_path, bad):
    normals = np.array(NORMALS)
    normals[bad] = np.nan
    rows = [(*p, *n) for p, n in zip(POINTS, normals)]
    cloud = read_cloud(write(tmp_path, "scan.xyz", "x y z nx ny nz\n" + rows_text(rows)))
    np.testing.assert_array_equal(cloud.points, POINTS)
    assert cloud.normals is None
    assert any(w.startswith("scan.xyz: ") and f"{len(bad)} points have NaN or infinite normals" in w
               for w in cloud.warnings), cloud.warnings


def test_nan_normals_of_nan_points_keep_the_other_normals(tmp_path):
    rows = [(*p, *n) for p, n in zip(POINTS, NORMALS)] + [(np.nan,) * 6]
    cloud = read_cloud(write(tmp_path, "scan.xyz", "x y z nx ny nz\n" + rows_text(rows)))
    np.testing.assert_array_equal(cloud.points, POINTS)
    np.testing.assert_array_equal(cloud.normals, NORMALS)
    assert not any("normals" in w for w in cloud.warnings), cloud.warnings


# --- meshes -----------------------------------------------------------------------------------

TETRA = np.array([(0, 0, 0), (10, 0, 0), (0, 10, 0), (0, 0, 10)], dtype=float)
TETRA_FACES = np.array([(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)])


def assert_same_surface(cloud, points, triangles):
    """Same triangles corner for corner (vertex numbering may differ), each vertex stored once."""
    np.testing.assert_array_equal(cloud.points[cloud.triangles], np.asarray(points)[np.asarray(triangles)])
    assert len(np.unique(cloud.points, axis=0)) == len(cloud.points)


def test_stl_ascii_merges_shared_corners(tmp_path):
    facets = "".join("facet normal 0 0 0\n  outer loop\n"
                     + "".join(f"    vertex {x:e} {y} {z}\n" for x, y, z in TETRA[face])
                     + "  endloop\nendfacet\n" for face in TETRA_FACES)
    facets = facets.replace("vertex 0.000000e+00 0.0 0.0", "VERTEX -0.0 0 0", 1)  # same vertex
    cloud = read_cloud(write(tmp_path, "tetra.stl", f"solid tetra\n{facets}endsolid tetra\n"))
    assert len(cloud.points) == 4 and len(cloud.triangles) == 4
    assert_same_surface(cloud, TETRA, TETRA_FACES)


def test_stl_binary_even_with_a_header_starting_with_solid(tmp_path):
    records = b"".join(struct.pack("<12fH", 0, 0, 0, *TETRA[face].ravel(), 0) for face in TETRA_FACES)
    data = b"solid but binary".ljust(80) + struct.pack("<I", 4) + records
    cloud = read_cloud(write(tmp_path, "tetra.STL", data))
    assert len(cloud.points) == 4
    assert_same_surface(cloud, TETRA, TETRA_FACES)


def test_obj_all_face_forms_negative_indices_and_polygons(tmp_path):
    text = """# a quad and more
mtllib part.mtl
o part
v 0 0 0
v 1.5 0 0
v 1.5 2.25 0 1.0
v 0 2.25 -0.5 0.2 0.3 0.4
vt 0 0
vn 0 0 1
g faces
f 1 2 3
f 1/1 3/1 4/1
f 1//1 2//1 3//1   # trailing comment
f 1/1/1 2/1/1 3/1/1 4/1/1
v 0 0 1
usemtl red
f -1 -5 -4
l 1 2
"""
    cloud = read_cloud(write(tmp_path, "part.obj", text))
    np.testing.assert_array_equal(cloud.points, POINTS + [(0, 0, 1)])
    # Each form gives the same faces (a wrong parse would add a face); the copies are dropped.
    np.testing.assert_array_equal(cloud.triangles, [(0, 1, 2), (0, 2, 3), (4, 0, 1)])
    assert cloud.warnings == ["part.obj: ignored 3 faces repeating an earlier face"]


def test_obj_without_faces_is_a_point_cloud(tmp_path):
    cloud = read_cloud(write(tmp_path, "points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"))
    assert cloud.triangles is None and len(cloud) == 3


def test_off_plain_with_comments_and_a_quad(tmp_path):
    text = "OFF\n# made by hand\n4 1 0\n" + rows_text(POINTS) + "\n4 0 1 2 3\n"
    cloud = read_cloud(write(tmp_path, "quad.off", text))
    np.testing.assert_array_equal(cloud.points, POINTS)
    np.testing.assert_array_equal(cloud.triangles, TRIANGLES)


def test_coff_counts_on_the_header_line_and_face_colours(tmp_path):
    text = "COFF 4 2 0\n" + rows_text([(*p, 255, 0, 0, 255) for p in POINTS]) + "3 0 1 2 255 0 0\n3 0 2 3 0 0 255\n"
    cloud = read_cloud(write(tmp_path, "quad.off", text))
    np.testing.assert_array_equal(cloud.points, POINTS)
    np.testing.assert_array_equal(cloud.triangles, TRIANGLES)


def test_noff_gives_normals(tmp_path):
    text = "NOFF\n4 2 0\n" + rows_text([(*p, *n) for p, n in zip(POINTS, NORMALS)]) + "3 0 1 2\n3 0 2 3\n"
    cloud = read_cloud(write(tmp_path, "quad.off", text))
    np.testing.assert_array_equal(cloud.normals, NORMALS)
    np.testing.assert_array_equal(cloud.triangles, TRIANGLES)


# --- writers and units ------------------------------------------------------------------------

def mesh_cloud():
    rng = np.random.default_rng(7)
    points = rng.uniform(-100, 100, (50, 3))
    normals = rng.normal(size=(50, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    return Cloud(points, normals, np.array([rng.choice(50, 3, replace=False) for _ in range(80)]), "part")


@pytest.mark.parametrize("binary", [True, False])
def test_ply_round_trip_is_exact_with_normals_and_faces(tmp_path, binary):
    cloud = mesh_cloud()
    write_ply(tmp_path / "out.ply", cloud, binary=binary)
    back = read_cloud(tmp_path / "out.ply")
    np.testing.assert_array_equal(back.points, cloud.points)
    np.testing.assert_array_equal(back.normals, cloud.normals)
    np.testing.assert_array_equal(back.triangles, cloud.triangles)
    assert b"comment units mm" in (tmp_path / "out.ply").read_bytes()


def test_ply_written_by_workcal_reads_in_open3d(tmp_path):
    o3d = pytest.importorskip("open3d")
    cloud = mesh_cloud()
    write_ply(tmp_path / "out.ply", cloud)
    mesh = o3d.io.read_triangle_mesh(str(tmp_path / "out.ply"))
    np.testing.assert_array_equal(np.asarray(mesh.vertices), cloud.points)
    np.testing.assert_array_equal(np.asarray(mesh.vertex_normals), cloud.normals)
    np.testing.assert_array_equal(np.asarray(mesh.triangles), cloud.triangles)


def test_ply_written_in_metres_is_read_back_by_its_units_comment(tmp_path):
    cloud = mesh_cloud()
    write_ply(tmp_path / "metres.ply", cloud, units="m")
    np.testing.assert_allclose(read_cloud(tmp_path / "metres.ply", units=None).points, cloud.points, rtol=1e-12)
    as_mm = read_cloud(tmp_path / "metres.ply")  # the caller's unit wins
    np.testing.assert_allclose(as_mm.points * 1000, cloud.points, rtol=1e-12)
    assert any("probably in metres" in w for w in as_mm.warnings)


def test_xyz_round_trip_with_and_without_normals(tmp_path):
    cloud = Cloud(mesh_cloud().points, mesh_cloud().normals, name="scan")
    write_xyz(tmp_path / "n.xyz", cloud)
    back = read_cloud(tmp_path / "n.xyz")
    np.testing.assert_array_equal(back.points, cloud.points)
    np.testing.assert_array_equal(back.normals, cloud.normals)
    write_xyz(tmp_path / "p.xyz", Cloud(cloud.points), units="in")
    back = read_cloud(tmp_path / "p.xyz", units="inch")
    assert back.normals is None
    np.testing.assert_allclose(back.points, cloud.points, rtol=1e-12)


def test_stl_round_trip(tmp_path):
    cloud = Cloud(TETRA, triangles=TETRA_FACES)
    write_stl(tmp_path / "tetra.stl", cloud)
    back = read_cloud(tmp_path / "tetra.stl")
    assert_same_surface(back, TETRA, TETRA_FACES)
    assert (tmp_path / "tetra.stl").stat().st_size == 84 + 50 * 4


@pytest.mark.parametrize("units, factor", [("m", 1000.0), ("cm", 10.0), ("in", 25.4), ("mm", 1.0)])
def test_units_scale_points_but_not_normals(tmp_path, units, factor):
    text = "x y z nx ny nz\n" + rows_text([(*p, *n) for p, n in zip(POINTS, NORMALS)])
    cloud = read_cloud(write(tmp_path, "scan.xyz", text), units=units, name="probe")
    np.testing.assert_allclose(cloud.points, np.array(POINTS) * factor)
    np.testing.assert_array_equal(cloud.normals, NORMALS)
    assert cloud.name == "probe"


@pytest.mark.parametrize("bad", [
    Cloud([(0, 0, 0), (np.nan, 0, 0), (1, 1, 1)], triangles=[(0, 1, 2)]),
    Cloud([(0, 0, 0), (1, 0, 0), (1, 1, 1)], normals=[(0, 0, 1), (0, 0, np.inf), (0, 0, 1)], triangles=[(0, 1, 2)]),
    Cloud([(0, 0, 0), (1, 0, 0), (1, 1, 1)], triangles=[(0, 1, 3)]),
    Cloud(np.zeros((0, 3))),
], ids=["nan point", "inf normal", "face index", "empty"])
@pytest.mark.parametrize("writer", [write_ply, write_xyz, write_stl])
def test_writers_refuse_invalid_clouds_and_leave_the_old_file(tmp_path, writer, bad):
    path = tmp_path / "old.out"
    path.write_text("previous")
    with pytest.raises(InputError, match="old.out"):
        writer(path, bad)
    assert path.read_text() == "previous" and [p.name for p in tmp_path.iterdir()] == ["old.out"]


def test_write_stl_needs_triangles(tmp_path):
    with pytest.raises(InputError, match="no triangles"):
        write_stl(tmp_path / "x.stl", Cloud(POINTS))


# --- bad input --------------------------------------------------------------------------------

VERTEX_HEADER = "ply\nformat {} 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n"


def binary_vertices(count, data_points):
    header = VERTEX_HEADER.format("binary_little_endian", count) + "end_header\n"
    return header.encode() + np.zeros((data_points, 3), "<f4").tobytes()


def pcd_xyz(encoding, declared, data):
    return pcd_header("x y z", "4 4 4", "F F F", "1 1 1", declared, 1, encoding) + data


BAD_FILES = {  # name: (file name, content, what the message must say)
    "empty": ("scan.ply", b"", "empty"),
    "unknown extension": ("scan.las", b"1 2 3\n", "WorkCal reads .ply, .pcd, .e57"),
    "not a ply": ("scan.ply", b"1 2 3\n", "not a PLY file"),
    "no end_header": ("scan.ply", VERTEX_HEADER.format("ascii", 1) + "1 2 3\n", "no end_header"),
    "no format": ("scan.ply", "ply\nelement vertex 1\nproperty float x\nend_header\n1\n", "no 'format"),
    "bad format": ("scan.ply", "ply\nformat binary 1.0\nend_header\n", "line 2"),
    "unknown type": ("scan.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float16 x\nend_header\n1\n",
                     "unknown property type"),
    "no vertex element": ("scan.ply", "ply\nformat ascii 1.0\nelement point 1\nproperty float x\nend_header\n1\n",
                          "no vertex element"),
    "no z": ("scan.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
             "end_header\n1 2\n", "no z"),
    "ascii truncated": ("scan.ply", VERTEX_HEADER.format("ascii", 40256) + "end_header\n"
                        + "1 2 3\n" * 1203 + "1 2\n", "header declares 40256 vertices, data ends after 1203"),
    "binary truncated": ("scan.ply", binary_vertices(10, 7) + b"\0\0",
                         "header declares 10 vertices, data ends after 7"),
    "faces truncated": ("scan.ply", ply_bytes("binary_little_endian", [
        ("vertex", ["float x", "float y", "float z"], POINTS),
        ("face", ["list uchar int vertex_indices"], [([0, 1, 2],), ([0, 2, 3],)])])[:-5],
        "header declares 2 faces, data ends after 1"),
    "ascii non-numeric": ("scan.ply", VERTEX_HEADER.format("ascii", 2) + "end_header\n1 2 3\n4 five 6\n",
                          "non-numeric value 'five'"),
    "face index out of range": ("scan.ply", ply_bytes("ascii", [
        ("vertex", ["float x", "float y", "float z"], POINTS),
        ("face", ["list uchar int vertex_indices"], [([0, 1, 4],)])]), "vertices that do not exist"),
    "zero points": ("scan.ply", VERTEX_HEADER.format("ascii", 0) + "end_header\n", "no points"),
    "binary with a text extension": ("scan.xyz", binary_vertices(3, 3), "binary data"),
    "binary ply as obj": ("scan.obj", binary_vertices(3, 3), "binary data"),
    "text non-numeric": ("scan.xyz", "1 2 3\n4 5 6\n7 eight 9\n", "line 3: non-numeric"),
    "text column count": ("scan.csv", "x,y,z\n1,2,3\n4,5,6\n7,8\n", "line 4 has 2 values"),
    "text empty field": ("scan.csv", "1,2,3\n4,,6\n", "line 2"),
    "text without points": ("scan.pts", "40097\nhello world\n", "no line with at least three numbers"),
    "pcd no data line": ("scan.pcd", "VERSION 0.7\nFIELDS x y z\n", "no 'DATA' line"),
    "pcd unsupported data": ("scan.pcd", pcd_xyz("binary_zipped", 1, b""), "unsupported PCD DATA"),
    "pcd field mismatch": ("scan.pcd", pcd_header("x y z", "4 4", "F F F", "1 1 1", 1, 1, "ascii") + b"1 2 3\n",
                           "one entry per field"),
    "pcd binary truncated": ("scan.pcd", pcd_xyz("binary", 10, bytes(12 * 4)),
                             "header declares 10 points, data ends after 4"),
    "pcd ascii truncated": ("scan.pcd", pcd_xyz("ascii", 3, b"1 2 3\n4 5 6\n"),
                            "header declares 3 points, data ends after 2"),
    "pcd corrupt lzf": ("scan.pcd", pcd_xyz("binary_compressed", 1, struct.pack("<II", 3, 12) + b"\x40\x00\x00"),
                        "corrupt"),
    "pcd lzf size": ("scan.pcd", pcd_xyz("binary_compressed", 2, struct.pack("<II", 13, 12) + lzf_literals(bytes(12))),
                     "the compressed block holds 12"),
    "stl binary truncated": ("scan.stl", b"\0" * 80 + struct.pack("<I", 5) + bytes(50 * 3 + 20),
                             "header declares 5 triangles, data ends after 3"),
    "stl ascii cut in a facet": ("scan.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n",
                                 "ends inside a facet"),
    "stl too short": ("scan.stl", b"abc", "not an STL file"),
    "obj index zero": ("scan.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "vertex 0"),
    "obj index too large": ("scan.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "line 4: 'f' refers to vertex 4, and the file has 3 vertices in all"),
    "obj short vertex": ("scan.obj", "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n", "fewer than three coordinates"),
    "obj nan vertex": ("scan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "NaN or infinite"),
    "off not off": ("scan.off", "PLY\n1 2 3\n", "not an OFF file"),
    "off 4d": ("scan.off", "4OFF\n1 0 0\n1 2 3 4\n", "not supported"),
    "off faces truncated": ("scan.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
                            "header declares 2 faces, data ends after 1"),
    "off bad face": ("scan.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n", "declares 3 corners, lists 2"),
}


@pytest.mark.parametrize("case", BAD_FILES)
def test_bad_input_is_an_input_error_naming_the_file(tmp_path, case):
    name, content, expected = BAD_FILES[case]
    path = write(tmp_path, name, content)
    with pytest.raises(InputError) as error:
        read_cloud(path)
    assert name in str(error.value) and expected in str(error.value)


def test_missing_file_folder_and_bad_unit(tmp_path):
    with pytest.raises(InputError, match="nothing.ply: file does not exist"):
        read_cloud(tmp_path / "nothing.ply")
    (tmp_path / "folder.ply").mkdir()
    with pytest.raises(InputError, match="folder.ply: is a folder"):
        read_cloud(tmp_path / "folder.ply")
    with pytest.raises(InputError, match="unknown length unit"):
        read_cloud(write(tmp_path, "a.xyz", "1 2 3\n"), units="furlong")
    path = write(tmp_path, "declared.ply", VERTEX_HEADER.format("ascii", 1).replace(
        "element", "comment units furlong\nelement") + "end_header\n1 2 3\n")
    with pytest.raises(InputError, match="declared.ply: the file declares unknown length unit"):
        read_cloud(path, units=None)


# --- real scanner data ------------------------------------------------------------------------

def test_bunny_scan_and_mesh_match_open3d(bunny):
    o3d = pytest.importorskip("open3d")
    scan = read_cloud(bunny / "bun045.ply", units="m")
    assert len(scan) == 40097 and scan.triangles is None and scan.warnings == []
    reference = np.asarray(o3d.io.read_point_cloud(str(bunny / "bun045.ply")).points) * 1000
    np.testing.assert_array_equal(scan.points, reference)

    model = read_cloud(bunny / "bun_zipper.ply", units="m")
    assert model.points.shape == (35947, 3) and model.triangles.shape == (69451, 3)
    mesh = o3d.io.read_triangle_mesh(str(bunny / "bun_zipper.ply"))
    np.testing.assert_array_equal(model.points, np.asarray(mesh.vertices) * 1000)
    np.testing.assert_array_equal(model.triangles, np.asarray(mesh.triangles))
    assert 150 < np.ptp(model.points, axis=0).max() < 160  # "about 155 x 154 x 121 mm"


def test_bunny_read_as_mm_warns_about_the_unit(bunny):
    cloud = read_cloud(bunny / "bun045.ply")
    assert any("probably in metres" in w and "bun045.ply" in w for w in cloud.warnings)


def test_a_cloud_written_on_one_line_is_refused_naming_the_line(tmp_path):
    """An XYZ file whose points are all on one line (90,000 numbers; the finding: 27 million, 23 s and
    1.4 GB before "only 1 usable points") is refused from the line's length, naming the file and line."""
    path = tmp_path / "one_line.xyz"
    path.write_text("# x y z\n" + " ".join(["1.5", "2.5", "3.5"] * 30_000) + "\n")
    with pytest.raises(InputError, match=r"one_line.xyz: line 2 is 359,999 characters long \(at most 10,000\)"):
        read_cloud(path)


def test_a_ply_header_of_200000_properties_is_said_to_be_too_long(tmp_path):
    path = tmp_path / "wide.ply"
    properties = "".join(f"property float p{i}\n" for i in range(200_000))
    path.write_text(f"ply\nformat ascii 1.0\nelement vertex 1\n{properties}end_header\n" + "0 " * 200_000 + "\n")
    with pytest.raises(InputError, match=r"wide.ply: the PLY header goes on past 1,048,576 bytes without an "
                                         r"end_header line"):
        read_cloud(path)


@pytest.mark.parametrize("face, message", [
    ("f 1 2 9", r"line 5: 'f' refers to vertex 9, and the file has 3 vertices in all"),
    ("f 1 2 -4", r"line 5: 'f' refers to vertex -4, and the file has 3 vertices before that line"),
    ("f 1 2 0", r"line 5: 'f' refers to vertex 0; OBJ vertices count from 1"),
    ("f 1 2 x/1", r"line 5: 'f' refers to vertex 'x', not a whole number"),
])
def test_an_obj_face_that_refers_to_no_vertex_names_the_file_and_line(tmp_path, face, message):
    path = tmp_path / "part.obj"
    path.write_text(f"# a triangle\nv 0 0 0\nv 1 0 0\nv 0 1 0\n{face}\n")
    with pytest.raises(InputError, match=rf"part.obj: {message}"):
        read_cloud(path)
