"""``python3 -m workcal_wb``: the headless command line."""
import os
import sys
import threading

from workcal_wb.cli import main


def _exit(status: int) -> None:
    """End the process with ``status`` once its output is flushed, without the interpreter's teardown:
    freeing every module, array and library one by one (open3d's among them) costs a cell's
    scan-after-scan run ~0.05-0.1 s and changes nothing on disk.  Every file is written and closed
    when ``main`` returns; only when another thread is still running (it may still have work to
    finish) does the interpreter end as usual."""
    try:
        sys.stdout.flush()
        sys.stderr.flush()
    except (OSError, ValueError):  # a closed or broken pipe: let the interpreter report it as usual
        sys.exit(status)
    if threading.active_count() > 1 or not isinstance(status, int):
        sys.exit(status)
    os._exit(status)


_exit(main())
