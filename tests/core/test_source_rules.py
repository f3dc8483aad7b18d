"""Rules the source must keep that a run seldom catches.

FreeCAD 0.20 and 1.0 (the versions CI runs) wrap PySide2; 1.1 is built on Qt6/PySide6, where these
Qt5 idioms fail: QAction lives in QtGui, flags are not ints, ``exec_`` is deprecated.  No panel walks up
into FreeCAD's widgets (workcal_wb/gui/README.md).  And a module
never binds again a name it imports (a tuning constant named like a reason code replaced the code).
"""
import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SOURCES = sorted((ROOT / "workcal_wb").rglob("*.py"))

QT6_BREAKERS = {
    r"QtWidgets\.QAction\b": "QAction is in QtGui on Qt6: use menu.addAction(text)",
    r"\bint\(\s*QtWidgets\.QDialogButtonBox": "PySide6 flags are not ints: return task_panels.OK_CANCEL",
    r"\.exec_\(": "exec_ is deprecated in PySide6: use task_panels.run_modal(dialog)",
    r"from PySide[26]\b|import PySide[26]\b": "import FreeCAD's PySide wrapper, never PySide2/PySide6 directly",
}
# Wrappers PySide makes on the way up from a panel, or for a scroll area's widget, can delete FreeCAD's own
# widgets when Python collects them (workcal_wb/gui/README.md).  The GUI tests run in the same FreeCAD.
WIDGET_WALKS = r"\.parentWidget\s*\(|(?<!\bself)\.widget\s*\(\)"
GUI_SOURCES = SOURCES + sorted((ROOT / "tests" / "gui").rglob("*.py"))


@pytest.mark.parametrize("pattern", sorted(QT6_BREAKERS))
def test_no_qt5_only_idioms(pattern):
    found = [f"{path.relative_to(ROOT)}:{n}" for path in SOURCES
             for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1) if re.search(pattern, line)]
    assert not found, f"{QT6_BREAKERS[pattern]}: {', '.join(found)}"


def test_no_walk_up_into_freecads_widgets():
    found = [f"{path.relative_to(ROOT)}:{n}" for path in GUI_SOURCES
             for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
             if re.search(WIDGET_WALKS, line)]
    assert not found, f"reach a scroll area through task_panels.common.scroll_area_around: {', '.join(found)}"


def test_the_walk_rule_sees_the_walks_and_a_panels_own_scroll_area_is_left_alone():
    assert re.search(WIDGET_WALKS, "parent = parent.parentWidget()")
    assert re.search(WIDGET_WALKS, "self.form.mapTo(self.area.widget(), point)")
    assert not re.search(WIDGET_WALKS, "content = self.widget()")


def rebound_imports(source: str) -> list:
    """(line, name) of each module-level assignment to a name the module imports at module level."""
    tree = ast.parse(source)
    imported = {alias.asname or alias.name.split(".")[0] for node in tree.body
                if isinstance(node, (ast.Import, ast.ImportFrom)) for alias in node.names}
    found = []
    for node in tree.body:
        targets = node.targets if isinstance(node, ast.Assign) else [node.target] if isinstance(
            node, (ast.AnnAssign, ast.AugAssign)) else []
        for target in targets:
            for name in ast.walk(target):
                if isinstance(name, ast.Name) and name.id in imported:
                    found.append((node.lineno, name.id))
    return found


def test_no_module_binds_again_a_name_it_imports():
    found = [f"{path.relative_to(ROOT)}:{line} {name}" for path in SOURCES
             for line, name in rebound_imports(path.read_text(encoding="utf-8"))]
    assert not found, "a module-level assignment replaces an imported name: " + ", ".join(found)


def test_the_rebinding_check_sees_a_constant_named_like_an_imported_code():
    source = "from .result import THIN_WALL, RIVAL\nTHIN_PART, THIN_WALL = 0.08, 0.25\nOTHER = 1\n"
    assert rebound_imports(source) == [(2, "THIN_WALL")]
