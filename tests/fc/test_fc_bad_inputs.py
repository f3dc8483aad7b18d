"""Inside FreeCAD the fuzz tests' bad files get a message in the Report view and leave the document as it
was: no object added, no undo step.  Run under freecadcmd through the ``workcal_wb.fc`` functions the
GUI commands record and run (import scan, import model, calibrated toolpath from a G-code file, a
calibration whose stored result is corrupt), wrapped in ``guarded`` as every command's Activated is."""
import numpy as np
import pytest

FreeCAD = pytest.importorskip("FreeCAD")

from fuzz_inputs import GCODE, POINTS, SEEDS, apply, random_mutations, result_json  # noqa: E402

from workcal_wb.core.errors import WorkCalError  # noqa: E402
from workcal_wb.core.readers import read_cloud  # noqa: E402
from workcal_wb.core.toolpath import read_gcode  # noqa: E402
from workcal_wb.core.result import CalibrationResult  # noqa: E402
from workcal_wb.fc import calibration_object as co  # noqa: E402
from workcal_wb.fc import lookups  # noqa: E402
from workcal_wb.fc.models import import_model  # noqa: E402
from workcal_wb.fc.scan import import_scan  # noqa: E402
from workcal_wb.fc.toolpath import make_calibrated_path  # noqa: E402

PER_FORMAT = 4  # refused files per format: the first half of the file, and mutations the reader refuses


def refused(folder, name: str, data: bytes, read, count: int, seed: int) -> list:
    """``count`` files made from ``data`` that ``read`` refuses with a WorkCalError (first: the first half)."""
    rng = np.random.default_rng(seed)
    candidates = [data[:len(data) // 2]] + [apply(data, random_mutations(rng)) for _ in range(50 * count)]
    found = []
    for number, content in enumerate(candidates):
        path = folder / f"bad{number}-{name}"
        path.write_bytes(content)
        try:
            read(path)
        except WorkCalError:
            found.append(path)
            if len(found) == count:
                return found
    raise AssertionError(f"fewer than {count} refused variants of {name}")


@pytest.fixture(scope="module")
def bad_models(tmp_path_factory):
    folder = tmp_path_factory.mktemp("bad-models")
    half = folder / "half-declared.ply"  # the finding: a header declaring half the points, the rest ignored
    half.write_bytes(f"ply\nformat binary_little_endian 1.0\nelement vertex {len(POINTS) // 2}\nproperty float x\n"
                     "property float y\nproperty float z\nend_header\n".encode() + POINTS.astype("<f4").tobytes())
    return [half] + [path for index, (name, data) in enumerate(SEEDS.items())
                     for path in refused(folder, name, data, read_cloud, PER_FORMAT, index)]


@pytest.fixture
def doc():
    document = FreeCAD.newDocument("WorkCalBadInputs")
    document.UndoMode = 1  # as in the GUI: every change would be an undo step
    yield document
    FreeCAD.closeDocument(document.Name)


def state(doc) -> tuple:
    return sorted(o.Name for o in doc.Objects), doc.UndoCount, sorted(o.Name for o in doc.Objects if "Touched" in o.State)


def run_command(title, function, *args, **kwargs):
    """What a command's Activated does (``gui.task_panels.common.guarded``, not importable headless): the
    WorkCalError becomes a Report view message, nothing is raised."""
    try:
        return function(*args, **kwargs)
    except WorkCalError as exc:
        FreeCAD.Console.PrintError(f"WorkCal: {exc}\n")
    return None


def assert_reported(capfd, path):
    err = capfd.readouterr().err
    assert f"WorkCal: {path}" in err or str(path) in err, err
    assert "unexpected error" not in err and "Traceback" not in err, err


def test_bad_scan_files_are_reported_and_change_nothing(bad_models, doc, capfd):
    capfd.readouterr()
    before = state(doc)
    for path in bad_models:
        assert run_command("Import scan", import_scan, doc, path, "mm") is None
        assert_reported(capfd, path)
        assert state(doc) == before, path


def test_bad_model_files_are_reported_and_change_nothing(bad_models, doc, capfd):
    capfd.readouterr()
    before = state(doc)

    for path in bad_models:
        assert run_command("Models", import_model, doc, path, "mm") is None
        assert_reported(capfd, path)
        assert state(doc) == before, path


@pytest.fixture
def calibration(doc):
    """An ok calibration object, as the Calibrate command leaves it (not recomputed: it has no inputs here)."""
    obj = doc.addObject("Part::FeaturePython", "Calibration")
    co.CalibrationFeature(obj)
    co.store_result(obj, CalibrationResult.from_text(result_json(), "result"))
    obj.purgeTouched()
    doc.clearUndos()
    return obj


def test_bad_gcode_files_are_reported_and_change_nothing(doc, calibration, tmp_path, capfd):
    capfd.readouterr()
    before = state(doc)
    for path in refused(tmp_path, "part.nc", GCODE, read_gcode, 12, 14):
        assert run_command("Calibrated toolpath", make_calibrated_path, calibration, path) is None
        assert_reported(capfd, path)
        assert state(doc) == before, path


def test_a_corrupt_stored_result_is_reported_and_changes_nothing(doc, calibration, tmp_path, capfd):
    (tmp_path / "part.nc").write_bytes(GCODE)
    capfd.readouterr()
    rng = np.random.default_rng(14)
    tried = 0
    for _ in range(200):
        calibration.ResultJson = apply(result_json(), random_mutations(rng)).decode("utf-8", "replace")
        calibration.purgeTouched()
        try:
            lookups.result_of(calibration)
            continue  # still a usable result: nothing to report
        except WorkCalError:
            pass
        before = state(doc)
        assert run_command("Calibrated toolpath", make_calibrated_path, calibration, tmp_path / "part.nc") is None
        err = capfd.readouterr().err
        assert "calibration 'Calibration'" in err and "unexpected error" not in err, err
        assert state(doc) == before
        tried += 1
    assert tried >= 20
