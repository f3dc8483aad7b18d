"""The view providers of every WorkCal document object, and the one registry that attaches them.

``REGISTRY`` maps an object kind (the ``TYPE`` of its proxy in ``workcal_wb.fc``) to its view provider
class; ``register()`` (run by the workbench at GUI start-up) hands it to ``workcal_wb.fc.proxies``,
which attaches the view provider whenever the FreeCAD layer makes an object, so that layer never
imports GUI code.  FreeCAD re-creates view providers from the class path saved in the document.
"""
from workcal_wb.fc import proxies

REGISTRY = {
    "WorkCal::Scan": "workcal_wb.gui.view_providers.scan:ViewProviderScan",
    "WorkCal::Setup": "workcal_wb.gui.view_providers.setup:ViewProviderSetup",
    "WorkCal::Calibration": "workcal_wb.gui.view_providers.calibration:ViewProviderCalibration",
    "WorkCal::PlacedModel": "workcal_wb.gui.view_providers.placed_model:ViewProviderPlacedModel",
    "WorkCal::DeviationMap": "workcal_wb.gui.view_providers.deviation_map:ViewProviderDeviationMap",
    "WorkCal::CalibratedPath": "workcal_wb.gui.view_providers.calibrated_path:ViewProviderCalibratedPath",
    "WorkCal::RobotPose": "workcal_wb.gui.view_providers.robot_pose:ViewProviderRobotPose",
}


def register() -> None:
    proxies.VIEW_PROVIDERS.update(REGISTRY)


def __getattr__(name):
    """Class paths that documents saved before the view providers had a module each still name."""
    moved = {"ViewProviderScan": "scan", "ViewProviderSetup": "setup", "ViewProviderPlacedModel": "placed_model"}
    if name in moved:
        import importlib

        return getattr(importlib.import_module(f"{__name__}.{moved[name]}"), name)
    raise AttributeError(name)
