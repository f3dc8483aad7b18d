"""Pick scan regions in the 3D view with a box or a lasso.

How it works (FreeCAD 0.20's Python API has no access to the C++ rubber-band selection):

* ``PickTool`` filters the 3D view's Qt mouse and key events: the left and right buttons are ours (no
  selection, no orbit, no context menu) while the middle button and the wheel still pan and zoom.
  Positions are converted to Coin pixels as FreeCAD does.  Box: press, drag, release.
  Lasso: click the corners (or drag freehand); right-click, Enter or a click on the first corner
  closes it; Esc drops it.  Shift adds to the region, Ctrl subtracts from it.
* ``polygon_mask`` projects every scan point with the camera's view volume (vectorised, same result as
  FreeCAD's ``getPointOnScreen``) and tests it against the polygon (``matplotlib.path``).  With
  "Visible points only" (the default) ``visible_mask`` keeps only the points no other scan point hides
  (a depth buffer of the points themselves), so a box over the part does not take the platform
  under it; without it the selection goes through the whole depth, like FreeCAD's point-cloud cut.
  All positions are Coin pixels (origin bottom-left), as in the events and ``view.getSize()``.
* ``PickPanel`` is the task panel: region (workpiece/reference), tool, mode, counts, undo of the last
  pick.  The whole session is one undo step: OK records the final regions as one command
  (``fc.regions.set_regions``, replayable in a macro), Cancel restores them.
"""
from __future__ import annotations

import numpy as np

import FreeCAD
import FreeCADGui

import workcal_wb
from workcal_wb.core import frames
from workcal_wb.core.errors import InputError, WorkCalError
from workcal_wb.fc import prefs
from workcal_wb.fc import scan as fc_scan
from workcal_wb.fc.placements import container_matrix
from workcal_wb.gui import region_display, replay
from workcal_wb.gui.task_panels import OK_CANCEL, QtCore, QtGui, QtWidgets
from workcal_wb.gui.task_panels.common import close_dialog

translate = FreeCAD.Qt.translate

BOX, LASSO = "box", "lasso"
REPLACE, ADD, SUBTRACT = "replace", "add", "subtract"
ROLES = ("workpiece", "reference")
CLOSE_LASSO_PX = 8  # a click this close to the first corner closes the lasso
FREEHAND_STEP_PX = 6  # while dragging with the button held, a corner every this many pixels
MIN_BOX_PX = 2  # a smaller "box" is a click, not a selection


# --- projection ----------------------------------------------------------------------------------

def world_points(obj) -> np.ndarray:
    """The scan points in document coordinates (the Placement of containing App::Parts added)."""
    points = fc_scan.scan_cloud(obj).points
    T = container_matrix(obj)
    return points if T is None else frames.apply(T, points)


def project(view, points: np.ndarray):
    """(N, 2) Coin pixel positions of ``points`` in ``view`` and a mask of those in front of the camera."""
    width, height = view.getSize()
    volume = view.getCameraNode().getViewVolume(float(width) / float(height))
    M = np.array(volume.getMatrix().getValue(), dtype=np.float64)  # row vectors: [x y z 1] @ M
    H = np.asarray(points, dtype=np.float64) @ M[:3] + M[3]
    w = H[:, 3]
    valid = w > 1e-12
    safe = np.where(valid, w, 1.0)
    xy = np.empty((len(H), 2))
    xy[:, 0] = (H[:, 0] / safe + 1.0) * 0.5 * width
    xy[:, 1] = (H[:, 1] / safe + 1.0) * 0.5 * height
    return xy, valid


def eye_depth(view, points: np.ndarray) -> np.ndarray:
    """Distance (mm) of each point in front of the camera, along its viewing direction."""
    from pivy import coin

    camera = view.getCameraNode()
    direction = np.array(camera.orientation.getValue().multVec(coin.SbVec3f(0, 0, -1)).getValue())
    position = np.array(camera.position.getValue().getValue())
    return (np.asarray(points, dtype=np.float64) - position) @ direction


# A point is hidden when a point nearer the camera by more than DEPTH_CELLS cell widths (in mm)
# projects into its cell; cells are CELL_SPACINGS times the points' spacing on the screen (so a
# surface of points is closed) and at least MIN_CELL_PX wide.
CELL_SPACINGS, DEPTH_CELLS, MIN_CELL_PX = 1.5, 5.0, 2.0


def visible_mask(view, points: np.ndarray) -> np.ndarray:
    """Which points no other point hides, as the camera of ``view`` sees them."""
    xy, valid = project(view, points)
    depth = eye_depth(view, points)
    return visible_points(xy, depth, valid, view.getSize(), _mm_per_pixel(view, depth[valid]))


def visible_points(xy: np.ndarray, depth: np.ndarray, valid: np.ndarray, size, mm_per_px: float) -> np.ndarray:
    """The points themselves rendered into a coarse depth buffer: a point is visible when no point in
    its cell is nearer by more than the slack a surface tilted up to about 80 degrees spans in a cell.
    ``xy``: screen pixels, ``depth``: mm in front of the camera, ``size``: (width, height) pixels."""
    from scipy.spatial import cKDTree

    idx = np.flatnonzero(valid)
    visible = valid.copy()
    if len(idx) < 2:
        return visible
    sample = idx[np.random.default_rng(0).choice(len(idx), min(len(idx), 4000), replace=False)]
    spacing_px = float(np.median(cKDTree(xy[sample]).query(xy[sample], k=2)[0][:, 1]))
    cell = max(MIN_CELL_PX, CELL_SPACINGS * spacing_px)
    width, height = size
    cells = np.floor(xy[idx] / cell).astype(np.int64)
    inside = (cells[:, 0] >= 0) & (cells[:, 1] >= 0) & (xy[idx, 0] < width) & (xy[idx, 1] < height)
    cells, depths, owners = cells[inside], depth[idx][inside], idx[inside]
    columns = int(width // cell) + 1
    key = cells[:, 1] * columns + cells[:, 0]
    nearest = np.full(key.max() + 1, np.inf)
    np.minimum.at(nearest, key, depths)
    hidden = depths > nearest[key] + DEPTH_CELLS * cell * mm_per_px
    visible[owners[hidden]] = False
    return visible


def _mm_per_pixel(view, depth: np.ndarray) -> float:
    """How many mm one screen pixel spans at the points' median depth (orthographic or perspective camera)."""
    camera = view.getCameraNode()
    height_px = float(view.getSize()[1])
    if hasattr(camera, "heightAngle"):
        return 2.0 * float(np.median(depth)) * float(np.tan(camera.heightAngle.getValue() / 2)) / height_px
    return float(camera.height.getValue()) / height_px


def polygon_mask(view, points: np.ndarray, polygon) -> np.ndarray:
    """Which points project inside ``polygon`` (Coin pixels; a box is its 4 corners)."""
    polygon = np.asarray(polygon, dtype=np.float64).reshape(-1, 2)
    if len(polygon) < 3:
        raise InputError(translate("WorkCal", "a selection needs at least 3 corners"))
    xy, valid = project(view, points)
    low, high = polygon.min(axis=0), polygon.max(axis=0)
    mask = valid & np.all((xy >= low) & (xy <= high), axis=1)
    if not _is_axis_aligned_box(polygon):
        from matplotlib.path import Path

        candidates = np.flatnonzero(mask)
        inside = Path(polygon).contains_points(xy[candidates])
        mask[candidates[~inside]] = False
    return mask


def _is_axis_aligned_box(polygon: np.ndarray) -> bool:
    if len(polygon) != 4:
        return False
    xs, ys = np.unique(polygon[:, 0]), np.unique(polygon[:, 1])
    return len(xs) == 2 and len(ys) == 2 and len({tuple(p) for p in polygon.tolist()}) == 4


def box_polygon(p0, p1) -> list:
    (x0, y0), (x1, y1) = p0, p1
    return [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]


def combine(regions: dict, role: str, picked: np.ndarray, mode: str) -> dict:
    """New {workpiece, reference} index arrays after applying ``picked`` to ``role`` with ``mode``.

    A point belongs to one object: what is added to one region leaves the other."""
    other = ROLES[1 - ROLES.index(role)]
    empty = np.empty(0, dtype=np.int64)
    current = {r: (regions.get(r) if regions.get(r) is not None else empty) for r in ROLES}
    picked = np.unique(np.asarray(picked, dtype=np.int64))
    if mode == REPLACE:
        current[role] = picked
    elif mode == ADD:
        current[role] = np.union1d(current[role], picked)
    elif mode == SUBTRACT:
        current[role] = np.setdiff1d(current[role], picked, assume_unique=True)
    else:
        raise InputError(f"unknown selection mode {mode!r}")
    if mode != SUBTRACT:
        current[other] = np.setdiff1d(current[other], picked, assume_unique=True)
    return current


# --- the interactive tool ------------------------------------------------------------------------

class PickTool(QtCore.QObject):
    """Box/lasso input on a 3D view; calls ``on_shape(polygon, modifier_mode)`` for each finished shape
    (polygon in Coin pixels), with ``modifier_mode`` ADD (Shift), SUBTRACT (Ctrl) or None.

    Input comes from a Qt event filter on the view's viewport: left and right button events (and moves
    while a shape is drawn) are consumed before FreeCAD sees them, so clicking on the scan neither
    selects it nor orbits the camera, and right-click opens no context menu; the middle button and the
    wheel still reach FreeCAD's navigation.  (Coin event callbacks are not enough: when the press is on
    an object, FreeCAD's selection node grabs the events that follow and the release never arrives.)
    Qt positions are converted to Coin pixels the way FreeCAD's Quarter widget does:
    x * dpr, height - 1 - y * dpr.
    """

    def __init__(self, view, on_shape, shape: str = BOX, alive=None, on_dead=None, doc_name: str = ""):
        super().__init__()
        self.view = view
        self.doc_name = doc_name  # the view's document
        self.on_shape = on_shape
        self.shape = shape
        self.alive = alive or (lambda: True)  # False once the owner (task panel) is gone
        self.on_dead = on_dead or (lambda: None)
        self.corners = []
        self.cursor = None
        self.held = False
        self.modifier = None
        self._feedback = None
        self._coords = None
        self._lines = None
        self._watched = []
        self.active = False

    # set-up
    def start(self) -> None:
        from pivy import coin

        if self.active:
            return
        self._feedback = coin.SoAnnotation()
        self._feedback.setName("WorkCalPickFeedback")
        colour = coin.SoBaseColor()
        colour.rgb = (0.9, 0.1, 0.1)
        style = coin.SoDrawStyle()
        style.lineWidth = 2
        style.linePattern = 0xF0F0
        light = coin.SoLightModel()
        light.model = coin.SoLightModel.BASE_COLOR
        self._coords = coin.SoCoordinate3()
        self._lines = coin.SoLineSet()
        self._lines.numVertices.setValue(0)
        for node in (light, colour, style, self._coords, self._lines):
            self._feedback.addChild(node)
        self.view.getSceneGraph().addChild(self._feedback)
        graphics_view = self.view.graphicsView()
        self._watched = [graphics_view.viewport(), graphics_view]
        for widget in self._watched:
            widget.installEventFilter(self)
        self._viewport().setCursor(QtCore.Qt.CrossCursor)
        self.active = True

    def stop(self) -> None:
        """Give the view back.  Only Qt objects are touched here (they say when they are gone), never
        FreeCAD's view itself, which may be half destroyed when its document closes; the feedback node
        leaves its scene graph from the event loop, if the document is still open then."""
        if not self.active:
            return
        self.active = False
        try:
            for widget in self._watched:
                widget.removeEventFilter(self)
            if self._watched:
                self._watched[0].unsetCursor()
        except RuntimeError:  # the widgets went with the view
            pass
        self._watched = []
        feedback, self._feedback = self._feedback, None
        doc_name = self.doc_name
        QtCore.QTimer.singleShot(0, lambda: _remove_feedback(doc_name, feedback))

    def set_shape(self, shape: str) -> None:
        self.cancel()
        self.shape = shape

    def cancel(self) -> None:
        self.corners, self.held, self.cursor = [], False, None
        self._draw()

    def _viewport(self):
        return self.view.graphicsView().viewport()

    def to_coin(self, qt_pos):
        """Coin pixels (origin bottom-left, as ``view.getSize()``) of a viewport position."""
        viewport = self._viewport()
        ratio = viewport.devicePixelRatioF()
        height = self.view.getSize()[1]
        return (float(qt_pos.x()) * ratio, height - 1.0 - float(qt_pos.y()) * ratio)

    # events
    @staticmethod
    def _modifier(modifiers):
        if modifiers & QtCore.Qt.ShiftModifier:
            return ADD
        if modifiers & QtCore.Qt.ControlModifier:
            return SUBTRACT
        return None

    def eventFilter(self, watched, event):  # noqa: N802  (Qt's name)
        if not self.active:
            return False
        if not self.alive():  # e.g. the task dialog was closed without OK/Cancel
            self.stop()
            self.on_dead()
            return False
        kind = event.type()
        try:
            if kind in (QtCore.QEvent.MouseButtonPress, QtCore.QEvent.MouseButtonDblClick,
                        QtCore.QEvent.MouseButtonRelease):
                return self._button(event, kind != QtCore.QEvent.MouseButtonRelease)
            if kind == QtCore.QEvent.MouseMove:
                return self._move(event)
            if kind == QtCore.QEvent.KeyPress:
                return self._key(event)
            if kind == QtCore.QEvent.ContextMenu:
                return True
        except Exception as exc:  # never let an exception escape into Qt's event dispatch
            import traceback

            FreeCAD.Console.PrintError(f"WorkCal: picking failed: {exc}\n{traceback.format_exc()}")
            return True
        return False

    def _button(self, event, down: bool) -> bool:
        button = event.button()
        if button not in (QtCore.Qt.LeftButton, QtCore.Qt.RightButton):
            return False  # middle button: FreeCAD's navigation
        pos = self.to_coin(event.pos())
        if button == QtCore.Qt.RightButton:
            if down:
                if self.shape == LASSO and len(self.corners) >= 3:
                    self._close_lasso()
                else:
                    self.cancel()
            return True
        if down:
            self._viewport().setFocus()
        if self.shape == BOX:
            if down:
                self.corners, self.cursor, self.held = [pos], pos, True
                self.modifier = self._modifier(event.modifiers())
            elif self.held:
                self.held = False
                start = self.corners[0]
                self.corners = []
                self._draw()
                if abs(pos[0] - start[0]) >= MIN_BOX_PX and abs(pos[1] - start[1]) >= MIN_BOX_PX:
                    self._emit(box_polygon(start, pos))
            return True
        if down:
            if not self.corners:
                self.modifier = self._modifier(event.modifiers())
                self.corners = [pos]
            elif len(self.corners) >= 3 and _distance(pos, self.corners[0]) <= CLOSE_LASSO_PX:
                self._close_lasso()
                return True
            elif _distance(pos, self.corners[-1]) >= 1:
                self.corners.append(pos)
            self.cursor, self.held = pos, True
            self._draw()
        else:
            self.held = False
        return True

    def _move(self, event) -> bool:
        if not self.corners:
            return False  # not drawing: FreeCAD's preselection and navigation as usual
        pos = self.to_coin(event.pos())
        self.cursor = pos
        if self.shape == LASSO and self.held and _distance(pos, self.corners[-1]) >= FREEHAND_STEP_PX:
            self.corners.append(pos)
        self._draw()
        return True

    def _key(self, event) -> bool:
        key = event.key()
        if key in (QtCore.Qt.Key_Return, QtCore.Qt.Key_Enter):
            if self.shape == LASSO and len(self.corners) >= 3:
                self._close_lasso()
            return True
        if key == QtCore.Qt.Key_Escape and self.corners:
            self.cancel()
            return True
        return False

    def _close_lasso(self) -> None:
        polygon = list(self.corners)
        self.corners, self.held, self.cursor = [], False, None
        self._draw()
        self._emit(polygon)

    def _emit(self, polygon) -> None:
        try:
            self.on_shape(polygon, self.modifier)
        except WorkCalError as exc:  # shown, never raised into Qt's event handling
            from workcal_wb.gui.task_panels.common import show_error

            show_error(translate("WorkCal", "Pick region"), str(exc))

    # feedback
    def outline(self) -> list:
        """The shape being drawn, in Coin pixels (closed), as the feedback shows it."""
        if not self.corners:
            return []
        if self.shape == BOX:
            corners = box_polygon(self.corners[0], self.cursor or self.corners[0])
        else:
            corners = list(self.corners) + ([self.cursor] if self.cursor and self.cursor != self.corners[-1] else [])
        return corners + [corners[0]]

    def _draw(self) -> None:
        if self._coords is None:
            return
        outline = self.outline()
        if len(outline) < 2:
            self._lines.numVertices.setValue(0)
            self._coords.point.setNum(0)
            return
        vectors = [self.view.getPointOnFocalPlane(int(round(x)), int(round(y))) for x, y in outline]
        self._coords.point.setValues(0, len(vectors), [(v.x, v.y, v.z) for v in vectors])
        self._coords.point.setNum(len(vectors))
        self._lines.numVertices.setValue(len(vectors))


def _remove_feedback(doc_name: str, feedback) -> None:
    gui_doc = FreeCADGui.getDocument(doc_name) if doc_name in FreeCAD.listDocuments() else None
    view = gui_doc.ActiveView if gui_doc is not None else None
    graph = view.getSceneGraph() if view is not None and hasattr(view, "getSceneGraph") else None
    if graph is not None and feedback is not None and graph.findChild(feedback) >= 0:
        graph.removeChild(feedback)


def _distance(a, b) -> float:
    return float(np.hypot(a[0] - b[0], a[1] - b[1]))


# --- the task panel ------------------------------------------------------------------------------

class PickPanel:
    """Task panel for picking the workpiece and reference regions of one scan.  ``on_close()`` runs once
    the panel has closed, whichever way (the guide opens again there)."""

    def __init__(self, obj, view, shape: str = BOX, role: str = "workpiece", on_close=None):
        self.obj, self.doc, self.view = obj, obj.Document, view
        self.points = world_points(obj)  # raises InputError for an empty or unusable scan
        self.initial = fc_scan.get_regions(obj)  # stale regions: refuse before anything changes
        self.on_close = on_close or (lambda: None)
        self.history = []
        self.picks = 0
        self.last_polygon = None  # the last box/lasso applied, Coin pixels
        self.tool = PickTool(view, self.apply_polygon, shape, alive=self._form_alive, on_dead=self._closed_outside,
                             doc_name=self.doc.Name)
        self.form = self._build_form()
        self.set_role(role)
        self.set_shape(shape)
        self.set_mode(REPLACE)
        self.transaction = bool(getattr(self.doc, "UndoMode", 0))
        if self.transaction:
            self.doc.openTransaction(translate("WorkCal", "Pick scan regions"))
        if hasattr(obj, "ViewObject") and obj.ViewObject is not None:
            obj.ViewObject.Visibility = True
        FreeCADGui.Selection.clearSelection()  # its highlight would hide the region colours
        region_display.update(obj)
        self.tool.start()
        self._refresh()

    # widgets
    def _build_form(self):
        form = QtWidgets.QWidget()
        form.setObjectName("WorkCalPickPanel")
        form.setWindowTitle(translate("WorkCal", "Pick scan regions"))
        form.setWindowIcon(QtGui.QIcon(workcal_wb.icon("WorkCal_PickBox")))
        layout = QtWidgets.QVBoxLayout(form)
        self.scan_label = QtWidgets.QLabel()
        self.scan_label.setWordWrap(True)
        layout.addWidget(self.scan_label)

        self.role_buttons = self._group(layout, translate("WorkCal", "Region"), [
            ("workpiece", translate("WorkCal", "Workpiece"), translate("WorkCal", "The points on the workpiece "
                                                                                  "(matched to its model X-A)")),
            ("reference", translate("WorkCal", "Reference object"), translate(
                "WorkCal", "The points on the fixed reference object (matched to its model B-P)"))])
        self.shape_buttons = self._group(layout, translate("WorkCal", "Tool"), [
            (BOX, translate("WorkCal", "Box"), translate("WorkCal", "Drag a rectangle")),
            (LASSO, translate("WorkCal", "Lasso"), translate("WorkCal", "Click the corners of a polygon"))],
            horizontal=True)
        self.mode_buttons = self._group(layout, translate("WorkCal", "Mode"), [
            (REPLACE, translate("WorkCal", "Replace"), translate("WorkCal", "The region becomes what you pick")),
            (ADD, translate("WorkCal", "Add (Shift)"), translate("WorkCal", "Add what you pick to the region")),
            (SUBTRACT, translate("WorkCal", "Subtract (Ctrl)"), translate("WorkCal", "Take what you pick out of "
                                                                                     "the region"))])
        for value, button in self.shape_buttons.items():
            button.toggled.connect(lambda checked, v=value: checked and self.tool.set_shape(v))
        self.visible_box = QtWidgets.QCheckBox(translate("WorkCal", "Visible points only"))
        self.visible_box.setObjectName("WorkCal_visible_only")
        self.visible_box.setToolTip(translate("WorkCal", "Take only the points you see, not those hidden behind "
                                                         "them (e.g. the platform under the part)"))
        self.visible_box.setChecked(bool(prefs.get("PickVisibleOnly")))
        self.visible_box.toggled.connect(lambda on: prefs.set("PickVisibleOnly", int(bool(on))))
        layout.addWidget(self.visible_box)

        self.count_label = QtWidgets.QLabel()
        self.count_label.setObjectName("WorkCalRegionCounts")
        self.count_label.setWordWrap(True)
        layout.addWidget(self.count_label)
        row = QtWidgets.QHBoxLayout()
        self.undo_button = QtWidgets.QPushButton(translate("WorkCal", "Undo pick"))
        self.undo_button.setToolTip(translate("WorkCal", "Undo the last pick"))
        self.undo_button.clicked.connect(self.undo_pick)
        self.clear_button = QtWidgets.QPushButton(translate("WorkCal", "Clear region"))
        self.clear_button.setToolTip(translate("WorkCal", "Empty the region chosen above"))
        self.clear_button.clicked.connect(self.clear_role)
        row.addWidget(self.undo_button)
        row.addWidget(self.clear_button)
        layout.addLayout(row)
        help_text = QtWidgets.QLabel(translate(
            "WorkCal", "Box: drag with the left button.  Lasso: click the corners (or drag), then right-click, "
                       "press Enter or click the first corner.  Shift adds, Ctrl subtracts, Esc drops the "
                       "shape.  The middle button and the wheel still pan and zoom."))
        help_text.setWordWrap(True)
        layout.addWidget(help_text)
        layout.addStretch(1)
        return form

    @staticmethod
    def _group(layout, title, options, horizontal: bool = False):
        box = QtWidgets.QGroupBox(title)
        inner = QtWidgets.QHBoxLayout(box) if horizontal else QtWidgets.QVBoxLayout(box)
        buttons = {}
        for value, text, tip in options:
            button = QtWidgets.QRadioButton(text)
            button.setObjectName(f"WorkCal_{value}")
            button.setToolTip(tip)
            inner.addWidget(button)
            buttons[value] = button
        layout.addWidget(box)
        return buttons

    # state
    def role(self) -> str:
        return next(v for v, b in self.role_buttons.items() if b.isChecked())

    def mode(self) -> str:
        return next(v for v, b in self.mode_buttons.items() if b.isChecked())

    def shape(self) -> str:
        return next(v for v, b in self.shape_buttons.items() if b.isChecked())

    def set_role(self, role: str) -> None:
        self.role_buttons[role].setChecked(True)

    def set_mode(self, mode: str) -> None:
        self.mode_buttons[mode].setChecked(True)

    def set_shape(self, shape: str) -> None:
        self.shape_buttons[shape].setChecked(True)

    def _refresh(self) -> None:
        regions = fc_scan.get_regions(self.obj)
        count = {r: 0 if regions[r] is None else len(regions[r]) for r in ROLES}
        self.scan_label.setText(translate("WorkCal", "Scan: {} ({} points)").format(
            self.obj.Label, len(self.points)))
        self.count_label.setText(translate("WorkCal", "Workpiece: {} points\nReference: {} points").format(
            count["workpiece"], count["reference"]))
        self.undo_button.setEnabled(bool(self.history))

    # picking
    def apply_polygon(self, polygon, modifier=None) -> np.ndarray:
        """Apply a finished box/lasso (Coin pixels); returns the indices inside it."""
        self.last_polygon = [tuple(p) for p in polygon]
        mask = polygon_mask(self.view, self.points, polygon)
        if self.visible_box.isChecked():
            mask &= visible_mask(self.view, self.points)
        picked = np.flatnonzero(mask)
        self.apply_selection(picked, modifier or self.mode())
        return picked

    def apply_selection(self, picked, mode: str | None = None, role: str | None = None) -> None:
        regions = fc_scan.get_regions(self.obj)
        updated = combine(regions, role or self.role(), picked, mode or self.mode())
        self.history.append(regions)
        fc_scan.set_regions(self.obj, updated["workpiece"], updated["reference"], source="user")
        self.picks += 1
        region_display.update(self.obj)
        self._refresh()

    def undo_pick(self) -> None:
        if not self.history:
            return
        previous = self.history.pop()
        fc_scan.set_regions(self.obj, previous["workpiece"], previous["reference"],
                            source=previous["source"] or "user")
        region_display.update(self.obj)
        self._refresh()

    def clear_role(self) -> None:
        self.apply_selection(np.empty(0, dtype=np.int64), REPLACE)

    def _form_alive(self) -> bool:
        """False once FreeCAD closed the dialog: it then sets ``form`` to None and deletes the widgets."""
        form = getattr(self, "form", None)
        if form is None:
            return False
        try:
            form.objectName()
        except RuntimeError:
            return False
        return True

    def _restore(self) -> None:
        """The regions as they were before the panel opened (the live picks are only shown)."""
        if self.transaction:
            self.doc.abortTransaction()
            self.transaction = False
        elif self.history:  # no undo available: put the regions back by hand
            first = self.initial
            fc_scan.set_regions(self.obj, first["workpiece"], first["reference"], source=first["source"] or "user")

    def _closed_outside(self) -> None:
        """The dialog went away without OK or Cancel (e.g. closed by other code): treat it as Cancel."""
        try:
            self._restore()
            region_display.update(self.obj)
        except (RuntimeError, ReferenceError):  # the document is gone too
            pass
        self.on_close()

    # task dialog protocol
    def getStandardButtons(self):
        return OK_CANCEL

    def accept(self):
        """Record the final regions as one command (one undo step, replayable in a macro)."""
        from workcal_wb.fc.regions import ranges

        self.tool.stop()
        final = fc_scan.get_regions(self.obj)
        self._restore()
        if self.picks:
            runs = {role: replay.Code("workcal_wb.fc.regions.indices({!r})".format(
                ranges(() if final[role] is None else final[role]))) for role in ROLES}
            replay.run("workcal_wb.fc.regions.set_regions", self.obj, workpiece=runs["workpiece"],
                       reference=runs["reference"])
            FreeCAD.Console.PrintMessage(translate("WorkCal", "WorkCal: regions of {}: workpiece {} points, "
                                                              "reference {} points\n").format(
                self.obj.Label, *(0 if final[r] is None else len(final[r]) for r in ROLES)))
        region_display.update(self.obj)
        close_dialog()
        self.on_close()
        return True

    def reject(self):
        self.tool.stop()
        self._restore()
        region_display.update(self.obj)
        close_dialog()
        self.on_close()
        return True
