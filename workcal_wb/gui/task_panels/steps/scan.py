"""Step 1: the scan of the mounted workpiece and the reference object."""
from __future__ import annotations

import FreeCAD

from workcal_wb.gui.view import FROM_SCANNER

from .base import DONE, TODO, Scene, Step, UnitChooser, button, combo, label

translate = FreeCAD.Qt.translate


class ScanStep(Step):
    NAME = "scan"
    TITLE = translate("WorkCal", "Scan")
    HEADING = translate("WorkCal", "Scan: the part and the reference object, seen at once")
    TIP = translate("WorkCal", "One 3D scan that sees both the workpiece and the fixed reference object (scanner "
                               "frame S)")

    def build(self, layout) -> None:
        self.info = label(name="WorkCalScanInfo")
        layout.addWidget(self.info)
        self.unit_chooser = UnitChooser("WorkCalScanUnit", self.read_in)
        self.units, self.unit_warning, self.unit_fix = (self.unit_chooser.combo, self.unit_chooser.warning,
                                                        self.unit_chooser.fix)
        layout.addWidget(self.unit_chooser)
        layout.addWidget(button(translate("WorkCal", "Import a scan file..."),
                                translate("WorkCal", "PLY, PCD, XYZ, ASC, PTS, CSV, E57, STL, OBJ or OFF; it becomes "
                                                     "the scan of this document"), self.ask_and_import,
                                "WorkCalImportScan"))
        layout.addWidget(label(translate("WorkCal", "Or use a point cloud of this document:")))
        self.choice = combo("WorkCal_scan", translate("WorkCal", "A point cloud or mesh already in the document"))
        self.choice.activated.connect(lambda index: self.run_guarded(translate("WorkCal", "Choose the scan"),
                                                                     self.use_chosen))
        layout.addWidget(self.choice)

    def state(self) -> tuple:
        scan = self.setup()["scan"]
        if scan is None:
            return TODO, translate("WorkCal", "Import the scan of the part and the reference object")
        count = scan.Points.CountPoints if hasattr(scan, "Points") else scan.Mesh.CountPoints
        return DONE, translate("WorkCal", "{}: {} points").format(scan.Label, f"{count:,}".replace(",", "\u2009"))

    def refresh(self) -> None:
        from workcal_wb.fc.scan import declared_units
        from workcal_wb.gui.actions import scan_candidates

        scan = self.setup()["scan"]
        units = getattr(scan, "Units", "") if scan is not None else ""
        source = getattr(scan, "SourceFile", "") if scan is not None else ""
        declared = bool(source) and declared_units(source) is not None
        self.info.setText(self.state()[1] + (translate("WorkCal", ", read in {} (the file says so)").format(units)
                                             if units and declared else ""))
        warning, suggestion = self._unit_warning(scan) if units and source and not declared else ("", None)
        self.unit_chooser.show_units(units if source and not declared else "", warning, suggestion)
        self.candidates = scan_candidates(self.doc)
        self.choice.blockSignals(True)
        self.choice.clear()
        for obj in self.candidates:
            self.choice.addItem(obj.Label, obj.Name)
        self.choice.setCurrentIndex(self.candidates.index(scan) if scan in self.candidates else -1)
        self.choice.blockSignals(False)

    def _unit_warning(self, scan) -> tuple:
        """The scan's unit warning, worked out again only when its points or unit changed."""
        from workcal_wb.fc.scan import scan_unit_warning
        from workcal_wb.gui.task_panels.common import for_people

        key = (scan.Name, scan.Units, scan.PointCount, str(scan.Points.BoundBox))
        if getattr(self, "_unit_key", None) != key:
            text, suggestion = scan_unit_warning(scan)
            self._unit_key, self._unit_result = key, (for_people(text), suggestion)
        return self._unit_result

    def read_in(self, units: str) -> None:
        """Read the scan's file again in ``units`` (recorded, one undo step)."""
        from workcal_wb.gui import replay

        scan = self.setup()["scan"]
        if scan is None or not units or units == scan.Units:
            return
        self.run_guarded(translate("WorkCal", "Scan unit"),
                         lambda: replay.run("workcal_wb.fc.scan.change_units", scan, units, result="scan"))
        self.guide.go(self.NAME)

    def ask_and_import(self) -> None:
        from workcal_wb.gui.actions import ask_for_scan_files

        paths = ask_for_scan_files()
        if paths:
            self.import_files(paths)

    def import_files(self, paths, units: str | None = None) -> list:
        """Import scan files (recorded), then show the scan."""
        from workcal_wb.gui.actions import import_scan_files

        created = self.run_guarded(translate("WorkCal", "Import scan"),
                                   lambda: import_scan_files(paths, units, self.doc)) or []
        self.guide.go(self.NAME)
        return created

    def use_chosen(self) -> None:
        from workcal_wb.gui.actions import choose_models

        index = self.choice.currentIndex()
        if 0 <= index < len(self.candidates):
            choose_models(self.doc, scan=self.candidates[index])
            self.guide.go(self.NAME)

    def scene(self) -> Scene:
        from workcal_wb.gui.actions import scan_candidates

        scan = self.setup()["scan"]
        if scan is None:  # none chosen yet: the scans there are to choose from stay in sight
            return Scene(show=scan_candidates(self.doc))
        return Scene(show=[scan], labels=[(translate("WorkCal", "Scan"), scan)], orientation=FROM_SCANNER)
