"""The WorkCal guide: one task panel that takes a designer through a calibration, step by step.

The steps - scan, models, regions, calibrate, result, toolpath, export - are listed at the top with
the state of each (done, to do, needs attention) read from the document, and the next one to do
highlighted; below is the page of the step shown.  Going to a step brings the 3D view to what it is
about (``Step.scene``): the objects it concerns are shown, the others of the calibration hidden, the
view fitted to them and each labelled in plain words.  The guide follows the document: any change
(an undo, a command run from the toolbar) refreshes the states.

Pages change the document only through recorded ``workcal_wb.fc`` calls (``gui.replay``), so a macro
recorded while using the guide replays headless.
"""
from __future__ import annotations

import FreeCAD

import workcal_wb
from workcal_wb.fc import proxies
from workcal_wb.fc.setup import get_setup
from workcal_wb.gui import candidate_display
from workcal_wb.gui import view as gui_view
from workcal_wb.gui.task_panels import CLOSE, QtCore, QtGui, QtWidgets
from workcal_wb.gui.task_panels.common import close_dialog, scroll_area_around, show_panel
from workcal_wb.gui.task_panels.steps import ATTENTION, DONE, FAILED, STEPS, TODO
from workcal_wb.gui.task_panels.steps.base import reveal

translate = FreeCAD.Qt.translate

MARKS = {DONE: ("\u2713", "#2e7d32"), TODO: ("\u25cb", "#777777"), ATTENTION: ("!", "#d06000"),
         FAILED: ("\u2717", "#c62828")}
NEXT_MARK = ("\u25b6", "#2a62b0")
NEXT_STYLE = "QFrame#{} {{ background: #dce8f7; border-left: 3px solid #2a62b0; border-radius: 3px; }}"
SHOWN_STYLE = "QFrame#{} {{ border: 1px solid #9aa4ae; border-radius: 3px; }}"


# A step's state in the list is cut to about this many characters (two lines of the default panel); the
# whole of it is in the row's tooltip and on the step's page.
STATE_CHARS = 70


def short(text: str) -> str:
    """The state as the step list shows it: whole when short, else cut at a word with an ellipsis."""
    if len(text) <= STATE_CHARS:
        return text
    return text[:STATE_CHARS].rsplit(" ", 1)[0].rstrip(",;:(") + "\u2026"


class StepRow(QtWidgets.QFrame):
    """One line of the step list: a mark, the step's name and its state in words; a click opens it."""

    clicked = QtCore.Signal()

    def __init__(self, number: int, step):
        super().__init__()
        self.setObjectName(f"WorkCalStep_{step.NAME}")
        self.setCursor(QtCore.Qt.PointingHandCursor)
        self.setToolTip(step.TIP)
        grid = QtWidgets.QGridLayout(self)
        grid.setContentsMargins(4, 2, 4, 2)
        grid.setHorizontalSpacing(6)
        grid.setVerticalSpacing(0)
        self.mark = QtWidgets.QLabel()
        self.mark.setFixedWidth(14)
        self.title = QtWidgets.QLabel(f"{number}. {step.TITLE}")
        self.state = QtWidgets.QLabel()
        self.state.setWordWrap(True)
        self.state.setObjectName(f"WorkCalStepState_{step.NAME}")
        font = self.state.font()
        font.setPointSizeF(max(font.pointSizeF() - 1, 7.0))
        self.state.setFont(font)
        grid.addWidget(self.mark, 0, 0)
        grid.addWidget(self.title, 0, 1)
        grid.addWidget(self.state, 1, 1)
        grid.setColumnStretch(1, 1)

    def show_state(self, state: str, text: str, is_next: bool, shown: bool) -> None:
        from workcal_wb.gui.task_panels.common import for_people

        mark, colour = NEXT_MARK if is_next and state != FAILED else MARKS[state]
        self.mark.setText(f"<b style='color:{colour}'>{mark}</b>")
        text = for_people(text)
        self.state.setText(short(text))
        self.state.setToolTip(text if short(text) != text else "")
        title_font = self.title.font()
        title_font.setBold(shown or is_next)
        self.title.setFont(title_font)
        name = self.objectName()
        self.setStyleSheet(NEXT_STYLE.format(name) if is_next else SHOWN_STYLE.format(name) if shown else "")

    def mouseReleaseEvent(self, event):  # noqa: N802  (Qt's name)
        self.clicked.emit()


class PageScroll(QtWidgets.QScrollArea):
    """The guide's scroll area: as wide as its content needs (plus its scroll bar), so the content is never
    cut at the right; only the height is the task view's to give."""

    def minimumSizeHint(self):  # noqa: N802  (Qt's name)
        hint = super().minimumSizeHint()
        content = self.widget()
        if content is not None:
            hint.setWidth(content.minimumSizeHint().width() + self.verticalScrollBar().sizeHint().width())
        return hint

    def sizeHint(self):  # noqa: N802
        hint = super().sizeHint()
        hint.setWidth(self.minimumSizeHint().width())
        return hint


class FitToTaskView(QtCore.QObject):
    """Keeps the guide's form as tall as the room FreeCAD's task view shows below the form's top, so the
    task view itself never scrolls: the guide's own scroll area takes the overflow and the button under it
    stays in sight.  Follows the task view's resizes (the window, the docks)."""

    # Never shorter than this (px): a few lines of the page and the button, on the smallest screens.
    MIN_HEIGHT = 240
    # Room left below the form for the task box's frame and the task view's margin (px).
    BOTTOM_MARGIN = 16

    def __init__(self, form):
        super().__init__(form)
        self.form = form
        self.area = None
        QtCore.QTimer.singleShot(0, self.attach)

    def attach(self) -> None:
        area = scroll_area_around(self.form)  # None: the panel closed, or is not shown in a task view (yet)
        if area is None:
            return
        self.area = area
        area.viewport().installEventFilter(self)
        self.fit()

    def eventFilter(self, watched, event):  # noqa: N802  (Qt's name)
        if event.type() == QtCore.QEvent.Resize:
            QtCore.QTimer.singleShot(0, self.fit)
        return False

    def fit(self) -> None:
        try:
            viewport = self.area.viewport()
            # The form's top in the scrolled content (which lies that far up the viewport).
            top = self.form.mapTo(viewport, QtCore.QPoint(0, 0)).y() + self.area.verticalScrollBar().value()
        except (RuntimeError, AttributeError):
            return
        height = max(self.MIN_HEIGHT, viewport.height() - top - self.BOTTOM_MARGIN)
        if self.form.minimumHeight() != height:
            self.form.setFixedHeight(height)
        QtCore.QTimer.singleShot(0, self.trim)

    def trim(self) -> None:
        """Take off what still makes the task view scroll (its frames and margins, measured once laid out)."""
        try:
            overflow = self.area.verticalScrollBar().maximum()
        except (RuntimeError, AttributeError):
            return
        if overflow > 0 and self.form.height() - overflow >= self.MIN_HEIGHT:
            self.form.setFixedHeight(self.form.height() - overflow)


class DocumentWatcher:
    """FreeCAD document observer: any change to the guide's document refreshes it (once per event-loop turn)."""

    def __init__(self, guide):
        self.guide = guide

    def _ours(self, obj) -> bool:
        return getattr(obj, "Document", None) is self.guide.doc

    def slotCreatedObject(self, obj):  # noqa: N802  (FreeCAD's names)
        if self._ours(obj):
            self.guide.schedule_refresh()

    def slotDeletedObject(self, obj):  # noqa: N802
        if self._ours(obj):
            self.guide.schedule_refresh()

    def slotChangedObject(self, obj, prop):  # noqa: N802
        if self._ours(obj):
            self.guide.schedule_refresh()

    def slotUndoDocument(self, doc):  # noqa: N802
        if doc is self.guide.doc:
            self.guide.schedule_refresh()

    def slotRedoDocument(self, doc):  # noqa: N802
        if doc is self.guide.doc:
            self.guide.schedule_refresh()

    def slotDeletedDocument(self, doc):  # noqa: N802
        if doc is self.guide.doc:
            self.guide.document_closed()


class GuidePanel:
    """The guide's task panel.  ``go(name)`` opens a step; ``states()`` is what the step list shows."""

    current = None  # the guide last opened (FreeCAD's activeDialog() does not give the Python object)

    def __init__(self, doc, step: str | None = None):
        GuidePanel.current = self
        self.doc = doc
        self.shown = None
        self.closed = False
        self.document_gone = False  # set when the document closes under the guide
        self.exported = None  # the last program written from this guide (the export step's state)
        self._refresh_pending = False
        self.steps = {cls.NAME: cls(self) for cls in STEPS}
        self.form = self._build()
        self.labels = gui_view.Labels(self.view()) if self.view() is not None else None
        self.watcher = DocumentWatcher(self)
        FreeCAD.addDocumentObserver(self.watcher)
        self.refresh()
        self.go(step or self.next_step())

    @classmethod
    def open(cls, doc=None, step: str | None = None):
        """The guide of ``doc`` at ``step`` (default: the next step to do), the open one switched to it;
        returns the panel.  A step reopens its guide through this (``self.guide.open``) after a panel
        that took the guide's place closes.  Without ``doc`` it does nothing: FreeCAD calls ``open()`` of
        every task dialog it shows."""
        import FreeCADGui

        if doc is None:
            return None

        current = cls.current
        if current is not None and current.alive() and FreeCADGui.Control.activeDialog():
            if current.doc is doc:
                current.go(step or current.next_step())
                return current
            current.close()
        return show_panel(lambda: cls(doc, step))

    # ------------------------------------------------------------------ widgets
    def _build(self):
        """The step list and the page scroll inside the panel; the Next button stays below them, in sight:
        the form is kept as tall as the part of FreeCAD's task view it can show (``FitToTaskView``)."""
        form = QtWidgets.QWidget()
        form.setObjectName("WorkCalGuide")
        form.setWindowTitle(translate("WorkCal", "WorkCal calibration"))
        form.setWindowIcon(QtGui.QIcon(workcal_wb.icon("WorkCal_Guide")))
        outer = QtWidgets.QVBoxLayout(form)
        outer.setContentsMargins(0, 0, 0, 0)
        outer.setSpacing(4)
        self.scroll = PageScroll()
        self.scroll.setObjectName("WorkCalGuideScroll")
        self.scroll.setWidgetResizable(True)
        self.scroll.setFrameShape(QtWidgets.QFrame.NoFrame)
        content = QtWidgets.QWidget()
        content.setObjectName("WorkCalGuideContent")
        layout = QtWidgets.QVBoxLayout(content)
        layout.setContentsMargins(2, 2, 4, 2)  # narrow: the scroll bar beside it takes the width they would
        layout.setSpacing(4)
        self.rows = {}
        for number, (name, step) in enumerate(self.steps.items(), 1):
            row = StepRow(number, step)
            row.clicked.connect(lambda n=name: self.go(n))
            layout.addWidget(row)
            self.rows[name] = row
        line = QtWidgets.QFrame()
        line.setFrameShape(QtWidgets.QFrame.HLine)
        layout.addWidget(line)
        self.page_title = QtWidgets.QLabel()
        self.page_title.setObjectName("WorkCalPageTitle")
        self.page_title.setWordWrap(True)
        font = self.page_title.font()
        font.setBold(True)
        font.setPointSizeF(font.pointSizeF() + 1)
        self.page_title.setFont(font)
        layout.addWidget(self.page_title)
        self.stack = QtWidgets.QStackedWidget()
        for step in self.steps.values():
            self.stack.addWidget(step.widget)
        layout.addWidget(self.stack)
        layout.addStretch(1)
        self.scroll.setWidget(content)
        outer.addWidget(self.scroll, 1)
        self.next_button = QtWidgets.QPushButton()
        self.next_button.setObjectName("WorkCalNextStep")
        self.next_button.clicked.connect(lambda: self.go(self.next_step()))
        outer.addWidget(self.next_button)
        self.fitter = FitToTaskView(form)
        return form

    def view(self):
        import FreeCADGui

        gui_doc = FreeCADGui.getDocument(self.doc.Name) if self.doc.Name in FreeCAD.listDocuments() else None
        view = gui_doc.ActiveView if gui_doc is not None else None
        return view if hasattr(view, "getSceneGraph") else None

    # ------------------------------------------------------------------ states
    def states(self) -> dict:
        """{step name: (DONE|TODO|ATTENTION, the state in words)} as the document stands."""
        return {name: step.state() for name, step in self.steps.items()}

    def next_step(self) -> str:
        """The first step not done (the last one when all are)."""
        states = self.states()
        return next((name for name in self.steps if states[name][0] != DONE), list(self.steps)[-1])

    def calibration(self):
        """The document's latest calibration of the chosen scan and models (None when there is none)."""
        from workcal_wb.fc.lookups import find_calibrations

        setup = get_setup(self.doc)
        for obj in reversed(find_calibrations(self.doc)):
            if (obj.Scan, obj.Workpiece, obj.Reference) == (setup["scan"], setup["workpiece"], setup["reference"]):
                return obj
        return None

    # ------------------------------------------------------------------ navigation
    def go(self, name: str) -> None:
        """Open the step ``name``: its page, and the 3D view brought to what it is about."""
        if self.closed:
            return
        step = self.steps[name]
        self.shown = name
        for other in self.steps.values():  # the stack takes the height of the page shown, not of the tallest
            policy = QtWidgets.QSizePolicy.Preferred if other is step else QtWidgets.QSizePolicy.Ignored
            other.widget.setSizePolicy(policy, policy)
        self.stack.setCurrentWidget(step.widget)
        self.page_title.setText(f"{list(self.steps).index(name) + 1}. {step.HEADING}")
        step.refresh()
        self._show_rows()
        reveal(self.page_title)
        self.show_scene()

    def show_scene(self) -> None:
        """Show the objects of the open step, hide the calibration's others, fit and label."""
        view = self.view()
        if view is None or self.shown is None:
            return
        scene = self.steps[self.shown].scene()
        shown = set(id(o) for o in scene.show)
        for obj in self._calibration_objects():
            vobj = getattr(obj, "ViewObject", None)
            if vobj is not None:
                visible = id(obj) in shown
                if bool(vobj.Visibility) != visible:
                    vobj.Visibility = visible
        if scene.orientation == "isometric":
            with gui_view.without_animation(view):
                view.viewIsometric()
            orientation = None
        else:
            orientation = scene.orientation
        gui_view.look_at(view, scene.fit or scene.show, orientation)
        candidate_display.draw(view, scene.poses)
        if self.labels is not None:
            boxes = [(text, where if not hasattr(where, "ViewObject") else gui_view.bounding_box([where]))
                     for text, where in scene.labels]
            boxes = [(text, box) for text, box in boxes if box is not None]
            points = gui_view.label_points(view, [box for _, box in boxes])
            self.labels.show([(text, point) for (text, _), point in zip(boxes, points)])

    def _calibration_objects(self) -> list:
        """What the guide shows and hides: the chosen scan and models, and WorkCal's own objects."""
        setup = [o for o in get_setup(self.doc).values() if o is not None]
        ours = [o for o in self.doc.Objects if proxies.type_of(o) not in (None, "WorkCal::Setup")]
        return setup + [o for o in ours if o not in setup]

    def refresh(self) -> None:
        """Read the states and the open page from the document again."""
        self._refresh_pending = False
        if self.closed or self.doc.Name not in FreeCAD.listDocuments():
            return
        if not self.alive():  # FreeCAD closed the dialog under us: stop following the document
            self.closed = True
            FreeCAD.removeDocumentObserver(self.watcher)
            return
        if self.shown is not None:
            self.steps[self.shown].refresh()
        self._show_rows()

    def _show_rows(self) -> None:
        states = self.states()
        following = self.next_step()
        for name, row in self.rows.items():
            state, text = states[name]
            row.show_state(state, text, is_next=(name == following and state != DONE), shown=(name == self.shown))
        title = self.steps[following].TITLE
        self.next_button.setText(translate("WorkCal", "Next: {}").format(title))
        self.next_button.setVisible(following != self.shown)

    def schedule_refresh(self) -> None:
        if not self._refresh_pending and not self.closed:
            self._refresh_pending = True
            QtCore.QTimer.singleShot(0, self.refresh)

    # ------------------------------------------------------------------ task dialog protocol
    def getStandardButtons(self):
        return CLOSE

    def reject(self):
        """Close: stop a running calibration first (the dialog closes once the worker has stopped)."""
        if self.steps["calibrate"].busy():
            self.steps["calibrate"].cancel()
            return False
        self.close()
        return True

    def accept(self):
        return self.reject()

    def close(self) -> None:
        if self.closed:
            return
        shown = self._form_exists()  # else FreeCAD closed the dialog, and the one open now is another's
        self.closed = True
        FreeCAD.removeDocumentObserver(self.watcher)
        if self.labels is not None:
            self.labels.remove()
        view = None if self.document_gone else self.view()
        if view is not None:
            candidate_display.clear(view)
        if shown:
            close_dialog()
        if GuidePanel.current is self:
            GuidePanel.current = None

    def document_closed(self) -> None:
        # Its view goes with the document: FreeCAD 1.0 has already deleted the GUI document (asking
        # for it raises) and its 3D view may be half torn down, so nothing drawn in it is touched.
        self.labels = None
        self.document_gone = True
        self.close()

    def alive(self) -> bool:
        """Whether the panel's widgets still exist (FreeCAD may close the dialog under us)."""
        return self._form_exists() and not self.closed

    def _form_exists(self) -> bool:
        try:
            self.form.objectName()
        except (RuntimeError, AttributeError):  # its widgets deleted, or the form taken back by FreeCAD
            return False
        return True
