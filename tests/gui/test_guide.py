"""The guided flow in the real FreeCAD window at its default size (Xvfb), recorded as a macro.

From a new document to the robot program, through the guide's pages as a designer uses them: every
page fits FreeCAD's default task panel (no text cut off, no sideways scrolling), every step brings the
3D view to what it is about (the scan fills at least a third of it), the result shows the verdict and
W, the deviation map's legend stays clear of the navigation cube, and the export step offers the
machine profile.  A screenshot of the window is taken at each step.  The macro FreeCAD recorded meanwhile
is then run by freecadcmd, which must find the same W.

The tests share one document and run in file order; a failed step makes the later ones skip.
"""
import json
import os
import re
import subprocess
import sys

import numpy as np
import pytest

FreeCAD = pytest.importorskip("FreeCAD")
if not FreeCAD.GuiUp:
    pytest.skip("needs the FreeCAD GUI (run tests/gui/run_gui_tests.py under xvfb-run freecad)",
                allow_module_level=True)

import FreeCADGui  # noqa: E402

from workcal_wb.core import frames  # noqa: E402
from workcal_wb.core.toolpath import linearised, read_gcode  # noqa: E402
from workcal_wb.fc import calibration_object as co  # noqa: E402
from workcal_wb.fc import lookups  # noqa: E402
from workcal_wb.fc.placements import matrix_of  # noqa: E402
from workcal_wb.fc.scan import PARAMS, scan_cloud  # noqa: E402
from workcal_wb.fc.toolpath_input import read_toolpath  # noqa: E402
from workcal_wb.gui.task_panels import QtCore, QtWidgets, common  # noqa: E402

ROT_TOL_DEG, TRANS_TOL_MM = 0.05, 0.1
MACRO = "workcal_guided_flow"


@pytest.fixture(scope="module")
def flow(tmp_path_factory, request, workbench):
    """The simulated scene's files, the macro being recorded, and what each step made."""
    from workcal_wb.cli.simulate import write_simulation

    folder = tmp_path_factory.mktemp("guided")
    scene, scans = write_simulation(folder, "car", seed=0, clay_change=["lump"])
    group = FreeCAD.ParamGet(PARAMS)
    units = group.GetString("ScanUnits", "")
    group.SetString("ScanUnits", "mm")
    state = {"dir": folder, "scene": scene, "scan_truth": scans[0][1],
             "failures_at_start": request.session.testsfailed}
    yield state
    if units:
        group.SetString("ScanUnits", units)
    else:
        group.RemString("ScanUnits")
    if FreeCADGui.Control.activeDialog():
        FreeCADGui.Control.closeDialog()
    doc = state.get("doc")
    if doc is not None and doc.Name in FreeCAD.listDocuments():
        FreeCAD.closeDocument(doc.Name)


@pytest.fixture
def step(flow, request):
    if request.session.testsfailed > flow["failures_at_start"]:
        pytest.skip("an earlier step of the guided flow failed")
    return flow


def guide():
    from workcal_wb.gui.task_panels.guide import GuidePanel

    panel = GuidePanel.current
    assert panel is not None and panel.alive() and FreeCADGui.Control.activeDialog(), "the guide is not open"
    return panel


def pump(seconds=0.05):
    common.process_events(seconds)


@pytest.fixture
def check_page(page_fits):
    """``check_page(panel, name)``: the page of ``name`` is shown, fits the panel and every text is whole."""

    def check(panel, name):
        assert panel.shown == name
        page_fits(panel.form)

    return check


@pytest.fixture
def scan_share(view_share):
    from workcal_wb.fc.setup import get_setup

    return lambda doc: view_share(scan_cloud(get_setup(doc)["scan"]).points)


def record_macro(folder):
    """Start FreeCAD's macro recorder (Macro > Macro recording...) on ``folder``/MACRO.FCMacro."""
    started = []

    def fill_in():
        dialog = QtWidgets.QApplication.activeModalWidget()
        if dialog is None or dialog.findChild(QtWidgets.QLineEdit, "lineEditPath") is None:
            QtCore.QTimer.singleShot(50, fill_in)
            return
        dialog.findChild(QtWidgets.QLineEdit, "lineEditMacroPath").setText(os.path.join(str(folder), ""))
        dialog.findChild(QtWidgets.QLineEdit, "lineEditPath").setText(MACRO)
        dialog.findChild(QtWidgets.QPushButton, "buttonStart").click()
        started.append(True)

    QtCore.QTimer.singleShot(50, fill_in)
    FreeCADGui.runCommand("Std_DlgMacroRecord")
    pump(0.1)
    assert started, "the macro recorder did not start"


def stop_recording():
    """Macro > Stop macro recording: its own command on FreeCAD 0.20; on 1.x the record command toggles."""
    stop = "Std_MacroStopRecord" if "Std_MacroStopRecord" in FreeCADGui.listCommands() else "Std_DlgMacroRecord"
    FreeCADGui.runCommand(stop)
    pump(0.1)


def test_01_scan(step, shoot_window, check_page, scan_share):
    from workcal_wb.gui.commands.guide import open_guide

    record_macro(step["dir"])
    FreeCADGui.runCommand("Std_New")
    pump(0.2)
    doc = FreeCAD.ActiveDocument
    step["doc"] = doc
    panel = open_guide(doc)
    assert panel.shown == "scan" and panel.next_step() == "scan"
    panel.steps["scan"].import_files([str(step["dir"] / "scan.ply")])
    states = panel.states()
    assert states["scan"][0] == "done" and "scan.ply" in states["scan"][1]
    assert panel.next_step() == "models" and "Models" in panel.next_button.text()
    check_page(panel, "scan")
    assert scan_share(doc) >= 1 / 3
    assert panel.labels.texts == ["Scan"]
    shoot_window("01_scan")


def test_02_models(step, shoot_window, check_page, view_share):
    panel = guide()
    panel.go("models")
    page = panel.steps["models"]
    page.load_file("workpiece", str(step["dir"] / "workpiece.ply"), units="mm")
    page.load_file("reference", str(step["dir"] / "reference.ply"), units="mm")
    assert panel.states()["models"][0] == "done"
    assert page.combos["workpiece"].currentText() == "workpiece.ply"
    check_page(panel, "models")
    from workcal_wb.fc.setup import get_setup

    chosen = get_setup(step["doc"])
    points = np.vstack([np.array([tuple(v) for v in chosen[r].Mesh.Topology[0]]) for r in ("workpiece", "reference")])
    assert view_share(points) >= 1 / 3
    assert len(panel.labels.texts) == 2
    shoot_window("02_models")


def test_03_regions(step, shoot_window, check_page, scan_share):
    panel = guide()
    assert panel.next_step() == "regions"
    panel.go("regions")
    panel.steps["regions"].find()
    state, text = panel.states()["regions"]
    assert state == "done" and "found" in text
    check_page(panel, "regions")
    assert scan_share(step["doc"]) >= 1 / 3
    assert panel.labels.texts == ["Workpiece", "Reference object"]
    shoot_window("03_regions")


def test_04_calibrate(step, shoot_window, check_page, scan_share):
    panel = guide()
    assert panel.next_step() == "calibrate"
    panel.go("calibrate")
    page = panel.steps["calibrate"]
    check_page(panel, "calibrate")
    assert scan_share(step["doc"]) >= 1 / 3
    assert page.auto_regions.isChecked() is False and page.picked_regions.isChecked()  # the regions just found
    assert not page.advanced.isVisible()  # method, seed, refits, scanner position, up: out of the way
    page.advanced_toggle.click()
    assert page.advanced.isVisible() and page.scanner.value() is None and page.up.value() is None  # automatic
    # Where the scanner stood (the scan is in its frame S) and which way is up (B's z seen from S).
    page.set_options(scanner_origin=("0", "", ""))
    assert not page.start() and "Scanner position" in page.last_error and panel.calibration() is None
    up = tuple(float(v) for v in step["scan_truth"].V[:3, :3] @ np.array([0.0, 0.0, 1.0]))
    page.set_options(scanner_origin=(0, 0, 0), up=up)
    assert page.message.text() == ""  # the complaint went with the mended field
    check_page(panel, "calibrate")
    shoot_window("04_calibrate_advanced")
    page.advanced_toggle.click()
    assert page.start()
    assert page.cancel_button.isVisible()
    shoot_window("04_calibrating")
    # The core calibration runs with them.
    assert page.runner.inputs.options.scanner_origin == (0.0, 0.0, 0.0)
    assert page.runner.inputs.options.up == pytest.approx(up, abs=1e-6)
    assert page.wait(180) == "done", page.last_error
    assert panel.shown == "result"  # the result step opens by itself and stays open
    # Stored on the calibration object, read back as the core's options and into the page.
    cal = panel.calibration()
    assert cal.ScannerOn and tuple(cal.Scanner) == (0.0, 0.0, 0.0) and tuple(cal.Up) == pytest.approx(up, abs=1e-6)
    options = co.options_of(cal)
    assert options.scanner_origin == (0.0, 0.0, 0.0) and options.up == pytest.approx(up, abs=1e-6)
    page.refresh()
    assert page.scanner.value() == (0.0, 0.0, 0.0) and page.up.value() == pytest.approx(up, abs=1e-5)
    step["up"] = up


def test_05_result(step, shoot_window, check_page, scan_share):
    panel = guide()
    page = panel.steps["result"]
    cal = panel.calibration()
    assert cal is not None and cal.Status == "ok", cal.Reasons
    W = matrix_of(cal.W)
    truth = step["scene"].W
    assert frames.rotation_between_deg(W, truth) < ROT_TOL_DEG and np.linalg.norm(W[:3, 3] - truth[:3, 3]) < TRANS_TOL_MM
    check_page(panel, "result")
    # The verdict in words and in colour, W as a placement and as the paper's angles, the checks.
    assert page.verdict.text().startswith("OK") and "#2e7d32" in page.verdict.styleSheet()
    x, y, z = W[:3, 3]
    assert page.position.text() == f"{x:.3f}, {y:.3f}, {z:.3f}"
    phi, theta, psi = frames.euler_zyz(W)
    assert page.euler.text() == f"{phi:.3f}, {theta:.3f}, {psi:.3f}"
    assert page.omega.text() == f"{frames.omega(W):.3f} deg"
    assert "phi, theta, psi" in page.euler.toolTip() and "Omega" in page.omega.toolTip()
    gates = lookups.result_of(cal).quality_gates
    assert page.checks.rowCount() == len(gates) > 5
    assert all(page.checks.item(i, 2).text() == "\u2713" for i in range(len(gates)))
    assert "toolpath" not in page.uncertainty.text() or "mm" in page.uncertainty.text()
    assert not page.poses.isVisible()  # an ok result has no rival poses to step through
    # The models placed on the scan, the scan filling the view, both labelled.
    from workcal_wb.fc.placed_model import ON_SCAN, find

    assert all(find(cal, r, ON_SCAN).ViewObject.Visibility for r in ("workpiece", "reference"))
    assert scan_share(step["doc"]) >= 1 / 3
    assert panel.labels.texts == ["Workpiece model, placed", "Reference model, placed"]
    shoot_window("05_result")
    # The report, written and shown.
    html = page.open_report()
    assert html and os.path.isfile(html) and page.report_shown in ("freecad", "browser")
    # Accept: recorded, and the guide moves on.
    page.accept_button.click()
    pump(0.1)
    assert cal.Accepted and panel.shown == "toolpath"
    step["cal"] = cal


def test_06_deviation_map(step, shoot_window, settle, view_share):
    from workcal_wb.gui.view import navigation_cube_rect
    from workcal_wb.fc.deviation_map import scale_of
    from workcal_wb.gui.view_providers.deviation_map import FONT_PIXELS, legend_image, legend_rect

    panel = guide()
    panel.go("result")
    page = panel.steps["result"]
    page.map_button.click()
    settle()
    from workcal_wb.fc.deviation_map import deviation_maps

    [dev] = deviation_maps(step["cal"])
    assert dev.ViewObject.Visibility and not panel.calibration().Scan.ViewObject.Visibility
    assert dev.Limit.Value == pytest.approx(3 * dev.Tolerance.Value)  # against the tolerance
    vp = dev.ViewObject.Proxy
    assert vp.switch.whichChild.getValue() == 0
    width, height = FreeCADGui.ActiveDocument.ActiveView.getSize()

    def clear_of_the_cube():
        legend = legend_rect(vp.image_size, (width, height))
        cube = navigation_cube_rect(width, height)
        assert cube is not None
        overlap_x = min(legend[2], cube[2]) - max(legend[0], cube[0])
        overlap_y = min(legend[3], cube[3]) - max(legend[1], cube[1])
        assert overlap_x <= 0 or overlap_y <= 0, f"legend {legend} overlaps the navigation cube {cube}"
        return legend

    assert clear_of_the_cube()[3] == height  # the cube sits top right by default: the legend bottom right
    assert FONT_PIXELS >= 12 and legend_image(scale_of(dev))[1].pixelSize() >= 12  # legible
    assert vp.image_size[1] < height - 132
    # With the cube moved to the bottom-right corner (both FreeCAD versions' preferences), the legend
    # moves to the top.
    groups = [FreeCAD.ParamGet(f"User parameter:BaseApp/Preferences/{g}") for g in ("View", "NaviCube")]
    try:
        for group in groups:
            group.SetInt("CornerNaviCube", 3)
        dev.Legend = False
        dev.Legend = True
        assert clear_of_the_cube()[1] == 0
    finally:
        for group in groups:
            group.RemInt("CornerNaviCube")
        dev.Legend = False
        dev.Legend = True
    assert view_share(np.array([tuple(p) for p in dev.Points.Points])) >= 1 / 3
    shoot_window("06_deviation_map")
    page.map_button.click()  # back to the scan
    assert not dev.ViewObject.Visibility and panel.calibration().Scan.ViewObject.Visibility


def test_07_toolpath(step, shoot_window, check_page, view_share):
    panel = guide()
    panel.go("toolpath")
    page = panel.steps["toolpath"]
    gcode = str(step["dir"] / "toolpath.nc")
    from workcal_wb.gui.actions import start_folder

    assert os.path.samefile(start_folder(step["doc"]), step["dir"])  # the file dialog opens where the scan lies
    page.use_file(gcode)
    assert page.choice.currentText() == "toolpath.nc"
    made = page.show_in_robot_frame()
    assert made is not None and panel.states()["toolpath"][0] == "done"
    moved = read_gcode(gcode)
    shown = read_toolpath(made).points()
    np.testing.assert_allclose(shown, frames.apply(matrix_of(step["cal"].W), linearised(moved).points()), atol=1e-5)
    check_page(panel, "toolpath")
    assert made.ViewObject.Visibility and made.ViewObject.DisplayMode in made.ViewObject.listDisplayModes()
    from workcal_wb.fc.placed_model import IN_ROBOT_FRAME, find

    placed = find(step["cal"], "workpiece", IN_ROBOT_FRAME)
    assert placed.ViewObject.Visibility
    model = placed.Mesh.copy()
    model.Placement = placed.Placement
    assert view_share(np.vstack([shown, [tuple(v) for v in model.Topology[0]]])) >= 1 / 3  # the path on the part
    assert panel.labels.texts[:2] == ["Toolpath in the robot frame", "Workpiece, placed"]
    shoot_window("07_toolpath")


def test_08_export_with_the_machine_profile(step, shoot_window, check_page):
    panel = guide()
    panel.go("export")
    page = panel.steps["export"]
    check_page(panel, "export")
    # The toolpath is the one chosen in the toolpath step: no second choice here.
    assert os.path.dirname(page.path.text()) == str(step["dir"]) and "toolpath" in os.path.basename(page.path.text())
    # G-code for a 3-axis machine: the sample scene's part sits tilted, so it is refused, in words.
    out = step["dir"] / "part.nc"
    page.set_options(fmt="gcode", machine="3axis", path=out)
    assert page.tilt.isVisible() and not page.rotary.isVisible()
    assert page.export() is None and not out.exists()
    text = page.refusal_text.text()
    assert page.refusal.isVisible() and "tilted" in text and "--" not in text  # no command-line flags
    check_page(panel, "export")
    shoot_window("08_export_refused")
    expected = frames.apply(matrix_of(step["cal"].W), linearised(read_gcode(str(step["dir"] / "toolpath.nc"))).points())
    # Allowing the tilt: the vertical tolerance set on the page is the one the exporter checked.
    page.allow_button.click()
    assert page.machine_profile() == "3axis" and page.tilt.value() == pytest.approx(page.allowed) and out.exists()
    header = out.read_text().splitlines()[:30]
    assert any("machine 3axis" in line for line in header)
    assert any(f"within the tolerance {page.tilt.value():g} deg" in line for line in header), header
    np.testing.assert_allclose(read_gcode(out).points(), expected, atol=1e-3)
    page.five_axis_button.click()
    assert page.machine_profile() == "5axis-tcp" and page.rotary.isVisible() and out.exists()
    assert panel.states()["export"][0] == "done"
    header = out.read_text().splitlines()[:30]
    assert any("machine 5axis-tcp" in line for line in header)
    letters = page.rotary.currentData().upper()
    assert any(f"rotary axes {letters[0]} {letters[1]}" in line for line in header), header
    np.testing.assert_allclose(read_gcode(out).points(), expected, atol=1e-3)
    # A robot program: the machine profile is the robot's, not to be chosen.
    page.set_options(fmt="krl", path=step["dir"] / "part.src")
    assert not page.machine.isEnabled() and page.machine_profile() == "robot"
    assert page.robot.isVisible() and not page.tcp.isVisible()  # no robot chosen: no TCP to give
    assert page.export() is not None and (step["dir"] / "part.src").exists()
    assert "reach not checked (no robot given)" in (step["dir"] / "part.src").read_text()
    # The robot that runs it, with its TCP: the program is checked against it and takes its configuration.
    assert [page.robot.itemData(i) for i in range(1, page.robot.count())] == [
        "kuka_kr120_r2700_2", "kuka_kr16_2", "kuka_kr6_r700_sixx"]  # the KUKA robots only, for KRL
    page.set_options(robot="kuka_kr16_2", tool="0, 0, 150, 0, 0, 0")
    assert page.tcp.isVisible() and page.export() is not None
    text = (step["dir"] / "part.src").read_text()
    assert ";reach: checked for KUKA KR 16-2 (kuka_kr16_2) with the TCP X 0.000 Y 0.000 Z" in text
    assert re.search(r"^PTP \{X [^}]*, S [0-7], T \d+\}$", text, flags=re.M)
    # A robot too small for where the part sits: refused, the question says why and where to put the part.
    page.set_options(robot="kuka_kr6_r700_sixx")
    asked = []
    assert page.export(confirm=lambda reason: asked.append(reason) or False) is None
    assert "cannot follow this program" in asked[0] and "move the part" in asked[0] and "--" not in asked[0]
    assert ";reach: checked for KUKA KR 16-2" in (step["dir"] / "part.src").read_text()  # left as it was
    page.set_options(tool="0, 0, 150")
    assert page.export() is None  # a TCP of three numbers: refused naming the field
    page.set_options(robot="kuka_kr16_2", tool="0, 0, 150, 0, 0, 0")
    check_page(panel, "export")
    shoot_window("08_export")
    stop_recording()


def test_09_the_recorded_macro_replays_headless(step, output_dir):
    """The macro of the whole calibration, run by freecadcmd in a fresh process, gives the same W."""
    macro = step["dir"] / f"{MACRO}.FCMacro"
    assert macro.is_file(), "FreeCAD wrote no macro"
    text = macro.read_text(encoding="utf-8")
    for call in ("workcal_wb.fc.scan.import_scan", "workcal_wb.fc.models.import_model", "workcal_wb.fc.setup.choose_models",
                 "workcal_wb.fc.regions.auto_regions", "workcal_wb.fc.calibration_object.make_calibration",
                 "workcal_wb.fc.calibration_object.accept", "workcal_wb.fc.setup.choose_toolpath",
                 "workcal_wb.fc.toolpath.make_calibrated_path", "workcal_wb.fc.toolpath.export_program"):
        assert call in text, f"{call} was not recorded"
    assert "workcal_wb.gui" not in text
    assert "scanner_origin=(0.0, 0.0, 0.0)" in text and f"up=({step['up'][0]!r}," in text  # the advanced options
    assert "robot='kuka_kr16_2', tool=[0.0, 0.0, 150.0, 0.0, 0.0, 0.0]" in text  # the export's robot and TCP
    (output_dir / f"{MACRO}.FCMacro").write_text(text, encoding="utf-8")
    result = step["dir"] / "replayed.json"
    script = step["dir"] / "replay.py"
    script.write_text(
        "import json, FreeCAD\n"
        f"exec(compile(open({str(macro)!r}).read(), {str(macro)!r}, 'exec'))\n"
        "from workcal_wb.fc.lookups import find_calibrations\n"
        "from workcal_wb.fc.placements import matrix_of\n"
        "[cal] = find_calibrations(FreeCAD.ActiveDocument)\n"
        f"json.dump({{'W': matrix_of(cal.W).tolist(), 'status': cal.Status, 'accepted': cal.Accepted}}, "
        f"open({str(result)!r}, 'w'))\n", encoding="utf-8")
    done = subprocess.run(["freecadcmd", str(script)], env=dict(os.environ), capture_output=True, text=True,
                          timeout=600)
    assert result.is_file(), f"replay failed:\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
    replayed = json.loads(result.read_text())
    assert replayed["status"] == "ok" and replayed["accepted"]
    np.testing.assert_allclose(replayed["W"], matrix_of(step["cal"].W), atol=1e-9)
    sys.stdout.write(f"\nreplayed {macro.name}: W equal to 1e-9\n")
