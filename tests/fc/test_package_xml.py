"""package.xml as FreeCAD itself reads it: an addon with a wrong entry is silently skipped or loses its icon."""
import ast
from pathlib import Path

import pytest

FreeCAD = pytest.importorskip("FreeCAD")

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def metadata():
    return FreeCAD.Metadata(str(ROOT / "package.xml"))


@pytest.fixture(scope="module")
def workbench(metadata):
    items = metadata.Content.get("workbench", [])
    assert len(items) == 1, "exactly one <workbench> content item"
    return items[0]


def registered_workbench_classes():
    """Names of the classes handed to FreeCADGui.addWorkbench in the module InitGui.py imports."""
    init_gui = ast.parse((ROOT / "InitGui.py").read_text())
    imported = [alias.name for node in ast.walk(init_gui) if isinstance(node, ast.Import) for alias in node.names]
    assert imported, "InitGui.py imports the module that registers the workbench"
    module = ROOT / (imported[0].replace(".", "/") + ".py")
    tree = ast.parse(module.read_text())
    names = []
    for node in ast.walk(tree):
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "addWorkbench"
                and node.args and isinstance(node.args[0], ast.Call) and isinstance(node.args[0].func, ast.Name)):
            names.append(node.args[0].func.id)
    return names


def test_name_and_version(metadata):
    import workcal_wb

    assert metadata.Name == "WorkCal"
    assert metadata.Version == workcal_wb.__version__


def test_workbench_classname_is_the_registered_class(workbench):
    assert registered_workbench_classes() == [workbench.Classname] == ["WorkCalWorkbench"]


def test_subdirectory_is_the_repository_root(workbench):
    # FreeCAD 0.20 runs Init.py/InitGui.py from <addon>/<subdirectory>; both live at the root.
    assert workbench.Subdirectory in ("./", ".")
    assert (ROOT / workbench.Subdirectory / "InitGui.py").is_file()
    assert (ROOT / workbench.Subdirectory / "Init.py").is_file()


def test_runs_on_freecad_0_20(metadata, workbench):
    # Stated for the package (the 1.1 Addon Manager asks for it there) and for the workbench (what the
    # 0.20 loader reads); never above 0.20, or Debian 12's FreeCAD skips the workbench.
    assert metadata.FreeCADMin.startswith("0.20") and workbench.FreeCADMin.startswith("0.20")
    assert metadata.supportsCurrentFreeCAD() and workbench.supportsCurrentFreeCAD()


def test_icon_files_exist(metadata, workbench):
    for icon in (metadata.Icon, workbench.Icon):
        assert icon, "an <icon> entry"
        path = ROOT / icon
        assert path.is_file(), f"icon {icon} missing"
        assert path.read_text().lstrip().startswith(("<svg", "<?xml")) and "</svg>" in path.read_text()


def test_python_dependencies(workbench):
    import xml.etree.ElementTree as ET

    assert {d["package"] for d in workbench.Depend} >= {"numpy", "scipy", "open3d"}
    # Packages off the Addon Manager's allow-list must be optional, or it refuses to install WorkCal.
    ns = {"p": "https://wiki.freecad.org/Package_Metadata"}
    depends = ET.parse(ROOT / "package.xml").getroot().findall(".//p:workbench/p:depend", ns)
    assert {d.text: d.get("optional") for d in depends if d.text in ("open3d", "pye57")} == {"open3d": "true",
                                                                                           "pye57": "true"}


def test_author_and_maintainer(metadata):
    assert metadata.Author and metadata.Maintainer


def test_translation_template_is_a_qt_ts_file():
    """The folder the workbench registers with addLanguagePath holds the template translators start from."""
    import xml.etree.ElementTree as ET

    import workcal_wb

    assert Path(workcal_wb.TRANSLATIONS).resolve() == ROOT / "resources" / "translations"
    root = ET.parse(ROOT / "resources" / "translations" / "workcal.ts").getroot()
    assert root.tag == "TS"
    sources = {(c.findtext("name"), m.findtext("source")) for c in root.iter("context") for m in c.iter("message")}
    assert ("WorkCal_ImportScan", "Import scan...") in sources
    assert ("Workbench", "WorkCal") in sources
