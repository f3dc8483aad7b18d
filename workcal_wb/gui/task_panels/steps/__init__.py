"""The steps of the WorkCal guide, one module each; ``STEPS`` is their order.

A step is a page of the guide (``widget``), a state read from the document (``state()``: DONE, TODO or
ATTENTION and a few words) and a scene (``scene()``): which objects the 3D view shows, fits and
labels while the step is open.  Pages are built for FreeCAD's default task panel width: one column,
labels that wrap, the paper's symbols in tooltips rather than in the labels.
"""
from .base import ATTENTION, DONE, FAILED, TODO, Scene, Step
from .calibrate import CalibrateStep
from .export import ExportStep
from .models import ModelsStep
from .regions import RegionsStep
from .result import ResultStep
from .scan import ScanStep
from .toolpath import ToolpathStep

STEPS = (ScanStep, ModelsStep, RegionsStep, CalibrateStep, ResultStep, ToolpathStep, ExportStep)

__all__ = ["ATTENTION", "DONE", "FAILED", "TODO", "Scene", "Step", "STEPS"]
