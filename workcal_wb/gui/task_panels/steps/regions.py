"""Step 3: where the workpiece and the reference object are in the scan."""
from __future__ import annotations

import numpy as np

import FreeCAD

from workcal_wb.core.errors import WorkCalError
from workcal_wb.gui.view import FROM_SCANNER

from .base import ATTENTION, DONE, FAILED, TODO, Scene, Step, button, label, row

translate = FreeCAD.Qt.translate


class RegionsStep(Step):
    NAME = "regions"
    TITLE = translate("WorkCal", "Regions")
    HEADING = translate("WorkCal", "Regions: the workpiece and the reference object in the scan")
    TIP = translate("WorkCal", "Which scan points are on the workpiece and which on the reference object: found "
                               "with the models, or picked by hand")

    def build(self, layout) -> None:
        self.counts = label(name="WorkCalRegionInfo")
        layout.addWidget(self.counts)
        layout.addWidget(button(translate("WorkCal", "Find them automatically"),
                                translate("WorkCal", "Remove the platform, split the objects and match each model to "
                                                     "them"), self.find, "WorkCalFindRegions"))
        layout.addLayout(row(
            button(translate("WorkCal", "Pick: box"), translate("WorkCal", "Pick a region by dragging boxes in the 3D "
                                                                           "view"), lambda: self.pick("box")),
            button(translate("WorkCal", "Pick: lasso"), translate("WorkCal", "Pick a region by drawing polygons in the "
                                                                             "3D view"), lambda: self.pick("lasso"))))
        layout.addWidget(button(translate("WorkCal", "Clear the regions"),
                                translate("WorkCal", "Forget both regions of the scan"), self.clear))
        layout.addWidget(label(translate(
            "WorkCal", "Orange: the workpiece. Blue: the reference object. Check them before calibrating; the "
                       "calibration can also find them itself.")))

    def _regions(self):
        from workcal_wb.fc import scan as fc_scan

        scan = self.setup()["scan"]
        if scan is None:
            return None, {}
        try:
            return scan, fc_scan.get_regions(scan)
        except WorkCalError:  # stale regions: the state says so
            return scan, {"stale": True}

    def state(self) -> tuple:
        scan, found = self._regions()
        if scan is None:
            return TODO, translate("WorkCal", "Import the scan first")
        if found.get("stale"):
            return TODO, translate("WorkCal", "The regions no longer fit the scan: find or pick them again")
        if found.get("workpiece") is None and found.get("reference") is None:
            used = self._calibration_regions()
            if used:
                counts = [0 if used.get(r) is None else len(used[r]) for r in ("workpiece", "reference")]
                return DONE if all(counts) else FAILED, translate(
                    "WorkCal", "found by the calibration: workpiece {} points, reference {}").format(*counts)
            return TODO, translate("WorkCal", "Find the workpiece and the reference object in the scan")
        how = translate("WorkCal", "found") if found.get("source") == "auto" else translate("WorkCal", "picked")
        counts = [0 if found.get(r) is None else len(found[r]) for r in ("workpiece", "reference")]
        return DONE if all(counts) else ATTENTION, translate("WorkCal", "{}: workpiece {} points, reference {}").format(
            how, *(0 if found.get(r) is None else len(found[r]) for r in ("workpiece", "reference")))

    def _calibration_regions(self) -> dict:
        """The regions the latest calibration found for itself (automatic regions), or {}."""
        from workcal_wb.fc.lookups import result_of

        calibration = self.guide.calibration()
        if calibration is None or not calibration.ResultJson:
            return {}
        try:
            return result_of(calibration).regions or {}
        except WorkCalError:
            return {}

    def refresh(self) -> None:
        self.counts.setText(self.state()[1])

    def find(self) -> None:
        from workcal_wb.gui.commands.regions import auto_regions

        self.run_guarded(translate("WorkCal", "Find regions automatically"), lambda: auto_regions(self.setup()["scan"]))
        self.guide.go(self.NAME)

    def clear(self) -> None:
        from workcal_wb.gui.commands.regions import clear_regions

        self.run_guarded(translate("WorkCal", "Clear regions"), lambda: clear_regions(self.setup()["scan"]))
        self.guide.go(self.NAME)

    def pick(self, shape: str):
        """Hand over to the pick panel (one task panel at a time); the guide comes back when it closes."""
        from workcal_wb.gui.commands.regions import open_pick_panel

        doc, scan = self.doc, self.setup()["scan"]
        if scan is None:
            return self.run_guarded(translate("WorkCal", "Pick region"), lambda: open_pick_panel(None))
        self.guide.close()
        return self.run_guarded(translate("WorkCal", "Pick region"), lambda: open_pick_panel(
            scan, shape, on_close=lambda: self.guide.open(doc, self.NAME)))

    def scene(self) -> Scene:
        scan, found = self._regions()
        if scan is None:
            return Scene()
        labels = []
        points = None
        for role, text in (("workpiece", translate("WorkCal", "Workpiece")),
                           ("reference", translate("WorkCal", "Reference object"))):
            idx = found.get(role)
            if idx is not None and len(idx):
                if points is None:
                    from workcal_wb.fc.scan import scan_cloud

                    points = scan_cloud(scan).points
                region = points[np.asarray(idx)]
                labels.append((text, np.array([region.min(axis=0), region.max(axis=0)])))
        return Scene(show=[scan], labels=labels or [(translate("WorkCal", "Scan"), scan)], orientation=FROM_SCANNER)
