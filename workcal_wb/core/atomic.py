"""Write files so that a failure never leaves half a file: temporary file, fsync, rename.

The temporary file is a hidden ``.NAME.PID.RANDOM.part`` beside the target.  An exception (also
KeyboardInterrupt, and SIGTERM once the CLI has turned it into one) removes it; a process killed
outright (SIGKILL, power loss) cannot, so every write into a folder first removes the parts whose
writer is no longer running.
"""
from __future__ import annotations

import os
import re
import shutil
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

from .errors import OutputError

PART_SUFFIX = ".part"
# ".NAME.PID.RANDOM.part": the writer's process id tells whether the part is still being written.
_PART = re.compile(r"^\..+\.(\d+)\.[^.]+\.part$")
# A part whose name carries no process id (an older WorkCal wrote it) is stale after this long.
STALE_AFTER_S = 3600.0


@contextmanager
def atomic_open(path, mode: str = "w", encoding: str | None = "utf-8"):
    """Open a temporary file beside ``path``; it replaces ``path`` only if the block succeeds.

    Anything the operating system refuses (no folder, a folder in the way, no permission, disk full,
    the file-size limit) is an OutputError naming ``path``."""
    path = Path(path)
    if not path.parent.is_dir():
        raise OutputError(f"{path}: folder {path.parent} does not exist")
    if path.is_dir():
        raise OutputError(f"{path}: is a folder; give a file name")
    remove_stale_parts(path.parent)
    binary = "b" in mode
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.{os.getpid()}.", suffix=PART_SUFFIX, dir=path.parent)
    except OSError as exc:
        raise OutputError(f"{path}: cannot write in {path.parent} ({exc.strerror or exc})") from None
    try:
        with os.fdopen(fd, mode, encoding=None if binary else encoding, newline=None if binary else "") as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except OSError as exc:
        _unlink(tmp)
        raise OutputError(f"{path}: cannot be written ({exc.strerror or exc}); nothing was written") from None
    except BaseException:
        _unlink(tmp)
        raise


def atomic_write_text(path, text: str) -> None:
    with atomic_open(path, "w") as fh:
        fh.write(text)


def atomic_write_bytes(path, data: bytes) -> None:
    with atomic_open(path, "wb") as fh:
        fh.write(data)


def remove_stale_parts(folder) -> list[str]:
    """Remove the ``.part`` files and folders in ``folder`` that no running process is writing; their names."""
    try:
        entries = [entry for entry in os.scandir(folder) if entry.name.endswith(PART_SUFFIX)]
    except OSError:
        return []
    removed = []
    for entry in entries:
        if not is_stale(entry.name, entry.path):
            continue
        try:
            if entry.is_dir(follow_symlinks=False):
                shutil.rmtree(entry.path)
            else:
                os.unlink(entry.path)
            removed.append(entry.name)
        except OSError:  # gone already, or not ours to remove: not worth failing a write for
            pass
    return removed


def is_stale(name: str, path) -> bool:
    """A part is stale when the process that named it has ended (or, without a process id, when old)."""
    match = _PART.match(name)
    if match and os.name == "posix":
        return not _running(int(match.group(1)))
    try:
        return time.time() - os.lstat(path).st_mtime > STALE_AFTER_S
    except OSError:
        return False


def _running(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except (ProcessLookupError, OverflowError):  # ended, or a number no process can have
        return False
    except PermissionError:  # another user's process
        return True
    return True


def _unlink(path) -> None:
    try:
        os.unlink(path)
    except FileNotFoundError:
        pass
