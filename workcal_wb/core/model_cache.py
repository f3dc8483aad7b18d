"""Prepared models kept between runs: a content-addressed cache on disk.

Preparing a model (surface samples and normals, its symmetries, the FPFH features of the global
search, the nearest-sample grids) costs more than matching a scan against it, and a cell matches
scan after scan against the same two models.  ``ModelCache`` looks a model up by everything that
shapes its preparation: the model file's bytes and type (or, for a model given as points, e.g. from
FreeCAD, its points, normals and faces), the unit it is read in, the options (seed, symmetry
tolerance), the libraries' versions and a format version that also fingerprints the code that
prepares it.  A miss prepares the model as usual; ``store`` then writes what the run built (also
features and grid cells computed lazily during the match), after the run's own outputs.  A hit gives
the same model, so a match is bit-identical with and without the cache.

One file per model, ``<key>.model``: a fixed magic line, a JSON header (format, key, names and
numbers, and each array's dtype, shape, offset and CRC-32) and the raw arrays, read with numpy from
a copy-on-write memory map; no pickle, nothing executable.  A file that is truncated, corrupt, of
another format or keyed otherwise is never trusted: the model is prepared again and the file
replaced.  Files are written atomically (atomic.py), so two processes filling one entry both succeed
(the last rename wins; both wrote the same model).  The folder is bounded: past ``max_bytes`` the
least recently used files go (a hit refreshes a file's modification time).
"""
from __future__ import annotations

import hashlib
import json
import mmap
import os
import struct
import sys
import zlib
from pathlib import Path

import numpy as np

from .errors import OutputError
from .geometry import Cloud
from .surface import SurfaceModel

FORMAT_VERSION = 4  # 2: a mesh is prepared without its collapsed faces, 3: nor its repeated ones (geometry.checked), and a precomputed grid holds its diagonal cells, 4: with its sample cover and float32 features
MAGIC = b"WorkCal prepared model\n"
SUFFIX = ".model"
DEFAULT_MAX_BYTES = 2 << 30
ALIGN = 64
# The checksums read a file this many bytes at a time (not through its mapping, whose every page read
# would stay resident in the process).
CHECK_CHUNK = 1 << 20
# Only these dtypes are ever written or read (little-endian numbers and booleans).
DTYPES = ("<f8", "<f4", "<i8", "<i4", "|b1")
# A model loaded from the cache is written again when its run added features, or grid cells
# numbering at least this many and this fraction of those stored: filling them again costs every
# later run of that view far more than writing the file once (docs/tuning.md).
GROWTH_CELLS, GROWTH_FRACTION = 5000, 0.02
# Modules (or packages) whose source shapes a prepared model (for a model file, also how it is read):
# their bytes go into every key, so changed code never meets a model prepared by the old one.
SHAPING_MODULES = ("surface", "symmetry", "robust", "pointops", "features", "global_search", "geometry")
READING_MODULES = ("readers", "units", "files")


def default_folder() -> Path:
    """The user's cache folder for WorkCal's models: $XDG_CACHE_HOME/workcal/models (~/.cache when
    unset) or, on Windows, %LOCALAPPDATA%\\WorkCal\\cache\\models."""
    if sys.platform == "win32" and os.environ.get("LOCALAPPDATA"):
        return Path(os.environ["LOCALAPPDATA"]) / "WorkCal" / "cache" / "models"
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "workcal" / "models"


class ModelCache:
    """Prepared models by content.  ``folder`` None keeps nothing on disk (every model is prepared)."""

    def __init__(self, folder=None, max_bytes: int = DEFAULT_MAX_BYTES):
        self.folder = None if folder is None else Path(folder)
        self.max_bytes = int(max_bytes)
        self._handed_out = []  # (key, surface, what it held when loaded; None when just prepared)
        self.hits, self.misses = 0, 0
        self.notes: list[str] = []  # why something could not be written (the CLI prints these)

    # -- looking models up --------------------------------------------------------------------

    def model_file(self, path, units: str | None = "mm", seed: int = 0, unit_option: str = "unit",
                   symmetry_tolerance_mm: float | None = None) -> SurfaceModel:
        """The model in file ``path`` (read as ``readers.read_cloud`` reads it), prepared; the file is
        parsed only when the cache does not hold it.  Its reading warnings are ``.warnings``."""
        from .files import read_bytes
        from .readers import read_cloud
        from .units import mm_per_unit

        path = Path(path)
        scale = "file" if units is None else repr(mm_per_unit(units))
        data = read_bytes(path)
        key = _key(b"file", path.suffix.lower().encode(), hashlib.sha256(data).digest(), scale.encode(),
                   _options(seed, symmetry_tolerance_mm), modules=SHAPING_MODULES + READING_MODULES)
        del data
        surface = self._load(key)
        if surface is not None:
            surface.name = path.name
            surface.warnings = [_filled(w, path) for w in surface.warnings]
            return surface
        surface = SurfaceModel(read_cloud(path, units=units, unit_option=unit_option), seed, symmetry_tolerance_mm)
        self._handed_out.append((key, surface, None, path))
        return surface

    def model(self, cloud: Cloud, seed: int = 0, symmetry_tolerance_mm: float | None = None) -> SurfaceModel:
        """``cloud`` prepared (a SurfaceModel), from the cache when it holds one of the same content."""
        key = cloud_key(cloud, seed, symmetry_tolerance_mm)
        surface = self._load(key)
        if surface is not None:
            surface.name, surface.warnings = cloud.name, list(cloud.warnings)
            return surface
        surface = SurfaceModel(cloud, seed, symmetry_tolerance_mm)
        self._handed_out.append((key, surface, None, None))
        return surface

    def _load(self, key: str) -> SurfaceModel | None:
        if self.folder is None:
            self.misses += 1
            return None
        path = self.folder / f"{key}{SUFFIX}"
        try:
            meta, arrays = read_entry(path, key)
            surface = SurfaceModel.from_state(meta, arrays)
        except (OSError, ValueError, KeyError, TypeError, IndexError):  # missing, or not to be trusted
            self.misses += 1
            return None
        try:
            os.utime(path)  # recently used
        except OSError:
            pass
        self.hits += 1
        self._handed_out.append((key, surface, _held(surface), None))
        return surface

    # -- keeping them ---------------------------------------------------------------------------

    def store(self) -> list[str]:
        """Write every model handed out that was prepared here or grew during the run; the names of
        the files written.  A folder that cannot be written is noted in ``notes``, never raised."""
        if self.folder is None:
            return []
        written = []
        for key, surface, held, path in self._handed_out:
            if held is not None and not _grew(surface, held):
                continue
            meta, arrays = surface.state()
            if path is not None:
                meta["warnings"] = [_template(w, path) for w in meta["warnings"]]
            target = self.folder / f"{key}{SUFFIX}"
            try:
                self.folder.mkdir(parents=True, exist_ok=True)
                write_entry(target, key, meta, arrays)
            except (OSError, OutputError) as exc:
                self.notes.append(f"the model cache {self.folder} cannot be written ({exc}); the models will be "
                                  "prepared again next time")
                break
            written.append(target.name)
            self._evict(keep=target)
        self._handed_out = [(key, surface, _held(surface), path) for key, surface, _, path in self._handed_out]
        return written

    def _evict(self, keep: Path) -> None:
        """Remove the least recently used files until the folder holds at most ``max_bytes``."""
        entries = []
        for path in self.folder.glob(f"*{SUFFIX}"):
            try:
                st = path.stat()
            except OSError:
                continue
            entries.append((st.st_mtime, st.st_size, path))
        total = sum(size for _, size, _ in entries)
        for _, size, path in sorted(entries):
            if total <= self.max_bytes:
                break
            if path == keep:
                continue
            try:
                path.unlink()
            except FileNotFoundError:  # another process evicted it first
                pass
            except OSError:  # in use (Windows) or not ours: leave it
                continue
            total -= size


def cloud_key(cloud: Cloud, seed: int = 0, symmetry_tolerance_mm: float | None = None) -> str:
    """The cache key of a model given as points (with its normals and faces) and options."""
    parts = [b"cloud"]
    for name, a, dtype in (("points", cloud.points, np.float64), ("normals", cloud.normals, np.float64),
                           ("triangles", cloud.triangles, np.int64)):
        if a is None:
            parts.append(f"{name}:none".encode())
            continue
        a = np.ascontiguousarray(a, dtype=dtype)
        parts += [f"{name}:{a.shape}".encode(), hashlib.sha256(a.data).digest()]
    return _key(*parts, _options(seed, symmetry_tolerance_mm), modules=SHAPING_MODULES)


def _options(seed: int, symmetry_tolerance_mm) -> bytes:
    return f"seed={int(seed)} symmetry={symmetry_tolerance_mm!r}".encode()


def _key(*parts: bytes, modules) -> str:
    h = hashlib.sha256(f"workcal-model-cache {FORMAT_VERSION} numpy {np.__version__} scipy "
                       f"{_scipy_version()}".encode())
    h.update(_code_fingerprint(modules))
    for part in parts:
        h.update(len(part).to_bytes(8, "little"))
        h.update(part)
    return h.hexdigest()


_fingerprints: dict = {}


def _source(folder: Path, name: str) -> bytes:
    """The source of module ``name``, or of package ``name`` (each of its modules, in name order)."""
    if not (folder / name).is_dir():
        return (folder / f"{name}.py").read_bytes()
    sources = sorted((folder / name).glob("*.py"))
    if not sources:
        raise FileNotFoundError(folder / name / "__init__.py")
    return b"".join(path.read_bytes() for path in sources)


def _code_fingerprint(modules) -> bytes:
    """SHA-256 of the source of the core modules named (the code that prepares a model)."""
    modules = tuple(modules)
    if modules not in _fingerprints:
        h = hashlib.sha256()
        folder = Path(__file__).parent
        for name in modules:
            try:
                h.update(_source(folder, name))
            except OSError:  # no source beside us (a frozen install): the version must do
                from workcal_wb import __version__

                h.update(f"{name} {__version__}".encode())
        _fingerprints[modules] = h.digest()
    return _fingerprints[modules]


def _scipy_version() -> str:
    import scipy

    return scipy.__version__


def _held(surface: SurfaceModel) -> tuple:
    """What a model holds beyond its samples: its feature and grid keys, and the grid cells filled."""
    grids = list(surface._grids.values()) + list(surface._custom_grids.values())
    return (frozenset(surface._features), frozenset(surface._occupied), frozenset(surface._grids),
            frozenset(surface._custom_grids), sum(g.known() for g in grids))


def _grew(surface: SurfaceModel, held: tuple) -> bool:
    now = _held(surface)
    if any(a - b for a, b in zip(now[:4], held[:4])):
        return True
    added = now[4] - held[4]
    return added >= GROWTH_CELLS and added >= GROWTH_FRACTION * held[4]


# A file's own name and path in its reading warnings, stored as placeholders (the same bytes may be
# read from another path next time).
_PATH, _NAME = "\0path\0", "\0name\0"


def _template(text: str, path: Path) -> str:
    return text.replace(str(path), _PATH).replace(path.name, _NAME)


def _filled(text: str, path: Path) -> str:
    return text.replace(_PATH, str(path)).replace(_NAME, path.name)


# -- the file format ----------------------------------------------------------------------------

def write_entry(path: Path, key: str, meta: dict, arrays: dict) -> None:
    """One cache file: MAGIC, the header's length (8 bytes, little-endian), the JSON header, then
    each array's bytes at a 64-byte boundary.  Atomic: the file appears whole or not at all."""
    from .atomic import atomic_open

    listed, blobs, offset = [], [], 0
    for name, a in arrays.items():
        a = np.asarray(a)
        a = a if a.flags.c_contiguous else a.copy()  # (ascontiguousarray would make a 0-d array 1-d)
        if a.dtype.str not in DTYPES:
            raise ValueError(f"{name}: dtype {a.dtype.str} is not stored")
        listed.append({"name": name, "dtype": a.dtype.str, "shape": list(a.shape), "offset": offset,
                       "bytes": a.nbytes, "crc32": zlib.crc32(a.data)})
        blobs.append((offset, a))
        offset += -(-a.nbytes // ALIGN) * ALIGN
    header = json.dumps({"format": FORMAT_VERSION, "key": key, "meta": meta, "arrays": listed}).encode()
    start = -(-(len(MAGIC) + 8 + len(header)) // ALIGN) * ALIGN
    with atomic_open(path, "wb") as fh:
        fh.write(MAGIC + struct.pack("<Q", len(header)) + header)
        fh.write(b"\0" * (start - fh.tell()))
        for at, a in blobs:
            fh.write(b"\0" * (start + at - fh.tell()))
            fh.write(a.data)


def read_entry(path: Path, key: str) -> tuple[dict, dict]:
    """(meta, arrays) of a cache file written for ``key``; ValueError when it is not such a file
    whole and unchanged (wrong magic, format or key, a size or checksum that does not agree).  The
    arrays are mapped from the file, each page read when used; the checksums read the file through a
    small buffer, so the cells a run never visits do not count in its memory."""
    with open(path, "rb") as fh:
        size = os.fstat(fh.fileno()).st_size
        lead = fh.read(len(MAGIC) + 8)
        if len(lead) < len(MAGIC) + 8 or lead[:len(MAGIC)] != MAGIC:
            raise ValueError("not a WorkCal model cache file")
        length = struct.unpack("<Q", lead[len(MAGIC):])[0]
        if length > size:
            raise ValueError("truncated header")
        header = json.loads(fh.read(length).decode("utf-8"))
        if not isinstance(header, dict) or header.get("format") != FORMAT_VERSION or header.get("key") != key:
            raise ValueError("another format or another model")
        memory = mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_COPY)
        start = -(-(len(MAGIC) + 8 + length) // ALIGN) * ALIGN
        arrays, buffer = {}, memoryview(bytearray(CHECK_CHUNK))
        for entry in header["arrays"]:
            dtype, shape, at, nbytes = entry["dtype"], tuple(entry["shape"]), start + entry["offset"], entry["bytes"]
            if dtype not in DTYPES or any(not isinstance(n, int) or n < 0 for n in shape):
                raise ValueError(f"{entry['name']}: unexpected dtype or shape")
            count = int(np.prod(shape))
            if count * np.dtype(dtype).itemsize != nbytes or (nbytes and at + nbytes > size):
                raise ValueError(f"{entry['name']}: truncated")
            if not nbytes:
                arrays[entry["name"]] = np.empty(shape, dtype)
                continue
            if _checksum(fh, at, nbytes, buffer) != entry["crc32"]:
                raise ValueError(f"{entry['name']}: checksum")
            arrays[entry["name"]] = np.frombuffer(memory, dtype, count, at).reshape(shape)
    if not isinstance(header.get("meta"), dict):
        raise ValueError("no model description")
    return header["meta"], arrays


def _checksum(fh, at: int, nbytes: int, buffer: memoryview) -> int:
    """CRC-32 of ``nbytes`` of the file from ``at``, read through ``buffer``."""
    fh.seek(at)
    crc = 0
    while nbytes:
        got = fh.readinto(buffer[:min(nbytes, len(buffer))])
        if not got:
            raise ValueError("truncated")
        crc, nbytes = zlib.crc32(buffer[:got], crc), nbytes - got
    return crc


def describe(cache: ModelCache) -> str:
    """One line for a run's output: where the cache is and what it gave."""
    if cache.folder is None:
        return "model cache: off"
    return f"model cache {cache.folder}: {cache.hits} model(s) reused, {cache.misses} prepared"

