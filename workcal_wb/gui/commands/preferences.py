"""WorkCal's preference page (Edit > Preferences > WorkCal) and the WorkCal_Preferences command.

The page is resources/ui/preferences.ui driven by a Python class, so values are stored as plain
strings/numbers under "User parameter:BaseApp/Preferences/Mod/WorkCal" (``workcal_wb.fc.prefs``),
which every command reads for its defaults.  Importing this module registers the page once.
"""
from __future__ import annotations

import os

import FreeCAD

import workcal_wb
from workcal_wb.core.match import METHODS
from workcal_wb.core.model_cache import default_folder
from workcal_wb.core.toolpath import FORMATS
from workcal_wb.fc import prefs
from workcal_wb.fc.prepared_models import KEPT
from workcal_wb.gui.task_panels.common import Command

QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP
translate = FreeCAD.Qt.translate

UI_FILE = os.path.join(workcal_wb.RESOURCES, "ui", "preferences.ui")
GROUP = "WorkCal"


class PreferencePage:
    """Loaded by FreeCAD's preference dialog: ``form`` plus loadSettings/saveSettings."""

    def __init__(self, parent=None):
        import FreeCADGui

        self.form = FreeCADGui.PySideUic.loadUi(UI_FILE)
        self.form.setWindowTitle(translate("WorkCal", "WorkCal"))
        self.form.deviationRange.setSpecialValueText(translate("WorkCal", "automatic (3 tolerances)"))
        self.form.reportDirBrowse.clicked.connect(
            lambda: self.browse(self.form.reportDir, translate("WorkCal", "Report folder")))
        self.form.modelCacheDir.setPlaceholderText(str(default_folder()))
        self.form.modelCacheDirBrowse.clicked.connect(
            lambda: self.browse(self.form.modelCacheDir, translate("WorkCal", "Prepared models folder")))
        self.form.keepPreparedModels.toggled.connect(self._show_cache_folder)
        self.form.units.addItem(translate("WorkCal", "ask at the first import"), "")
        for unit in prefs.UNITS:
            self.form.units.addItem(unit, unit)
        self.form.method.addItems(list(METHODS))
        self.form.regions.addItems(list(prefs.REGION_MODES))
        for name, module in FORMATS.items():
            self.form.exportFormat.addItem(f"{module.NAME} ({name})", name)

    def loadSettings(self):
        values = prefs.all_values()
        f = self.form
        f.units.setCurrentIndex(max(0, f.units.findData(values["ScanUnits"])))
        f.tolerance.setValue(values["ToleranceMm"])
        f.method.setCurrentIndex(max(0, f.method.findText(values["Method"])))
        f.regions.setCurrentIndex(max(0, f.regions.findText(values["Regions"])))
        f.seed.setValue(values["Seed"])
        f.resamples.setValue(values["Resamples"])
        f.exportFormat.setCurrentIndex(max(0, f.exportFormat.findData(values["ExportFormat"])))
        f.deviationRange.setValue(values["DeviationRangeMm"])
        f.pathReach.setValue(values["PathReachMm"])
        f.reportDir.setText(values["ReportDir"])
        f.pickVisibleOnly.setChecked(bool(values["PickVisibleOnly"]))
        f.keepPreparedModels.setChecked(bool(values["KeepPreparedModels"]))
        f.modelCacheDir.setText(values["ModelCacheDir"])
        self._show_cache_folder(f.keepPreparedModels.isChecked())

    def saveSettings(self):
        f = self.form
        prefs.set("ScanUnits", f.units.currentData() or "")
        prefs.set("ToleranceMm", f.tolerance.value())
        prefs.set("Method", f.method.currentText())
        prefs.set("Regions", f.regions.currentText())
        prefs.set("Seed", f.seed.value())
        prefs.set("Resamples", f.resamples.value())
        prefs.set("ExportFormat", f.exportFormat.currentData() or "krl")
        prefs.set("DeviationRangeMm", f.deviationRange.value())
        prefs.set("PathReachMm", f.pathReach.value())
        prefs.set("ReportDir", f.reportDir.text().strip())
        prefs.set("PickVisibleOnly", int(f.pickVisibleOnly.isChecked()))
        prefs.set("KeepPreparedModels", int(f.keepPreparedModels.isChecked()))
        prefs.set("ModelCacheDir", f.modelCacheDir.text().strip())
        if not f.keepPreparedModels.isChecked():
            KEPT.clear()  # off: the models kept in memory go now, not at the next calibration

    def browse(self, line_edit, title: str) -> None:
        """Choose a folder for ``line_edit``, starting from the one it names (or its placeholder's, or home)."""
        from workcal_wb.gui.task_panels import QtWidgets

        start = line_edit.text().strip() or line_edit.placeholderText()
        start = start if os.path.isdir(start) else os.path.expanduser("~")
        folder = QtWidgets.QFileDialog.getExistingDirectory(self.form, title, start)
        if folder:
            line_edit.setText(folder)

    def _show_cache_folder(self, keep: bool) -> None:
        """The cache folder matters only while models are kept."""
        for widget in (self.form.modelCacheDirLabel, self.form.modelCacheDir, self.form.modelCacheDirBrowse):
            widget.setEnabled(keep)


_registered = False


def register_page() -> None:
    """Add the page to FreeCAD's preferences (once per session)."""
    global _registered
    if _registered or not FreeCAD.GuiUp:
        return
    import FreeCADGui

    FreeCADGui.addPreferencePage(PreferencePage, GROUP)
    _registered = True


def show_preferences() -> None:
    import FreeCADGui

    register_page()
    FreeCADGui.showPreferences(GROUP)


class PreferencesCommand(Command):
    NAME, TITLE = "WorkCal_Preferences", "Preferences"
    MENU_TEXT = QT_TRANSLATE_NOOP("WorkCal_Preferences", "Preferences...")
    TOOL_TIP = QT_TRANSLATE_NOOP("WorkCal_Preferences", "Default units, tolerance, matching method and export format")
    NEEDS_DOCUMENT = False

    def run(self):
        show_preferences()


register_page()

COMMANDS = {"WorkCal_Preferences": PreferencesCommand()}
TOOLBAR = []  # menu only
