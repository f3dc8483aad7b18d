"""The errors WorkCal raises on purpose: each message names the file or object and what is wrong.

Callers (CLI, FreeCAD commands) show ``str(error)`` to the user as is; anything else escaping is a bug.
"""


class WorkCalError(Exception):
    """A problem the user can act on (bad input, impossible request)."""


class InputError(WorkCalError):
    """A file, object or parameter that cannot be used as given."""


class NotFound(InputError):
    """An object the scan should show (the reference, the workpiece) is not in it: the calibration
    ran and failed, so ``calibrate`` reports it as a failed result rather than raising."""


class OutputError(WorkCalError):
    """An output cannot be written (no such folder, a file in the way, no permission, disk full)."""


class MissingDependency(WorkCalError):
    """A Python package WorkCal needs is not installed; the message says what to install."""


def require_open3d():
    """Import open3d or explain how to get it (Debian ships it as python3-open3d)."""
    try:
        import open3d
    except ImportError as exc:
        raise MissingDependency(
            "open3d is not installed for this Python; on Debian/Ubuntu run: "
            "sudo apt-get install python3-open3d  (elsewhere: pip install open3d)"
        ) from exc
    return open3d


class Cancelled(WorkCalError):
    """The user stopped a long job; whatever it was building is discarded."""


class Stopped(Exception):
    """A search was stopped because nothing waits for its result any more (locate's search ahead); it is
    never read, so it never reaches a user (not a WorkCalError: no user's cancel)."""
