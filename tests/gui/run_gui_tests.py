"""Run the GUI tests inside a real FreeCAD window: `xvfb-run freecad tests/gui/run_gui_tests.py`.

FreeCAD executes this file once its main window is up (as module "run_gui_tests", not "__main__").
pytest runs from a timer so the event loop and the 3D view exist; its status becomes FreeCAD's.
"""
import os
import shlex
import sys

from PySide import QtCore

TESTS = os.path.dirname(os.path.abspath(__file__))


def _run():
    import pytest

    # FreeCAD 1.x sends sys.stdout to its Report view only; the run's log belongs on the terminal.
    sys.stdout, sys.stderr = sys.__stdout__, sys.__stderr__
    # --durations: the slowest GUI tests named in the CI log, as the headless run does (CI must stay well under 30 min).
    # WORKCAL_GUI_PYTEST_ARGS (make test-gui GUI_PYTEST_ARGS="-k name"): a chosen few, while working on them.
    # Files or tests named there are run alone (with the whole folder too, a file would run twice, its
    # second run on what the first left behind).
    chosen = shlex.split(os.environ.get("WORKCAL_GUI_PYTEST_ARGS", ""))
    named = [arg for arg in chosen if not arg.startswith("-") and os.path.exists(arg.split("::")[0])]
    rc = pytest.main(["-q", "-rfEs", "--durations=10", "-p", "no:cacheprovider", "--rootdir", os.path.dirname(TESTS), *chosen,
                      *([] if named else [TESTS])])
    sys.stdout.flush()
    os._exit(int(rc))  # FreeCAD ignores QApplication.exit codes; leave with pytest's status


QtCore.QTimer.singleShot(0, _run)
