"""The document-level use cases a headless script calls (the GUI records the same calls): the toolpath
chosen once and used by the calibration, the calibrated toolpath and the program; regions as ranges;
the report; one identity scheme.  Under freecadcmd, without any GUI module."""
import json
import sys

import numpy as np
import pytest

FreeCAD = pytest.importorskip("FreeCAD")

from workcal_wb.core import frames  # noqa: E402
from workcal_wb.core.errors import InputError  # noqa: E402
from workcal_wb.core.geometry import Cloud  # noqa: E402
from workcal_wb.core.result import CalibrationResult  # noqa: E402
from workcal_wb.core.simulate.scanner import Scanner  # noqa: E402
from workcal_wb.core.simulate.scene import build_scene  # noqa: E402
from workcal_wb.core.simulate.toolpath_sample import sample_toolpath  # noqa: E402
from workcal_wb.core.toolpath import (CalibrationNotOk, Move, ToolTilted, Toolpath, format_gcode, linearised,  # noqa: E402
                                      read_gcode)
from workcal_wb.core.toolpath.safety import PathOffModel  # noqa: E402
from workcal_wb.fc import calibration_object as co  # noqa: E402
from workcal_wb.fc import lookups  # noqa: E402
from workcal_wb.fc import proxies, regions, report, setup, toolpath, toolpath_input  # noqa: E402
from workcal_wb.fc.models import add_model  # noqa: E402
from workcal_wb.fc.placements import matrix_of  # noqa: E402
from workcal_wb.fc.scan import get_regions, make_scan  # noqa: E402

SEED = 0


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    world = build_scene("car", seed=0, clay_change=["lump"])
    scan = Scanner.aimed_at(world).scan(world)
    folder = tmp_path_factory.mktemp("use_cases")
    gcode = folder / "finishing.nc"
    gcode.write_text(format_gcode(sample_toolpath(world)), encoding="utf-8")
    return {"world": world, "scan": scan, "gcode": str(gcode), "dir": folder}


@pytest.fixture
def doc(scene):
    """A document with its setup (scan, both models), its toolpath chosen, undo on."""
    document = FreeCAD.newDocument("WorkCalUseCases")
    document.UndoMode = 1
    world = scene["world"]
    setup.set_setup(document, scan=make_scan(document, Cloud(scene["scan"].points, name="scan"), "Scan"),
                    workpiece=add_model(document, world.workpiece_model(), "Workpiece"),
                    reference=add_model(document, world.reference_model(), "Reference"))
    document.recompute()
    name = document.Name
    yield document
    if name in FreeCAD.listDocuments():
        FreeCAD.closeDocument(name)


def names(doc):
    return sorted(o.Name for o in doc.Objects)


@pytest.mark.slow
def test_the_toolpath_is_chosen_once_and_used_everywhere(doc, scene, tmp_path):
    with pytest.raises(InputError, match="nothing.nc"):
        setup.choose_toolpath(doc, str(tmp_path / "nothing.nc"))
    assert setup.toolpath_of(doc) is None
    setup.choose_toolpath(doc, scene["gcode"])
    assert setup.toolpath_of(doc) == scene["gcode"] and doc.UndoNames[0] == "Choose toolpath"
    cal = co.make_calibration(doc, seed=SEED, resamples=2)  # scan, models and toolpath from the setup
    assert cal.Status == "ok", cal.Reasons
    assert cal.GcodeFile == scene["gcode"] and lookups.result_of(cal).inputs["toolpath_points"] > 100
    # The calibrated toolpath: the chosen toolpath carried into B by W, a Path object that follows W.
    path_obj = toolpath.make_calibrated_path(cal)
    assert proxies.type_of(path_obj) == toolpath.TYPE and toolpath.calibrated_paths(cal) == [path_obj]
    expected = linearised(read_gcode(scene["gcode"])).points()
    shown = toolpath_input.read_toolpath(path_obj).points()
    np.testing.assert_allclose(shown, frames.apply(matrix_of(cal.W), expected), atol=1e-5)
    assert np.abs(shown - frames.apply(scene["world"].W, expected)).max() < 0.1  # against the truth
    assert "finishing.nc" in path_obj.Label
    # The program from the same toolpath, for a 5-axis machine (the sample scene's part sits tilted).
    out = tmp_path / "part.nc"
    with pytest.raises(ToolTilted) as refused:
        toolpath.export_program(cal, out, "gcode")  # 3-axis by default
    assert refused.value.tilt_deg > refused.value.tolerance_deg and not out.exists()
    job = toolpath.export_program(cal, out, "gcode", machine="5axis-tcp", rotary="ac")
    assert job.machine == "5axis-tcp" and out.exists()
    np.testing.assert_allclose(read_gcode(out, rotary="ac").points(), frames.apply(matrix_of(cal.W), expected),
                               atol=1e-3)
    assert "on the workpiece model Workpiece: cutting moves a median" in out.read_text().replace(")\n(", " ")
    # Another part's toolpath (its pass 40 mm off this part's surface) is refused by both, naming the model.
    chosen = read_gcode(scene["gcode"])
    other = tmp_path / "other.nc"
    other.write_text(format_gcode(Toolpath.from_moves([Move(m.kind, m.end + 40 * m.tool_axis, feed=m.feed,
                                                            tool_axis=m.tool_axis) for m in chosen.moves])))
    before = names(doc)
    with pytest.raises(PathOffModel, match="from the workpiece model Workpiece"):
        toolpath.make_calibrated_path(cal, source=str(other))
    assert names(doc) == before
    with pytest.raises(PathOffModel) as refused:
        toolpath.export_program(cal, tmp_path / "other_calibrated.nc", "gcode", source=str(other),
                                machine="5axis-tcp", rotary="ac")
    assert 35 < refused.value.median_mm < 45 and not (tmp_path / "other_calibrated.nc").exists()


@pytest.mark.slow
def test_a_calibration_that_is_not_ok_refuses_the_calibrated_toolpath(doc, scene):
    setup.choose_toolpath(doc, scene["gcode"])
    cal = co.make_calibration(doc, seed=SEED, resamples=1)
    good = lookups.result_of(cal)
    co.store_result(cal, CalibrationResult.from_dict({**good.to_dict(), "status": "ambiguous",
                                                      "reasons": ["test: two poses"]}), cal.InputsKey)
    before = names(doc)
    with pytest.raises(CalibrationNotOk) as refused:
        toolpath.make_calibrated_path(cal)
    assert refused.value.status == "ambiguous" and names(doc) == before
    forced = toolpath.make_calibrated_path(cal, force=True)
    assert forced.Forced and forced.Label.endswith("(FORCED)")
    assert forced.Path.Commands[0].Name.startswith("(FORCED EXPORT")
    with pytest.raises(InputError, match="only an ok calibration"):
        co.accept(cal)


@pytest.mark.slow
def test_accepting_is_one_undo_step_and_a_new_result_clears_it(doc):
    cal = co.make_calibration(doc, seed=SEED, resamples=1)
    co.accept(cal)
    assert cal.Accepted and doc.UndoNames[0] == "Accept the calibration"
    doc.undo()
    assert not cal.Accepted
    doc.redo()
    co.update_calibration(cal, tolerance_mm=0.4)
    assert not cal.Accepted and lookups.result_of(cal).tolerance_mm == pytest.approx(0.4)


def test_picked_regions_recorded_as_ranges_replay_exactly(doc, scene):
    scan = setup.get_setup(doc)["scan"]
    truth = {role: np.flatnonzero(scene["scan"].mask(role)) for role in ("workpiece", "reference")}
    runs = {role: regions.ranges(idx) for role, idx in truth.items()}
    assert all(len(r) < len(truth[role]) / 5 for role, r in runs.items())  # a scan's rows: few runs
    regions.set_regions(scan, workpiece=regions.indices(runs["workpiece"]), reference=regions.indices(runs["reference"]))
    found = get_regions(scan)
    for role in truth:
        np.testing.assert_array_equal(found[role], truth[role])
    assert found["source"] == "user" and doc.UndoNames[0] == "Pick scan regions"
    assert regions.ranges([]) == [] and len(regions.indices([])) == 0
    assert regions.clear_regions(scan) and not regions.clear_regions(scan)


@pytest.mark.slow
def test_the_report_uses_the_deviation_map_scale(doc, tmp_path):
    from workcal_wb.fc.deviation_map import make_deviation_map

    cal = co.make_calibration(doc, seed=SEED, resamples=1)
    paths = report.write_report(cal, str(tmp_path / "plain"))
    assert json.loads(open(paths["json"]).read())["deviation"]["colour_scale"]["limit_mm"] == pytest.approx(
        3 * cal.Tolerance.Value)
    dev = make_deviation_map(cal, limit_mm=2.0)
    assert not dev.AutoLimit and dev.Limit.Value == pytest.approx(2.0)
    paths = report.write_report(cal, str(tmp_path / "with_map"))
    data = json.loads(open(paths["json"]).read())
    assert data["deviation"]["colour_scale"] == {"tolerance_mm": pytest.approx(cal.Tolerance.Value),
                                                 "limit_mm": pytest.approx(2.0)}


@pytest.mark.slow
def test_one_identity_scheme_and_older_files_lose_their_role_property(doc, tmp_path):
    cal = co.make_calibration(doc, seed=SEED, resamples=1, overlays=True)
    kinds = {proxies.type_of(o) for o in doc.Objects} - {None}
    assert kinds == {"WorkCal::Scan", "WorkCal::Setup", "WorkCal::Calibration", "WorkCal::PlacedModel"}
    assert all(not hasattr(o, "WorkCalRole") for o in doc.Objects)
    cal.addProperty("App::PropertyString", "WorkCalRole", "Base", "how WorkCal 0.1 recognised its objects")
    cal.WorkCalRole = "WorkCalCalibration"
    # As WorkCal 0.1 saved it: long property names, W also as a matrix, the status as text.
    W = matrix_of(cal.W)
    cal.removeProperty("Frames")
    cal.addProperty("App::PropertyBool", "ShowFrames", "Display", "")
    cal.ShowFrames = False
    cal.removeProperty("Status")
    cal.addProperty("App::PropertyString", "Status", "Result", "")
    cal.Status = "ok"
    cal.addProperty("App::PropertyMatrix", "WMatrix", "Result", "")
    path = str(tmp_path / "older.FCStd")
    doc.saveAs(path)
    name = cal.Name
    FreeCAD.closeDocument(doc.Name)
    reopened = FreeCAD.openDocument(path)
    try:
        cal = reopened.getObject(name)
        assert lookups.is_calibration(cal) and "WorkCalRole" not in cal.PropertiesList
        assert lookups.find_calibrations(reopened) == [cal]
        assert {"ShowFrames", "WMatrix"}.isdisjoint(cal.PropertiesList) and cal.Frames is False
        assert cal.getTypeIdOfProperty("Status") == "App::PropertyEnumeration" and cal.Status == "ok"
        np.testing.assert_allclose(matrix_of(cal.W), W, atol=1e-9)
        assert "Touched" not in cal.State
    finally:
        FreeCAD.closeDocument(reopened.Name)


def test_no_gui_module_was_imported():
    """Everything above ran through workcal_wb.fc without pulling in the GUI layer."""
    assert not [m for m in sys.modules if m.startswith("workcal_wb.gui")]


def test_the_report_views_summary_of_a_calibration_has_no_command_line_flags(monkeypatch):
    from workcal_wb.core.result import Reason

    said = []
    monkeypatch.setattr(FreeCAD.Console, "PrintWarning", said.append)
    result = CalibrationResult(status="failed", W=None,
                               reasons=[Reason("not_found", "the scan shows too little of it (use --regions auto)")])
    co.report(result, "Calibration")
    assert len(said) == 1 and "too little of it" in said[0] and "--" not in said[0], said
