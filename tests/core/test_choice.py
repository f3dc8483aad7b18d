"""Choosing one pose of an ambiguous calibration: the difference from the best named in words, the user's
choice recorded in the result (and result.json), the status "ok (chosen)" only with that record, and the
exported program saying so in its header."""
import dataclasses
import json
import re

import numpy as np
import pytest

from workcal_wb.core import choice, frames
from workcal_wb.core.errors import InputError
from workcal_wb.core.result import (AMBIGUOUS, BEHIND_SURFACE, CHOSEN, MANY_WAYS, OK, OTHER_SIDE, RIVAL, SEARCH_DOUBT,
                                    SYMMETRIC, TIE_UNBROKEN, UNDER_CONSTRAINED, Candidate, CalibrationResult,
                                    MatchResult, Reason)
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
    chosen = choice.choose(ambiguous(), "workpiece", 2, axes, who="anna", when="2026-01-02T03:04:05+00:00")
    export(path, chosen, "krl", tmp_path / "prog.src", calibration_source="result.json")
    text = (tmp_path / "prog.src").read_text()
    assert "FORCED" not in text
    assert "calibration status ok (chosen)" in text
    header = krl_header(text)
    assert "pose chosen by the user anna on 2026-01-02T03:04:05+00:00 among 3 candidate poses" in header
    assert "turned 180 deg about the part's long axis (X)" in header


# Characters textwrap keeps inside a word but str.splitlines (and so a reader of the program) breaks a
# line at, and NUL, which ends a string on some controllers.
LINE_BREAKERS = ("\x1c", "\x85", "\u2028", "\x00", "\n", "\r")
# Each format's comment line (stripped), as its controller reads it: nothing after it is code.
COMMENT_LINE = {
    "krl": lambda s: s.startswith(";") and not re.match(r";\s*(END)?FOLD", s, re.IGNORECASE),
    "rapid": lambda s: s.startswith("!"),
    "urscript": lambda s: s.startswith("#"),
    "fanuc": lambda s: re.fullmatch(r"(\d+:\s*)?![^;]*;", s) is not None,
    "gcode": lambda s: re.fullmatch(r"\([^()]*\)", s) is not None,
}
EXTENSIONS = {"krl": ".src", "rapid": ".mod", "urscript": ".script", "fanuc": ".ls", "gcode": ".nc"}


@pytest.mark.parametrize("fmt", sorted(COMMENT_LINE))
def test_the_user_name_stays_inside_its_comment(axes, tmp_path, fmt):
    who = "anna" + "".join(f"{c}X_INJECTED{i} " for i, c in enumerate(LINE_BREAKERS))
    chosen = choice.choose(ambiguous(), "workpiece", 2, axes, who=who, when="2026-01-02T03:04:05+00:00")
    out = tmp_path / f"prog{EXTENSIONS[fmt]}"
    export(parse_gcode(SOURCE, "part.nc"), chosen, fmt, out, calibration_source="result.json",
           **({"machine": "5axis-tcp"} if fmt == "gcode" else {}))
    marked = [line for line in out.read_text().splitlines() if "X_INJECTED" in line]
    assert marked  # the name is in the header
    assert all(COMMENT_LINE[fmt](line.strip()) for line in marked), marked


def test_the_command_line_lists_the_poses_and_chooses_one_from_the_stored_result(monkeypatch, tmp_path, capsys):
    from workcal_wb.cli import build_parser, main
    from workcal_wb.cli import calibrate as command

    model = tmp_path / "box.xyz"
    np.savetxt(model, box_points(), fmt="%.4f")
    gcode = tmp_path / "part.nc"
    gcode.write_text(SOURCE)
    monkeypatch.setattr(command, "calibrate", lambda *args, **kwargs: ambiguous())
    monkeypatch.setattr("workcal_wb.core.report.write_report", lambda *args, **kwargs: None)
    args = build_parser().parse_args(["calibrate", "--scan", str(model), "--workpiece", str(model), "--reference",
                                      str(model), "--toolpath", str(gcode), "--format", "krl", "--out",
                                      str(tmp_path / "open"), "--no-cache"])
    assert command.run(args) == 1  # the program refused, as without a choice
    err = capsys.readouterr().err
    written = tmp_path / "open" / "result.json"
    assert f"3 poses the scan cannot tell apart (choose one with: python3 -m workcal_wb choose {written} N" in err
    assert "pose 3: turned 180 deg about the part's long axis (X)" in err
    assert json.loads(written.read_text())["status"] == "ambiguous"
    assert not (tmp_path / "open" / "toolpath_calibrated.src").exists()
    with pytest.raises(SystemExit):  # calibrate no longer takes a pose blind
        build_parser().parse_args(["calibrate", "--scan", str(model), "--workpiece", str(model), "--reference",
                                   str(model), "--choose", "3"])

    assert main(["choose", str(written), "--model", str(model), "--no-cache"]) == 0  # listed, nothing written
    out = capsys.readouterr().out
    assert "pose 2: shifted 12 mm along the part's long axis (X)" in out and "pose 3: turned 180 deg" in out
    assert not (tmp_path / "open-chosen").exists()
    assert main(["choose", str(written), "4", "--model", str(model), "--no-cache"]) == 2
    assert "has 3 poses (1 to 3)" in capsys.readouterr().err
    assert main(["choose", str(written), "3", "--model", str(model), "--no-cache", "--out",
                 str(tmp_path / "open")]) == 2  # the calibration's own set stays as written
    assert json.loads(written.read_text())["status"] == "ambiguous"

    assert main(["choose", str(written), "3", "--model", str(model), "--no-cache"]) == 0
    chosen = tmp_path / "open-chosen" / "result.json"
    back = CalibrationResult.from_json(chosen)
    assert back.status == CHOSEN and back.choice.index == 2 and back.choice.who == choice.user_name()
    assert json.loads((tmp_path / "open-chosen" / "manifest.json").read_text())["command"] == "choose"
    assert main(["choose", str(chosen), "2", "--model", str(model), "--no-cache", "--out",
                 str(tmp_path / "again")]) == 2  # chosen already
    program = tmp_path / "prog.src"
    assert main(["toolpath", "--in", str(gcode), "--calibration", str(chosen), "--out", str(program)]) == 0
    assert "among 3 candidate poses" in krl_header(program.read_text()) and "FORCED" not in program.read_text()


def test_the_command_line_says_when_an_ambiguous_result_has_no_tie_to_choose(tmp_path, capsys):
    from workcal_wb.cli import main

    model = tmp_path / "box.xyz"
    np.savetxt(model, box_points(), fmt="%.4f")
    path = tmp_path / "result.json"
    doubtful([Reason(RIVAL, "a rival"), Reason(UNDER_CONSTRAINED, "slides along X")]).to_json(path)
    assert main(["choose", str(path), "1", "--model", str(model), "--no-cache"]) == 2
    err = capsys.readouterr().err
    assert "no tie between poses to choose from" in err and "more than a tie" in err


def doubtful(workpiece_reasons, reference=None):
    """An ambiguous calibration whose workpiece match has a non-rival candidate and the reasons given;
    the reference match ``reference`` (default: ok)."""
    worse = Candidate(U @ frames.rigid(translation=[40.0, 0.0, 0.0]), score=0.2, score_ratio=0.3,
                      standard_errors_below_best=25.0, rival=False, fits=False)
    rival = Candidate(U @ frames.rigid(translation=[12.0, 0.0, 0.0]), score=0.8, score_ratio=0.97,
                      standard_errors_below_best=0.4, rival=True)
    ruled_out = Candidate(U @ frames.rigid(translation=[0.0, 9.0, 0.0]), score=0.79, score_ratio=0.96,
                          standard_errors_below_best=0.5, rival=True, ruled_out_by="the platform")
    symmetry = {"axis": [1.0, 0.0, 0.0], "point_mm": CENTRE.tolist(), "order": 2, "deviation_mm": 0.01,
                "description": "half a turn about its long axis gives the same surface"}
    workpiece = MatchResult(AMBIGUOUS, "robust", U, candidates=[Candidate(U, score=0.82), worse, rival, ruled_out],
                            symmetries=[symmetry], reasons=workpiece_reasons)
    reference = reference or MatchResult(OK, "robust", V)
    gates = [{"code": f"{role}_status", "name": f"{role} match status", "value": m.status, "limit": OK,
              "passed": m.status == OK, "unit": ""} for role, m in (("workpiece", workpiece), ("reference", reference))]
    return CalibrationResult(AMBIGUOUS, frames.invert(V) @ U, U=U, V=V, workpiece=workpiece, reference=reference,
                             quality_gates=gates, reasons=[r.within("workpiece match", "workpiece")
                                                           for r in workpiece_reasons])


def test_the_poses_are_only_those_tied_with_the_best():
    rival_only = choice.poses(doubtful([Reason(RIVAL, "a rival")]), "workpiece")
    assert len(rival_only) == 2  # the best and the rival: neither the clearly worse, nor the ruled out, nor a turn
    assert rival_only[1].candidate.rival and rival_only[1].candidate.ruled_out_by is None
    symmetric = choice.poses(doubtful([Reason(SYMMETRIC, "symmetric"), Reason(RIVAL, "a rival")]), "workpiece")
    assert len(symmetric) == 3 and symmetric[2].symmetry["order"] == 2


@pytest.mark.parametrize("code", [UNDER_CONSTRAINED, BEHIND_SURFACE, MANY_WAYS, SEARCH_DOUBT])
def test_doubt_other_than_a_tie_is_not_settled_by_a_choice(axes, code):
    result = doubtful([Reason(RIVAL, "a rival"), Reason(code, "other doubt")])
    assert choice.chosen_role(result) is None
    for index in (0, 1):
        with pytest.raises(InputError, match="more than a tie"):
            choice.choose(result, "workpiece", index, axes, who="mallory")


def test_a_tie_is_not_settled_by_a_choice_while_the_other_match_is_in_doubt(axes):
    reference = MatchResult(AMBIGUOUS, "robust", V, reasons=[Reason(BEHIND_SURFACE, "much of the view lies behind")])
    result = doubtful([Reason(RIVAL, "a rival")], reference)
    assert choice.chosen_role(result) is None
    with pytest.raises(InputError, match="reference match"):
        choice.choose(result, "workpiece", 1, axes, who="mallory")
    with pytest.raises(InputError, match="reference match"):
        choice.choose(result, "reference", 0, axes, who="mallory")


def test_a_lone_pose_with_other_doubt_is_not_confirmed_by_a_choice(axes):
    """The review's case: the workpiece under-constrained and the reference behind its surface."""
    reference = MatchResult(AMBIGUOUS, "robust", V, reasons=[Reason(BEHIND_SURFACE, "much of the view lies behind")])
    result = doubtful([Reason(UNDER_CONSTRAINED, "slides along X")], reference)
    for role in ("workpiece", "reference"):
        with pytest.raises(InputError):
            choice.choose(result, role, 0, axes, who="mallory")


@pytest.mark.parametrize("codes", [(RIVAL,), (SYMMETRIC,), (OTHER_SIDE, TIE_UNBROKEN), (SYMMETRIC, RIVAL)])
def test_a_pure_tie_is_settled_by_a_choice_the_best_confirmed_too(axes, codes):
    result = doubtful([Reason(code, "tied") for code in codes])
    assert choice.chosen_role(result) == "workpiece"
    for index in range(len(choice.poses(result, "workpiece"))):
        chosen = choice.choose(result, "workpiece", index, axes, who="anna")
        assert chosen.status == CHOSEN and chosen.choice.index == index


def test_a_chosen_export_lets_only_the_chosen_match_status_gate_fail(axes, tmp_path):
    from workcal_wb.core.toolpath.safety import check_calibration

    chosen = choice.choose(doubtful([Reason(RIVAL, "a rival")]), "workpiece", 1, axes, who="anna")
    assert check_calibration(chosen, force=False) is False
    for edit in ({"code": "reference_status", "name": "reference match status", "value": "failed", "limit": OK,
                  "passed": False, "unit": ""},
                 {"code": "workpiece_explained", "name": "workpiece region explained", "value": 10.0, "limit": 80.0,
                  "passed": False, "unit": ""}):
        edited = dataclasses.replace(chosen, quality_gates=chosen.quality_gates + [edit])
        with pytest.raises(InputError, match="contradicts itself"):
            check_calibration(edited, force=False)


def chosen_file(axes, role="workpiece"):
    """The JSON values of a result with a pose chosen (of the workpiece's rival, or the reference's)."""
    if role == "workpiece":
        result = doubtful([Reason(RIVAL, "a rival")])
    else:
        rival = Candidate(V @ frames.rigid(translation=[0.0, 7.0, 0.0]), score=0.8, score_ratio=0.97,
                          standard_errors_below_best=0.4, rival=True)
        reference = MatchResult(AMBIGUOUS, "robust", V, candidates=[Candidate(V, score=0.82), rival],
                                reasons=[Reason(RIVAL, "a rival")])
        gates = [{"code": "workpiece_status", "name": "workpiece match status", "value": OK, "limit": OK,
                  "passed": True, "unit": ""},
                 {"code": "reference_status", "name": "reference match status", "value": AMBIGUOUS, "limit": OK,
                  "passed": False, "unit": ""}]
        result = CalibrationResult(AMBIGUOUS, frames.invert(V) @ U, U=U, V=V, workpiece=MatchResult(OK, "robust", U),
                                   reference=reference, quality_gates=gates)
    return choice.choose(result, role, 1, axes, who="anna", when="2026-01-02T03:04:05+00:00").to_dict(
        region_indices=False)


def test_a_chosen_result_as_written_reads_back(axes, tmp_path):
    for role in ("workpiece", "reference"):
        path = tmp_path / f"{role}.json"
        path.write_text(json.dumps(chosen_file(axes, role)))
        back = CalibrationResult.from_json(path)
        assert back.status == CHOSEN and back.choice.role == role


def _edits():
    def moved(matrix):  # a micron along X
        return (np.asarray(matrix) @ frames.rigid(translation=[1e-3, 0.0, 0.0])).tolist()

    def both_moved(data):  # U and the chosen pose alike, W left as it was
        data["U"] = data["choice"]["matrix"] = moved(data["U"])

    return {
        "the chosen pose is not U": lambda d: d["choice"].__setitem__("matrix", np.eye(4).tolist()),
        "the chosen pose a micron off U": lambda d: d["choice"].__setitem__("matrix", moved(d["choice"]["matrix"])),
        "W is not V^-1 U": lambda d: d.__setitem__("W", moved(d["W"])),
        "U and the choice moved together, W not": both_moved,
        "the other match failed": lambda d: d["reference"].__setitem__("status", "failed"),
        "the other match missing": lambda d: d.__setitem__("reference", None),
        "the chosen match ok": lambda d: d["workpiece"].__setitem__("status", "ok"),
        "the chosen match missing": lambda d: d.__setitem__("workpiece", None),
        "the chosen match in doubt beyond the tie": lambda d: d["workpiece"]["reasons"].append(
            {"code": UNDER_CONSTRAINED, "text": "slides along X"}),
        "version 3": lambda d: d.__setitem__("version", 3),
        "no one chose": lambda d: d["choice"].__setitem__("who", ""),
        "a blank who": lambda d: d["choice"].__setitem__("who", "  "),
        "no time": lambda d: d["choice"].__setitem__("when", ""),
    }


@pytest.mark.parametrize("name", sorted(_edits()))
def test_a_chosen_result_that_contradicts_itself_is_refused_naming_the_file(axes, tmp_path, name):
    data = chosen_file(axes)
    _edits()[name](data)
    path = tmp_path / "result.json"
    path.write_text(json.dumps(data))
    with pytest.raises(InputError, match=f"{path}: .*contradicts itself"):
        CalibrationResult.from_json(path)


def test_a_chosen_reference_pose_is_checked_against_v(axes, tmp_path):
    data = chosen_file(axes, "reference")
    data["choice"]["matrix"] = data["U"]
    path = tmp_path / "result.json"
    path.write_text(json.dumps(data))
    with pytest.raises(InputError, match="contradicts itself"):
        CalibrationResult.from_json(path)


def reference_tie():
    """An ambiguous calibration whose reference match has a rival turned a quarter about Z."""
    rival = Candidate(V @ turn([0.0, 0.0, 1.0], 90.0, [20.0, 10.0, 0.0]), score=0.8, score_ratio=0.97,
                      standard_errors_below_best=0.4, rival=True)
    reference = MatchResult(AMBIGUOUS, "robust", V, candidates=[Candidate(V, score=0.82), rival],
                            reasons=[Reason(RIVAL, "a rival")])
    gates = [{"code": "reference_status", "name": "reference match status", "value": AMBIGUOUS, "limit": OK,
              "passed": False, "unit": ""}]
    return CalibrationResult(AMBIGUOUS, frames.invert(V) @ U, U=U, V=V, workpiece=MatchResult(OK, "robust", U),
                             reference=reference, quality_gates=gates)


def test_the_workpiece_is_placed_where_the_robot_would_take_it_for_each_pose(axes):
    result = reference_tie()
    placed = choice.workpiece_placements(result, "reference")
    np.testing.assert_allclose(placed[0], U, atol=1e-9)  # the best: the workpiece where the scan shows it
    chosen = choice.choose(result, "reference", 1, axes, who="anna")
    # Seen through the best reference pose (how the scan shows the robot base), W of the choice.
    np.testing.assert_allclose(frames.invert(V) @ placed[1], chosen.W, atol=1e-9)
    assert not np.allclose(placed[1], choice.poses(result, "reference")[1].matrix)  # not at the reference's pose
    np.testing.assert_allclose(choice.workpiece_placements(chosen, "reference")[1], placed[1], atol=1e-9)
    workpiece = choice.workpiece_placements(ambiguous(), "workpiece")
    for placement, pose in zip(workpiece, choice.poses(ambiguous(), "workpiece")):
        np.testing.assert_allclose(placement, pose.matrix)


def test_the_program_header_says_the_failed_status_gate_was_resolved_by_the_choice(axes, tmp_path):
    chosen = choice.choose(ambiguous(), "workpiece", 2, axes, who="anna", when="2026-01-02T03:04:05+00:00")
    export(parse_gcode(SOURCE, "part.nc"), chosen, "krl", tmp_path / "prog.src", calibration_source="result.json")
    header = krl_header((tmp_path / "prog.src").read_text())
    assert "gate workpiece match status = ambiguous, limit ok: FAILED (resolved by the person's choice below)" in header
    assert header.index("resolved by the person's choice below") < header.index("pose chosen by the user anna")
    assert header.count("resolved by the person's choice") == 1


def test_the_report_gives_each_status_one_css_class_of_its_own(axes):
    from workcal_wb.core import report
    from workcal_wb.core.result import STATUSES

    assert set(report.STATUS_CLASS) == set(STATUSES)
    assert all(re.fullmatch(r"[a-z]+", name) for name in report.STATUS_CLASS.values())
    assert len(set(report.STATUS_CLASS.values())) == len(STATUSES)
    chosen = choice.choose(ambiguous(), "workpiece", 2, axes, who="anna")
    assert f'class="banner {report.STATUS_CLASS[CHOSEN]}"' in report._banner(chosen)
    assert f".{report.STATUS_CLASS[CHOSEN]}{{" in report.CSS


@pytest.mark.parametrize("entry", [{"index": [1], "difference": "x"}, {"index": 1, "difference": 7},
                                   {"index": 1, "difference": "x", "score_ratio": "high"}])
def test_the_evidence_of_a_choice_is_checked_when_read(axes, entry):
    data = chosen_file(axes)
    data["choice"]["evidence"][1] = entry
    with pytest.raises(InputError, match="result.json: choice: .*evidence"):
        CalibrationResult.from_dict(data, "result.json")
