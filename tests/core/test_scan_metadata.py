"""What a scan file tells about its scanner: PCD VIEWPOINT, a PLY 'comment viewpoint', the poses of the
scans of an E57 file (read with pye57, which `make test` installs)."""
import os
import sys

import numpy as np
import pytest

from workcal_wb.core import frames
from workcal_wb.core.errors import InputError, MissingDependency
from workcal_wb.core.readers import read_cloud

PCD = """# .PCD v0.7
VERSION 0.7
FIELDS x y z
SIZE 4 4 4
TYPE F F F
COUNT 1 1 1
WIDTH 4
HEIGHT 1
VIEWPOINT {viewpoint}
POINTS 4
DATA ascii
0 0 0
1 0 0
0 1 0
0 0 1
"""


def test_pcd_viewpoint_is_the_scanner_position(tmp_path):
    path = tmp_path / "scan.pcd"
    path.write_text(PCD.format(viewpoint="0.5 -2 3 1 0 0 0"))
    assert read_cloud(path, units="m").sensors.tolist() == [[500.0, -2000.0, 3000.0]]
    path.write_text(PCD.format(viewpoint="0 0 0 1 0 0 0"))  # what PCL writes when it knows nothing
    assert read_cloud(path).sensors is None
    path.write_text(PCD.format(viewpoint="1 2 x 1 0 0 0"))
    with pytest.raises(InputError, match="scan.pcd: the PCD VIEWPOINT must be 7 finite numbers"):
        read_cloud(path)


def test_ply_comment_viewpoint(tmp_path):
    path = tmp_path / "scan.ply"
    body = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
    header = "ply\nformat ascii 1.0\ncomment units m\ncomment viewpoint {}\nelement vertex 4\nproperty float x\n" \
             "property float y\nproperty float z\nend_header\n"
    path.write_text(header.format("1 2 3") + body)
    cloud = read_cloud(path, units=None)
    assert cloud.sensors.tolist() == [[1000.0, 2000.0, 3000.0]] and cloud.points.max() == 1000.0
    path.write_text(header.format("1 2") + body)
    with pytest.raises(InputError, match="PLY header line 4: comment viewpoint must be 3 finite numbers"):
        read_cloud(path)


def _pye57():
    if os.environ.get("WORKCAL_REQUIRE_PYE57"):  # make test installs it: its absence there is a failure
        import pye57
        return pye57
    return pytest.importorskip("pye57")


def test_e57_scans_are_brought_into_one_frame_with_their_scanner_positions(tmp_path):
    pye57 = _pye57()
    rng = np.random.default_rng(0)
    path = tmp_path / "two scans.e57"
    writer = pye57.E57(str(path), mode="w")
    expected, poses = [], [frames.rigid(frames.rot_z(25.0) @ frames.rot_x(10.0), (1.0, 2.0, 0.5)),
                           frames.rigid(frames.rot_y(-40.0), (-1.5, 0.2, 0.8))]
    for pose in poses:
        local = rng.uniform(-0.5, 0.5, (400, 3))
        writer.write_scan_raw({f"cartesian{a}": local[:, i] for i, a in enumerate("XYZ")},
                              rotation=frames.quaternion_wxyz(pose), translation=pose[:3, 3])
        expected.append(frames.apply(pose, local) * 1000.0)
    writer.close()
    cloud = read_cloud(path)  # E57 is in metres by the standard, whatever --units says
    np.testing.assert_allclose(cloud.sensors, [p[:3, 3] * 1000.0 for p in poses], atol=1e-6)
    assert np.bincount(cloud.sensor_of).tolist() == [400, 400]
    for k in range(2):
        np.testing.assert_allclose(np.sort(cloud.points[cloud.sensor_of == k], axis=0), np.sort(expected[k], axis=0),
                                   atol=1e-3)


def test_e57_without_pye57_names_what_to_install(tmp_path, monkeypatch):
    path = tmp_path / "scan.e57"
    path.write_bytes(b"ASTM-E57")
    monkeypatch.setitem(sys.modules, "pye57", None)
    with pytest.raises(MissingDependency, match="scan.e57: E57 files are read with the Python package pye57"):
        read_cloud(path)
