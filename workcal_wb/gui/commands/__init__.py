"""The WorkCal command registry.

Each module listed in ``MODULES`` exposes ``COMMANDS = {"WorkCal_X": CommandInstance, ...}`` (in menu
order) and may narrow where they appear with ``TOOLBAR = [...]`` / ``MENU = [...]`` (default: all).
``TOOLBAR`` and ``MENU`` below are the command names in module order, "Separator" between modules;
``register_all()`` hands every command to FreeCAD.  Importing this package only imports the command
modules (they import their heavy dependencies when a command runs).
"""
import importlib

SEPARATOR = "Separator"

# Add a module here to add its commands to the workbench (order = toolbar and menu order).
MODULES = [
    "guide",  # WorkCal_Guide
    "import_scan",  # WorkCal_ImportScan
    "models",  # WorkCal_ChooseModels
    "regions",  # WorkCal_PickBox, WorkCal_PickLasso, WorkCal_AutoRegions, WorkCal_ClearRegions
    "calibrate",  # WorkCal_Calibrate
    "report",  # WorkCal_DeviationMap, WorkCal_ShowInRobotFrame (menu only), WorkCal_Report, WorkCal_Studies
    "toolpath",  # WorkCal_TransformToolpath, WorkCal_ExportToolpath
    "preferences",  # WorkCal_Preferences (menu only)
]


def modules() -> list:
    return [importlib.import_module(f"{__name__}.{name}") for name in MODULES]


def commands() -> dict:
    """All commands by name, in order."""
    found = {}
    for module in modules():
        for name, command in module.COMMANDS.items():
            if name in found:
                raise ValueError(f"command {name} defined twice (in {module.__name__})")
            found[name] = command
    return found


def _layout(attribute: str) -> list:
    names = []
    for module in modules():
        group = list(getattr(module, attribute, module.COMMANDS))
        if group and names:
            names.append(SEPARATOR)
        names += group
    return names


def register_all() -> list:
    """Register every command with FreeCAD (again-safe); returns their names."""
    import FreeCADGui

    known = set(FreeCADGui.listCommands())
    for name, command in commands().items():
        if name not in known:
            FreeCADGui.addCommand(name, command)
    return list(commands())


TOOLBAR = _layout("TOOLBAR")
MENU = _layout("MENU")
