"""What the guide's steps share: the Step base class, the Scene a step shows, narrow-panel widgets."""
from __future__ import annotations

from dataclasses import dataclass, field

import FreeCAD

from workcal_wb.core.result import USABLE
from workcal_wb.gui.task_panels import QtCore, QtWidgets
from workcal_wb.gui.task_panels.common import scroll_area_around

translate = FreeCAD.Qt.translate

# FAILED: the step was done and went wrong (a calibration that failed, a region it found empty).
DONE, TODO, ATTENTION, FAILED = "done", "todo", "attention", "failed"


@dataclass
class Scene:
    """What the 3D view shows for a step: ``show`` these objects (the calibration's others are hidden),
    fit the view to ``fit`` (default: all shown), ``labels``: (text, object or (2, 3) box) pairs,
    ``orientation``: a FreeCAD.Rotation, "isometric", or None to keep the camera's."""

    show: list = field(default_factory=list)
    fit: list = field(default_factory=list)
    labels: list = field(default_factory=list)
    orientation: object = None
    poses: object = None  # gui.candidate_display.Poses drawn over the view (an ambiguous result's poses)


class Step:
    NAME = TITLE = HEADING = TIP = ""

    def __init__(self, guide):
        self.guide = guide
        self.doc = guide.doc
        self.widget = QtWidgets.QWidget()
        self.widget.setObjectName(f"WorkCalPage_{self.NAME}")
        layout = QtWidgets.QVBoxLayout(self.widget)
        layout.setContentsMargins(0, 0, 0, 0)
        # What went wrong in the page's last action, at its top: the file or object and what is wrong.
        self.problem = label(name=f"WorkCalProblem_{self.NAME}")
        self.problem.setStyleSheet("QLabel { color: #c62828; }")
        self.problem.setVisible(False)
        layout.addWidget(self.problem)
        self.build(layout)
        layout.addStretch(1)

    def build(self, layout) -> None:
        raise NotImplementedError

    def state(self) -> tuple:
        raise NotImplementedError

    def refresh(self) -> None:
        """Read the page's widgets from the document again."""

    def scene(self) -> Scene:
        return Scene()

    def setup(self) -> dict:
        from workcal_wb.fc.setup import get_setup

        return get_setup(self.doc)

    def reveal(self, widget) -> None:
        reveal(widget)

    def run_guarded(self, title: str, action):
        """Run ``action()`` as a command runs, nothing raised escaping: a refusal (WorkCalError) is shown at
        the top of the page and in the Report view; a bug's traceback goes to the Report view only."""
        from workcal_wb.core.errors import Cancelled, WorkCalError
        from workcal_wb.gui.task_panels.common import error, for_people, guarded

        def shown_on_the_page():
            try:
                return action()
            except Cancelled:
                raise
            except WorkCalError as exc:
                error(str(exc))
                self.show_problem(for_people(str(exc)))
                return None

        self.show_problem("")
        result = guarded(title)(shown_on_the_page)()
        self.guide.refresh()
        return result

    def show_problem(self, text: str) -> None:
        self.problem.setText(text)
        self.problem.setVisible(bool(text))
        if text:
            reveal(self.problem)


def off_model_advice(calibration) -> str:
    """For a calibration that is not ok: per region, how many of its points its placed model leaves
    unexplained (the red points in the 3D view), where they lie and what to do, in plain words; "" when
    the calibration is ok or says nothing of them."""
    from workcal_wb.fc.regions import off_model
    from workcal_wb.gui.task_panels.common import for_people

    if calibration is None or calibration.Status in (*USABLE, "new"):
        return ""
    paragraphs = []
    for role, note in off_model(calibration).items():
        if not note["count"]:
            continue
        region = translate("WorkCal", "workpiece") if role == "workpiece" else translate("WorkCal", "reference object")
        paragraphs.append(translate("WorkCal", "The {} region holds {} points its model does not explain (red in the "
                                               "3D view), {}.\nWhat to do: {}. Pick the region again in the Regions "
                                               "step, or take the red points out of it with Subtract (Ctrl), then "
                                               "calibrate again.").format(region, note["count"], note["where"],
                                                                          note["change"]))
    return for_people("\n\n".join(paragraphs))


def reveal(widget) -> None:
    """Scroll FreeCAD's task view so that ``widget`` (a message just shown, a page just opened) is in sight,
    from the event loop: a panel being built is not in the window yet."""
    QtCore.QTimer.singleShot(0, lambda: _ensure_visible(widget))


def _ensure_visible(widget) -> None:
    area = scroll_area_around(widget)  # None: the panel closed meanwhile
    try:
        if area is not None:
            area.ensureWidgetVisible(widget)
    except RuntimeError:  # the panel closed meanwhile
        pass


class WrappingLabel(QtWidgets.QLabel):
    """A QLabel that wraps and asks for the height its text needs at the width it got: layouts inside
    FreeCAD's task view size a wrapping label from its width hint, so a text that wraps to more lines
    at the width the label finally gets would be cut off at the bottom."""

    def resizeEvent(self, event):
        super().resizeEvent(event)
        needed = self.heightForWidth(self.width())
        if needed > 0 and needed != self.minimumHeight():
            self.setMinimumHeight(needed)


def label(text: str = "", tip: str = "", name: str = "") -> QtWidgets.QLabel:
    """A label that wraps: it never widens the panel, and it is as tall as its text needs."""
    widget = WrappingLabel(text)
    widget.setWordWrap(True)
    widget.setTextFormat(QtCore.Qt.PlainText)
    if tip:
        widget.setToolTip(tip)
    if name:
        widget.setObjectName(name)
    return widget


def button(text: str, tip: str, slot, name: str = "") -> QtWidgets.QPushButton:
    widget = QtWidgets.QPushButton(text)
    widget.setToolTip(tip)
    widget.clicked.connect(lambda checked=False: slot())
    if name:
        widget.setObjectName(name)
    return widget


def form_layout() -> QtWidgets.QFormLayout:
    """A form whose fields go under their labels when the panel is narrow."""
    form = QtWidgets.QFormLayout()
    form.setRowWrapPolicy(QtWidgets.QFormLayout.WrapLongRows)
    form.setFieldGrowthPolicy(QtWidgets.QFormLayout.AllNonFixedFieldsGrow)
    return form


def combo(name: str, tip: str) -> QtWidgets.QComboBox:
    """A combo box that takes the width it is given (long entries are shortened, never the panel widened)."""
    widget = QtWidgets.QComboBox()
    widget.setObjectName(name)
    widget.setToolTip(tip)
    widget.setSizeAdjustPolicy(QtWidgets.QComboBox.AdjustToMinimumContentsLengthWithIcon)
    widget.setMinimumContentsLength(8)
    return widget


class UnitChooser(QtWidgets.QWidget):
    """The unit a file was read in, to be changed (``on_change(unit)``), and under it a warning when the
    size it gives makes no sense, with the one-click fix ("Read it in m")."""

    def __init__(self, name: str, on_change):
        from workcal_wb.gui.actions import UNIT_CHOICES

        super().__init__()
        self.setObjectName(name)
        self.on_change = on_change
        self.suggestion = None
        layout = QtWidgets.QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        self.combo = combo(f"{name}_units", translate("WorkCal", "The length unit of the numbers in the file; "
                                                                 "choosing another reads the file again in it"))
        for unit in UNIT_CHOICES:
            self.combo.addItem(unit, unit)
        self.combo.activated.connect(lambda index: self.on_change(self.combo.itemData(index)))
        caption = QtWidgets.QLabel(translate("WorkCal", "Read in"))
        caption.setToolTip(self.combo.toolTip())
        line = QtWidgets.QHBoxLayout()
        line.addWidget(caption)
        line.addWidget(self.combo, 1)
        layout.addLayout(line)
        self.warning = label(name=f"{name}_warning")
        self.warning.setStyleSheet("QLabel { color: #b04a00; }")
        layout.addWidget(self.warning)
        self.fix = button("", translate("WorkCal", "Read the file again in the unit its size suggests"),
                          lambda: self.on_change(self.suggestion), f"{name}_fix")
        layout.addWidget(self.fix)

    def show_units(self, units: str, warning: str = "", suggestion=None) -> None:
        """Show ``units`` ("" hides the chooser: no file whose unit can change) and the warning, if any."""
        self.setVisible(bool(units))
        self.combo.blockSignals(True)
        self.combo.setCurrentIndex(self.combo.findData(units))
        self.combo.blockSignals(False)
        self.suggestion = suggestion
        if warning and warning != self.warning.text():
            reveal(self.warning)
        self.warning.setText(warning)
        self.warning.setVisible(bool(warning))
        self.fix.setText(translate("WorkCal", "Read it in {}").format(suggestion) if suggestion else "")
        self.fix.setVisible(bool(suggestion))


def row(*widgets) -> QtWidgets.QHBoxLayout:
    layout = QtWidgets.QHBoxLayout()
    for widget in widgets:
        layout.addWidget(widget)
    return layout


