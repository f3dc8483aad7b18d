"""Step 4: calibrate, in a worker thread, with progress and cancel.

The inputs are read here (main thread), the calibration runs in a worker (``runner.CalibrationRunner``)
and, when it has finished, the recorded ``fc.calibration_object.make_calibration`` (or
``update_calibration`` for the calibration already there) adds the result in one undo step, finding
the worker's result instead of computing it again.  An error or a cancel leaves the document as it
was.  Options a designer rarely touches (method, seed, refits, where the scanner stood, which way is
up) sit under "Advanced options"; the scanner position and the up direction left empty are automatic.
After a calibration that is not ok, the page says what each region holds that its model does not
explain (the red points in the 3D view), where, and what to change.
"""
from __future__ import annotations

import traceback

import FreeCAD

from workcal_wb.core.errors import InputError, WorkCalError
from workcal_wb.core.match import METHODS
from workcal_wb.fc import prefs
from workcal_wb.gui import replay
from workcal_wb.gui.task_panels import QtCore, QtWidgets

from .base import ATTENTION, DONE, FAILED, TODO, Scene, Step, button, form_layout, label, off_model_advice, row

translate = FreeCAD.Qt.translate

KEEP = object()  # set_options: leave the field as it is


class VectorField(QtWidgets.QWidget):
    """Three number fields (X, Y, Z) that may all be left empty, meaning "automatic"."""

    def __init__(self, name: str, what: str, tip: str):
        super().__init__()
        self.setObjectName(name)
        self.what = what
        layout = QtWidgets.QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        self.edits = []
        for axis in "XYZ":
            edit = QtWidgets.QLineEdit()
            edit.setObjectName(f"{name}_{axis}")
            edit.setPlaceholderText(translate("WorkCal", "auto"))
            edit.setToolTip(f"{axis}: {tip}")
            edit.setMinimumWidth(40)
            layout.addWidget(edit)
            self.edits.append(edit)
        self.setToolTip(tip)

    def value(self):
        """(x, y, z), or None when all three are empty; InputError names a field that is not a number."""
        texts = [e.text().strip() for e in self.edits]
        if not any(texts):
            return None
        if not all(texts):
            raise InputError(translate("WorkCal", "{}: give X, Y and Z, or leave all three empty (automatic)")
                             .format(self.what))
        try:
            return tuple(float(t.replace(",", ".")) for t in texts)
        except ValueError:
            raise InputError(translate("WorkCal", "{}: {} is not a number").format(self.what, ", ".join(texts))) \
                from None

    def set_value(self, value) -> None:
        for edit, v in zip(self.edits, value if value is not None else ("", "", "")):
            edit.setText(v if isinstance(v, str) else f"{v:g}")


class CalibrateStep(Step):
    NAME = "calibrate"
    TITLE = translate("WorkCal", "Calibrate")
    HEADING = translate("WorkCal", "Calibrate: find where the workpiece is for the robot")
    TIP = translate("WorkCal", "Match the workpiece (U = ^S X) and the reference object (V = ^S B) in the scan and "
                               "compute W = V^-1 U, the workpiece in the robot base frame")

    def build(self, layout) -> None:
        self.runner = None
        self.status = None  # the status-bar progress bar while running
        self.state_name = "idle"  # idle, running, cancelling, done, failed, cancelled
        self.last_error = ""
        # At the top, in sight when the page opens: what a region holds that its model does not explain,
        # and what to change, after a calibration that is not ok.
        self.off_model = label(name="WorkCalOffModel")
        self.off_model.setStyleSheet("QLabel { color: #c62828; }")
        layout.addWidget(self.off_model)
        self.correct_regions = button(translate("WorkCal", "Correct the regions"),
                                      translate("WorkCal", "Go to the Regions step to pick the regions again"),
                                      lambda: self.guide.go("regions"), "WorkCalCorrectRegions")
        layout.addWidget(self.correct_regions)
        for widget in (self.off_model, self.correct_regions):  # until a calibration says something
            widget.setVisible(False)
        options = form_layout()
        self.tolerance = QtWidgets.QDoubleSpinBox()
        self.tolerance.setObjectName("WorkCal_tolerance")
        self.tolerance.setDecimals(3)
        self.tolerance.setRange(0.001, 100.0)
        self.tolerance.setSingleStep(0.05)
        self.tolerance.setSuffix(" mm")
        self.tolerance.setToolTip(translate("WorkCal", "The milling tolerance: the fit of both models and the "
                                                       "uncertainty at the toolpath must stay within it"))
        options.addRow(translate("WorkCal", "Tolerance"), self.tolerance)
        layout.addLayout(options)
        self.auto_regions = QtWidgets.QRadioButton(translate("WorkCal", "Find the regions itself"))
        self.auto_regions.setToolTip(translate("WorkCal", "Find the workpiece and the reference object in the scan "
                                                          "with their models"))
        self.picked_regions = QtWidgets.QRadioButton(translate("WorkCal", "Use the scan's regions"))
        self.picked_regions.setToolTip(translate("WorkCal", "Use the regions found or picked in the Regions step"))
        layout.addWidget(self.auto_regions)
        layout.addWidget(self.picked_regions)

        self.advanced_toggle = QtWidgets.QToolButton()
        self.advanced_toggle.setText(translate("WorkCal", "Advanced options"))
        self.advanced_toggle.setCheckable(True)
        self.advanced_toggle.setToolButtonStyle(QtCore.Qt.ToolButtonTextBesideIcon)
        self.advanced_toggle.setArrowType(QtCore.Qt.RightArrow)
        self.advanced_toggle.toggled.connect(
            lambda on: self.advanced_toggle.setArrowType(QtCore.Qt.DownArrow if on else QtCore.Qt.RightArrow))
        self.advanced = QtWidgets.QWidget()
        self.advanced.setObjectName("WorkCalAdvancedOptions")
        advanced = form_layout()
        advanced.setContentsMargins(0, 0, 0, 0)
        self.method = QtWidgets.QComboBox()
        self.method.addItems(list(METHODS))
        self.method.setToolTip(translate("WorkCal", "How the models are fitted: robust (default) weighs down points "
                                                    "off the model; icp and hausdorff are the paper's measures D and H"))
        self.seed = QtWidgets.QSpinBox()
        self.seed.setRange(0, 2 ** 31 - 1)
        self.seed.setToolTip(translate("WorkCal", "Seed of the random search and of the uncertainty estimate: the "
                                                  "same seed gives the same W"))
        self.resamples = QtWidgets.QSpinBox()
        self.resamples.setRange(1, 100)
        self.resamples.setToolTip(translate("WorkCal", "How many times both matches are refitted on resampled points "
                                                       "to estimate the uncertainty (bootstrap)"))
        self.scanner = VectorField("WorkCal_scanner_position", translate("WorkCal", "Scanner position"), translate(
            "WorkCal", "Where the scanner stood when it took the scan, in the scan's coordinates (mm): the origin of "
                       "the scanner frame S. It tells which side of each object the scan shows. Empty: the "
                       "position the scan's file gives (PCD VIEWPOINT, E57 pose, PLY comment), else none"))
        self.up = VectorField("WorkCal_up_direction", translate("WorkCal", "Up direction"), translate(
            "WorkCal", "Which way is up from the platform, in the scan's coordinates: the side the workpiece and "
                       "the reference object P stand on (a direction; its length does not matter). Empty: from "
                       "the data"))
        advanced.addRow(translate("WorkCal", "Fitting"), self.method)
        advanced.addRow(translate("WorkCal", "Random seed"), self.seed)
        advanced.addRow(translate("WorkCal", "Refits"), self.resamples)
        advanced.addRow(label(translate("WorkCal", "Scanner position (mm)"), self.scanner.toolTip()))
        advanced.addRow(self.scanner)
        advanced.addRow(label(translate("WorkCal", "Up direction"), self.up.toolTip()))
        advanced.addRow(self.up)
        advanced.addRow(label(translate("WorkCal", "Empty fields: automatic.")))
        self.advanced.setLayout(advanced)
        self.advanced.setVisible(False)
        self.advanced_toggle.toggled.connect(self.advanced.setVisible)
        layout.addWidget(self.advanced_toggle)
        layout.addWidget(self.advanced)

        self.start_button = button(translate("WorkCal", "Calibrate"), self.TIP, self.start, "WorkCalCalibrate")
        self.cancel_button = button(translate("WorkCal", "Cancel"), translate("WorkCal", "Stop the calibration; the "
                                                                                         "document stays as it was"),
                                    self.cancel, "WorkCalCancelCalibration")
        layout.addLayout(row(self.start_button, self.cancel_button))
        self.progress_bar = QtWidgets.QProgressBar()
        self.progress_bar.setRange(0, 100)
        layout.addWidget(self.progress_bar)
        self.message = label(name="WorkCalCalibrateStatus")
        layout.addWidget(self.message)
        self.option_widgets = [self.tolerance, self.auto_regions, self.picked_regions, self.advanced]
        for edit in self.scanner.edits + self.up.edits:  # a field mended: its complaint goes
            edit.textChanged.connect(lambda text: self._show(None, "") if self.state_name == "failed" else None)
        self._busy(False)

    # ------------------------------------------------------------------ state
    def state(self) -> tuple:
        if self.state_name in ("running", "cancelling"):
            return TODO, translate("WorkCal", "Calibrating...")
        setup = self.setup()
        if any(setup[r] is None for r in ("scan", "workpiece", "reference")):
            return TODO, translate("WorkCal", "Needs the scan and both models")
        calibration = self.guide.calibration()
        if calibration is None:
            return TODO, translate("WorkCal", "Find where the workpiece is")
        if calibration.Status == "error":
            return FAILED, translate("WorkCal", "Could not calibrate: {}").format(
                calibration.Reasons[0] if calibration.Reasons else "")
        if calibration.Status == "failed":
            return FAILED, translate("WorkCal", "FAILED in {:.1f} s: {}").format(
                calibration.Seconds, calibration.Reasons[0] if calibration.Reasons else "")
        if calibration.Status == "ambiguous":
            return ATTENTION, translate("WorkCal", "Calibrated in {:.1f} s, ambiguous").format(calibration.Seconds)
        return DONE, translate("WorkCal", "Calibrated in {:.1f} s").format(calibration.Seconds)

    def refresh(self) -> None:
        if self.state_name in ("running", "cancelling"):
            return
        from workcal_wb.fc.calibration_object import scanner_of, up_of
        from workcal_wb.fc.scan import has_regions

        calibration = self.guide.calibration()
        scan = self.setup()["scan"]
        if calibration is not None:
            self.tolerance.setValue(calibration.Tolerance.Value)
            self.method.setCurrentIndex(list(METHODS).index(calibration.Method))
            self.seed.setValue(calibration.Seed)
            self.resamples.setValue(calibration.Refits)
            self.scanner.set_value(scanner_of(calibration))
            self.up.set_value(up_of(calibration))
            picked = calibration.Regions == "Picked"
        else:
            self.tolerance.setValue(prefs.get("ToleranceMm"))
            self.method.setCurrentIndex(list(METHODS).index(prefs.get("Method")))
            self.seed.setValue(prefs.get("Seed"))
            self.resamples.setValue(prefs.get("Resamples"))
            self.scanner.set_value(None)
            self.up.set_value(None)
            picked = scan is not None and has_regions(scan)
        self.picked_regions.setEnabled(scan is not None and has_regions(scan))
        (self.picked_regions if picked and self.picked_regions.isEnabled() else self.auto_regions).setChecked(True)
        self.start_button.setText(translate("WorkCal", "Calibrate again") if calibration is not None
                                  else translate("WorkCal", "Calibrate"))
        self._show_off_model(calibration)

    def _show_off_model(self, calibration) -> None:
        if not self._alive():
            return
        advice = off_model_advice(calibration)
        self.off_model.setText(advice)
        self.off_model.setVisible(bool(advice))
        self.correct_regions.setVisible(bool(advice))

    def set_options(self, tolerance_mm=None, regions=None, method=None, seed=None, resamples=None,
                    scanner_origin=KEEP, up=KEEP) -> None:
        """Set the page's options as a user would (tests and scripts); ``scanner_origin`` and ``up``
        None empty their fields (automatic), text goes into the fields as typed."""
        if tolerance_mm is not None:
            self.tolerance.setValue(float(tolerance_mm))
        if regions is not None:
            (self.picked_regions if regions == "Picked" else self.auto_regions).setChecked(True)
        if method is not None:
            self.method.setCurrentIndex(list(METHODS).index(method))
        if seed is not None:
            self.seed.setValue(int(seed))
        if resamples is not None:
            self.resamples.setValue(int(resamples))
        if scanner_origin is not KEEP:
            self.scanner.set_value(scanner_origin)
        if up is not KEEP:
            self.up.set_value(up)

    def options(self) -> dict:
        """The options as the fc functions take them; InputError for a scanner position or up direction
        that is not three numbers."""
        return {"tolerance_mm": self.tolerance.value(), "method": self.method.currentText(),
                "seed": self.seed.value(), "resamples": self.resamples.value(),
                "scanner_origin": self.scanner.value(), "up": self.up.value(),
                "regions": "Picked" if self.picked_regions.isChecked() else "Auto"}

    # ------------------------------------------------------------------ work
    def busy(self) -> bool:
        return self.state_name in ("running", "cancelling")

    def start(self) -> bool:
        """Read the inputs and start the worker; False (and the reason on the page and in the Report view)
        when the inputs are not usable or a calibration is already running."""
        from workcal_wb.fc import inputs as fc_inputs
        from workcal_wb.fc.setup import toolpath_of
        from workcal_wb.gui.task_panels.common import message
        from workcal_wb.gui.task_panels.runner import CalibrationRunner, StatusProgress

        if self.busy():
            return False
        setup = self.setup()
        self.toolpath = toolpath_of(self.doc)
        try:
            options = self.options()
            inputs = fc_inputs.gather_inputs(
                setup["scan"], setup["workpiece"], setup["reference"], regions=options["regions"],
                options=fc_inputs.options_from(options["tolerance_mm"], options["method"], options["seed"],
                                               options["resamples"], options["scanner_origin"], options["up"]),
                toolpath=self.toolpath)
        except WorkCalError as exc:
            self._failed(str(exc))
            return False
        self.started_with = options  # what the recorded call is given when the worker has finished
        self.runner = CalibrationRunner(inputs)
        self.runner.progressed.connect(self._on_progress)
        self.runner.succeeded.connect(self._on_success)
        self.runner.failed.connect(self._failed)
        self.runner.cancelled.connect(self._on_cancelled)
        self.state_name, self.last_error = "running", ""
        self._busy(True)
        self.status = StatusProgress(translate("WorkCal", "Calibrating"))
        self._on_progress(0.0, translate("WorkCal", "starting"))
        message(translate("WorkCal", "calibrating {} against {} and {} ...").format(
            inputs.labels["scan"], inputs.labels["workpiece"], inputs.labels["reference"]))
        self.runner.start()
        self.guide.refresh()
        self.reveal(self.progress_bar)
        return True

    def cancel(self) -> None:
        if self.runner is not None and self.state_name == "running":
            self.state_name = "cancelling"
            self.runner.cancel()
            self._show(None, translate("WorkCal", "Cancelling..."))

    def wait(self, timeout_s: float = 120.0) -> str:
        """Keep the event loop running until the worker has finished and its result is handled."""
        from workcal_wb.gui.task_panels.runner import wait_until

        wait_until(lambda: not self.busy(), timeout_s)
        return self.state_name

    def _alive(self) -> bool:
        try:
            self.widget.objectName()
        except RuntimeError:
            return False
        return True

    def _show(self, fraction, text) -> None:
        if not self._alive():
            return
        if fraction is not None:
            self.progress_bar.setValue(int(round(100 * fraction)))
        if text is not None:
            from workcal_wb.gui.task_panels.common import for_people

            self.message.setText(for_people(text))

    def _busy(self, busy: bool) -> None:
        if not self._alive():
            return
        for widget in self.option_widgets:
            widget.setEnabled(not busy)
        self.start_button.setEnabled(not busy)
        self.cancel_button.setVisible(busy)
        self.progress_bar.setVisible(busy or self.progress_bar.value() > 0)

    def _end(self, state: str) -> None:
        if self.status is not None:
            self.status.close()
            self.status = None
        self.state_name = state
        self._busy(False)

    def _on_progress(self, fraction: float, text: str) -> None:
        self._show(fraction, text)
        if self.status is not None:
            self.status.update(fraction, text)

    def _on_success(self, result) -> None:
        options = self.started_with
        calibration = self.guide.calibration()
        if self.doc.Name not in FreeCAD.listDocuments():  # closed while the worker ran
            self._end("cancelled")
            return
        try:
            if calibration is not None:
                replay.run("workcal_wb.fc.calibration_object.update_calibration", calibration, overlays=True,
                           result="result", **options)
            else:
                setup = self.setup()
                replay.run("workcal_wb.fc.calibration_object.make_calibration", self.doc, setup["scan"],
                           setup["workpiece"], setup["reference"], toolpath=self.toolpath, overlays=True,
                           result="calibration", **options)
        except WorkCalError as exc:
            self._failed(str(exc))
            return
        except Exception as exc:  # a bug: reported, FreeCAD keeps running
            self._failed(f"unexpected error while adding the result: {exc}\n{traceback.format_exc()}")
            return
        self._end("done")
        self._show(1.0, translate("WorkCal", "Calibration {}").format(result.status))
        self._show_off_model(self.guide.calibration())
        if self.guide.alive():
            self.guide.go("result")

    def _failed(self, text: str) -> None:
        from workcal_wb.gui.task_panels.common import error

        self._end("failed")
        self.last_error = text
        error(translate("WorkCal", "calibration not done: {}").format(text))
        self._show(0.0, translate("WorkCal", "Not calibrated: {}").format(text.splitlines()[0] if text else ""))
        if self._alive():
            self.reveal(self.message)
        self.guide.refresh()

    def _on_cancelled(self) -> None:
        from workcal_wb.gui.task_panels.common import message

        self._end("cancelled")
        message(translate("WorkCal", "calibration cancelled; the document is unchanged"))
        self._show(0.0, translate("WorkCal", "Cancelled: the document is unchanged."))
        self.guide.refresh()

    def scene(self) -> Scene:
        return self.guide.steps["regions"].scene()
