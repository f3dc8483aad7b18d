"""Reading an input file: only a regular file is read, and every failure is an InputError naming it.

A FIFO, a terminal or a device given as a scan would block forever or never end; a folder or a
missing file must say so instead of raising an OSError.
"""
from __future__ import annotations

import os
import stat
from pathlib import Path

from .errors import InputError


def checked_input(path, what: str = "file") -> Path:
    """``path`` if it names a readable regular file; an InputError saying what is wrong otherwise."""
    path = Path(path)
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        raise InputError(f"{path}: {what} does not exist") from None
    except OSError as exc:
        raise InputError(f"{path}: cannot be read ({exc.strerror or exc})") from None
    if stat.S_ISDIR(mode):
        raise InputError(f"{path}: is a folder, not a {what}")
    if not stat.S_ISREG(mode):
        raise InputError(f"{path}: is not a regular file (a pipe, socket or device?); give the {what} itself")
    if not os.access(path, os.R_OK):
        raise InputError(f"{path}: cannot be read (permission denied)")
    return path


def read_bytes(path, what: str = "file") -> bytes:
    """The whole content of a regular file; an empty file is an error too."""
    path = checked_input(path, what)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputError(f"{path}: cannot be read ({exc.strerror or exc})") from None
    if not data or data.isspace():
        raise InputError(f"{path}: file is empty")
    return data


def read_text(path, what: str = "file") -> str:
    """A text file as str (UTF-8; undecodable bytes replaced, so the parser names the bad spot)."""
    return read_bytes(path, what).decode("utf-8", errors="replace")
