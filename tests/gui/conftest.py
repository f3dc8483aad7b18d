"""Shared fixtures for the GUI tests (run inside FreeCAD by tests/gui/run_gui_tests.py under Xvfb).

* ``workbench``: the WorkCal workbench, activated (session).
* ``doc``: a fresh document with its 3D view, active; closed afterwards with any task dialog left open.
* ``shoot(name)``: save the active 3D view as ``<output_dir>/<name>.png`` and return the path.
* ``report``: the Report view; ``report.mark()`` then ``report.since()`` gives what was printed after.
* ``view_driver``: synthetic mouse and key events sent through the real 3D view (Coin pixel positions).
* ``pump(seconds)``: run the event loop for a while; ``settle()``: wait until the 3D view stops changing.
* ``assert_ok_cancel(panel)``: the panel's standard buttons are OK and Cancel.
* ``choose_folder(button, folder)``: click a Browse... button and answer its folder dialog.
* ``shoot_window(name)``: the whole main window as the user sees it (panel, tree and 3D view) as a PNG.
* ``clipped_texts(widget)``, ``horizontal_scroll(widget)``, ``view_share(points)``: what a step must get
  right at FreeCAD's default sizes: no text cut off, no sideways scrolling, the objects fill the view.
Message boxes are off (``task_panels.common.INTERACTIVE = False``) so no modal dialog blocks a test;
messages still reach the Report view, which is where tests read them.
"""
from pathlib import Path

import pytest

FreeCAD = pytest.importorskip("FreeCAD")
if not FreeCAD.GuiUp:  # pragma: no cover - these tests need the GUI
    collect_ignore_glob = ["test_*.py"]
else:
    import FreeCADGui

    from workcal_wb.gui.task_panels import QtCore, QtGui, QtWidgets, common
    from workcal_wb.gui.view import look

SHOT_SIZE = (1000, 750)


def pump(seconds: float = 0.05) -> None:
    """Process events for ``seconds`` (at least once)."""
    common.process_events(seconds)


def settle(timeout_s: float = 5.0, quiet_s: float = 0.3) -> None:
    """Wait until the active 3D view stops changing: FreeCAD 1.x narrows it about a second after a task
    panel opens, and animates camera moves.  Screen positions computed before that are stale."""
    import time

    view = active_view()

    def state():
        return tuple(view.getSize()), view.getCamera()

    last, since = state(), time.monotonic()
    end = since + timeout_s
    while time.monotonic() < end:
        pump(0.05)
        now = state()
        if now != last:
            last, since = now, time.monotonic()
        elif time.monotonic() - since >= quiet_s:
            return


def clipped_texts(root) -> list:
    """The texts of visible labels, buttons, group boxes and combo boxes under ``root`` that do not fit the
    room they have (Qt elides or clips them): a label's size hint wider than the label (or, for a wrapping
    label, taller than it at its width), a button or combo box narrower than its text."""
    found = []
    for widget in root.findChildren(QtWidgets.QWidget):
        if not widget.isVisible() or widget.width() <= 0:
            continue
        if isinstance(widget, QtWidgets.QLabel) and widget.text() and not widget.pixmap():
            if widget.wordWrap():
                if widget.heightForWidth(widget.width()) > widget.height() + 1:
                    found.append(f"label {widget.text()!r}: {widget.heightForWidth(widget.width())} px high "
                                 f"in {widget.height()} px")
            elif widget.sizeHint().width() > widget.width() + 1:
                found.append(f"label {widget.text()!r}: {widget.sizeHint().width()} px in {widget.width()} px")
        elif isinstance(widget, QtWidgets.QAbstractButton) and widget.text():
            if widget.sizeHint().width() > widget.width() + 1:
                found.append(f"button {widget.text()!r}: {widget.sizeHint().width()} px in {widget.width()} px")
        elif isinstance(widget, QtWidgets.QGroupBox) and widget.title():
            needed = widget.fontMetrics().boundingRect(widget.title()).width() + 16
            if needed > widget.width():
                found.append(f"group {widget.title()!r}: {needed} px in {widget.width()} px")
        elif isinstance(widget, QtWidgets.QComboBox) and widget.currentText():
            needed = widget.fontMetrics().boundingRect(widget.currentText()).width() + 30  # the arrow
            if needed > widget.width():
                found.append(f"combo {widget.currentText()!r}: {needed} px in {widget.width()} px")
    return found


def horizontal_scroll(widget) -> bool:
    """Whether the task view holding ``widget`` scrolls sideways (its content wider than the panel)."""
    area = common.scroll_area_around(widget)
    return area is not None and area.horizontalScrollBar().isVisible()


def view_share(points) -> float:
    """The largest share of the 3D view's width or height the box of ``points`` covers on the screen
    (0 when part of it is off screen)."""
    import numpy as np

    from workcal_wb.gui.view import box_corners, screen_box

    points = np.asarray(points, dtype=float).reshape(-1, 3)
    box = np.array([points.min(axis=0), points.max(axis=0)])
    x0, y0, x1, y1 = screen_box(active_view(), box_corners(box))
    width, height = active_view().getSize()
    if x0 < -2 or y0 < -2 or x1 > width + 2 or y1 > height + 2:
        return 0.0
    return max((x1 - x0) / width, (y1 - y0) / height)


def assert_ok_cancel(panel) -> None:
    """The task panel asks FreeCAD for OK and Cancel in a form every PySide accepts (Qt6 flags are not ints)."""
    box = QtWidgets.QDialogButtonBox(panel.getStandardButtons())
    assert box.button(QtWidgets.QDialogButtonBox.Ok) and box.button(QtWidgets.QDialogButtonBox.Cancel)


def choose_folder(button, folder) -> bool:
    """Click ``button`` (a Browse... button) and answer the folder dialog it opens with ``folder``;
    whether a dialog was answered."""
    chosen = []

    def answer():
        dialog = QtWidgets.QApplication.activeModalWidget()
        if isinstance(dialog, QtWidgets.QFileDialog):
            dialog.setDirectory(str(folder))
            chosen.append(True)
            dialog.accept()
        else:
            QtCore.QTimer.singleShot(50, answer)

    QtCore.QTimer.singleShot(50, answer)
    button.click()
    return bool(chosen)


@pytest.fixture(name="choose_folder")
def choose_folder_fixture():
    return choose_folder


@pytest.fixture(name="assert_ok_cancel")
def assert_ok_cancel_fixture():
    return assert_ok_cancel


@pytest.fixture(name="page_fits")
def page_fits_fixture():
    """``page_fits(widget)``: wait for the view to settle, then assert no text is cut off and nothing scrolls
    sideways in the task panel holding ``widget``."""

    def check(widget):
        settle()
        assert not clipped_texts(widget), clipped_texts(widget)
        assert not horizontal_scroll(widget), "the panel is wider than FreeCAD's task view"

    return check


@pytest.fixture(name="view_share")
def view_share_fixture():
    return view_share


@pytest.fixture(name="settle")
def settle_fixture():
    return settle


@pytest.fixture(name="pump")
def pump_fixture():
    return pump


@pytest.fixture(autouse=True)
def non_interactive():
    before = common.INTERACTIVE
    common.INTERACTIVE = False
    yield
    common.INTERACTIVE = before


LOAD_LOG = {}  # the Report view after start-up and the workbench's first activation, before any test


def pytest_collection_modifyitems(session, config, items):
    """Activate WorkCal once before the first test, so its load messages are not mixed with tests'."""
    if not FreeCAD.GuiUp or "text" in LOAD_LOG:
        return
    LOAD_LOG["activated"] = FreeCADGui.activateWorkbench("WorkCalWorkbench") if \
        "WorkCalWorkbench" in FreeCADGui.listWorkbenches() else False
    pump(0.1)
    LOAD_LOG["text"] = Report().text()


@pytest.fixture(scope="session")
def workbench():
    FreeCADGui.activateWorkbench("WorkCalWorkbench")  # False when it is active already
    pump(0.1)
    assert FreeCADGui.activeWorkbench().name() == "WorkCalWorkbench"
    LOAD_LOG.setdefault("text", Report().text())
    return FreeCADGui.activeWorkbench()


@pytest.fixture
def load_log(workbench) -> str:
    """The Report view text at the first activation of the workbench by these fixtures."""
    return LOAD_LOG["text"]


def close_task_dialog() -> None:
    if FreeCADGui.Control.activeDialog():
        FreeCADGui.Control.closeDialog()
        pump(0.05)


@pytest.fixture
def doc(workbench, request):
    """A new, active document with a 3D view; closed (with any open task panel) after the test."""
    close_task_dialog()
    before = set(FreeCAD.listDocuments())
    name = "T_" + "".join(c if c.isalnum() else "_" for c in request.node.name)[:40]
    document = FreeCAD.newDocument(name)
    FreeCAD.setActiveDocument(document.Name)
    FreeCADGui.activeDocument()  # the view exists once the new document was shown
    pump(0.1)
    yield document
    close_task_dialog()
    FreeCADGui.Selection.clearSelection()
    for left in set(FreeCAD.listDocuments()) - before:
        FreeCAD.closeDocument(left)
    pump(0.05)


def active_view():
    view = FreeCADGui.ActiveDocument.ActiveView
    assert hasattr(view, "saveImage"), "the active view is not a 3D view"
    return view


def grab_window(path) -> None:
    """The main window as a PNG with the 3D view drawn in (Qt's grab leaves an OpenGL view grey)."""
    import os
    import tempfile

    window = FreeCADGui.getMainWindow()
    pump(0.1)
    image = window.grab().toImage()
    view = active_view()
    viewport = view.graphicsView().viewport()
    width, height = viewport.width(), viewport.height()
    with tempfile.TemporaryDirectory() as folder:
        rendered = os.path.join(folder, "view.png")
        view.saveImage(rendered, width, height, "Current")
        painter = QtGui.QPainter(image)
        painter.drawImage(viewport.mapTo(window, QtCore.QPoint(0, 0)), QtGui.QImage(rendered))
        painter.end()
    assert image.save(str(path)), f"screenshot {path} not written"


@pytest.fixture
def shoot_window(output_dir):
    def save(name: str) -> Path:
        path = Path(output_dir) / f"{name}.png"
        grab_window(path)
        return path

    return save


@pytest.fixture
def shoot(output_dir):
    """``shoot("name")`` saves the active 3D view to <output_dir>/name.png (asserted non-trivial)."""

    def save(name: str, fit: bool = False) -> Path:
        view = active_view()
        if fit:
            look(view)
        pump(0.05)
        path = Path(output_dir) / f"{name}.png"
        view.saveImage(str(path), SHOT_SIZE[0], SHOT_SIZE[1], "White")
        assert path.is_file() and path.stat().st_size > 2000, f"screenshot {path} not written"
        return path

    return save


class Report:
    """The Report view's text (where FreeCAD.Console messages go)."""

    def __init__(self):
        widget = FreeCADGui.getMainWindow().findChild(QtWidgets.QTextEdit, "Report view")
        assert widget is not None, "no Report view in the main window"
        self.widget = widget
        self._mark = 0

    def text(self) -> str:
        pump(0.02)
        return self.widget.toPlainText()

    def mark(self) -> None:
        self._mark = len(self.text())

    def since(self) -> str:
        return self.text()[self._mark:]


@pytest.fixture
def report():
    found = Report()
    found.mark()
    return found


class ViewDriver:
    """Mouse and key events sent to the 3D view's viewport, as a user's would arrive.

    Positions are Coin pixels (origin bottom-left, ``view.getSize()``); they are converted to the
    viewport's Qt coordinates, which FreeCAD maps back (±1 px)."""

    def __init__(self, view):
        self.view = view
        self.viewport = view.graphicsView().viewport()

    def to_qt(self, x, y):
        width, height = self.view.getSize()
        return QtCore.QPointF(x * self.viewport.width() / width, (height - y) * self.viewport.height() / height)

    def _mouse(self, kind, x, y, button=None, modifiers=None):
        button = button or QtCore.Qt.LeftButton
        modifiers = modifiers or QtCore.Qt.NoModifier
        pos = self.to_qt(x, y)
        held = QtCore.Qt.NoButton if kind == QtCore.QEvent.MouseButtonRelease else button
        if kind == QtCore.QEvent.MouseMove:
            button = QtCore.Qt.NoButton
        event = QtGui.QMouseEvent(kind, pos, QtCore.QPointF(self.viewport.mapToGlobal(pos.toPoint())),
                                  button, held, modifiers)
        QtWidgets.QApplication.sendEvent(self.viewport, event)
        pump(0.01)

    def press(self, x, y, button=None, modifiers=None):
        self._mouse(QtCore.QEvent.MouseButtonPress, x, y, button, modifiers)

    def release(self, x, y, button=None, modifiers=None):
        self._mouse(QtCore.QEvent.MouseButtonRelease, x, y, button, modifiers)

    def move(self, x, y, modifiers=None, held=None):
        event_button = held or QtCore.Qt.NoButton
        pos = self.to_qt(x, y)
        global_pos = QtCore.QPointF(self.viewport.mapToGlobal(pos.toPoint()))
        event = QtGui.QMouseEvent(QtCore.QEvent.MouseMove, pos, global_pos, QtCore.Qt.NoButton, event_button,
                                  modifiers or QtCore.Qt.NoModifier)
        QtWidgets.QApplication.sendEvent(self.viewport, event)
        pump(0.01)

    def click(self, x, y, button=None, modifiers=None):
        self.press(x, y, button, modifiers)
        self.release(x, y, button, modifiers)

    def drag(self, start, end, modifiers=None, steps=4):
        self.press(*start, modifiers=modifiers)
        for i in range(1, steps + 1):
            self.move(start[0] + (end[0] - start[0]) * i / steps, start[1] + (end[1] - start[1]) * i / steps,
                      modifiers, held=QtCore.Qt.LeftButton)
        self.release(*end, modifiers=modifiers)

    def key(self, key, modifiers=None):
        for kind in (QtCore.QEvent.KeyPress, QtCore.QEvent.KeyRelease):
            event = QtGui.QKeyEvent(kind, key, modifiers or QtCore.Qt.NoModifier)
            QtWidgets.QApplication.sendEvent(self.viewport, event)
        pump(0.01)


@pytest.fixture
def view_driver(doc):
    return ViewDriver(active_view())


def pytest_runtest_logreport(report):
    """Print a failure as soon as it happens: if FreeCAD crashes later, the cause is already on the terminal."""
    if report.failed:
        import sys

        sys.stdout.write(f"\n--- {report.nodeid} failed ({report.when}) ---\n{report.longreprtext}\n")
        sys.stdout.flush()
