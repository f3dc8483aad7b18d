"""Choosing one pose of an ambiguous calibration: the difference from the best named in words, the user's
choice recorded in the result (and result.json), the status "ok (chosen)" only with that record, and the
exported program saying so in its header."""
import json

import numpy as np
import pytest

from workcal_wb.core import choice, frames
from workcal_wb.core.errors import InputError
from workcal_wb.core.result import AMBIGUOUS, CHOSEN, OK, SYMMETRIC, Candidate, CalibrationResult, MatchResult, Reason
from workcal_wb.core.symmetry import turn
from workcal_wb.core.toolpath import CalibrationNotOk, export, parse_gcode

# A box 200 x 80 x 30 mm (long along X, short along Z), its frame at a corner: the centre is off the origin.
SIZE = np.array([200.0, 80.0, 30.0])
CENTRE = SIZE / 2
U = frames.rigid(frames.from_rotvec([0.2, -0.1, 0.4])[:3, :3], [300.0, -50.0, 900.0])
V = frames.rigid(frames.from_rotvec([0.0, 0.0, 0.3])[:3, :3], [-400.0, 20.0, 1000.0])
SOURCE = "G0 X10 Y10 Z20\nG1 Z0 F300\nG1 X150 F600\nG0 Z20\n"


def box_points(count=4000, seed=0):
    rng = np.random.default_rng(seed)
    points = rng.uniform(0.0, 1.0, size=(count, 3)) * SIZE
    face = rng.integers(0, 6, size=count)
    points[np.arange(count), face % 3] = np.where(face < 3, 0.0, SIZE[face % 3])
    return np.vstack([points, SIZE - points])  # mirrored through the centre: the box's axes exactly


def krl_header(text: str) -> str:
    """A KRL program's comment lines as one text (the header wraps its lines at spaces)."""
    return " ".join(line.lstrip("; ").strip() for line in text.splitlines() if line.startswith(";"))


@pytest.fixture(scope="module")
def axes():
    return choice.part_axes(box_points())


def test_half_a_turn_about_the_long_axis_is_named_so(axes):
    half_turn = turn([1.0, 0.0, 0.0], 180.0, CENTRE)
    named = choice.difference(U, U @ half_turn, axes)
    assert named.angle_deg == pytest.approx(180.0)
    assert np.linalg.norm(named.shift_mm) < 1e-9  # turned about its centre: the centre stays
    assert named.words == "turned 180 deg about the part's long axis (X)"


def test_a_pure_shift_is_named_in_mm_along_the_part_axis(axes):
    named = choice.difference(U, U @ frames.rigid(translation=[12.0, 0.0, 0.0]), axes)
    assert named.angle_deg == pytest.approx(0.0, abs=1e-9)
    assert named.words == "shifted 12 mm along the part's long axis (X)"
    sideways = choice.difference(U, U @ frames.rigid(translation=[0.0, -3.5, 0.0]), axes)
    assert sideways.words == "shifted -3.5 mm along the part's middle axis (Y)"
    small = choice.difference(U, U @ frames.rigid(translation=[0.0, 0.0, -0.5]), axes)
    assert small.words == "shifted -0.5 mm along the part's short axis (Z)"


def test_a_turn_and_a_shift_off_the_axes_are_both_said(axes):
    axis = np.array([1.0, 1.0, 0.0]) / np.sqrt(2)
    named = choice.difference(U, U @ turn(axis, 90.0, CENTRE) @ frames.rigid(translation=[0.0, 0.0, 5.0]), axes)
    assert named.words.startswith("turned 90 deg about (0.71, 0.71, 0.00) in the part's frame, shifted ")
    assert choice.difference(U, U, axes).words == "the same pose"


def ambiguous():
    """An ambiguous calibration: the workpiece match found a rival and the model has a half-turn symmetry."""
    rival = Candidate(U @ frames.rigid(translation=[12.0, 0.0, 0.0]), score=0.8, score_ratio=0.97,
                      standard_errors_below_best=0.4, rival=True)
    symmetry = {"axis": [1.0, 0.0, 0.0], "point_mm": CENTRE.tolist(), "order": 2, "deviation_mm": 0.01,
                "description": "half a turn about its long axis gives the same surface"}
    workpiece = MatchResult(AMBIGUOUS, "robust", U, candidates=[Candidate(U, score=0.82), rival],
                            symmetries=[symmetry], reasons=[Reason(SYMMETRIC, "the model is symmetric")])
    reference = MatchResult(OK, "robust", V)
    gates = [{"code": "workpiece_status", "name": "workpiece match status", "value": AMBIGUOUS, "limit": OK,
              "passed": False, "unit": ""},
             {"code": "uncertainty", "name": "uncertainty at the toolpath", "value": 0.05, "limit": 0.3,
              "passed": True, "unit": "mm"}]
    return CalibrationResult(AMBIGUOUS, frames.invert(V) @ U, U=U, V=V, workpiece=workpiece, reference=reference,
                             quality_gates=gates, reasons=[Reason(SYMMETRIC, "workpiece match: the model is symmetric",
                                                                  "workpiece")])


def test_the_poses_are_the_best_the_rivals_and_the_symmetric_turns():
    poses = choice.poses(ambiguous(), "workpiece")
    assert len(poses) == 3
    np.testing.assert_allclose(poses[0].matrix, U)
    assert poses[1].candidate.rival and poses[2].symmetry["order"] == 2
    assert len(choice.poses(ambiguous(), "reference")) == 1  # the reference match had no doubt


def test_the_choice_is_recorded_and_makes_the_status_ok_chosen(axes, tmp_path):
    chosen = choice.choose(ambiguous(), "workpiece", 2, axes, who="anna", when="2026-01-02T03:04:05+00:00")
    assert chosen.status == CHOSEN and chosen.ok
    record = chosen.choice
    assert (record.who, record.when, record.role, record.index, record.count) == (
        "anna", "2026-01-02T03:04:05+00:00", "workpiece", 2, 3)
    expected_U = U @ turn([1.0, 0.0, 0.0], 180.0, CENTRE)
    np.testing.assert_allclose(record.matrix, expected_U, atol=1e-9)
    np.testing.assert_allclose(record.best, U, atol=1e-12)
    np.testing.assert_allclose(chosen.U, expected_U, atol=1e-9)
    np.testing.assert_allclose(chosen.W, frames.invert(V) @ expected_U, atol=1e-9)
    assert [e["index"] for e in record.evidence] == [0, 1, 2]
    assert record.evidence[1]["difference"] == "shifted 12 mm along the part's long axis (X)"
    assert record.evidence[1]["standard_errors_below_best"] == pytest.approx(0.4)
    assert record.evidence[2]["difference"] == "turned 180 deg about the part's long axis (X)"
    assert "symmetry" in record.evidence[2]
    # The pose list stays as it was shown: the best first, though the result now holds the chosen one.
    np.testing.assert_allclose(choice.poses(chosen, "workpiece")[0].matrix, U, atol=1e-12)

    path = tmp_path / "result.json"
    chosen.to_json(path)
    data = json.loads(path.read_text())
    assert data["status"] == "ok (chosen)" and data["choice"]["who"] == "anna" and data["choice"]["index"] == 2
    back = CalibrationResult.from_json(path)
    assert back.status == CHOSEN and back.choice == record
    np.testing.assert_allclose(back.W, chosen.W)
    assert back.to_json_text() == chosen.to_json_text()


def test_ok_chosen_only_with_the_record(axes, tmp_path):
    with pytest.raises(ValueError, match="chosen"):
        CalibrationResult(CHOSEN, np.eye(4))
    chosen = choice.choose(ambiguous(), "workpiece", 1, axes, who="anna")
    with pytest.raises(ValueError, match="chosen"):  # a record on a result that is not "ok (chosen)"
        CalibrationResult(AMBIGUOUS, np.eye(4), choice=chosen.choice)
    data = chosen.to_dict(region_indices=False)
    del data["choice"]
    with pytest.raises(InputError, match="chosen"):
        CalibrationResult.from_dict(data, "result.json")
    with pytest.raises(InputError, match="result.json: choice: the choice has no when"):
        CalibrationResult.from_dict({**data, "choice": {"who": "anna"}}, "result.json")


def test_only_an_ambiguous_result_offers_a_choice(axes):
    ok = CalibrationResult(OK, np.eye(4), U=U, V=V)
    with pytest.raises(InputError, match="ambiguous"):
        choice.choose(ok, "workpiece", 1, axes, who="anna")
    with pytest.raises(InputError, match="no pose 7"):
        choice.choose(ambiguous(), "workpiece", 7, axes, who="anna")
    assert choice.chosen_role(ambiguous()) == "workpiece"


def test_the_program_header_says_the_pose_was_chosen_among_the_candidates(axes, tmp_path):
    path = parse_gcode(SOURCE, "part.nc")
    with pytest.raises(CalibrationNotOk):  # without a choice: refused unless forced, as before
        export(path, ambiguous(), "krl", tmp_path / "refused.src")
    chosen = choice.choose(ambiguous(), "workpiece", 2, axes, who="anna\nX_INJECTED", when="2026-01-02T03:04:05+00:00")
    export(path, chosen, "krl", tmp_path / "prog.src", calibration_source="result.json")
    text = (tmp_path / "prog.src").read_text()
    assert "FORCED" not in text
    assert "calibration status ok (chosen)" in text
    header = krl_header(text)
    assert "pose chosen by the user anna X_INJECTED on 2026-01-02T03:04:05+00:00 among 3 candidate poses" in header
    assert "turned 180 deg about the part's long axis (X)" in header
    assert not any(line.strip() == "X_INJECTED" for line in text.splitlines())  # the name stays inside its comment


def test_the_command_line_lists_the_poses_and_records_the_one_chosen(monkeypatch, tmp_path, capsys):
    from workcal_wb.cli import build_parser
    from workcal_wb.cli import calibrate as command

    model = tmp_path / "box.xyz"
    np.savetxt(model, box_points(), fmt="%.4f")
    gcode = tmp_path / "part.nc"
    gcode.write_text(SOURCE)
    monkeypatch.setattr(command, "calibrate", lambda *args, **kwargs: ambiguous())
    monkeypatch.setattr("workcal_wb.core.report.write_report", lambda *args, **kwargs: None)

    def run(out, *extra):
        args = build_parser().parse_args(["calibrate", "--scan", str(model), "--workpiece", str(model), "--reference",
                                          str(model), "--toolpath", str(gcode), "--format", "krl", "--out",
                                          str(out), "--no-cache", *extra])
        return command.run(args)

    assert run(tmp_path / "open") == 1  # the program refused, as without a choice
    err = capsys.readouterr().err
    assert "3 poses the scan cannot tell apart (choose one with --choose N)" in err
    assert "pose 3: turned 180 deg about the part's long axis (X)" in err
    assert json.loads((tmp_path / "open" / "result.json").read_text())["status"] == "ambiguous"
    assert not (tmp_path / "open" / "toolpath_calibrated.src").exists()

    assert run(tmp_path / "chosen", "--choose", "3") == 0
    back = CalibrationResult.from_json(tmp_path / "chosen" / "result.json")
    assert back.status == CHOSEN and back.choice.index == 2 and back.choice.who == choice.user_name()
    program = (tmp_path / "chosen" / "toolpath_calibrated.src").read_text()
    assert "among 3 candidate poses" in krl_header(program) and "FORCED" not in program
