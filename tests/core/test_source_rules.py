"""Rules the source must keep that no test on our FreeCADs could catch: FreeCAD 1.1's Qt6 builds.

FreeCAD 0.20 and 1.0 (the versions CI runs) wrap PySide2; 1.1 is built on Qt6/PySide6, where these
Qt5 idioms fail: QAction lives in QtGui, flags are not ints, ``exec_`` is deprecated.
"""
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


@pytest.mark.parametrize("pattern", sorted(QT6_BREAKERS))
def test_no_qt5_only_idioms(pattern):
    found = [f"{path.relative_to(ROOT)}:{n}" for path in SOURCES
             for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1) if re.search(pattern, line)]
    assert not found, f"{QT6_BREAKERS[pattern]}: {', '.join(found)}"
