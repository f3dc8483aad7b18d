"""Prepared models kept in memory as long as the document objects they came from.

A calibration prepares its two models (``core.surface.SurfaceModel``: samples, symmetries, features,
nearest-sample grids, KD-tree and mesh BVH), and inside FreeCAD one model object is calibrated
against scan after scan.  The model cache on disk (``core.model_cache``) keeps what can be stored
between sessions; here the prepared model itself stays in memory, so the next calibration in the
session gets the very same object, with everything it filled, and reads no file.

An entry is found by its source, (document name, object name), and holds the content key that
shaped it (``model_cache.cloud_key``: points, normals and faces as the object gives them, the seed,
the code's fingerprint) and the cache folder: a model whose content, options or folder differ is
prepared again (from the disk cache when it holds it).  A document observer drops an entry when its
object changes (any property but its label or visibility), is deleted, or its document is closed;
the content key also catches changes the observer does not see (a containing App::Part moved, a
linked object edited).  With the KeepPreparedModels preference off nothing is kept here.

Thread-safety: ``model`` may run in the GUI's worker thread while the observer runs in the main
thread; the entries are guarded by a lock, and so is each nearest-sample grid while it is read or
grown.  A model's lazily filled grids give the same answers
however and whenever they are filled, so reusing one never changes a result.
"""
from __future__ import annotations

import threading
from dataclasses import dataclass
from pathlib import Path

import FreeCAD

from workcal_wb.core.geometry import Cloud
from workcal_wb.core.model_cache import ModelCache, cloud_key
from workcal_wb.core.surface import SurfaceModel

# Properties whose change leaves the model as it was.
COSMETIC = frozenset({"Label", "Label2", "Visibility"})


@dataclass
class Entry:
    key: str  # model_cache.cloud_key of the content and options that shaped it
    folder: Path  # the disk cache it came from and grows into
    surface: SurfaceModel
    cache: ModelCache  # writes what later runs add to the model (grid cells, features) to ``folder``


class PreparedModels:
    """Prepared models by source object; see the module's docstring."""

    def __init__(self):
        self._lock = threading.Lock()
        self._entries: dict[tuple, Entry] = {}
        self._observer = None

    def model(self, source: tuple | None, cloud: Cloud, seed: int, folder: Path | None) -> tuple[SurfaceModel, ModelCache]:
        """``cloud`` prepared, and the ModelCache to ``store()`` after the run.  Kept for ``source``
        (document name, object name) once ``watch`` was called, unless ``folder`` is None (the
        preference is off: nothing is kept, and what was kept is released) or there is no source."""
        if folder is None:
            self.clear()
        if folder is None or source is None or self._observer is None:
            cache = ModelCache(folder)
            return cache.model(cloud, seed), cache
        key = cloud_key(cloud, seed)
        with self._lock:
            entry = self._entries.get(source)
        if entry is not None and entry.key == key and entry.folder == folder:
            entry.surface.name, entry.surface.warnings = cloud.name, list(cloud.warnings)
            return entry.surface, entry.cache
        cache = ModelCache(folder)
        surface = cache.model(cloud, seed)
        with self._lock:
            self._entries[source] = Entry(key, folder, surface, cache)
        return surface, cache

    def forget(self, document: str, name: str | None = None) -> None:
        """Release the model of object ``name`` of ``document``, or all of the document's (None)."""
        with self._lock:
            for source in [s for s in self._entries if s[0] == document and name in (None, s[1])]:
                del self._entries[source]

    def clear(self) -> None:
        with self._lock:
            self._entries.clear()

    def sources(self) -> list[tuple]:
        """(document name, object name) of every model kept."""
        with self._lock:
            return list(self._entries)

    def watch(self) -> None:
        """Observe the documents (from the main thread, as FreeCAD's signals are connected there), so
        that models can be kept; once a session, when the first calibration's inputs are gathered
        (FreeCAD calls an observer for every property change of every document: none before)."""
        if self._observer is None:
            self._observer = _Observer(self)
            FreeCAD.addDocumentObserver(self._observer)


class _Observer:
    """A FreeCAD document observer (the application's, no GUI): releases the models of changed,
    deleted and closed objects."""

    def __init__(self, store: PreparedModels):
        self.store = store

    def slotChangedObject(self, obj, prop):
        if prop not in COSMETIC and self.store._entries:
            self.store.forget(obj.Document.Name, obj.Name)

    def slotDeletedObject(self, obj):
        if self.store._entries:
            self.store.forget(obj.Document.Name, obj.Name)

    def slotDeletedDocument(self, doc):
        if self.store._entries:
            self.store.forget(doc.Name)


KEPT = PreparedModels()  # the session's models


def source_of(obj) -> tuple | None:
    """(document name, object name) of a document object; None for anything else."""
    document = getattr(obj, "Document", None)
    name = getattr(obj, "Name", None)
    return None if document is None or name is None else (document.Name, name)
