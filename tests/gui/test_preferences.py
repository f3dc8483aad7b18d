"""The preference page's prepared-models settings, set as a user would and read back: the parameters
and what a calibration's preparation does both follow them."""
import pytest

FreeCAD = pytest.importorskip("FreeCAD")

from workcal_wb.core.geometry import Cloud  # noqa: E402
from workcal_wb.core.model_cache import SUFFIX, default_folder  # noqa: E402
from workcal_wb.core.simulate import shapes  # noqa: E402
from workcal_wb.fc import inputs as fc_inputs  # noqa: E402
from workcal_wb.fc import prefs  # noqa: E402
from workcal_wb.fc.models import add_model  # noqa: E402
from workcal_wb.fc.prepared_models import KEPT  # noqa: E402
from workcal_wb.fc.scan import make_scan  # noqa: E402


def test_prepared_models_preferences_are_set_on_the_page_and_followed(doc, tmp_path, choose_folder):
    from workcal_wb.gui.commands.preferences import PreferencePage

    folder = tmp_path / "prepared models"
    folder.mkdir()
    workpiece, reference = add_model(doc, shapes.peg(), "Peg"), add_model(doc, shapes.plate(), "Plate")
    scan = make_scan(doc, Cloud(shapes.peg().points, name="scan"), "Scan", "mm", "test")
    doc.recompute()

    def prepare():
        inputs = fc_inputs.gather_inputs(scan, workpiece, reference)
        for _, cache in fc_inputs.prepare_models(inputs):
            cache.store()
        return inputs

    saved = prefs.all_values()
    prefs.reset()
    KEPT.clear()
    try:
        page = PreferencePage()
        page.loadSettings()
        form = page.form
        assert form.keepPreparedModels.isChecked() and form.modelCacheDir.text() == ""  # the defaults
        assert form.modelCacheDir.placeholderText() == str(default_folder()) and form.modelCacheDir.isEnabled()
        assert choose_folder(form.modelCacheDirBrowse, folder) and form.modelCacheDirBrowse.text() == "Browse..."
        assert form.modelCacheDir.text() == str(folder)
        page.saveSettings()
        assert prefs.get("KeepPreparedModels") == 1 and prefs.get("ModelCacheDir") == str(folder)
        assert prepare().model_cache == folder
        assert len(list(folder.glob(f"*{SUFFIX}"))) == 2 and len(KEPT.sources()) == 2  # on disk and in memory

        form.keepPreparedModels.setChecked(False)
        assert not form.modelCacheDir.isEnabled() and not form.modelCacheDirBrowse.isEnabled()
        page.saveSettings()
        assert prefs.get("KeepPreparedModels") == 0 and KEPT.sources() == []  # released at once
        for entry in folder.glob(f"*{SUFFIX}"):
            entry.unlink()
        assert prepare().model_cache is None
        assert list(folder.glob(f"*{SUFFIX}")) == [] and KEPT.sources() == []  # nothing kept anywhere

        again = PreferencePage()  # what the page shows next time
        again.loadSettings()
        assert not again.form.keepPreparedModels.isChecked() and again.form.modelCacheDir.text() == str(folder)
    finally:
        prefs.reset()
        for name, value in saved.items():
            prefs.set(name, value)
        KEPT.clear()


def test_the_toolpath_reach_set_on_the_page_is_what_exports_hold_the_toolpath_to(doc):
    from types import SimpleNamespace

    from workcal_wb.core.toolpath.safety import DEFAULT_PATH_REACH_MM
    from workcal_wb.fc.toolpath import held_to_workpiece
    from workcal_wb.gui.commands.preferences import PreferencePage

    calibration = SimpleNamespace(Workpiece=add_model(doc, shapes.peg(), "Peg"))
    doc.recompute()
    saved = prefs.all_values()
    prefs.reset()
    try:
        page = PreferencePage()
        page.loadSettings()
        assert page.form.pathReach.value() == DEFAULT_PATH_REACH_MM
        assert held_to_workpiece(calibration)["path_reach_mm"] == DEFAULT_PATH_REACH_MM
        page.form.pathReach.setValue(80.0)
        page.saveSettings()
        held = held_to_workpiece(calibration)
        assert held["path_reach_mm"] == 80.0 and len(held["workpiece_model"].triangles) > 0
        again = PreferencePage()
        again.loadSettings()
        assert again.form.pathReach.value() == 80.0
    finally:
        prefs.reset()
        for name, value in saved.items():
            prefs.set(name, value)
