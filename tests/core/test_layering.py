"""The house rule of docs/architecture.md, checked on the source: data flows gui -> fc -> core, never back.

``workcal_wb.core`` and ``workcal_wb.fc`` never import the GUI layer (``workcal_wb.gui``, FreeCADGui),
Qt (PySide) or Coin (pivy), not even inside a function: a headless script (freecadcmd) imports ``fc``
and must never pull in GUI code.  ``core`` does not import FreeCAD or ``fc`` either.
"""
import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "workcal_wb"
GUI_ONLY = ("workcal_wb.gui", "FreeCADGui", "PySide", "PySide2", "PySide6", "pivy")
FORBIDDEN = {"core": GUI_ONLY + ("workcal_wb.fc", "FreeCAD", "Part", "Mesh", "Points", "Path"), "fc": GUI_ONLY}


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imported_names(path: Path):
    """(line, absolute module name) of every import in the file, at any depth."""
    package = module_name(path) if path.name == "__init__.py" else module_name(path).rsplit(".", 1)[0]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                name = ".".join(base + ([node.module] if node.module else []))
            else:
                name = node.module
            yield node.lineno, name
            for alias in node.names:  # "from workcal_wb import gui"
                yield node.lineno, f"{name}.{alias.name}"


def violations(layer: str) -> list:
    found = []
    for path in sorted((PACKAGE / layer).rglob("*.py")):
        for line, name in imported_names(path):
            if any(name == bad or name.startswith(bad + ".") for bad in FORBIDDEN[layer]):
                found.append(f"{path.relative_to(ROOT)}:{line} imports {name}")
    return found


@pytest.mark.parametrize("layer", sorted(FORBIDDEN))
def test_layer_never_imports_the_gui(layer):
    assert not violations(layer), "\n".join(violations(layer))


def test_the_checker_sees_imports_inside_functions(tmp_path, monkeypatch):
    """The rule would be worthless if an import tucked into a function slipped through."""
    fake = tmp_path / "workcal_wb" / "fc"
    fake.mkdir(parents=True)
    (fake / "x.py").write_text("def f():\n    from ..gui.task_panels import QtWidgets\n    import pivy.coin\n")
    monkeypatch.setattr(__import__(__name__), "ROOT", tmp_path)
    monkeypatch.setattr(__import__(__name__), "PACKAGE", tmp_path / "workcal_wb")
    assert len(violations("fc")) >= 3
