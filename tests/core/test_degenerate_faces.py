"""A mesh face with two corners at one point (a repeated index, or two vertices written at the same
place) made open3d's distance query abort the process (an Eigen assertion): inside FreeCAD that is
FreeCAD gone.  Such faces cover nothing, so they are dropped with a warning."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

from workcal_wb.core.geometry import Cloud
from workcal_wb.core.writers import write_ply

ROOT = Path(__file__).resolve().parents[2]
CORNERS = np.array([[x, y, z] for x in (0, 10) for y in (0, 10) for z in (0, 10)], float)
FACES = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
         (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]
QUERIES = [[5, 5, 2], [20, 5, 5], [5, -3, 5], [13, 14, 5]]


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
