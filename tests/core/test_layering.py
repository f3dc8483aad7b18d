"""The house rule of docs/architecture.md, checked on the source: data flows gui -> fc -> core, never back.

``workcal_wb.core`` and ``workcal_wb.fc`` never import the GUI layer (``workcal_wb.gui``, FreeCADGui),
Qt (PySide) or Coin (pivy), not even inside a function: a headless script (freecadcmd) imports ``fc``
and must never pull in GUI code.  ``core`` does not import FreeCAD or ``fc`` either.

Within a layer no two modules import each other, directly or round a longer loop, not even inside a
function: a reader can then read the modules leaves first.  Lazy imports of heavy packages (open3d)
are not WorkCal modules, so they stay out of the graph.
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


def import_statements(path: Path):
    """(line, absolute module name, names imported from it) of every import in the file, at any depth.

    ``import a.b`` gives ``("a.b", [])``; ``from .m import f, g`` gives ``("<package>.m", ["f", "g"])``.
    Imports under ``if TYPE_CHECKING:`` count like any other: a type a module only names in a hint still
    ties the reader to the module that defines it.
    """
    package = module_name(path) if path.name == "__init__.py" else module_name(path).rsplit(".", 1)[0]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name, []
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                name = ".".join(base + ([node.module] if node.module else []))
            else:
                name = node.module
            yield node.lineno, name, [alias.name for alias in node.names]


def imported_names(path: Path):
    """(line, absolute module name) of every import in the file, at any depth."""
    for line, name, names in import_statements(path):
        yield line, name
        for alias in names:  # "from workcal_wb import gui"
            yield line, f"{name}.{alias}"


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


def import_graph() -> dict:
    """WorkCal module -> {WorkCal module it imports: first line of that import}, imports at any depth.

    ``from . import x`` is an edge to module ``x`` where ``x`` is a module, else to the package (its
    ``__init__``, a node of its own); ``from .m import f`` is an edge to ``m``.
    """
    modules = {module_name(path): path for path in sorted(PACKAGE.rglob("*.py"))}
    graph = {}
    for module, path in modules.items():
        edges = {}
        for line, name, names in import_statements(path):
            targets = {f"{name}.{alias}" if f"{name}.{alias}" in modules else name for alias in names} or {name}
            for target in targets:
                if target in modules and target != module:
                    edges.setdefault(target, line)
        graph[module] = edges
    return graph


def strongly_connected(graph: dict) -> list:
    """The strongly connected components of the graph (Tarjan's algorithm, iterative), each a sorted list."""
    index, low, on_stack, stack, components = {}, {}, set(), [], []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, successors = work[-1]
            for successor in successors:
                if successor not in index:
                    index[successor] = low[successor] = len(index)
                    stack.append(successor)
                    on_stack.add(successor)
                    work.append((successor, iter(sorted(graph[successor]))))
                    break
                if successor in on_stack:
                    low[node] = min(low[node], index[successor])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    component = []
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        component.append(member)
                        if member == node:
                            break
                    components.append(sorted(component))
    return components


def cycle_through(graph: dict, component: list) -> list:
    """One loop of imports inside the component, from its first module back to it (breadth-first: shortest)."""
    start, members = component[0], set(component)
    came_from = {start: None}
    queue = [start]
    while queue:
        node = queue.pop(0)
        for successor in sorted(graph[node]):
            if successor == start:
                chain = [node]
                while came_from[chain[-1]] is not None:
                    chain.append(came_from[chain[-1]])
                return chain[::-1] + [start]
            if successor in members and successor not in came_from:
                came_from[successor] = node
                queue.append(successor)
    return component


def import_cycles() -> list:
    """Each loop of imports among WorkCal modules, written as a chain "a:line -> b:line -> ... -> a"."""
    graph = import_graph()
    cycles = []
    for component in strongly_connected(graph):
        if len(component) > 1:
            chain = cycle_through(graph, component)
            links = [f"{a}:{graph[a][b]}" for a, b in zip(chain, chain[1:])]
            others = sorted(set(component) - set(chain))
            cycles.append(" -> ".join(links + [chain[-1]])
                          + (f"  (the same knot also holds {', '.join(others)})" if others else ""))
    return cycles


def test_no_import_cycles():
    """No module imports, at any depth, a module that imports it back (directly or through others)."""
    cycles = import_cycles()
    assert not cycles, "import cycles (module:line of the import):\n" + "\n".join(cycles)


def test_the_checker_sees_cycles_through_imports_inside_functions(tmp_path, monkeypatch):
    """A loop closed by an import inside a function is a loop all the same; a one-way import is none."""
    fake = tmp_path / "workcal_wb" / "core"
    fake.mkdir(parents=True)
    (tmp_path / "workcal_wb" / "__init__.py").write_text("")
    (fake / "__init__.py").write_text("")
    (fake / "a.py").write_text("from .b import thing\n")
    (fake / "b.py").write_text("thing = 1\n\ndef f():\n    from . import a\n    import open3d\n")
    (fake / "c.py").write_text("from . import a\n")
    monkeypatch.setattr(__import__(__name__), "ROOT", tmp_path)
    monkeypatch.setattr(__import__(__name__), "PACKAGE", tmp_path / "workcal_wb")
    assert import_cycles() == ["workcal_wb.core.a:1 -> workcal_wb.core.b:4 -> workcal_wb.core.a"]
