"""An output folder a cell can trust: one consistent set of files, never a mix of two runs.

A run stages everything it writes in a fresh hidden folder inside the output folder
(``.workcal-staging.PID.RANDOM.part``) and ``commit`` swaps the set in at the end, under a lock and
with SIGINT/SIGTERM held back for the few renames it takes: the files of the previous set that this
run does not write again (a program in another format, a program a failed calibration must not
leave) are removed, the staged files moved in, and ``manifest.json`` written last: it names the
command, the status and the SHA-256 of every file of the set, so a reader can check that what it
loads belongs together.  The old manifest goes first, so at every instant the folder holds a whole
set (its manifest and every file it lists) or none (no manifest: a run killed while it committed
leaves its staging folder beside whatever files it had moved); ``check_whole_set`` is what a
reader asks of a file in such a folder.

A run that ends in an error after it started removes the previous set too (nothing stale is left
beside an error); an interrupted run (Ctrl-C, SIGTERM) leaves the previous set as it was.  Files
in the folder that are not outputs of this kind of run (the user's own, the run's inputs) are
never touched.
"""
from __future__ import annotations

import datetime
import fnmatch
import hashlib
import json
import os
import shutil
import signal
import tempfile
import threading
from contextlib import contextmanager
from pathlib import Path

from .atomic import PART_SUFFIX, atomic_write_text, remove_stale_parts
from .errors import InputError, OutputError

MANIFEST = "manifest.json"
MANIFEST_FORMAT = "workcal-outputs"


def check_folder(path) -> Path:
    """Refuse an output folder that cannot be written, before any work is done: a file in the way, a
    place the system does not let us write (read-only, /proc, no permission)."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise OutputError(f"{path}: is a file, not a folder; give a folder for the outputs")
    _probe(_existing_ancestor(path), path)
    return path


def check_file(path) -> Path:
    """Refuse an output file that cannot be written, before any work is done."""
    path = Path(path)
    if path.is_dir():
        raise OutputError(f"{path}: is a folder; give a file name")
    if not path.parent.is_dir():
        raise OutputError(f"{path}: folder {path.parent} does not exist")
    _probe(path.parent, path)
    return path


def _existing_ancestor(path: Path) -> Path:
    for folder in [path, *path.absolute().parents]:
        if folder.exists():
            if not folder.is_dir():
                raise OutputError(f"{path}: {folder} is a file, so no folder can be made there")
            return folder
    return Path("/")


def _probe(folder: Path, path: Path) -> None:
    """Create and remove a file in ``folder``: the one test of writability every system answers truly."""
    try:
        fd, probe = tempfile.mkstemp(prefix=f".workcal-probe.{os.getpid()}.", suffix=PART_SUFFIX, dir=folder)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise OutputError(f"{path}: cannot write in {folder} ({exc.strerror or exc})") from None


class OutputFolder:
    """Stage a run's outputs and swap them into ``path`` as one set (see the module docstring).

    ``owned``: glob patterns of the names this kind of run writes (what a new run replaces or
    removes); ``keep``: paths never removed (the run's inputs).  Use as a context manager; ``file``
    gives the staged path of each output, ``commit`` swaps the set in."""

    def __init__(self, path, command: str, owned, keep=()):
        self.path, self.command, self.owned = Path(path), command, tuple(owned) + (MANIFEST,)
        self.keep = {os.path.realpath(p) for p in keep}
        self.staging: Path | None = None
        self.committed = False
        self._listed: dict = {}  # the files of the set committed so far (manifest entries)

    def __enter__(self) -> "OutputFolder":
        check_folder(self.path)
        return self

    def __exit__(self, kind, error, traceback) -> None:
        if self.staging is not None:
            shutil.rmtree(self.staging, ignore_errors=True)
        if error is not None and isinstance(error, Exception) and not self.committed:
            self._clear_after_error()

    def file(self, name: str) -> Path:
        """Where to write output ``name``: a path in the staging folder."""
        return self.folder() / name

    def folder(self) -> Path:
        """The staging folder (created on first use, so a run that fails early creates nothing)."""
        if self.staging is None:
            try:
                self.path.mkdir(parents=True, exist_ok=True)
                remove_stale_parts(self.path)
                self.staging = Path(tempfile.mkdtemp(prefix=f".workcal-staging.{os.getpid()}.", suffix=PART_SUFFIX,
                                                     dir=self.path))
            except OSError as exc:
                raise OutputError(f"{self.path}: cannot write the outputs ({exc.strerror or exc})") from None
        return self.staging

    def commit(self, status: str, adding: bool = False) -> dict:
        """Swap the staged files in as the folder's set; returns the manifest written.  With ``adding``
        the files staged since this run's last commit join its set (what a robot needs is committed
        first, the report with its figures after it)."""
        staged = sorted(os.listdir(self.staging)) if self.staging is not None else []
        files = {name: _digest(self.staging / name) for name in staged}
        listed = dict(self._listed) if adding and self.committed else {}
        listed.update({k: v for name in staged for k, v in _flat(name, files[name])})
        manifest = {"format": MANIFEST_FORMAT, "version": 1, "command": self.command, "status": status,
                    "written": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
                    "files": listed}
        try:
            with _locked(self.path), signals_deferred():
                (self.path / MANIFEST).unlink(missing_ok=True)  # no whole set from here to the new manifest
                if not (adding and self.committed):
                    self._remove_previous(keep=set(staged))
                for name in staged:
                    os.replace(self.staging / name, self.path / name)
                atomic_write_text(self.path / MANIFEST, json.dumps(manifest, indent=2) + "\n")
        except OSError as exc:
            raise OutputError(f"{self.path}: cannot write the outputs ({exc.strerror or exc})") from None
        self.committed, self._listed = True, listed
        if self.staging is not None:  # the next files a run stages start a new staging folder
            shutil.rmtree(self.staging, ignore_errors=True)
            self.staging = None
        return manifest

    def _remove_previous(self, keep: set) -> None:
        """The files of an earlier set of this kind (and the manifest), except those named in ``keep``
        (the new set replaces them) and the run's inputs."""
        for entry in os.listdir(self.path):
            target = self.path / entry
            replaced = entry in keep and not target.is_dir()  # os.replace puts the new file in its place
            if replaced or not any(fnmatch.fnmatch(entry, p) for p in self.owned) or self._holds_input(target):
                continue
            if target.is_dir() and not target.is_symlink():
                shutil.rmtree(target)
            else:
                os.unlink(target)

    def _holds_input(self, target: Path) -> bool:
        real = os.path.realpath(target)
        return any(path == real or path.startswith(real + os.sep) for path in self.keep)

    def _clear_after_error(self) -> None:
        """After an error nothing of an earlier set may stay to be mistaken for this run's result."""
        if not self.path.is_dir():
            return
        try:
            with _locked(self.path), signals_deferred():
                self._remove_previous(keep=set())
        except OSError:
            pass  # the error being raised says what went wrong; this one would hide it


def check_whole_set(path) -> None:
    """Refuse ``path`` when it lies in an output folder that holds no whole set: beside a manifest that
    does not list it with these contents, or beside a run's staging folder with no manifest (a run
    stopped while it swapped its set in).  A file with neither beside it is not such an output."""
    path = Path(path)
    folder, manifest = path.parent, path.parent / MANIFEST
    if manifest.is_file():
        try:
            listed = json.loads(manifest.read_text(encoding="utf-8"))["files"][path.name]
            whole = listed == _digest(path)
        except (OSError, ValueError, KeyError, TypeError):
            whole = False
        if not whole:
            raise InputError(f"{path}: not the file {manifest} lists (another run's, or changed since): "
                              "run the calibration again")
    elif any(entry.startswith(".workcal-staging.") for entry in os.listdir(folder)):
        raise InputError(f"{path}: {folder} holds no whole set of outputs (no {MANIFEST}, and a run's "
                          "staging folder: the run was stopped while it wrote them): run the calibration again")


def _digest(path: Path) -> dict:
    if path.is_dir():
        return {str(p.relative_to(path)): _digest(p) for p in sorted(path.rglob("*")) if p.is_file()}
    sha = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            sha.update(block)
    return {"sha256": sha.hexdigest(), "bytes": path.stat().st_size}


def _flat(name: str, digest: dict):
    """(relative path, digest) of a file, or of every file in a folder."""
    if "sha256" in digest:
        yield name, digest
        return
    for inner, value in digest.items():
        yield f"{name}/{inner}", value


@contextmanager
def _locked(folder: Path):
    """Hold an exclusive lock on ``folder`` (flock on the folder itself, POSIX) so that runs into one
    folder commit one after the other."""
    try:
        import fcntl
    except ImportError:  # Windows: no flock; commits of concurrent runs may interleave
        yield
        return
    fd = os.open(folder, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # closing releases the lock


@contextmanager
def signals_deferred(signals=(signal.SIGINT, signal.SIGTERM)):
    """Hold SIGINT and SIGTERM back during the block and deliver them after it (main thread only;
    elsewhere Python delivers no signals anyway)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught = []
    previous = {s: signal.getsignal(s) for s in signals}
    previous = {s: h for s, h in previous.items() if h is not None}  # None: a handler not set from Python
    for s in previous:
        signal.signal(s, lambda number, frame: caught.append(number))
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
        for number in caught[:1]:
            signal.raise_signal(number)
