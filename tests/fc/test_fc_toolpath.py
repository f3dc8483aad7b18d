"""FreeCAD layer under freecadcmd: read a Path Job, transform it, make a Path object and a Robot trajectory."""
import types

import numpy as np
import pytest

FreeCAD = pytest.importorskip("FreeCAD")

from workcal_wb.core import frames  # noqa: E402
from workcal_wb.core.errors import InputError  # noqa: E402
from workcal_wb.core.result import CalibrationResult  # noqa: E402
from workcal_wb.core.toolpath import ExportRefused, linearised, transformed  # noqa: E402
from workcal_wb.fc import toolpath as fctp  # noqa: E402
from workcal_wb.fc.placements import matrix_of  # noqa: E402
from workcal_wb.fc.toolpath_input import read_toolpath  # noqa: E402

TURNED = frames.rigid(frames.rot_z(30.0), (600.0, -50.0, 120.0))  # keeps the XY arcs of a Profile
TILTED = frames.from_euler_zyz(40.0, 20.0, -10.0, (800.0, 100.0, 50.0))


def job_modules():
    """PathJob and PathProfile in FreeCAD 1.x (CAM) or 0.20 (Path)."""
    try:
        import Path.Main.Job as PathJob
        import Path.Op.Profile as PathProfile
    except ImportError:
        from PathScripts import PathJob, PathProfile
    return PathJob, PathProfile


def calibration(W, status="ok"):
    return CalibrationResult(status, W, quality_gates=[{"name": "rms_mm", "value": 0.1, "limit": 0.3,
                                                        "passed": status == "ok", "unit": "mm"}])


@pytest.fixture(scope="module")
def job():
    doc = FreeCAD.newDocument("WorkCalToolpathTest")
    box = doc.addObject("Part::Box", "Box")
    box.Length, box.Width, box.Height = 50, 30, 10
    doc.recompute()
    PathJob, PathProfile = job_modules()
    job = PathJob.Create("Job", [box], None)
    controller = job.Tools.Group[0]
    controller.HorizFeed, controller.VertFeed = "600 mm/min", "300 mm/min"
    PathProfile.Create("Profile")
    doc.recompute()
    yield job
    FreeCAD.closeDocument(doc.Name)


def test_read_job_follows_its_commands_with_feeds_in_mm_per_min(job):
    tp = read_toolpath(job)
    commands = [c for op in job.Operations.Group for c in op.Path.Commands if c.Name in ("G0", "G1", "G2", "G3")]
    assert len(tp) == len(commands) > 10
    for move, command in zip(tp.moves, commands):
        for axis, value in zip("XYZ", move.end):
            if axis in command.Parameters:
                assert value == pytest.approx(command.Parameters[axis], abs=1e-6)
    assert {m.feed for m in tp.moves if m.kind == "linear"} >= {300.0, 600.0}
    assert any(m.is_arc for m in tp.moves)
    assert tp.header[0] == "Profile"


def path_object(path, name="calibrated"):
    """What read_toolpath needs of a document object holding ``path``."""
    return types.SimpleNamespace(Path=path, TypeId="Path::Feature", Label=name)


def test_path_object_round_trip_keeps_arcs(job):
    tp = read_toolpath(job)
    path, forced = fctp.calibrated_path(tp, calibration(TURNED))
    assert not forced
    again = read_toolpath(path_object(path))
    expected = transformed(tp, TURNED)
    assert [m.kind for m in again.moves] == [m.kind for m in expected.moves]
    for m, n in zip(again.moves, expected.moves):
        np.testing.assert_allclose(m.end, n.end, atol=1e-6)
        assert m.feed == pytest.approx(n.feed) if n.feed else m.feed is None
        if n.is_arc:
            np.testing.assert_allclose(m.centre, n.centre, atol=1e-6)


def test_path_object_of_a_tilted_w_matches_numpy_point_by_point(job):
    tp = read_toolpath(job)
    path, _ = fctp.calibrated_path(tp, calibration(TILTED))
    assert {c.Name for c in path.Commands if not c.Name.startswith("(")} <= {"G0", "G1"}
    again = read_toolpath(path_object(path))
    np.testing.assert_allclose(again.points(), frames.apply(TILTED, linearised(tp).points()), atol=1e-6)


def test_failed_calibration_is_refused_unless_forced(job):
    tp = read_toolpath(job)
    with pytest.raises(ExportRefused, match="status is 'failed'"):
        fctp.calibrated_path(tp, calibration(TURNED, "failed"))
    path, forced = fctp.calibrated_path(tp, calibration(TURNED, "failed"), force=True)
    assert forced and path.Commands[0].Name.startswith("(FORCED EXPORT")


def test_not_a_path_is_an_input_error(job):
    model = job.Model.Group[0]
    with pytest.raises(InputError, match="neither a Path/CAM Job"):
        read_toolpath(model)


@pytest.mark.skipif(not fctp.robot_available(), reason="FreeCAD's Robot workbench is not available")
def test_robot_trajectory_waypoints(job):
    doc = job.Document
    tp = read_toolpath(job)
    obj = fctp.make_robot_trajectory(doc, tp, calibration(TILTED), rapid_feed_mm_min=3000.0)
    waypoints = obj.Trajectory.Waypoints
    moves = linearised(tp).moves
    assert len(waypoints) == len(moves)
    expected_points = frames.apply(TILTED, np.array([m.end for m in moves]))
    for wp, move, p in zip(waypoints, moves, expected_points):
        pose = matrix_of(wp.Pos)
        np.testing.assert_allclose(pose[:3, 3], p, atol=1e-6)
        np.testing.assert_allclose(pose[:3, 2], -TILTED[:3, 2], atol=1e-9)  # tool Z along the approach
        assert wp.Type == "LIN"
        assert wp.Velocity == pytest.approx((move.feed or 3000.0) / 60.0)
    doc.removeObject(obj.Name)


def test_a_comment_command_never_becomes_a_move():
    """A Path comment whose text holds line breaks and G-code reads as one comment, and carries into
    the calibrated path as one; a move whose name holds a line break and another move (FreeCAD
    parses it into one command with a G parameter) is refused, naming the object and the line."""
    import Path

    commands = [Path.Command("G0", {"X": 0.0, "Y": 0.0, "Z": 20.0}),
                Path.Command("(label)\nG0 X0 Y0 Z-500\n;x)"),
                Path.Command("G1", {"X": 10.0, "Y": 0.0, "Z": 5.0, "F": 5.0})]
    tp = read_toolpath(path_object(Path.Path(commands)))
    np.testing.assert_allclose(tp.points(), [[0, 0, 20], [10, 0, 5]], atol=1e-9)
    assert "Z-500" in tp.comments[1] and "\n" not in tp.comments[1]
    moved, _ = fctp.calibrated_path(tp, calibration(TURNED))
    again = read_toolpath(path_object(moved))
    np.testing.assert_allclose(again.points(), frames.apply(TURNED, tp.points()), atol=1e-6)
    assert all("\n" not in c.Name for c in moved.Commands)

    bad = [commands[0], Path.Command("G1\nG0 Z-500", {"X": 1.0})]
    with pytest.raises(InputError, match=r"'injected': line 2: G1 and G0 are both in the motion group"):
        read_toolpath(path_object(Path.Path(bad), "injected"))


def test_a_recorded_export_names_its_robot_by_id_and_its_tool_by_six_numbers(job, tmp_path):
    """What a macro holds (the robot's id, the tool as X, Y, Z, A, B, C) becomes the robot and the 4x4 TCP the
    export checks the Job's program against; the program carries the configuration solved."""
    from workcal_wb.core.robots import load_robot
    from workcal_wb.core.toolpath import export

    options = fctp.robot_options(robot="kuka_kr16_2", tool=[0, 0, 150, 0, 0, 0], machine="robot")
    assert options["robot"] == load_robot("kuka_kr16_2") and options["machine"] == "robot"
    np.testing.assert_allclose(options["tool"], frames.rigid(None, (0.0, 0.0, 150.0)))
    out = tmp_path / "profile.src"
    exported = export(read_toolpath(job), calibration(TURNED), "krl", out, **options)
    assert exported.reach.reachable and "reach: checked for KUKA KR 16-2" in out.read_text()
    assert fctp.robot_options() == {}
