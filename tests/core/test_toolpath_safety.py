"""Refusals: failed calibrations, NaN, the work envelope; atomic writing; the FORCED banner."""
import math
import os
import re

import numpy as np
import pytest

from workcal_wb.core import frames
from workcal_wb.core.errors import InputError
from workcal_wb.core.result import CalibrationResult
from workcal_wb.core.toolpath import (CalibrationNotOk, Envelope, ExportRefused, FORMATS, Move, ToolTilted, Toolpath, export,
                                      parse_gcode)
from workcal_wb.core.toolpath.safety import number

W = frames.rigid(frames.rot_z(90.0), (1000.0, 0.0, 500.0))
SOURCE = "G0 X10 Y0 Z20\nG1 Z0 F300\nG3 X-10 Y0 I-10 J0 F600 (half circle through X0 Y10)\nG0 Z20\n"


def calibration(status="ok", matrix=W):
    gates = [{"name": "rms_mm", "value": 0.8, "limit": 0.3, "passed": status == "ok", "unit": "mm"},
             {"name": "coverage", "value": 0.9, "limit": 0.5, "passed": True, "unit": ""}]
    return CalibrationResult(status, matrix, quality_gates=gates, reasons=[] if status == "ok" else ["RMS too high"])


@pytest.fixture
def path():
    return parse_gcode(SOURCE, "part.nc")


def files(folder):
    return sorted(os.listdir(folder))


@pytest.mark.parametrize("status", ["failed", "ambiguous"])
def test_a_calibration_that_is_not_ok_is_refused(status, path, tmp_path):
    with pytest.raises(ExportRefused) as err:
        export(path, calibration(status), "krl", tmp_path / "prog.src", calibration_source="cal.json")
    message = str(err.value)
    assert message.startswith(f"cal.json: calibration status is '{status}'")
    assert "gate rms_mm = 0.8 mm, limit 0.3" in message and "coverage" not in message
    assert "--force" in message
    assert files(tmp_path) == []
    # Callers tell the refusal forcing overrides by its type, never by its words (GUI: "Use it anyway?").
    assert isinstance(err.value, CalibrationNotOk) and err.value.status == status


def test_refusals_that_forcing_cannot_help_are_not_calibration_refusals(path, tmp_path):
    tilted = frames.rigid(frames.rot_x(2.0), (500.0, 0.0, 0.0))
    with pytest.raises(ToolTilted) as err:
        export(path, calibration("failed", tilted), "gcode", tmp_path / "p.nc", force=True)
    assert err.value.tilt_deg == pytest.approx(2.0, abs=1e-6) and err.value.tolerance_deg == pytest.approx(0.05)
    assert not err.value.five_axis_path and not isinstance(err.value, CalibrationNotOk)
    with pytest.raises(ExportRefused) as err:
        export(path, calibration(), "krl", tmp_path / "p.src", envelope=Envelope.parse("0,0,0,1,1,1"))
    assert not isinstance(err.value, (CalibrationNotOk, ToolTilted))
    assert files(tmp_path) == []


def test_a_calibration_without_w_cannot_be_forced(path, tmp_path):
    with pytest.raises(InputError, match="no transform W"):
        export(path, CalibrationResult("failed", None), "csv", tmp_path / "p.csv", force=True)


@pytest.mark.parametrize("force", [False, True])
def test_a_calibration_ok_with_a_failed_gate_is_refused_as_inconsistent(force, path, tmp_path):
    """A result.json that says "ok" while a gate of it failed contradicts itself: no program, forced or not."""
    inconsistent = calibration()
    inconsistent.quality_gates[0]["passed"] = False
    with pytest.raises(InputError, match=r"cal.json: status 'ok' while its gate rms_mm = 0.8 mm, limit 0.3 "
                                         r"failed: the file contradicts itself"):
        export(path, inconsistent, "krl", tmp_path / "prog.src", calibration_source="cal.json", force=force)
    assert files(tmp_path) == []


@pytest.mark.parametrize("fmt", sorted(FORMATS))
def test_a_forced_export_says_so_before_any_motion(fmt, path, tmp_path):
    out = tmp_path / f"prog{FORMATS[fmt].EXTENSION}"
    job = export(path, calibration("failed"), fmt, out, force=True)
    assert job.forced
    lines = out.read_text().splitlines()
    first_banner = next(i for i, line in enumerate(lines) if "FORCED EXPORT" in line)
    # before any header line: after % (G-code), &ACCESS/DEF/EXT (KRL), MODULE (RAPID), def (URScript), /MN (Fanuc)
    assert first_banner <= {"rapid": 1, "fanuc": 21, "krl": 4, "gcode": 1, "urscript": 1}.get(fmt, 0)
    banner = " ".join(re.sub(r"^\s*(?:\d+:\s*!|[;#!(])\s*|\s*[;)]$", "", line)
                      for line in lines[first_banner:first_banner + 12])
    assert "gate rms_mm = 0.8 mm, limit 0.3" in banner and "Do not run" in banner
    if fmt == "fanuc":
        assert 'COMMENT\t\t= "FORCED";' in lines


def test_an_ok_export_has_no_banner(path, tmp_path):
    out = tmp_path / "prog.src"
    assert not export(path, calibration(), "krl", out).forced
    assert "FORCED" not in out.read_text()


def test_envelope_refusal_names_the_move_and_writes_nothing(path, tmp_path):
    out = tmp_path / "prog.src"
    out.write_text("older program\n")
    # In B the part sits at x 990..1010, y -10..10, z 500..520: cut the top off.
    envelope = Envelope.parse("900,-100,400,1100,100,510")
    with pytest.raises(ExportRefused) as err:
        export(path, calibration(), "krl", out, envelope=envelope)
    assert str(err.value) == (
        "part.nc: move 1 (line 1) reaches (1000.000, 10.000, 520.000) mm in the robot base frame, "
        "outside the work envelope x [900, 1100], y [-100, 100], z [400, 510]; nothing was written")
    assert out.read_text() == "older program\n"
    assert files(tmp_path) == ["prog.src"]  # no temporary file left behind


def test_envelope_is_checked_along_arcs_not_only_at_their_ends(path, tmp_path):
    # The half circle's ends are at x 1000 in B but it bulges to x 990 (Y10 in X -> -X in B).
    envelope = Envelope.parse("995,-100,400,1100,100,600")
    with pytest.raises(ExportRefused, match=r"move 3 \(line 3\) reaches \(99[0-4]\.\d+, "):
        export(path, calibration(), "csv", tmp_path / "p.csv", envelope=envelope)
    assert files(tmp_path) == []
    export(path, calibration(), "csv", tmp_path / "p.csv", envelope=Envelope.parse("989,-100,400,1100,100,600"))


@pytest.mark.parametrize("field, message", [("end", "non-finite position"), ("feed", "non-finite feed")])
def test_nan_is_refused(field, message, tmp_path):
    moves = [Move("rapid", [0, 0, 10]), Move("linear", [0, 0, 0], feed=100.0, line=7)]
    setattr(moves[1], field, np.array([0, math.nan, 0]) if field == "end" else math.nan)
    with pytest.raises(ExportRefused, match=f"move 2 \\(line 7\\) has a {message}"):
        export(Toolpath.from_moves(moves, source="bad"), calibration(), "urscript", tmp_path / "p.script")
    assert files(tmp_path) == []


def test_number_refuses_non_finite_values_and_negative_zero():
    for bad in (math.nan, math.inf, -math.inf):
        with pytest.raises(ExportRefused):
            number(bad, 3)
    assert number(-0.00001, 3) == "0.000" and number(-1.5, 1) == "-1.5"


@pytest.mark.parametrize("text", ["1,2,3", "a,b,c,d,e,f", "0,0,0,0,1,1", "0,0,0,1,1,nan"])
def test_bad_envelopes_are_input_errors(text):
    with pytest.raises(InputError, match="work envelope"):
        Envelope.parse(text)


def test_empty_toolpath_and_bad_tolerance_are_input_errors(path, tmp_path):
    with pytest.raises(InputError, match="no moves"):
        export(Toolpath(source="empty.nc"), calibration(), "csv", tmp_path / "p.csv")
    with pytest.raises(InputError, match="chordal tolerance"):
        export(path, calibration(), "csv", tmp_path / "p.csv", chord_tol_mm=0.0)
    with pytest.raises(InputError, match="unknown output format"):
        export(path, calibration(), "step", tmp_path / "p.csv")


def test_non_finite_quality_numbers_are_written_as_n_a(path, tmp_path):
    gates = [{"name": "rms_mm", "value": math.nan, "limit": 0.3, "passed": True, "unit": "mm"}]
    uncertainty = {"toolpath_bound_mm": math.nan}
    result = CalibrationResult("ok", W, quality_gates=gates, uncertainty=uncertainty)
    out = tmp_path / "p.csv"
    export(path, result, "csv", out)
    text = out.read_text().lower()
    assert "gate rms_mm = n/a mm, limit 0.3: passed" in text and "bound n/a mm" in text and "nan" not in text


def _right_hand_part():
    """A part on the right of a car (its frame X the car's, y to the left) and a finishing pass 1 mm above
    its top, as CAM makes it on the part's model."""
    from workcal_wb.core.geometry import Cloud
    from workcal_wb.core.simulate.shapes import car_body
    from workcal_wb.core.simulate.toolpath_sample import sample_toolpath_points

    body = car_body(edge_mm=4.0)
    model = Cloud(body.points + [0.0, -300.0, 0.0], None, body.triangles, "right_door.stl")
    points, feed = sample_toolpath_points(model, rows=8, points_per_row=32)
    moves = [Move("rapid", points[0] + [0, 0, 20])] + [Move("linear", p, feed=feed) for p in points]
    return model, Toolpath.from_moves(moves + [Move("rapid", points[-1] + [0, 0, 20])], source="right_door.nc")


def test_a_toolpath_made_for_the_mirrored_part_is_refused_with_its_distance(tmp_path):
    from workcal_wb.core.geometry import Cloud
    from workcal_wb.core.toolpath.safety import PathOffModel

    right, toolpath = _right_hand_part()
    left = Cloud(right.points * [1.0, -1.0, 1.0], None, right.triangles[:, ::-1], "left_door.stl")
    out = tmp_path / "prog.src"
    with pytest.raises(PathOffModel) as refused:
        export(toolpath, calibration(), "krl", out, workpiece_model=left)
    assert refused.value.median_mm > 400 and "left_door.stl" in str(refused.value)
    assert f"a median {refused.value.median_mm:.1f} mm from the workpiece model" in str(refused.value)
    assert not out.exists()
    # the right model: written, and the header says how the path lies on it
    export(toolpath, calibration(), "krl", out, workpiece_model=right)
    header = out.read_text().replace("\n;", " ")  # the header's comment lines wrapped
    assert re.search(r"on the workpiece model right_door.stl: cutting moves a median [12]\.\d\d mm from its "
                     r"surface, 100 % within the reach 25 mm", header)


def test_a_roughing_pass_inside_the_part_is_within_reach_and_a_path_far_off_only_with_a_larger_reach(tmp_path):
    from workcal_wb.core.toolpath.safety import PathOffModel

    model, toolpath = _right_hand_part()
    inside = Toolpath.from_moves([Move(m.kind, m.end - [0, 0, 16.0], feed=m.feed) for m in toolpath.moves],
                                 source="roughing.nc")
    export(inside, calibration(), "krl", tmp_path / "rough.src", workpiece_model=model)
    aside = Toolpath.from_moves([Move(m.kind, m.end + [0, 0, 60.0], feed=m.feed) for m in toolpath.moves],
                                source="aside.nc")
    with pytest.raises(PathOffModel):
        export(aside, calibration(), "krl", tmp_path / "aside.src", workpiece_model=model)
    export(aside, calibration(), "krl", tmp_path / "aside.src", workpiece_model=model, path_reach_mm=80.0)
    assert "within the reach 80 mm" in (tmp_path / "aside.src").read_text()


def test_the_path_is_measured_along_its_cutting_moves_only():
    from workcal_wb.core.toolpath.safety import cutting_points

    moves = [Move("rapid", (0, 0, 100)), Move("linear", (0, 0, 0), feed=100), Move("linear", (100, 0, 0), feed=100),
             Move("rapid", (100, 0, 500)), Move("rapid", (5000, 0, 500))]
    points = cutting_points(Toolpath.from_moves(moves), 0.01, count=100)
    # half of the cut is the plunge from z 100, half the pass along x; the rapids add nothing
    assert len(points) == 100 and np.all(points[:, 0] <= 100) and np.all(points[:, 1] == 0)
    assert np.isclose(np.mean(points[:, 2] > 0), 0.5, atol=0.02) and np.allclose(np.diff(points[50:, 0]), 2.0)


def test_without_a_model_the_program_says_the_path_was_not_checked(path, tmp_path):
    export(path, calibration(), "rapid", tmp_path / "prog.mod")
    assert "toolpath on the workpiece model: not checked (no model given)" in (tmp_path / "prog.mod").read_text()
