"""The calibration document object under freecadcmd: truth, save/reopen, recompute, bad inputs, deviation map."""
import json

import numpy as np
import pytest

FreeCAD = pytest.importorskip("FreeCAD")

from workcal_wb.core import frames  # noqa: E402
from workcal_wb.core.errors import InputError  # noqa: E402
from workcal_wb.core.geometry import Cloud  # noqa: E402
from workcal_wb.core.simulate.scanner import Scanner  # noqa: E402
from workcal_wb.core.simulate.scene import build_scene  # noqa: E402
from workcal_wb.fc import calibration_object as co  # noqa: E402
from workcal_wb.fc import lookups  # noqa: E402
from workcal_wb.fc import placed_model, proxies  # noqa: E402
from workcal_wb.fc.models import add_model  # noqa: E402
from workcal_wb.fc.placements import matrix_of as matrix  # noqa: E402

ROT_TOL_DEG, TRANS_TOL_MM = 0.05, 0.1
SEED = 0  # calibration seed (the default)


@pytest.fixture(scope="module")
def simulated():
    """The car with a clay lump beside the L-block, scanned once; truth U, V, W."""
    scene = build_scene("car", seed=0, clay_change=["lump"])
    scan = Scanner.aimed_at(scene).scan(scene)
    return scene, scan


def add_scan(doc, points: np.ndarray, name: str = "Scan"):
    from workcal_wb.fc.scan import make_scan

    return make_scan(doc, Cloud(points, name=name), name, "mm", "simulated scan")


@pytest.fixture
def document(simulated, tmp_path):
    """A document with the scan, X-A and B-P in it (what WorkCal's import commands produce)."""
    scene, scan = simulated
    doc = FreeCAD.newDocument("WorkCalCalibrationTest")
    objects = {
        "scan": add_scan(doc, scan.points),
        "workpiece": add_model(doc, scene.workpiece_model(), "Workpiece"),
        "reference": add_model(doc, scene.reference_model(), "Reference"),
    }
    doc.recompute()
    name = doc.Name
    yield doc, objects
    if name in FreeCAD.listDocuments():
        FreeCAD.closeDocument(name)


def assert_pose(T, truth, rot_tol=ROT_TOL_DEG, trans_tol=TRANS_TOL_MM):
    assert frames.rotation_between_deg(T, truth) < rot_tol
    assert np.linalg.norm(T[:3, 3] - truth[:3, 3]) < trans_tol


def names(doc):
    return sorted(o.Name for o in doc.Objects)


@pytest.mark.slow
def test_calibration_object_matches_truth_and_survives_reopen(simulated, document, tmp_path):
    scene, scan = simulated
    doc, objs = document
    cal = co.make_calibration(doc, objs["scan"], objs["workpiece"], objs["reference"], tolerance_mm=0.3,
                              method="robust", seed=SEED)
    assert cal.TypeId == "Part::FeaturePython" and lookups.is_calibration(cal)
    assert cal.Status == "ok", cal.Reasons
    W, U, V = matrix(cal.W), matrix(cal.U), matrix(cal.V)
    assert_pose(W, scene.W)
    assert_pose(U, scan.U)
    assert_pose(V, scan.V)
    np.testing.assert_allclose(W, frames.invert(V) @ U, atol=1e-6)
    np.testing.assert_allclose(matrix(cal.Placement), W, atol=1e-6)  # the object sits at W in B
    assert cal.EulerZYZ == co.euler_text(W) and "phi" in cal.EulerZYZ
    assert cal.Omega.Value == pytest.approx(frames.omega(W))
    assert 0 < cal.PartRMS.Value < 0.3 and 0 < cal.RefRMS.Value < 0.3
    assert 0 < cal.AtSurface.Value < 0.3
    assert cal.getEnumerationsOfProperty("Status") == co.STATUSES and not cal.Accepted
    assert cal.FrameSize.Value == pytest.approx(co.FRAME_FRACTION * scene.workpiece_model().diagonal())
    assert cal.Scan == objs["scan"] and cal.Workpiece == objs["workpiece"] and cal.Reference == objs["reference"]
    assert cal.Method == "robust" and cal.Tolerance.Value == pytest.approx(0.3) and cal.Regions == "Auto"
    assert len(cal.Shape.Edges) == 9  # triads of X, B and S
    result = lookups.result_of(cal)
    np.testing.assert_allclose(result.W, W, atol=1e-12)
    stored = json.loads(cal.ResultJson)
    before = {p: cal.getPropertyByName(p) for p in ("Status", "Warnings", "Reasons", "Method", "Regions", "Seed")}
    key, cal_name = cal.InputsKey, cal.Name
    input_names = {role: o.Name for role, o in objs.items()}

    path = str(tmp_path / "calibrated.FCStd")
    doc.saveAs(path)
    FreeCAD.closeDocument(doc.Name)
    doc = FreeCAD.openDocument(path)
    try:
        cal = doc.getObject(cal_name)
        assert isinstance(cal.Proxy, co.CalibrationFeature)
        assert json.loads(cal.ResultJson) == stored
        assert cal.InputsKey == key
        for prop, value in before.items():
            assert cal.getPropertyByName(prop) == value
        np.testing.assert_allclose(matrix(cal.W), W, atol=1e-9)
        np.testing.assert_allclose(matrix(cal.Placement), W, atol=1e-9)
        assert proxies.type_of(cal) == co.TYPE and "WorkCalRole" not in cal.PropertiesList
        assert {"scan": cal.Scan.Name, "workpiece": cal.Workpiece.Name, "reference": cal.Reference.Name} == input_names
        assert "Touched" not in cal.State
        again = lookups.result_of(cal)
        assert again.to_dict() == result.to_dict()

        calls = []
        original = co.fc_inputs.run
        co.fc_inputs.run = lambda *a, **k: calls.append(1) or original(*a, **k)
        try:
            cal.touch()
            doc.recompute()  # same inputs and options: no new calibration
        finally:
            co.fc_inputs.run = original
        assert calls == [] and cal.Status == "ok"
    finally:
        FreeCAD.closeDocument(doc.Name)


@pytest.mark.slow
def test_recomputes_when_the_scan_changes(simulated, document):
    scene, scan = simulated
    doc, objs = document
    cal = co.make_calibration(doc, objs["scan"], objs["workpiece"], objs["reference"], seed=SEED)
    assert cal.Status == "ok"
    # The scanner moved: every scan point seen from a frame 4 mm and 1 deg away.  U and V follow, W does not.
    T = frames.rigid(frames.rot_z(1.0), (4.0, -2.0, 1.0))
    import Points

    objs["scan"].Points = Points.Points([tuple(p) for p in frames.apply(T, scan.points).tolist()])
    doc.recompute()
    assert cal.Status == "ok"
    assert_pose(matrix(cal.U), T @ scan.U)
    assert_pose(matrix(cal.V), T @ scan.V)
    assert_pose(matrix(cal.W), scene.W)
    # An option change recomputes too: the stored options and the result follow.
    cal.Tolerance = 0.5
    doc.recompute()
    assert lookups.result_of(cal).tolerance_mm == pytest.approx(0.5)


@pytest.mark.slow
def test_picked_regions_are_used(simulated, document):
    scene, scan = simulated
    doc, objs = document
    from workcal_wb.fc.scan import set_regions

    with pytest.raises(InputError, match="region"):
        co.make_calibration(doc, objs["scan"], objs["workpiece"], objs["reference"], regions="Picked", seed=SEED)
    set_regions(objs["scan"], workpiece=np.flatnonzero(scan.mask("workpiece")),
                reference=np.flatnonzero(scan.mask("reference")))
    cal = co.make_calibration(doc, objs["scan"], objs["workpiece"], objs["reference"], regions="Picked", seed=SEED)
    assert cal.Regions == "Picked" and lookups.result_of(cal).regions["source"] == "user"
    assert_pose(matrix(cal.W), scene.W)


@pytest.mark.slow
def test_the_points_off_the_models_of_a_loose_region_come_from_the_document(tmp_path):
    """A reference region picked around the block and a band of the platform beside it: the calibration
    object's result says how many of its points lie off the block's model and where (fc.regions.off_model),
    the scan's overlay gets their indices (off_model_points), and once the region is picked again without
    them they are no longer the scan's to show."""
    from loose_regions import platform_band_beside_the_block
    from workcal_wb.fc import regions as fc_regions
    from workcal_wb.fc.scan import set_regions

    scene = platform_band_beside_the_block()
    doc = FreeCAD.newDocument("WorkCalOffModel")
    try:
        scan = add_scan(doc, scene.cloud.points)
        workpiece, reference = add_model(doc, scene.workpiece_model, "Workpiece"), add_model(
            doc, scene.reference_model, "Reference")
        set_regions(scan, workpiece=scene.regions["workpiece"], reference=scene.regions["reference"])
        cal = co.make_calibration(doc, scan, workpiece, reference, regions="Picked", seed=SEED, resamples=2)
        assert cal.Status == "failed" and any("reference region explained" in r for r in cal.Reasons)
        result = lookups.result_of(cal)
        said = fc_regions.off_model(cal)
        np.testing.assert_array_equal(said["reference"]["indices"], result.regions["reference_off_model"])
        assert said["reference"]["count"] > 1000 and "platform's plane" in said["reference"]["where"]
        assert said["workpiece"]["count"] == 0
        shown = fc_regions.off_model_points(scan)
        assert list(shown) == ["reference"]
        np.testing.assert_array_equal(shown["reference"], said["reference"]["indices"])
        set_regions(scan, workpiece=scene.regions["workpiece"], reference=scene.block)
        assert fc_regions.off_model_points(scan) == {}
    finally:
        FreeCAD.closeDocument(doc.Name)


def test_bad_inputs_leave_the_document_unchanged(simulated, document):
    doc, objs = document
    group = doc.addObject("App::DocumentObjectGroup", "NotAModel")
    empty = doc.addObject("Points::Feature", "EmptyScan")
    doc.recompute()
    before = names(doc)
    with pytest.raises(InputError, match="NotAModel"):
        co.make_calibration(doc, objs["scan"], group, objs["reference"])
    with pytest.raises(InputError, match="EmptyScan.*(no points|empty)|(no points|empty).*EmptyScan"):
        co.make_calibration(doc, empty, objs["workpiece"], objs["reference"], seed=SEED)
    with pytest.raises(InputError, match="scan cannot also be"):
        co.make_calibration(doc, objs["scan"], objs["scan"], objs["reference"])
    with pytest.raises(InputError, match="method"):
        co.make_calibration(doc, objs["scan"], objs["workpiece"], objs["reference"], method="magic")
    with pytest.raises(InputError, match="tolerance"):
        co.make_calibration(doc, objs["scan"], objs["workpiece"], objs["reference"], tolerance_mm=-1)
    with pytest.raises(InputError, match="no scan"):
        co.make_calibration(doc, None, objs["workpiece"], objs["reference"], seed=SEED)
    assert names(doc) == before


@pytest.mark.slow
def test_failed_calibration_is_kept_with_its_reasons(simulated, document):
    """A tolerance below the scanner noise: the RMS gates fail, the object is still added."""
    from workcal_wb.fc.scan import set_regions

    _, scan = simulated
    doc, objs = document
    set_regions(objs["scan"], workpiece=np.flatnonzero(scan.mask("workpiece")),
                reference=np.flatnonzero(scan.mask("reference")))
    cal = co.make_calibration(doc, objs["scan"], objs["workpiece"], objs["reference"], tolerance_mm=0.05,
                              regions="Picked", resamples=2, seed=SEED)
    assert cal.Status == "failed"
    assert cal.Reasons
    result = lookups.result_of(cal)
    assert result.status == cal.Status


def placed_models(doc):
    return placed_model.objects_of(doc, placed_model.TYPE)


@pytest.mark.slow
def test_placed_model_follows_w(simulated, document):
    scene, _ = simulated
    doc, objs = document
    cal = co.make_calibration(doc, objs["scan"], objs["workpiece"], objs["reference"], seed=SEED)
    placed = placed_model.show_in_robot_frame(cal)
    assert placed_models(doc) == [placed] and placed.Frame == placed_model.IN_ROBOT_FRAME
    assert placed.Source == objs["workpiece"] and placed.Calibration == cal
    W = matrix(cal.W)
    np.testing.assert_allclose(matrix(placed.Placement), W, atol=1e-9)
    # What the view shows is the workpiece model moved by W: X-A in the robot base frame B.
    shown = np.array([tuple(v) for v in placed.Mesh.Topology[0]])
    np.testing.assert_allclose(shown, frames.apply(W, scene.workpiece_model().points), atol=2e-4)  # float32 mesh
    assert placed_model.make_placed_model(cal) == placed  # not duplicated
    # It follows the model and W: move the model in its file's frame X, the calibration runs again and
    # the copy still lands where the scan saw the part.
    objs["workpiece"].Placement = FreeCAD.Placement(FreeCAD.Vector(5, 0, 0), FreeCAD.Rotation())
    doc.recompute()
    moved_W = matrix(cal.W)
    np.testing.assert_allclose(matrix(placed.Placement), moved_W @ frames.rigid(translation=[5, 0, 0]), atol=1e-9)
    np.testing.assert_allclose(matrix(placed.Placement), W, atol=0.05)


@pytest.mark.slow
def test_undo_redo_of_a_calibration_with_its_placed_model(simulated, document):
    """FreeCAD 1.0 leaves a nameless ghost when the creation of an App::Link is undone, duplicates it
    on redo and crashes when the document closes (FreeCAD issues 17900, 18326): undo and redo must
    give back exactly the objects that were there, and closing must work."""
    doc, objs = document
    doc.UndoMode = 1
    before = names(doc)
    cal = co.make_calibration(doc, objs["scan"], objs["workpiece"], objs["reference"], overlays=True,
                              resamples=2, seed=SEED)
    after = names(doc)
    assert len(after) == len(before) + 3 and len(placed_models(doc)) == 2  # the calibration and both models on the scan
    for _ in range(2):
        doc.undo()
        assert [o.Name for o in doc.Objects if o.Name is None] == [] and names(doc) == before
        doc.redo()
        assert names(doc) == after and len(placed_models(doc)) == 2
    assert doc.getObject(cal.Name).Status == "ok"
    FreeCAD.closeDocument(doc.Name)  # used to crash FreeCAD 1.0


@pytest.mark.slow
def test_models_on_the_scan_sit_on_its_points(simulated, document):
    """The result step's overlay: the workpiece model placed by U and the reference model by V land on the
    scan points they were matched to (to the scan's noise), so a wrong match shows at a glance."""
    _, scan = simulated
    doc, objs = document
    cal = co.make_calibration(doc, objs["scan"], objs["workpiece"], objs["reference"], overlays=True, seed=SEED)
    for role in placed_model.ROLES:
        placed = placed_model.find(cal, role, placed_model.ON_SCAN)
        assert placed is not None and placed.Role == role and placed.Candidate == 0
        model = placed.Mesh.copy()
        model.Placement = placed.Placement
        shown = np.array([tuple(v) for v in model.Topology[0]])
        truth = scan.U if role == "workpiece" else scan.V
        source = objs[role].Mesh
        expected = frames.apply(truth, np.array([tuple(v) for v in source.Topology[0]]))
        assert np.abs(shown - expected).max() < 0.3
    assert placed_model.candidate_poses(cal, "workpiece")[0] is not None
    assert placed_model.tie_breaker(cal, "workpiece") == "" or "differ" in placed_model.tie_breaker(cal, "workpiece")


@pytest.mark.slow
def test_deviation_map_shows_the_clay_lump(simulated, document, tmp_path):
    from workcal_wb.core.deviation import BEYOND_ADDED, WITHIN
    from workcal_wb.fc import deviation_map

    scene, scan = simulated
    doc, objs = document
    cal = co.make_calibration(doc, objs["scan"], objs["workpiece"], objs["reference"], seed=SEED)
    before = names(doc)
    dev = deviation_map.make_deviation_map(cal)
    assert names(doc) == sorted(before + [dev.Name])
    d = np.array(dev.Deviations)
    assert len(d) == len(lookups.result_of(cal).regions["workpiece"]) == dev.Points.CountPoints
    assert len(dev.Color) == len(d)
    assert np.nanmax(d) > 1.0  # the lump stands out of the model
    assert dev.Max.Value > 1.0 and dev.Within > 50
    colours = np.array(dev.Color)[:, :3]
    assert np.allclose(colours[int(np.nanargmax(d))], BEYOND_ADDED, atol=1 / 255)  # past the limit: dark red
    # Read against the tolerance: the lump's flanks, out of tolerance by a little, are plainly not green
    # (a scale stretched to the data's extremes painted them green).
    assert dev.AutoLimit and dev.Limit.Value == pytest.approx(3 * dev.Tolerance.Value)
    flank = np.flatnonzero((d > 1.3 * dev.Tolerance.Value) & (d < 2.5 * dev.Tolerance.Value))
    assert len(flank) > 5
    assert np.linalg.norm(colours[flank] - np.array(WITHIN), axis=1).min() > 0.5
    inside = np.flatnonzero(np.abs(d) <= dev.Tolerance.Value)
    np.testing.assert_allclose(colours[inside], np.tile(WITHIN, (len(inside), 1)), atol=1 / 255)
    # The points with a large deviation are where the clay was added (truth: the reshaped vertices).
    moved = scene.reshaped.displacement_mm > 1.0
    lump_centre_S = frames.apply(scan.U, scene.workpiece_model().points[moved].mean(axis=0)[None])[0]
    far = np.array([tuple(p) for p in dev.Points.Points])[d > 1.0]
    assert np.linalg.norm(far.mean(axis=0) - lump_centre_S) < 15.0

    # The map is saved with the document and comes back as it was, without recomputing.
    path, name, colours = str(tmp_path / "deviation.FCStd"), dev.Name, list(dev.Color)
    doc.saveAs(path)
    FreeCAD.closeDocument(doc.Name)
    doc = FreeCAD.openDocument(path)
    try:
        dev = doc.getObject(name)
        assert isinstance(dev.Proxy, deviation_map.DeviationFeature) and deviation_map.is_deviation_map(dev)
        np.testing.assert_array_equal(np.array(dev.Deviations), d)
        np.testing.assert_allclose(np.array(dev.Color), np.array(colours), atol=1 / 255)  # saved as 8-bit RGBA
        assert "Touched" not in dev.State
        assert dev.Calibration is not None and lookups.is_calibration(dev.Calibration)
    finally:
        FreeCAD.closeDocument(doc.Name)


@pytest.mark.slow
def test_deviation_map_refuses_a_calibration_without_u(document):
    from workcal_wb.core.result import CalibrationResult
    from workcal_wb.fc import deviation_map

    doc, objs = document
    cal = co.make_calibration(doc, objs["scan"], objs["workpiece"], objs["reference"], resamples=1, seed=SEED)
    co.store_result(cal, CalibrationResult("failed", W=None, reasons=["test: no pose"]), cal.InputsKey)
    before = names(doc)
    with pytest.raises(InputError, match="no U"):
        deviation_map.make_deviation_map(cal)
    assert names(doc) == before


@pytest.mark.slow
def test_uncertainty_at_a_gcode_toolpath(simulated, document, tmp_path):
    from workcal_wb.core.simulate.toolpath_sample import sample_toolpath
    from workcal_wb.core.toolpath import format_gcode

    scene, _ = simulated
    doc, objs = document
    gcode = tmp_path / "finishing.nc"
    gcode.write_text(format_gcode(sample_toolpath(scene)), encoding="utf-8")
    cal = co.make_calibration(doc, objs["scan"], objs["workpiece"], objs["reference"], toolpath=str(gcode),
                              seed=SEED)
    assert cal.GcodeFile == str(gcode) and cal.Toolpath is None
    result = lookups.result_of(cal)
    assert result.inputs["toolpath_points"] > 100
    assert 0 < cal.AtToolpath.Value == pytest.approx(result.uncertainty["toolpath_bound_mm"])
    assert cal.AtToolpath.Value < 0.3
    calls = []
    original = co.fc_inputs.run
    co.fc_inputs.run = lambda *a, **k: calls.append(1) or original(*a, **k)
    try:
        cal.touch()
        doc.recompute()  # the file is part of the inputs: unchanged, so no new calibration
    finally:
        co.fc_inputs.run = original
    assert calls == []


@pytest.mark.slow
def test_scanner_origin_and_up_are_document_inputs(simulated, document):
    """Where the scanner stood and which way is up, in the scan's coordinates: inputs of the document
    (the GUI's advanced options), stored on the object and used when it recomputes."""
    scene, scan = simulated
    doc, o = document
    up = tuple(float(v) for v in scan.V[:3, :3] @ np.array([0.0, 0.0, 1.0]))
    obj = co.make_calibration(doc, o["scan"], o["workpiece"], o["reference"], scanner_origin=(0.0, 0.0, 0.0), up=up,
                              resamples=2)
    assert obj.ScannerOn and tuple(obj.Scanner) == (0.0, 0.0, 0.0) and tuple(obj.Up) == pytest.approx(up)
    options = co.options_of(obj)
    assert options.scanner_origin == (0.0, 0.0, 0.0) and options.up == pytest.approx(up)
    assert co.inputs_of(obj).options == options
    assert obj.Status == "ok"
    assert_pose(matrix(obj.W), scene.W)
    co.update_calibration(obj, resamples=2)  # options not given stay
    assert co.options_of(obj).scanner_origin == (0.0, 0.0, 0.0) and co.options_of(obj).up == pytest.approx(up)
    co.update_calibration(obj, scanner_origin=None, up=None, resamples=2)  # None: from the file or the data again
    assert not obj.ScannerOn and obj.Up.Length == 0
    assert co.options_of(obj).scanner_origin is None and co.options_of(obj).up is None
    assert obj.Status == "ok"
    assert_pose(matrix(obj.W), scene.W)


@pytest.mark.slow
def test_prepared_models_are_kept_where_the_preference_says(document, tmp_path, monkeypatch):
    """The models are prepared once: a second calibration in the session reuses the very same prepared
    objects and reads no cache file; they are also kept in the folder the preferences name (the user's
    cache folder by default) for the next session.  Turned off, nothing is kept, in memory or on disk.
    The result is the same either way."""
    from workcal_wb.core import model_cache
    from workcal_wb.core.model_cache import SUFFIX, default_folder
    from workcal_wb.fc import inputs as fc_inputs
    from workcal_wb.fc import prefs
    from workcal_wb.fc.memo import LastResult
    from workcal_wb.fc.prepared_models import KEPT

    models, reads = [], []

    def run(inputs):  # without the last result remembered by the inputs' key, which would hide the models
        monkeypatch.setattr(fc_inputs, "_last", LastResult())
        models.clear()
        return fc_inputs.run(inputs)

    def gather():
        return fc_inputs.gather_inputs(objs["scan"], objs["workpiece"], objs["reference"])

    def calibrate(scan, workpiece, reference, **kwargs):  # the prepared models the calibration is given
        models.extend((workpiece, reference))
        return original_calibrate(scan, workpiece, reference, **kwargs)

    def read_entry(*args):
        reads.append(args[0])
        return original_read_entry(*args)

    doc, objs = document
    prepared = []

    class Counted(model_cache.SurfaceModel):  # counts the models prepared (a hit is loaded, not prepared)
        def __init__(self, *args, **kwargs):
            prepared.append(1)
            super().__init__(*args, **kwargs)

    original_calibrate, original_read_entry = fc_inputs.calibrate, model_cache.read_entry
    monkeypatch.setattr(fc_inputs, "calibrate", calibrate)
    monkeypatch.setattr(model_cache, "read_entry", read_entry)
    monkeypatch.setattr(model_cache, "SurfaceModel", Counted)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    prefs.reset()
    KEPT.clear()
    try:
        assert prefs.model_cache_folder() == default_folder() == tmp_path / "xdg" / "workcal" / "models"
        prefs.set("ModelCacheDir", str(tmp_path / "mine"))
        inputs = gather()
        assert inputs.model_cache == tmp_path / "mine"
        first = run(inputs)
        first_models = list(models)
        kept = sorted((tmp_path / "mine").glob(f"*{SUFFIX}"))
        assert first.status == "ok" and len(kept) == 2 and len(prepared) == 2
        reads.clear()
        again = run(gather())
        assert all(a is b for a, b in zip(models, first_models)) and len(models) == 2  # the very same objects
        assert reads == [] and len(prepared) == 2  # no cache file read, nothing prepared
        assert sorted(KEPT.sources()) == sorted((doc.Name, objs[r].Name) for r in ("workpiece", "reference"))
        KEPT.clear()  # as in a new session: both models come from the folder
        loaded = [surface for surface, _ in fc_inputs.prepare_models(gather())]
        assert len(reads) == 2 and len(prepared) == 2 and not any(m is f for m, f in zip(loaded, first_models))
        prefs.set("KeepPreparedModels", 0)
        off = gather()
        assert off.model_cache is None
        fresh = run(off)
        assert len(prepared) == 4 and KEPT.sources() == []
        for result in (again, fresh):
            assert np.array_equal(result.W, first.W) and result.status == first.status
        assert not (tmp_path / "xdg").exists() and sorted((tmp_path / "mine").glob(f"*{SUFFIX}")) == kept
        prefs.set("KeepPreparedModels", 1)
        prefs.set("ModelCacheDir", str(tmp_path / "a file" / "cache"))  # cannot be made: a warning, a result
        (tmp_path / "a file").write_text("x")
        blocked = run(gather())
        assert blocked.status == "ok" and any("model cache" in w for w in blocked.warnings)
    finally:
        prefs.reset()
        KEPT.clear()


@pytest.mark.slow
def test_prepared_models_live_as_long_as_their_objects(document, tmp_path, monkeypatch):
    """A model kept in memory is released when its object changes (a new one is prepared), is
    deleted, or its document is closed; a label change keeps it."""
    import gc
    import weakref

    from workcal_wb.fc import inputs as fc_inputs
    from workcal_wb.fc import prefs
    from workcal_wb.fc.prepared_models import KEPT

    doc, objs = document
    workpiece, reference = objs["workpiece"], objs["reference"]
    source = {role: (doc.Name, objs[role].Name) for role in ("workpiece", "reference")}

    def prepare():
        inputs = fc_inputs.gather_inputs(objs["scan"], workpiece, reference)
        return [weakref.ref(surface) for surface, _ in fc_inputs.prepare_models(inputs)]

    def dead(ref):
        gc.collect()
        return ref() is None

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    prefs.reset()
    KEPT.clear()
    try:
        first_workpiece, first_reference = prepare()
        workpiece.Label = "Workpiece renamed"
        assert prepare() == [first_workpiece, first_reference]  # the same objects (weakrefs compare by them)
        assert sorted(KEPT.sources()) == sorted(source.values())
        moved = FreeCAD.Placement(workpiece.Placement)
        moved.Base = moved.Base + FreeCAD.Vector(5, 0, 0)
        workpiece.Placement = moved
        assert KEPT.sources() == [source["reference"]] and dead(first_workpiece)  # changed: released
        second_workpiece, reference_again = prepare()
        assert reference_again == first_reference and second_workpiece() is not None
        doc.removeObject(workpiece.Name)
        assert KEPT.sources() == [source["reference"]] and dead(second_workpiece)  # deleted: released
        FreeCAD.closeDocument(doc.Name)
        assert KEPT.sources() == [] and dead(first_reference)  # document closed: released
    finally:
        prefs.reset()
        KEPT.clear()
