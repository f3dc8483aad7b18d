"""The peers of the whole-process benchmark, each a whole process as a user would run it on two files.

``python3 -m workcal_wb.core.benchmark.peers METHOD SCAN.ply MODEL.ply OUT.json`` reads both files,
finds the model's pose in the scan without an initial guess and writes ``{"matrix": U}`` (model ->
scan, mm).  Nothing is kept between runs: neither peer has a cache of prepared models.

* ``open3d``: Open3D's global-registration tutorial pipeline (stock.py), files read by Open3D.
* ``kiss``: KISS-Matcher (ICRA 2025) for the global pose, then small_gicp's point-to-plane ICP.  Both
  come from PyPI into PEERS_DIR (``make bench`` installs them there; never a runtime dependency),
  appended to sys.path so Debian's numpy stays the one imported.  KISS-Matcher works in the files'
  millimetres (it refuses voxels under a few units); its voxel is the stock pipeline's, its noise
  bounds not clamped to LiDAR's metre-scale defaults; the ICP's correspondences lie within the stock
  pipeline's ICP distance (0.4 voxel), on clouds thinned at voxel / 4.  The files
  (binary PLY as WorkCal writes them) are read with numpy: KISS-Matcher has no reader of its own.
"""
from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import numpy as np

PEERS_DIR = Path(__file__).resolve().parents[3] / "build" / "peers"
METHODS = ("open3d", "kiss")


def read_vertices(path) -> np.ndarray:
    """The vertices (x, y, z) of a binary little-endian PLY whose first element is the vertices."""
    data = Path(path).read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii")
    count = int(re.search(r"element vertex (\d+)", header).group(1))
    vertex_part = header.split("element vertex", 1)[1].split("element", 1)[0]
    types = {"double": "<f8", "float": "<f4"}
    fields = [(name, types[kind]) for kind, name in re.findall(r"property (\w+) (\w+)", vertex_part)]
    table = np.frombuffer(data, np.dtype(fields), count, end)
    return np.column_stack([table["x"], table["y"], table["z"]]).astype(np.float64)


def open3d_pose(scan_path, model_path) -> np.ndarray:
    import open3d as o3d

    from .stock import prepare_stock_model, stock_open3d

    scan = np.asarray(o3d.io.read_point_cloud(str(scan_path)).points)
    model = np.asarray(o3d.io.read_point_cloud(str(model_path)).points)
    diagonal = float(np.linalg.norm(model.max(axis=0) - model.min(axis=0)))
    return stock_open3d(scan, prepare_stock_model(model, diagonal))


def kiss_pose(scan_path, model_path) -> np.ndarray:
    sys.path.append(str(PEERS_DIR))
    import kiss_matcher
    import small_gicp

    from .stock import VOXELS_PER_DIAGONAL

    scan, model = read_vertices(scan_path), read_vertices(model_path)
    voxel = float(np.linalg.norm(model.max(axis=0) - model.min(axis=0))) / VOXELS_PER_DIAGONAL
    matcher = kiss_matcher.KISSMatcher(kiss_matcher.KISSMatcherConfig(voxel, enable_noise_bound_clamping=False))
    solution = matcher.estimate(model.astype(np.float32), scan.astype(np.float32))
    coarse = np.eye(4)
    coarse[:3, :3], coarse[:3, 3] = np.asarray(solution.rotation), np.asarray(solution.translation).ravel()
    fine = small_gicp.align(scan, model, coarse, registration_type="PLANE_ICP", downsampling_resolution=voxel / 4,
                            max_correspondence_distance=0.4 * voxel, max_iterations=100)
    return np.asarray(fine.T_target_source)


def main(argv) -> int:
    method, scan, model, out = argv
    pose = {"open3d": open3d_pose, "kiss": kiss_pose}[method](scan, model)
    Path(out).write_text(json.dumps({"matrix": pose.tolist()}))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
