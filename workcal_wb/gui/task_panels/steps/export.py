"""Step 7: the program for the robot or the machine, with the machine it is for.

The machine profile is the CLI's ``--machine`` (robot, 3axis, 5axis-tcp) with its ``--vertical-tol``
and ``--rotary``: a tilted W refused for a 3-axis machine is explained here in words, with its two
ways out a click away (allow the tilt, or export for a 5-axis machine).  For a robot program, the
robot that runs it and its TCP are the CLI's ``--robot`` and ``--tool``: the program is checked
against the robot and carries the configuration solved (a program the robot cannot follow is
refused with where to put the part instead, or written FORCED when the user says so).  After a check
against a robot the page says where the robot comes nearest a joint limit (or where it fails) and offers
to show the robot at that pose beside the part; a robot shown is updated by the next export.
"""
from __future__ import annotations

import math
import os

import FreeCAD

from workcal_wb.core.errors import WorkCalError
from workcal_wb.gui.task_panels import QtWidgets

from .base import DONE, TODO, Scene, Step, button, combo, form_layout, label, row
from .toolpath import robot_frame_scene

translate = FreeCAD.Qt.translate

MACHINES = (("robot", translate("WorkCal", "Robot")), ("3axis", translate("WorkCal", "3-axis machine")),
            ("5axis-tcp", translate("WorkCal", "5-axis machine")))
ROTARY_WORDS = {"ab": "A + B", "ac": "A + C", "bc": "B + C"}
NO_TOOL = "0, 0, 0, 0, 0, 0"  # the TCP at the flange


class ExportStep(Step):
    NAME = "export"
    TITLE = translate("WorkCal", "Export")
    HEADING = translate("WorkCal", "Export: the program for the robot or the machine")
    TIP = translate("WorkCal", "Write the calibrated toolpath as KUKA KRL, ABB RAPID, URScript, Fanuc LS, G-code or "
                               "CSV, checked for the machine it is for")

    def build(self, layout) -> None:
        from workcal_wb.core.toolpath import FORMATS
        from workcal_wb.core.toolpath.orientation import ROTARY
        from workcal_wb.core.toolpath.safety import DEFAULT_VERTICAL_TOL_DEG
        from workcal_wb.fc import prefs

        form = form_layout()
        self.format = combo("WorkCal_format", translate("WorkCal", "The controller's language"))
        for name, module in FORMATS.items():
            self.format.addItem(module.NAME, name)
        self.format.setCurrentIndex(max(0, self.format.findData(prefs.get("ExportFormat"))))
        self.machine = combo("WorkCal_machine", translate(
            "WorkCal", "What the program is for: a robot (KRL, RAPID, URScript, Fanuc, CSV), or for G-code a 3-axis "
                       "machine (the tool stays vertical) or a 5-axis machine with tool centre point control"))
        self.tilt = QtWidgets.QDoubleSpinBox()
        self.tilt.setObjectName("WorkCal_vertical_tol")
        self.tilt.setDecimals(3)
        self.tilt.setRange(0.0, 10.0)
        self.tilt.setSingleStep(0.05)
        self.tilt.setSuffix(" deg")
        self.tilt.setValue(DEFAULT_VERTICAL_TOL_DEG)
        self.tilt.setToolTip(translate("WorkCal", "3-axis machine: how far W may tilt the tool from the machine's "
                                                  "Z"))
        self.rotary = combo("WorkCal_rotary", translate("WorkCal", "5-axis machine: its two rotary axes"))
        for name in ROTARY:
            self.rotary.addItem(ROTARY_WORDS.get(name, name.upper()), name)
        self.robot = combo("WorkCal_robot", translate(
            "WorkCal", "The robot that runs the program: every move is checked against its reach, joint limits and "
                       "singularities before the program is written, and the program carries the configuration "
                       "solved; with None the program says its reach was not checked. Only "
                       "robots whose controller runs the chosen language are listed"))
        self.tcp = QtWidgets.QLineEdit(NO_TOOL)
        self.tcp.setObjectName("WorkCal_tcp")
        self.tcp.setToolTip(translate("WorkCal", "The TCP in the robot's flange frame: X, Y, Z in mm and A, B, C in "
                                                 "degrees, R = Rz(A) Ry(B) Rx(C)"))
        self.robot_title = QtWidgets.QLabel(translate("WorkCal", "Robot"))
        self.tcp_title = QtWidgets.QLabel(translate("WorkCal", "TCP (X, Y, Z, A, B, C)"))
        self.tilt_title = QtWidgets.QLabel(translate("WorkCal", "Tilt allowed"))
        self.rotary_title = QtWidgets.QLabel(translate("WorkCal", "Rotary axes"))
        form.addRow(translate("WorkCal", "Format"), self.format)
        form.addRow(translate("WorkCal", "Machine"), self.machine)
        form.addRow(self.tilt_title, self.tilt)
        form.addRow(self.rotary_title, self.rotary)
        form.addRow(self.robot_title, self.robot)
        form.addRow(self.tcp_title, self.tcp)
        layout.addLayout(form)
        self.path = QtWidgets.QLineEdit()
        self.path.setObjectName("WorkCal_program_file")
        self.path.setToolTip(translate("WorkCal", "The program file to write (replaced as a whole, never half "
                                                  "written)"))
        layout.addWidget(label(translate("WorkCal", "File")))
        layout.addWidget(self.path)
        layout.addLayout(row(button(translate("WorkCal", "Browse..."), translate("WorkCal", "Choose the file"),
                                    self.browse),
                             button(translate("WorkCal", "Export"), self.TIP, self.export, "WorkCalExport")))
        self.refusal = QtWidgets.QWidget()
        refusal = QtWidgets.QVBoxLayout(self.refusal)
        refusal.setContentsMargins(0, 0, 0, 0)
        self.refusal_text = label(name="WorkCalExportRefusal")
        self.allow_button = button("", translate("WorkCal", "Allow this tilt for the tool and export again"),
                                   self.allow_tilt, "WorkCalAllowTilt")
        self.five_axis_button = button(translate("WorkCal", "Export for 5 axes"),
                                       translate("WorkCal", "Write G-code with rotary axes for a 5-axis machine"),
                                       self.use_five_axes, "WorkCalUseFiveAxes")
        refusal.addWidget(self.refusal_text)
        refusal.addLayout(row(self.allow_button, self.five_axis_button))
        layout.addWidget(self.refusal)
        self.refusal.setVisible(False)
        self.written = label(name="WorkCalExported")
        layout.addWidget(self.written)
        self.worst = label(name="WorkCalWorstPose")
        self.show_robot_button = button(translate("WorkCal", "Show the robot at its worst pose"), translate(
            "WorkCal", "Draw the robot in the robot base frame, beside the part, at the pose of the program nearest a "
                       "joint limit (or where it fails)"), self.show_robot, "WorkCalShowRobot")
        layout.addWidget(self.worst)
        layout.addWidget(self.show_robot_button)
        self.checked = None  # the last check against a robot: its report and what the export was given
        self.format.currentIndexChanged.connect(lambda index: self._format_changed())
        self.machine.currentIndexChanged.connect(lambda index: self._machine_changed())
        self.robot.currentIndexChanged.connect(lambda index: self._robot_changed())
        self._format_changed()

    # ------------------------------------------------------------------ widgets
    def fmt(self) -> str:
        return self.format.currentData()

    def machine_profile(self) -> str:
        return self.machine.currentData()

    def _format_changed(self) -> None:
        from workcal_wb.core.toolpath import FORMATS

        gcode = self.fmt() == "gcode"
        self.machine.blockSignals(True)
        self.machine.clear()
        for name, words in MACHINES:
            if (name == "robot") != gcode:
                self.machine.addItem(words, name)
        self.machine.blockSignals(False)
        self.machine.setEnabled(gcode)
        self._machine_changed()
        self._fill_robots()
        text = self.path.text().strip()
        if text:
            self.path.setText(os.path.splitext(text)[0] + FORMATS[self.fmt()].EXTENSION)

    def _fill_robots(self) -> None:
        """The robots whose controller runs the chosen format (none for G-code), the choice kept if it still fits."""
        from workcal_wb.core.robots import builtin_robots, load_robot
        from workcal_wb.core.toolpath import FORMATS

        kept = self.robot.currentData()
        controllers = FORMATS[self.fmt()].CONTROLLERS
        self.robot.blockSignals(True)
        self.robot.clear()
        self.robot.addItem(translate("WorkCal", "None"), None)  # the program then says its reach is not checked
        for robot_id in builtin_robots():
            robot = load_robot(robot_id)
            if robot.controller in controllers:
                self.robot.addItem(robot.name, robot_id)
        self.robot.setCurrentIndex(max(0, self.robot.findData(kept)) if kept else 0)
        self.robot.blockSignals(False)
        for widget in (self.robot, self.robot_title):
            widget.setVisible(bool(controllers))
        self._robot_changed()

    def _robot_changed(self) -> None:
        from workcal_wb.core.toolpath import FORMATS

        chosen = bool(FORMATS[self.fmt()].CONTROLLERS) and self.robot.currentData() is not None
        for widget in (self.tcp, self.tcp_title):
            widget.setVisible(chosen)
        self.checked = None  # what the page said of the robot's reach was said of another robot
        self._show_check()

    def _machine_changed(self) -> None:
        for widget in (self.tilt, self.tilt_title):
            widget.setVisible(self.machine_profile() == "3axis")
        for widget in (self.rotary, self.rotary_title):
            widget.setVisible(self.machine_profile() == "5axis-tcp")
        self.refusal.setVisible(False)

    def set_options(self, fmt=None, machine=None, vertical_tol_deg=None, rotary=None, path=None, robot=None,
                    tool=None) -> None:
        """Set the page's choices as a user would (tests and scripts); ``robot`` a built-in id ("" for none),
        ``tool`` the TCP as the field takes it, "X, Y, Z, A, B, C"."""
        if fmt is not None:
            self.format.setCurrentIndex(self.format.findData(fmt))
        if robot is not None:
            self.robot.setCurrentIndex(max(0, self.robot.findData(robot)) if robot else 0)
        if tool is not None:
            self.tcp.setText(tool)
        if machine is not None:
            self.machine.setCurrentIndex(self.machine.findData(machine))
        if vertical_tol_deg is not None:
            self.tilt.setValue(float(vertical_tol_deg))
        if rotary is not None:
            self.rotary.setCurrentIndex(self.rotary.findData(rotary))
        if path is not None:
            self.path.setText(os.fspath(path))

    def options(self) -> dict:
        machine = self.machine_profile()
        out = {"machine": machine}
        if machine == "3axis":
            out["vertical_tol_deg"] = self.tilt.value()
        if machine == "5axis-tcp":
            out["rotary"] = self.rotary.currentData()
        if machine == "robot" and self.robot.currentData() is not None:
            out["robot"] = self.robot.currentData()
            out["tool"] = self.tool()
        return out

    def tool(self) -> list:
        """The TCP field as six numbers (InputError naming the field when it is not)."""
        from workcal_wb.core.errors import InputError

        text = self.tcp.text().strip() or NO_TOOL
        try:
            values = [float(v) for v in text.split(",")]
        except ValueError:
            values = []
        if len(values) != 6 or not all(map(math.isfinite, values)):
            raise InputError(translate("WorkCal", "TCP {!r}: expected six numbers X, Y, Z, A, B, C (mm and degrees, "
                                                  "the TCP in the robot's flange frame)").format(text))
        return values

    def default_path(self) -> str:
        from workcal_wb.core.toolpath import FORMATS
        from workcal_wb.fc.toolpath_input import source_label
        from workcal_wb.gui.actions import start_folder

        source = self.guide.steps["toolpath"].chosen()
        stem = os.path.splitext(source_label(source))[0] if source is not None else "toolpath"
        stem = "".join(c if c.isalnum() or c in "-_" else "_" for c in stem) or "toolpath"
        return os.path.join(start_folder(self.doc), f"{stem}_calibrated{FORMATS[self.fmt()].EXTENSION}")

    def browse(self) -> None:
        import FreeCADGui

        path, _ = QtWidgets.QFileDialog.getSaveFileName(FreeCADGui.getMainWindow(), translate("WorkCal", "Program"),
                                                        self.path.text().strip() or self.default_path())
        if path:
            self.path.setText(path)

    # ------------------------------------------------------------------ state
    def state(self) -> tuple:
        written = self.guide.exported
        if written:
            return DONE, translate("WorkCal", "written: {}").format(os.path.basename(written))
        calibration = self.guide.calibration()
        if calibration is None or self.guide.steps["toolpath"].chosen() is None:
            return TODO, translate("WorkCal", "Needs a calibration and the toolpath")
        return TODO, translate("WorkCal", "Write the program")

    def refresh(self) -> None:
        if not self.path.text().strip():
            self.path.setText(self.default_path())
        self.written.setText(self.state()[1] if self.guide.exported else "")

    # ------------------------------------------------------------------ export
    def export(self, confirm=None):
        """Write the program (recorded); forcing is asked for a calibration that is not ok and for a program
        the chosen robot cannot follow (the question says why and where to put the part instead); a tool
        tilted past what a 3-axis machine allows is explained on the page with its two ways out."""
        from workcal_wb.core.toolpath import ToolTilted
        from workcal_wb.core.toolpath.safety import PathOffModel
        from workcal_wb.gui.task_panels.common import show_error, with_force

        calibration = self.guide.calibration()
        path = self.path.text().strip() or self.default_path()
        self.refusal.setVisible(False)
        self.checked = None
        try:
            options = self.options()
            job = with_force(lambda force: self._checked_export(calibration, path, force, options), confirm)
        except ToolTilted as exc:
            self.show_tilt(exc)
            return None
        except PathOffModel as exc:
            show_error(translate("WorkCal", "Export robot program"), str(exc) + " " + translate(
                "WorkCal", "If it is this part's toolpath (a roughing pass deep in the stock), allow {} mm under "
                           "Edit > Preferences > WorkCal > Toolpath within.").format(math.ceil(exc.median_mm * 1.2)))
            return None
        except WorkCalError as exc:
            show_error(translate("WorkCal", "Export robot program"), str(exc))
            return None
        finally:
            self._show_check()
        if self.checked is not None and self.checked["pose"] is not None:
            from workcal_wb.fc.robot_pose import find

            if find(calibration) is not None:  # a robot shown: it follows the program just checked
                self.show_robot()
        if job is not None:
            self.guide.exported = path
            self.written.setText(translate("WorkCal", "Written: {} ({} for the {})").format(
                path, self.format.currentText(), self.machine.currentText().lower()))
            self.reveal(self.written)
        self.guide.refresh()
        return job

    def _checked_export(self, calibration, path, force: bool, options: dict):
        """The recorded export; the robot's reach it was checked against (a refusal's too) is kept for the
        line on the worst pose and the button that shows the robot there."""
        from workcal_wb.core.toolpath import ReachRefused
        from workcal_wb.gui.actions import export_program

        try:
            job = export_program(calibration, path, self.fmt(), force=force, **options)
        except ReachRefused as refused:
            self._keep_check(refused.report, force, options)
            raise
        if job is not None and job.reach is not None:
            self._keep_check(job.reach, force, options)
        return job

    def _keep_check(self, report, force: bool, options: dict) -> None:
        from workcal_wb.core.robots import load_robot
        from workcal_wb.core.robots.reach import worst_pose

        robot = load_robot(options["robot"])
        self.checked = {"robot": robot, "report": report, "pose": worst_pose(robot, report), "fmt": self.fmt(),
                        "force": force, "options": options}

    def _show_check(self) -> None:
        """The line on the last check's worst pose, and the button that shows the robot there."""
        check = self.checked
        if check is None:
            self.worst.setText("")
        elif check["pose"] is None:
            self.worst.setText(translate("WorkCal", "{} reaches none of the program: there is no pose to show.").format(
                check["robot"].name))
        elif check["report"].reachable:
            self.worst.setText(translate("WorkCal", "{} comes nearest a joint limit {}.").format(
                check["robot"].name, check["pose"].text))
        else:
            self.worst.setText(translate("WorkCal", "{} cannot follow the program; the pose to look at: {}.").format(
                check["robot"].name, check["pose"].text))
        self.worst.setVisible(check is not None)
        self.show_robot_button.setVisible(check is not None and check["pose"] is not None)

    def show_robot(self):
        """The robot of the last check drawn at its worst pose, beside the part (recorded)."""
        from workcal_wb.gui.actions import show_robot_at_worst_pose

        check, calibration = self.checked, self.guide.calibration()
        if check is None or check["pose"] is None or calibration is None:
            return None
        shown = self.run_guarded(translate("WorkCal", "Show the robot at its worst pose"),
                                 lambda: show_robot_at_worst_pose(calibration, check["fmt"], force=check["force"],
                                                                  **check["options"]))
        self.guide.go(self.NAME)
        return shown

    def show_tilt(self, refusal) -> None:
        needed = math.ceil(refusal.tilt_deg * 100) / 100
        if refusal.five_axis_path:
            text = translate("WorkCal", "This toolpath tilts the tool {:.2f} deg: a 3-axis machine cannot follow it. "
                                        "Export it for a 5-axis machine.").format(refusal.tilt_deg)
        else:
            text = translate("WorkCal", "The part sits tilted: W turns the tool {:.3f} deg away from the machine's "
                                        "Z, more than the {:g} deg allowed for a 3-axis machine. Level the part "
                                        "(shim it) and calibrate again, allow {:g} deg if your tool can take it, or "
                                        "export for a 5-axis machine.").format(refusal.tilt_deg,
                                                                               refusal.tolerance_deg, needed)
        self.refusal_text.setText(text)
        self.allow_button.setText(translate("WorkCal", "Allow {:g} deg").format(needed))
        self.allow_button.setVisible(not refusal.five_axis_path)
        self.allowed = needed
        self.refusal.setVisible(True)
        self.reveal(self.refusal)

    def allow_tilt(self):
        self.tilt.setValue(self.allowed)
        return self.export()

    def use_five_axes(self):
        self.machine.setCurrentIndex(self.machine.findData("5axis-tcp"))
        return self.export()

    def scene(self) -> Scene:
        """The toolpath and the part in the robot frame (toolpath step), with the robot at its worst pose when
        it is shown; fitted to all of them, so the robot is seen standing where it stands beside the part."""
        from workcal_wb.fc.robot_pose import find

        scene = robot_frame_scene(self)
        calibration = self.guide.calibration()
        robot = find(calibration) if calibration is not None else None
        if robot is None:
            return scene
        label = (translate("WorkCal", "Robot at its worst pose"), robot)
        if scene.fit:  # the calibrated toolpath and the placed part are shown: the robot joins them
            return Scene(show=scene.show + [robot], fit=scene.fit + [robot], labels=scene.labels + [label],
                         orientation="isometric")
        reference = self.setup()["reference"]
        return Scene(show=[robot] + ([reference] if reference is not None else []), labels=[label],
                     orientation="isometric")
