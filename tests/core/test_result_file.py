"""result.json: any malformed content is an InputError naming the file (never a traceback), and the region
indices go to a compact binary side file that is checked against the counts result.json records."""
import json

import numpy as np
import pytest

from workcal_wb.core import frames
from workcal_wb.core.errors import InputError
from workcal_wb.core.result import CalibrationResult, MatchResult, result_fingerprint

W = frames.rigid(frames.from_rotvec([0.1, -0.2, 0.3])[:3, :3], [800.0, 150.0, 120.0])
SCAN_POINTS = 5_000_000


def result(**changes) -> CalibrationResult:
    """A plausible ok calibration of a 5M-point scan (regions as ``changes`` say)."""
    match = MatchResult("ok", "robust", W, rms_mm=0.07, n_inliers=20000, percentiles_mm={"50": 0.05})
    fields = dict(U=W, V=np.eye(4), workpiece=match, reference=match,
                  inputs={"scan": "scan.ply", "scan_points": SCAN_POINTS},
                  uncertainty={"toolpath_bound_mm": 0.03, "method": "bootstrap"},
                  quality_gates=[{"name": "workpiece RMS", "value": 0.07, "limit": 0.3, "passed": True, "unit": "mm"}])
    fields.update(changes)
    return CalibrationResult("ok", W, **fields)


@pytest.fixture(scope="module")
def big():
    """Regions of a few million indices, as automatic regions find them in a 5M-point scan."""
    points = np.random.default_rng(0).permutation(SCAN_POINTS)
    return result(regions={"workpiece": np.sort(points[:2_000_000]), "reference": np.sort(points[2_000_000:2_600_000]),
                           "platform": np.sort(points[2_600_000:4_600_000]), "source": "auto"})


def test_region_indices_go_to_a_binary_side_file_and_read_back_exactly(big, tmp_path):
    # The finding: a 5M-point scan wrote two 74 MB JSON files, the index lists inline.
    path = tmp_path / "result.json"
    big.to_json(path)
    side = tmp_path / "result.regions.npz"
    assert side.is_file()
    assert path.stat().st_size < 50_000, path.stat().st_size
    assert side.stat().st_size < 4 * 4_600_000  # at most 4 bytes per index
    data = json.loads(path.read_text())
    assert data["regions"]["indices_file"] == "result.regions.npz"
    assert data["regions"]["counts"] == {"workpiece": 2_000_000, "reference": 600_000, "platform": 2_000_000}
    back = CalibrationResult.from_json(path)
    for role in ("workpiece", "reference", "platform"):
        np.testing.assert_array_equal(back.regions[role], big.regions[role])
    assert back.regions["source"] == "auto"
    np.testing.assert_allclose(back.W, W)


def test_a_result_json_without_its_side_file_names_it(big, tmp_path):
    big.to_json(tmp_path / "result.json")
    (tmp_path / "result.regions.npz").unlink()
    with pytest.raises(InputError, match=r"result.regions.npz.*does not exist"):
        CalibrationResult.from_json(tmp_path / "result.json")
    # W alone (what an exporter needs) reads without it.
    alone = CalibrationResult.from_json(tmp_path / "result.json", with_regions=False)
    np.testing.assert_allclose(alone.W, W)


def test_side_file_counts_are_checked_both_ways(tmp_path):
    small = result(regions={"workpiece": np.arange(10), "reference": np.arange(10, 15), "source": "user"})
    small.to_json(tmp_path / "result.json")
    data = json.loads((tmp_path / "result.json").read_text())
    for count, words in ((11, "holds 10 workpiece indices, result.json says 11"),
                         (9, "holds 10 workpiece indices, result.json says 9")):
        data["regions"]["counts"]["workpiece"] = count
        (tmp_path / "result.json").write_text(json.dumps(data))
        with pytest.raises(InputError, match=words):
            CalibrationResult.from_json(tmp_path / "result.json")
    data["regions"]["counts"] = {"workpiece": 10}
    (tmp_path / "result.json").write_text(json.dumps(data))
    with pytest.raises(InputError, match="reference indices that result.json does not list"):
        CalibrationResult.from_json(tmp_path / "result.json")


def test_a_corrupt_side_file_is_an_input_error(tmp_path):
    result(regions={"workpiece": np.arange(10), "reference": np.arange(10, 15), "source": "user"}).to_json(
        tmp_path / "result.json")
    side = tmp_path / "result.regions.npz"
    side.write_bytes(side.read_bytes()[:40])
    with pytest.raises(InputError, match="result.regions.npz: cannot be read as region indices"):
        CalibrationResult.from_json(tmp_path / "result.json")


def test_indices_outside_the_scan_are_refused(tmp_path):
    bad = result(regions={"workpiece": np.array([0, SCAN_POINTS]), "reference": np.arange(3), "source": "user"})
    bad.to_json(tmp_path / "result.json")
    with pytest.raises(InputError, match=f"workpiece indices outside the scan's {SCAN_POINTS} points"):
        CalibrationResult.from_json(tmp_path / "result.json")


def test_inline_regions_of_older_files_and_of_the_freecad_document_still_read(tmp_path):
    small = result(regions={"workpiece": np.arange(10), "reference": np.arange(10, 15), "source": "user"})
    data = small.to_dict()  # what the FreeCAD object stores: indices inline
    assert data["regions"]["workpiece"] == list(range(10))
    (tmp_path / "old.json").write_text(json.dumps(data))
    back = CalibrationResult.from_json(tmp_path / "old.json")
    np.testing.assert_array_equal(back.regions["reference"], np.arange(10, 15))


# What a result says of a region's points off its model (CalibrationResult.off_model).
_NOTE = {"count": 3, "where": "most of them within 4 mm of the platform's plane, on the region's +X side",
         "change": "Draw the region tighter on its +X side, so that it leaves the platform out"}


def test_a_result_written_before_off_model_points_were_kept_reads_as_before(tmp_path):
    """A result.json and side file without off-model points or notes: nothing is said of them."""
    old = result(regions={"workpiece": np.arange(10), "reference": np.arange(10, 15), "source": "user"})
    old.to_json(tmp_path / "result.json")
    back = CalibrationResult.from_json(tmp_path / "result.json")
    assert back.off_model("workpiece") is None and back.off_model("reference") is None


def test_off_model_points_and_notes_round_trip_whole(tmp_path):
    noted = result(regions={"workpiece": np.arange(10), "reference": np.arange(10, 15), "source": "user",
                            "workpiece_off_model": np.arange(0), "reference_off_model": np.array([11, 12, 14]),
                            "off_model": {"workpiece": {"count": 0, "where": "", "change": ""}, "reference": _NOTE}})
    noted.to_json(tmp_path / "result.json")
    counts = json.loads((tmp_path / "result.json").read_text())["regions"]["counts"]
    assert counts["reference_off_model"] == 3 and counts["workpiece_off_model"] == 0
    back = CalibrationResult.from_json(tmp_path / "result.json")
    np.testing.assert_array_equal(back.off_model("reference")["indices"], [11, 12, 14])
    assert {k: v for k, v in back.off_model("reference").items() if k != "indices"} == _NOTE
    assert back.to_json_text() == noted.to_json_text()


def _valid() -> dict:
    return result(regions={}).to_dict()


def _with(key, value) -> dict:
    data = _valid()
    data[key] = value
    return data


MALFORMED = {  # the findings (tracebacks) first, then their relatives
    "an array": [1, 2],
    "null": None,
    "gates a string": _with("quality_gates", "yes"),
    "gates of numbers": _with("quality_gates", [1, 2]),
    "gate why a number": _with("quality_gates", [{"name": "g", "passed": False, "why": 3}]),
    "uncertainty a list": _with("uncertainty", [1]),
    "uncertainty bound a string": _with("uncertainty", {"toolpath_bound_mm": "x"}),
    "distortion scale a string": _with("uncertainty", {"distortion_scale_pct": "x"}),
    "reasons a number": _with("reasons", 5),
    "warnings of lists": _with("warnings", [[1]]),
    "workpiece match a number": _with("workpiece", 5),
    "tolerance a string": _with("tolerance_mm", "x"),
    "tolerance negative": _with("tolerance_mm", -1),
    "W a string": _with("W", "abc"),
    "W not rigid": _with("W", [[2, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]),
    "status missing": {k: v for k, v in _valid().items() if k != "status"},
    "match rms a string": _with("workpiece", {**_valid()["workpiece"], "rms_mm": "low"}),
    "match percentiles a list": _with("workpiece", {**_valid()["workpiece"], "percentiles_mm": [1]}),
    "regions a list": _with("regions", [1, 2]),
    "region of strings": _with("regions", {"workpiece": ["a"], "source": "user"}),
    "region of fractions": _with("regions", {"workpiece": [1.5, 2], "source": "user"}),
    "time a bool": _with("time_s", True),
    "off-model points of strings": _with("regions", {"reference_off_model": ["a"], "source": "user"}),
    "off-model note a list": _with("regions", {"off_model": [3], "source": "user"}),
    "off-model note of another role": _with("regions", {"off_model": {"platform": _NOTE}, "source": "user"}),
    "off-model count a string": _with("regions", {"off_model": {"reference": {**_NOTE, "count": "3"}}}),
    "off-model count negative": _with("regions", {"off_model": {"reference": {**_NOTE, "count": -1}}}),
    "off-model where a number": _with("regions", {"off_model": {"reference": {**_NOTE, "where": 3}}}),
    "off-model change missing": _with("regions", {"off_model": {"reference": {"count": 0, "where": ""}}}),
    "off-model count not the indices'": _with("regions", {"reference_off_model": [1, 2],
                                                          "off_model": {"reference": _NOTE}}),
    "newer version": _with("version", 99),
}


@pytest.mark.parametrize("case", MALFORMED)
def test_malformed_result_json_is_an_input_error_naming_the_file(case, tmp_path):
    path = tmp_path / "result.json"
    path.write_text(json.dumps(MALFORMED[case]))
    with pytest.raises(InputError, match="result.json"):
        loaded = CalibrationResult.from_json(path)
        loaded.summary()  # what every consumer does first


def test_a_valid_result_json_reads_and_summarises(tmp_path):
    path = tmp_path / "result.json"
    path.write_text(json.dumps(_valid()))
    assert "calibration OK" in CalibrationResult.from_json(path).summary()


def test_a_result_read_back_gives_the_text_and_fingerprint_of_its_file(tmp_path):
    """Programs name their result by the SHA-256 of result.json: reading the file back (with or without
    its side file) must give the same text, so the same fingerprint."""
    written = result(regions={"workpiece": np.arange(10), "reference": np.arange(10, 15), "source": "auto"})
    written.to_json(tmp_path / "result.json")
    text = (tmp_path / "result.json").read_text()
    for with_regions in (True, False):
        back = CalibrationResult.from_json(tmp_path / "result.json", with_regions=with_regions)
        assert back.to_json_text() == text
        assert result_fingerprint(back) == result_fingerprint(written)


def test_reasons_and_candidates_keep_their_codes_and_names_through_result_json(tmp_path):
    """A reason is a code with its sentence (and the object it is about), a candidate pose a record of
    named fields: both come back from result.json as they were, and a reason an older WorkCal wrote as a
    bare sentence reads with the code "unknown"."""
    from workcal_wb.core.result import RIVAL, SINKS, UNCERTAINTY, UNKNOWN, Candidate, Reason, codes

    tie = Reason(RIVAL, "1 clearly different pose(s) explain the view about as well")
    match = MatchResult("ambiguous", "robust", W, reasons=[tie, Reason(SINKS, "it sinks")], ties=[tie],
                        candidates=[Candidate(W), Candidate(W @ frames.rigid(frames.rot_z(180.0)), score=0.9,
                                                            standard_errors_below_best=1.2, rival=True,
                                                            ruled_out_by="free space")])
    reasons = [tie.within("reference match", "reference"), Reason(UNCERTAINTY, "uncertainty 0.4 mm")]
    path = tmp_path / "result.json"
    written = CalibrationResult("failed", W, U=W, V=np.eye(4), workpiece=match, reference=match, reasons=reasons)
    written.to_json(path)
    data = json.loads(path.read_text())
    assert data["reasons"][0] == {"code": "rival", "text": "reference match: " + str(tie), "subject": "reference"}
    back = CalibrationResult.from_json(path)
    assert back.reasons == reasons and codes(back.reference.reasons) == [RIVAL, SINKS] and back.reference.ties == [tie]
    assert back.reference.candidates == match.candidates
    assert back.reference.candidates[1].ruled_out_by == "free space" and back.reference.candidates[1].rival
    data["reasons"] = ["an older sentence"]
    path.write_text(json.dumps(data))
    assert CalibrationResult.from_json(path).reasons == [Reason(UNKNOWN, "an older sentence")]
