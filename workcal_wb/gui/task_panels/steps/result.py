"""Step 5: the result, open until someone accepts it, calibrates again or closes the guide.

The verdict in colour, W as FreeCAD's placement (position, axis and angle) and as the paper's Z-Y-Z
angles and Omega, the checks as a table, the uncertainty at the toolpath, the models placed on the
scan, and Accept / Calibrate again / Open the report.  For an ambiguous result the other poses the
match found can be stepped through in the view, each drawn with the workpiece frame's axes and the
toolpath in its own colour (gui.candidate_display), its difference from the best in words and the
sentence on what would tell them apart, and one of them chosen ("ok (chosen)", recorded); for
a result that is not ok, what each region holds that its model does not explain (red in the view)
and what to change.
"""
from __future__ import annotations

import math

import FreeCAD

from workcal_wb.core import choice, frames
from workcal_wb.core.errors import WorkCalError
from workcal_wb.core.result import AMBIGUOUS, CHOSEN, OK, USABLE
from workcal_wb.gui import candidate_display, replay
from workcal_wb.gui.task_panels import QtCore, QtWidgets
from workcal_wb.gui.task_panels.common import for_people
from workcal_wb.gui.view import FROM_SCANNER

from .base import ATTENTION, DONE, FAILED, TODO, Scene, Step, button, form_layout, label, off_model_advice, row

translate = FreeCAD.Qt.translate

VERDICTS = {
    OK: ("#2e7d32", translate("WorkCal", "OK: W can be used")),
    CHOSEN: ("#2e7d32", translate("WorkCal", "OK (CHOSEN): W from the pose chosen among those that fit")),
    AMBIGUOUS: ("#d06000", translate("WorkCal", "AMBIGUOUS: another pose fits almost as well")),
    "failed": ("#c62828", translate("WorkCal", "FAILED: do not use W")),
    "error": ("#c62828", translate("WorkCal", "NOT CALIBRATED: the inputs could not be used")),
}


def _number(value, digits: int = 3) -> str:
    return f"{value:.{digits}f}" if isinstance(value, (int, float)) and math.isfinite(value) else str(value)


class ResultStep(Step):
    NAME = "result"
    TITLE = translate("WorkCal", "Result")
    HEADING = translate("WorkCal", "Result: where the workpiece is, and can it be trusted")
    TIP = translate("WorkCal", "The verdict, W = ^B X (the workpiece in the robot base frame), the checks and the "
                               "uncertainty; accept it, or calibrate again")

    def build(self, layout) -> None:
        self.candidate = 0
        self.map_shown = False
        self.verdict = label(name="WorkCalVerdict")
        layout.addWidget(self.verdict)
        self.reasons = label(name="WorkCalReasons")
        layout.addWidget(self.reasons)
        self.off_model = label(name="WorkCalResultOffModel")
        self.off_model.setStyleSheet("QLabel { color: #c62828; }")
        layout.addWidget(self.off_model)
        self.correct_regions = button(translate("WorkCal", "Correct the regions"),
                                      translate("WorkCal", "Go to the Regions step to pick the regions again"),
                                      lambda: self.guide.go("regions"), "WorkCalResultCorrectRegions")
        layout.addWidget(self.correct_regions)
        for widget in (self.off_model, self.correct_regions):  # until a calibration says something
            widget.setVisible(False)

        where = QtWidgets.QGroupBox(translate("WorkCal", "Where the workpiece is"))
        where.setToolTip(translate("WorkCal", "W = ^B X = V^-1 U: the workpiece frame X in the robot base frame B"))
        form = form_layout()
        form.setRowWrapPolicy(QtWidgets.QFormLayout.WrapAllRows)  # each value the panel's width: one line
        form.setVerticalSpacing(2)
        self.position = label(name="WorkCalPosition")
        self.rotation = label(name="WorkCalRotation")
        self.euler = label(name="WorkCalEulerZYZ")
        self.omega = label(name="WorkCalOmega")
        # The units in the captions, so that each value fits one line of the default panel.
        rows = ((translate("WorkCal", "Position, mm"), self.position, translate("WorkCal", "W's translation, mm")),
                (translate("WorkCal", "Rotation"), self.rotation, translate("WorkCal", "W's rotation as FreeCAD's "
                                                                                      "placement shows it: an angle "
                                                                                      "about an axis")),
                (translate("WorkCal", "Angles Z-Y-Z, deg"), self.euler, translate("WorkCal", "The paper's Euler angles "
                                                                                        "phi, theta, psi (Z-Y-Z)")),
                (translate("WorkCal", "Total turn"), self.omega, translate("WorkCal", "The paper's Omega: the angle "
                                                                                      "of W's rotation about its own "
                                                                                      "axis, acos((trace R - 1) / 2)")))
        for text, widget, tip in rows:
            title = QtWidgets.QLabel(text)
            title.setToolTip(tip)
            widget.setToolTip(tip)
            form.addRow(title, widget)
        where.setLayout(form)
        layout.addWidget(where)

        self.checks = QtWidgets.QTableWidget(0, 3)
        self.checks.setObjectName("WorkCalChecks")
        self.checks.setHorizontalHeaderLabels([translate("WorkCal", "Check"), translate("WorkCal", "Value"), ""])
        self.checks.verticalHeader().setVisible(False)
        self.checks.setEditTriggers(QtWidgets.QAbstractItemView.NoEditTriggers)
        self.checks.setWordWrap(True)
        # As tall as its rows (set in _fill_checks): the panel scrolls, never the table inside it.
        self.checks.setVerticalScrollBarPolicy(QtCore.Qt.ScrollBarAlwaysOff)
        self.checks.setHorizontalScrollBarPolicy(QtCore.Qt.ScrollBarAlwaysOff)
        header = self.checks.horizontalHeader()
        header.setSectionResizeMode(0, QtWidgets.QHeaderView.Stretch)
        header.setSectionResizeMode(1, QtWidgets.QHeaderView.ResizeToContents)
        header.setSectionResizeMode(2, QtWidgets.QHeaderView.ResizeToContents)
        layout.addWidget(self.checks)
        self.uncertainty = label(name="WorkCalUncertainty")
        layout.addWidget(self.uncertainty)

        self.poses = QtWidgets.QWidget()
        self.poses.setObjectName("WorkCalCandidates")
        poses = QtWidgets.QVBoxLayout(self.poses)
        poses.setContentsMargins(0, 0, 0, 0)
        self.pose_label = label(name="WorkCalCandidateLabel")
        self.previous_pose = button("\u25c0", translate("WorkCal", "The previous pose"), lambda: self.show_pose(-1))
        self.next_pose = button("\u25b6", translate("WorkCal", "The next pose"), lambda: self.show_pose(+1))
        poses.addWidget(label(translate("WorkCal", "Poses that fit:")))
        poses.addLayout(row(self.previous_pose, self.next_pose))
        poses.addWidget(self.pose_label)
        self.difference = label(name="WorkCalCandidateDifference")
        poses.addWidget(self.difference)
        self.tie = label(name="WorkCalTieBreaker")
        poses.addWidget(self.tie)
        self.choose_button = button(translate("WorkCal", "Choose this pose"),
                                    translate("WorkCal", "This pose is the right one: W from it, recorded with your "
                                                         "name, the time and the poses shown"), self.choose,
                                    "WorkCalChoosePose")
        self.chosen = label(name="WorkCalChosen")
        poses.addWidget(self.choose_button)
        poses.addWidget(self.chosen)
        layout.addWidget(self.poses)

        self.accept_button = button(translate("WorkCal", "Accept"), translate("WorkCal", "W is right: go on to the "
                                                                                         "toolpath"), self.accept,
                                    "WorkCalAccept")
        self.redo_button = button(translate("WorkCal", "Redo"), translate("WorkCal", "Change the options or the "
                                                                                     "regions and calibrate again"),
                                  lambda: self.guide.go("calibrate"), "WorkCalRedo")
        layout.addLayout(row(self.accept_button, self.redo_button))
        self.report_button = button(translate("WorkCal", "Open the report"),
                                    translate("WorkCal", "Write the full report (HTML) and open it"), self.open_report,
                                    "WorkCalOpenReport")
        self.map_button = button(translate("WorkCal", "Deviation map"),
                                 translate("WorkCal", "Colour the workpiece's scan points by their distance to its "
                                                      "model, against the tolerance"), self.toggle_map,
                                 "WorkCalDeviationMap")
        layout.addLayout(row(self.report_button, self.map_button))

    # ------------------------------------------------------------------ state
    def result(self):
        from workcal_wb.fc.lookups import result_of

        calibration = self.guide.calibration()
        if calibration is None or not calibration.ResultJson:
            return calibration, None
        key = (calibration.Name, calibration.ResultJson)  # read once per stored result: a large scan's is long
        if getattr(self, "_read", (None, None))[0] != key:
            try:
                self._read = key, result_of(calibration)
            except WorkCalError:
                self._read = key, None
        return calibration, self._read[1]

    def state(self) -> tuple:
        calibration, result = self.result()
        if calibration is None:
            return TODO, translate("WorkCal", "Calibrate first")
        status = calibration.Status
        if status in USABLE:
            return (DONE, translate("WorkCal", "{}, accepted").format(status.upper())) if calibration.Accepted else \
                (TODO, translate("WorkCal", "{}: check it and accept it").format(status.upper()))
        first = calibration.Reasons[0] if calibration.Reasons else ""
        return FAILED if status in ("failed", "error") else ATTENTION, f"{status.upper()}: {first}"

    def refresh(self) -> None:
        calibration, result = self.result()
        self.setEnabledAll(result is not None)
        if calibration is None:
            self.verdict.setText(translate("WorkCal", "No calibration yet."))
            self.verdict.setStyleSheet("")
            self.reasons.setText("")
            self.poses.setVisible(False)
            for widget in (self.off_model, self.correct_regions):
                widget.setVisible(False)
            return
        colour, words = VERDICTS.get(calibration.Status, VERDICTS["error"])
        self.verdict.setText(words)
        self.verdict.setStyleSheet(f"QLabel {{ background: {colour}; color: white; font-weight: bold; "
                                   "padding: 6px; border-radius: 4px; }")
        self.reasons.setText("\n".join(f"- {for_people(r)}" for r in calibration.Reasons))
        self.reasons.setVisible(bool(calibration.Reasons))
        advice = off_model_advice(calibration)
        self.off_model.setText(advice)
        for widget in (self.off_model, self.correct_regions):
            widget.setVisible(bool(advice))
        W = None if result is None else result.W
        if W is None:
            for widget in (self.position, self.rotation, self.euler, self.omega):
                widget.setText("-")
        else:
            pl = calibration.W
            self.position.setText("{}, {}, {}".format(*(_number(v, 3) for v in W[:3, 3])))
            axis = pl.Rotation.Axis
            self.rotation.setText(translate("WorkCal", "{}\u00b0 about ({}, {}, {})").format(
                _number(math.degrees(pl.Rotation.Angle), 3), *(_number(v, 3) for v in (axis.x, axis.y, axis.z))))
            phi, theta, psi = frames.euler_zyz(W)
            self.euler.setText("{}, {}, {}".format(*(_number(v, 3) for v in (phi, theta, psi))))
            self.omega.setText(f"{_number(frames.omega(W), 3)} deg")
        self._fill_checks(result)
        self._fill_uncertainty(calibration, result)
        self._fill_poses(calibration, result)
        self.accept_button.setEnabled(calibration.Status in USABLE and not calibration.Accepted)
        self.accept_button.setText(translate("WorkCal", "Accepted") if calibration.Accepted
                                   else translate("WorkCal", "Accept"))
        self.map_button.setEnabled(result is not None and result.U is not None)

    def setEnabledAll(self, enabled: bool) -> None:  # noqa: N802
        for widget in (self.accept_button, self.report_button, self.map_button):
            widget.setEnabled(enabled)

    def _fill_checks(self, result) -> None:
        from workcal_wb.gui.task_panels import QtGui

        gates = [] if result is None else result.quality_gates
        self.checks.setRowCount(len(gates))
        for i, gate in enumerate(gates):
            unit = f" {gate['unit']}" if gate.get("unit") else ""
            limit = gate.get("limit")
            sense = "\u2264" if gate.get("unit") == "mm" else "\u2265" if gate.get("unit") == "%" else "="
            cells = (str(gate["name"]).capitalize(), f"{_number(gate['value'], 3)}{unit}\n{sense} {_number(limit, 3)}",
                     "\u2713" if gate["passed"] else "\u2717")
            for column, text in enumerate(cells):
                item = QtWidgets.QTableWidgetItem(text)
                if column == 2:
                    item.setForeground(QtGui.QBrush(QtGui.QColor("#2e7d32" if gate["passed"] else "#c62828")))
                self.checks.setItem(i, column, item)
        self.checks.resizeRowsToContents()
        height = self.checks.horizontalHeader().height() + sum(self.checks.rowHeight(i) for i in range(len(gates)))
        self.checks.setFixedHeight(height + 2 * self.checks.frameWidth())
        self.checks.setVisible(bool(gates))

    def _fill_uncertainty(self, calibration, result) -> None:
        u = {} if result is None else result.uncertainty or {}
        tolerance = calibration.Tolerance.Value
        if "toolpath_bound_mm" in u:
            text = translate("WorkCal", "At the toolpath: off by up to {} mm (tolerance {} mm).").format(
                _number(u["toolpath_bound_mm"]), f"{tolerance:g}")
        elif "surface_bound_mm" in u:
            text = translate("WorkCal", "No toolpath chosen yet. On the workpiece surface: off by up to {} mm "
                                        "(tolerance {} mm).").format(_number(u["surface_bound_mm"]), f"{tolerance:g}")
        else:
            text = ""
        self.uncertainty.setText(text)
        self.uncertainty.setVisible(bool(text))

    # ------------------------------------------------------------------ candidate poses
    def rival_role(self):
        """The match with other poses that fit, when the result is ambiguous or one of them was chosen:
        "workpiece", "reference" or None."""
        return _rival_role(self.result()[1])

    def _fill_poses(self, calibration, result) -> None:
        from workcal_wb.fc.placed_model import tie_breaker

        role = _rival_role(result)
        shown = None if role is None else self.shown_poses(calibration, result, role)
        self.poses.setVisible(bool(shown))
        if not shown:
            return
        count = len(shown)
        self.candidate = min(self.candidate, count - 1)
        words = translate("WorkCal", "workpiece") if role == "workpiece" else translate("WorkCal", "reference object")
        self.pose_label.setText(translate("WorkCal", "Showing pose {} of {} of the {}{}").format(
            self.candidate + 1, count, words, translate("WorkCal", " (the calibration's)") if self.candidate == 0
            else ""))
        self.previous_pose.setEnabled(self.candidate > 0)
        self.next_pose.setEnabled(self.candidate < count - 1)
        self.difference.setText(_pose_words(shown[self.candidate]))
        self.difference.setStyleSheet(f"QLabel {{ color: {candidate_display.hex_colour(self.candidate)}; "
                                      "font-weight: bold; }")
        self.tie.setText(tie_breaker(calibration, role, max(self.candidate, 1)))
        record = result.choice
        self.choose_button.setVisible(record is None)
        self.choose_button.setEnabled(record is None)
        self.chosen.setVisible(record is not None)
        if record is not None:
            self.chosen.setText(translate("WorkCal", "Chosen by {} on {}: pose {} of {}.").format(
                record.who, record.when, record.index + 1, record.count))

    def shown_poses(self, calibration, result, role) -> list:
        """What the panel says of each pose of ``role``: core.choice.evidence, its difference from the best
        named along the model's axes (kept per calibration result: the model's axes cost a read); none
        when the model cannot be read."""
        key = (calibration.Name, role, calibration.ResultJson)
        if getattr(self, "_shown_key", None) != key:
            from workcal_wb.fc.models import model_cloud

            source = calibration.Workpiece if role == "workpiece" else calibration.Reference
            try:  # the model object may be gone (deleted) when a timer refreshes the panel
                axes = choice.part_axes(model_cloud(source, role=role).points)
            except WorkCalError:
                return []
            found = choice.poses(result, role)
            self._shown = [choice.evidence(p, i, choice.difference(found[0].matrix, p.matrix, axes))
                           for i, p in enumerate(found)]
            self._shown_key = key
        return self._shown

    def show_pose(self, step: int) -> None:
        """Show the models on the scan at the next or previous pose the match found."""
        calibration = self.guide.calibration()
        if calibration is None or self.rival_role() is None:
            return
        self.candidate = max(self.candidate + step, 0)
        replay.run("workcal_wb.fc.placed_model.show_candidate", calibration, self.candidate, result="placed_models")
        self.guide.go(self.NAME)
        self.reveal(self.poses)

    def choose(self) -> None:
        """Choose the pose shown: W from it, "ok (chosen)", recorded (one undo step)."""
        calibration = self.guide.calibration()
        if calibration is None or self.rival_role() is None:
            return
        index = self.candidate
        self.run_guarded(translate("WorkCal", "Choose the pose"), lambda: replay.run(
            "workcal_wb.fc.calibration_object.choose_pose", calibration, index))
        self.guide.go(self.NAME)
        self.reveal(self.poses)

    def drawn_poses(self, calibration):
        """The poses to draw over the view (candidate_display.Poses), None when there is no choice to make."""
        from workcal_wb.fc.calibration_object import toolpath_source
        from workcal_wb.fc.setup import toolpath_of

        _, result = self.result()
        role = _rival_role(result)
        if role is None:
            return None
        source = toolpath_source(calibration) or toolpath_of(calibration.Document)
        return candidate_display.Poses(choice.workpiece_placements(result, role), self.candidate,
                                       calibration.FrameSize.Value, self.toolpath_points(source))

    def toolpath_points(self, source):
        """The toolpath's points in X as it runs (None without one, or when it cannot be read), kept per source."""
        from workcal_wb.core.toolpath import linearised
        from workcal_wb.fc.toolpath_input import read_source

        if source is None:
            return None
        key = source if isinstance(source, str) else source.Name
        if getattr(self, "_path_key", None) != key:
            try:
                self._path = linearised(read_source(source)).points()
            except WorkCalError:
                self._path = None
            self._path_key = key
        return self._path

    # ------------------------------------------------------------------ actions
    def accept(self) -> None:
        calibration = self.guide.calibration()
        self.run_guarded(translate("WorkCal", "Accept"), lambda: replay.run(
            "workcal_wb.fc.calibration_object.accept", calibration))
        if calibration is not None and calibration.Accepted:
            self.guide.go("toolpath")

    def open_report(self) -> str:
        from workcal_wb.gui.commands.report import open_report, report_title, write_report

        calibration = self.guide.calibration()
        paths = self.run_guarded(translate("WorkCal", "Calibration report"), lambda: write_report(calibration))
        if paths:
            self.report_shown = open_report(paths["html"], report_title(calibration))
            return paths["html"]
        return ""

    def toggle_map(self) -> None:
        from workcal_wb.fc.deviation_map import deviation_maps
        from workcal_wb.gui.commands.report import deviation_map

        calibration = self.guide.calibration()
        self.map_shown = not self.map_shown
        if self.map_shown and not deviation_maps(calibration):
            if self.run_guarded(translate("WorkCal", "Deviation map"), lambda: deviation_map(calibration)) is None:
                self.map_shown = False
        self.map_button.setText(translate("WorkCal", "Show the scan") if self.map_shown
                                else translate("WorkCal", "Deviation map"))
        self.guide.go(self.NAME)

    def scene(self) -> Scene:
        from workcal_wb.fc.deviation_map import deviation_maps
        from workcal_wb.fc.placed_model import ON_SCAN, find

        calibration = self.guide.calibration()
        scan = self.setup()["scan"]
        if calibration is None or scan is None:
            return self.guide.steps["regions"].scene()
        maps = deviation_maps(calibration)
        if self.map_shown and maps:
            return Scene(show=[maps[-1]], labels=[(translate("WorkCal", "Deviation map"), maps[-1])],
                         orientation=FROM_SCANNER)
        placed = [(find(calibration, role, ON_SCAN), text) for role, text in (
            ("workpiece", translate("WorkCal", "Workpiece model, placed")),
            ("reference", translate("WorkCal", "Reference model, placed")))]
        placed = [(obj, text) for obj, text in placed if obj is not None]
        poses = self.drawn_poses(calibration)
        in_doubt = None if poses is None else find(calibration, self.rival_role(), ON_SCAN)
        return Scene(show=[scan] + [obj for obj, _ in placed], fit=[in_doubt or scan],  # the poses in doubt up close
                     labels=[(t, o) for o, t in placed], orientation=FROM_SCANNER, poses=poses)


def _rival_role(result) -> str | None:
    """The match of ``result`` whose poses a person may choose among (or chose among), or None."""
    return None if result is None else choice.chosen_role(result)


def _pose_words(shown: dict) -> str:
    """One pose as the panel says it: how it differs from the best, and what the match weighed of it."""
    if shown["index"] == 0:
        text = translate("WorkCal", "Pose 1: the pose the calibration found best.")
    else:
        text = translate("WorkCal", "Pose {}: {} from the best.").format(shown["index"] + 1, shown["difference"])
    if "standard_errors_below_best" in shown and shown["index"]:
        text += " " + translate("WorkCal", "Score {} of the best's, {} standard errors below it.").format(
            f"{100 * shown['score_ratio']:.0f} %", _number(shown["standard_errors_below_best"], 1))
    if "symmetry" in shown:
        text += " " + translate("WorkCal", "The model's symmetry gives it.")
    return text
