"""A mesh face with two corners at one point (a repeated index, or two vertices written at the same
place) made open3d's distance query abort the process (an Eigen assertion): inside FreeCAD that is
FreeCAD gone.  Such faces cover nothing, so they are dropped with a warning, as are vertices no face
uses."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from workcal_wb.core.geometry import Cloud
from workcal_wb.core.writers import write_ply

ROOT = Path(__file__).resolve().parents[2]
CORNERS = np.array([[x, y, z] for x in (0, 10) for y in (0, 10) for z in (0, 10)], float)
FACES = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
         (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]
QUERIES = [[5, 5, 2], [20, 5, 5], [5, -3, 5], [13, 14, 5]]


@pytest.mark.slow
def test_faces_folded_to_an_edge_or_a_point_are_dropped_with_a_warning_not_a_crash(tmp_path):
    points = np.vstack([CORNERS, CORNERS[1]])  # vertex 8 written where vertex 1 is
    faces = FACES + [(1, 1, 2), (1, 8, 2), (3, 3, 3)]
    write_ply(tmp_path / "box.ply", Cloud(points, triangles=np.array(faces), name="box.ply"))
    script = (f"import sys, json; sys.path.insert(0, {str(ROOT)!r})\n"
              "from workcal_wb.core.readers import read_cloud\n"
              "from workcal_wb.core.surface import SurfaceModel\n"
              f"model = SurfaceModel(read_cloud({str(tmp_path / 'box.ply')!r}))\n"
              f"closest, normals = model.closest_points(__import__('numpy').array({QUERIES}, float))\n"
              f"print(json.dumps([model.exact_distance(__import__('numpy').array({QUERIES}, float)).tolist(),"
              " closest.tolist(), normals.tolist(), len(model.triangles), model.warnings]))\n")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    distances, closest, normals, faces_kept, warnings = json.loads(done.stdout)
    assert np.allclose(distances, [2, 10, 3, 5], atol=1e-4)
    assert np.allclose(closest, [[5, 5, 0], [10, 5, 5], [5, 0, 5], [10, 10, 5]], atol=1e-4)
    assert np.allclose(np.array(normals)[:3], [[0, 0, -1], [1, 0, 0], [0, -1, 0]])  # the fourth is on an edge
    assert faces_kept == 12
    assert any("box.ply" in w and "3 faces" in w for w in warnings), warnings


def _run(script: str, timeout: float = 60) -> subprocess.CompletedProcess:
    """``script`` in a fresh interpreter with the box model built, so an abort is a return code."""
    head = (f"import sys, json; sys.path.insert(0, {str(ROOT)!r})\n"
            "import numpy as np\n"
            "from workcal_wb.core.geometry import Cloud\n"
            "from workcal_wb.core.surface import SurfaceModel\n"
            f"corners, faces = np.array({CORNERS.tolist()}), np.array({FACES})\n")
    return subprocess.run([sys.executable, "-c", head + script], capture_output=True, text=True, timeout=timeout)


@pytest.mark.slow
def test_a_query_point_that_is_not_finite_in_float32_gets_nan_not_a_crash():
    """open3d aborts on a NaN or infinite query point (the same Eigen assertion); 1e300 is infinite
    once held in float32.  A pose gone NaN would take FreeCAD down with it."""
    done = _run("model = SurfaceModel(Cloud(corners, triangles=faces, name='box'))\n"
                "q = np.array([[5, 5, 2], [np.nan, 0, 0], [1e300, 0, 0], [20, 5, 5], [0, -np.inf, 0]])\n"
                "closest, normals = model.closest_points(q)\n"
                "print(json.dumps([model.exact_distance(q).tolist(), closest.tolist(), normals.tolist()]))\n")
    assert done.returncode == 0, done.stderr[-2000:]
    distances, closest, normals = (np.array(a, float) for a in json.loads(done.stdout.replace("NaN", "null")))
    assert np.allclose(distances[[0, 3]], [2, 10], atol=1e-4)
    assert np.isnan(distances[[1, 2, 4]]).all()
    assert np.allclose(closest[[0, 3]], [[5, 5, 0], [10, 5, 5]], atol=1e-4)
    assert np.isnan(closest[[1, 2, 4]]).all() and np.isnan(normals[[1, 2, 4]]).all()
    assert np.allclose(normals[[0, 3]], [[0, 0, -1], [1, 0, 0]])


@pytest.mark.slow
def test_corners_a_float32_hair_apart_count_as_one_point():
    """Two corners 1e-40 mm apart about the vertices' mean are distinct float32 numbers (denormals),
    but the edge's squared length is 0 in float32: open3d aborted on that face as on a repeated corner."""
    done = _run("points = np.vstack([corners - 5, [[0, 0, 0], [1e-40, 0, 0], [0, 5, -5]]])\n"
                "model = SurfaceModel(Cloud(points, triangles=np.vstack([faces, [[8, 9, 10]]]), name='box'))\n"
                "print(json.dumps([model.exact_distance(np.array([[7.0, 0, 0], [0.1, 0.1, 0.1]])).tolist(), len(model.triangles),"
                " model.warnings]))\n")
    assert done.returncode == 0, done.stderr[-2000:]
    distances, faces_kept, warnings = json.loads(done.stdout)
    assert np.allclose(distances, [2, 4.9], atol=1e-4) and faces_kept == 12
    assert any("1 faces with two corners at one point" in w for w in warnings), warnings


@pytest.mark.slow
def test_repeated_faces_are_dropped_with_a_warning_not_sampled_without_bound():
    """Samples follow the faces' area: 500 copies of each face of a box asked for 62 million samples
    (minutes), a million faces on one edge for 10 billion (78 GB).  A copy covers nothing new."""
    repeated = np.vstack([FACES] * 500 + [np.array(FACES)[:, ::-1]])  # copies, and copies wound the other way
    done = _run(f"model = SurfaceModel(Cloud(corners, triangles=np.array({repeated.tolist()}), name='box.stl'))\n"
                "print(json.dumps([len(model.triangles), model.exact_distance(np.array([[5., 5, 2]])).tolist(),"
                " model.warnings]))\n", timeout=30)
    assert done.returncode == 0, done.stderr[-2000:]
    faces_kept, distance, warnings = json.loads(done.stdout)
    assert faces_kept == 12
    assert np.allclose(distance, [2], atol=1e-4)
    assert any("box.stl" in w and f"{len(repeated) - 12} faces repeating" in w for w in warnings), warnings


@pytest.mark.slow
def test_faces_folded_onto_each_other_are_sampled_within_a_budget(monkeypatch):
    """Layers of faces a hair apart are not copies, but ask for as many samples: the spacing grows to
    keep the samples within MAX_MESH_SAMPLES, the model says why, and distances stay exact."""
    from workcal_wb.core import surface

    monkeypatch.setattr(surface, "MAX_MESH_SAMPLES", 50_000)
    layers = 40
    points = np.vstack([CORNERS + [0, 0, 1e-3 * k] for k in range(layers)])
    faces = np.vstack([np.array(FACES) + 8 * k for k in range(layers)])
    model = surface.SurfaceModel(Cloud(points, triangles=faces, name="folded.stl"))
    assert len(model.points) <= 50_000 + len(faces)
    assert len(model.points) > 20_000  # the budget is used, not thrown away
    assert np.allclose(model.exact_distance(np.array([[5.0, 5, -2], [20, 5, 5]])), [2, 10], atol=1e-4)
    assert any("folded.stl" in w and "sampled more coarsely" in w for w in model.warnings), model.warnings


def test_a_mesh_whose_faces_all_cover_nothing_is_refused_naming_the_file(tmp_path):
    """With every face dropped the model was quietly its bare vertices (8 box corners) taken for a
    scanned surface: a mesh file with no usable face is an error."""
    import pytest

    from workcal_wb.core.errors import InputError
    from workcal_wb.core.readers import read_cloud
    from workcal_wb.core.surface import SurfaceModel

    path = tmp_path / "flat.off"
    path.write_text("OFF\n8 3 0\n" + "".join(f"{x:g} {y:g} {z:g}\n" for x, y, z in CORNERS)
                    + "3 0 0 1\n3 2 2 2\n3 1 3 1\n")
    with pytest.raises(InputError, match=r"flat.off: none of its 3 faces covers any area"):
        SurfaceModel(read_cloud(path))


@pytest.mark.slow
def test_vertices_no_face_uses_are_dropped_with_a_warning():
    """A stray vertex (a modeller's leftover) set a mesh model's size, so its sample spacing and the
    origin of its float32 distances, and its shape: a flat square with one passed as a solid."""
    from workcal_wb.core.errors import InputError
    from workcal_wb.core.surface import SurfaceModel

    square = np.array([[0, 0, 0], [100, 0, 0], [100, 100, 0], [0, 100, 0], [0, 0, 100]], float)
    with pytest.raises(InputError, match="square.stl: the model has its points on a plane"):
        SurfaceModel(Cloud(square, triangles=np.array([(0, 1, 2), (0, 2, 3)]), name="square.stl"))
    box = SurfaceModel(Cloud(CORNERS, triangles=np.array(FACES), name="box.ply"))
    faces = np.array(FACES)
    stray = SurfaceModel(Cloud(np.vstack([CORNERS[:4], [1e5, 0, 0], CORNERS[4:]]),
                               triangles=np.where(faces >= 4, faces + 1, faces), name="box.ply"))
    assert stray.diagonal == box.diagonal and stray.spacing == box.spacing
    np.testing.assert_array_equal(stray.points, box.points)
    np.testing.assert_array_equal(stray.exact_distance(np.array(QUERIES, float)),
                                  box.exact_distance(np.array(QUERIES, float)))
    assert any(w == "box.ply: ignored 1 vertex that no face uses" for w in stray.warnings), stray.warnings
