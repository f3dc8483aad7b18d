"""What every study shares: settings, one calibration of a simulated scan scored against the truth,
the result type, and writing its figure, CSV and JSON.

A study runs the real pipeline (``calibration.calibrate``) on scans from the virtual scanner, whose
true U, V and W are exact, so every error it reports is an error against the truth, not against
another estimate.  Rows are flat (one scalar per column) so the CSV and the JSON hold the same
numbers; a calibration that raised or failed keeps its row, with the reason, and no errors.
"""
from __future__ import annotations

import csv
import functools
import io
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import frames
from ..atomic import atomic_write_bytes, atomic_write_text
from ..calibration import CalibrationOptions, calibrate
from ..errors import InputError, WorkCalError
from ..geometry import Cloud
from ..report import fmt
from ..result import OK
from ..surface import SurfaceModel
from ..simulate.toolpath_sample import sample_toolpath_points

REGION_MODES = ("truth", "auto")
# Quick mode (tests, smoke runs): a smaller image of the same scene (~90k points instead of ~200k)
# and a lighter bootstrap.  Full mode is the paper's scanner image and the calibration defaults.
QUICK_IMAGE = (368, 276)
QUICK_RESAMPLES = 2
# Points on the model surface where the displacement of W is measured (the "surface" error).
SURFACE_SAMPLES = 2000
# The studies' targets for simulated scenes (0.1 mm noise, 25 cm part, 5 scanner positions).
TARGET_ROTATION_DEG = 0.02
TARGET_TRANSLATION_MM = 0.05
TARGET_OMEGA_SPREAD_DEG = 0.02


@dataclass(frozen=True)
class StudySettings:
    """Knobs shared by the studies.

    regions: "truth" gives calibrate the simulator's own object masks, like the paper's manually
    selected portions S-a and S-p (the study then measures matching, not segmentation); "auto"
    lets calibrate find the regions itself, as a user's run does.
    """

    quick: bool = False
    seed: int = 0
    regions: str = "truth"
    tolerance_mm: float = 0.3
    method: str = "robust"

    def __post_init__(self):
        if self.regions not in REGION_MODES:
            raise InputError(f"study regions must be one of {REGION_MODES}, not {self.regions!r}")

    def options(self, seed: int) -> CalibrationOptions:
        extra = dict(resamples=QUICK_RESAMPLES) if self.quick else {}
        return CalibrationOptions(tolerance_mm=self.tolerance_mm, method=self.method, seed=seed, **extra)

    def scanner_settings(self) -> dict:
        """Keyword settings for Scanner.aimed_at / scanner_ring (the zoom follows the image size)."""
        return {"image_size": QUICK_IMAGE} if self.quick else {}

    def to_dict(self) -> dict:
        return {"quick": self.quick, "seed": self.seed, "regions": self.regions,
                "tolerance_mm": self.tolerance_mm, "method": self.method}


class Truth:
    """A scene's models prepared once, its true W, and the points where W's error is measured."""

    def __init__(self, scene, seed: int = 0):
        self.scene = scene
        self.W = scene.W
        self.workpiece = SurfaceModel(scene.workpiece_model(), seed)
        self.reference = SurfaceModel(scene.reference_model(), seed)
        self.diagonal = self.workpiece.diagonal
        self.toolpath, _ = sample_toolpath_points(scene)
        rng = np.random.default_rng(seed)
        points = self.workpiece.points
        self.surface = points[rng.choice(len(points), min(SURFACE_SAMPLES, len(points)), replace=False)]


@functools.lru_cache(maxsize=4)
def prepared(workpiece: str, seed: int) -> tuple:
    """(scene, Truth) of a study's workpiece, built once per process: a study's tasks share it, and a
    worker of a pool inherits it or builds its own (the same, all is seeded)."""
    from ..simulate.scene import build_scene

    scene = build_scene(workpiece, seed=seed)
    return scene, Truth(scene, seed)


@functools.lru_cache(maxsize=2)
def capture(workpiece: str, settings: StudySettings):
    """The one capture of the default set-up that repeatability and point-count calibrate again and
    again, made once per process."""
    from ..simulate.scanner import Scanner

    scene, _ = prepared(workpiece, settings.seed)
    return Scanner.aimed_at(scene, seed=settings.seed, **settings.scanner_settings()).scan(scene)


def calibrate_scan(scan, truth: Truth, settings: StudySettings, seed: int, keep=None):
    """Calibrate one simulated capture (``keep``: indices of the scan points to use, default all).

    Returns (CalibrationResult or None, error message or "").  Bad input that calibrate refuses
    (e.g. automatic regions that cannot find the workpiece) is a result of the study, not a crash.
    """
    idx = np.arange(len(scan.points)) if keep is None else np.asarray(keep)
    cloud = Cloud(scan.points[idx], name="simulated scan")
    regions = None
    if settings.regions == "truth":
        regions = {role: np.flatnonzero(scan.mask(role)[idx]) for role in ("workpiece", "reference")}
        missing = [role for role, r in regions.items() if len(r) == 0]
        if missing:
            return None, f"the {' and '.join(missing)} is not in view"
    try:
        result = calibrate(cloud, truth.workpiece, truth.reference, regions=regions,
                           toolpath_points=truth.toolpath, options=settings.options(seed))
    except WorkCalError as exc:
        return None, str(exc)
    return result, ""


def pose_columns(prefix: str, T) -> dict:
    """The paper's Table 1 numbers of one matrix: Z-Y-Z Euler angles and Omega (deg)."""
    if T is None:
        return {f"{prefix}_{k}": None for k in ("phi_deg", "theta_deg", "psi_deg", "omega_deg")}
    phi, theta, psi = frames.euler_zyz(T)
    return {f"{prefix}_phi_deg": phi, f"{prefix}_theta_deg": theta, f"{prefix}_psi_deg": psi,
            f"{prefix}_omega_deg": frames.omega(T)}


def displacement(A, B, points) -> np.ndarray:
    """How far each point (in X) lands apart when placed by A and by B (mm)."""
    return np.linalg.norm(frames.apply(A, points) - frames.apply(B, points), axis=1)


def score(result, error: str, truth: Truth, scan=None) -> dict:
    """The columns every study row has: status, errors of W (and U, V) against the truth, the
    predicted bound and whether it covers the actual displacement."""
    row = {"status": result.status if result is not None else "error", "reason": error}
    if result is not None and not error:
        row["reason"] = "; ".join(map(str, result.reasons))
    W = None if result is None else result.W
    if W is None:
        row.update({"rotation_error_deg": None, "translation_error_mm": None, "toolpath_error_mm": None,
                    "surface_error_mm": None, "toolpath_bound_mm": None, "surface_bound_mm": None,
                    "within_bound": None, "U_rotation_error_deg": None, "V_rotation_error_deg": None,
                    "time_s": None if result is None else result.time_s})
        return row
    toolpath = displacement(W, truth.W, truth.toolpath)
    surface = displacement(W, truth.W, truth.surface)
    bound = result.uncertainty.get("toolpath_bound_mm")
    row.update({
        "rotation_error_deg": frames.rotation_between_deg(W, truth.W),
        "translation_error_mm": float(np.linalg.norm(W[:3, 3] - truth.W[:3, 3])),
        "toolpath_error_mm": float(toolpath.max()),
        "surface_error_mm": float(surface.max()),
        "toolpath_bound_mm": bound,
        "surface_bound_mm": result.uncertainty.get("surface_bound_mm"),
        "within_bound": None if bound is None else bool(toolpath.max() <= bound),
        "U_rotation_error_deg": None if scan is None else frames.rotation_between_deg(result.U, scan.U),
        "V_rotation_error_deg": None if scan is None else frames.rotation_between_deg(result.V, scan.V),
        "time_s": result.time_s,
    })
    return row


def accepted(rows) -> list:
    """Rows whose calibration came back "ok": the ones a user would act on."""
    return [r for r in rows if r["status"] == OK]


def values(rows, key) -> np.ndarray:
    return np.array([r[key] for r in rows if r.get(key) is not None], dtype=float)


def stat(rows, key, how) -> float | None:
    v = values(rows, key)
    return float(how(v)) if len(v) else None


def fraction(rows, key) -> float | None:
    """Share of the rows where ``key`` is true, among those where it is known."""
    known = [r[key] for r in rows if r.get(key) is not None]
    return float(np.mean(known)) if known else None


def spread(rows, key) -> float | None:
    v = values(rows, key)
    return float(v.max() - v.min()) if len(v) else None


def target(name: str, value, limit, unit: str, at_most: bool = True) -> dict:
    """One checked target; a missing value (nothing to measure) does not pass."""
    passed = value is not None and (value <= limit if at_most else value >= limit)
    return {"name": name, "value": value, "limit": limit, "unit": unit, "passed": bool(passed),
            "comparison": "<=" if at_most else ">="}


def clean(value):
    """JSON-ready: numpy -> Python, NaN/inf -> None, recursively."""
    if isinstance(value, dict):
        return {str(k): clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [clean(v) for v in value]
    if isinstance(value, np.ndarray):
        return clean(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


@dataclass
class StudyResult:
    """One study: its rows (one per calibration), summary numbers, checked targets, and files."""

    name: str
    title: str
    settings: dict
    rows: list
    summary: dict
    targets: list = field(default_factory=list)
    tables: dict = field(default_factory=dict)  # extra tables, e.g. "table1" (the paper's Table 1)
    files: dict = field(default_factory=dict)  # "figure", "csv", "json" -> path

    @property
    def passed(self) -> bool:
        return all(t["passed"] for t in self.targets)

    def to_dict(self) -> dict:
        return clean({"format": "workcal-study", "version": 1, "units": {"length": "mm", "angle": "deg"},
                      "name": self.name, "title": self.title, "settings": self.settings,
                      "summary": self.summary, "targets": self.targets, "passed": self.passed,
                      "tables": self.tables, "rows": self.rows,
                      "files": {k: Path(v).name for k, v in self.files.items()}})

    def write(self, out_dir, figure) -> dict:
        """Write <name>.png (from a matplotlib Figure), <name>.csv and <name>.json into out_dir."""
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        stem = self.name.replace("-", "_")
        self.files = {"figure": out / f"{stem}.png", "csv": out / f"{stem}.csv", "json": out / f"{stem}.json"}
        save_figure(figure, self.files["figure"])
        atomic_write_text(self.files["csv"], rows_to_csv(self.rows))
        atomic_write_text(self.files["json"], json.dumps(self.to_dict(), indent=2) + "\n")
        return self.files


def rows_to_csv(rows) -> str:
    """Columns in first-seen order; numbers written so that float(text) gives the JSON value back."""
    columns = list(dict.fromkeys(k for r in rows for k in r))
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(columns)
    for r in rows:
        writer.writerow([_cell(r.get(c)) for c in columns])
    return buffer.getvalue()


def _cell(value):
    value = clean(value)
    if value is None:
        return ""
    return repr(value) if isinstance(value, float) else value


def new_figure(width: float = 10.0, height: float = 4.2):
    """A matplotlib Figure on the Agg canvas, without pyplot (no global backend is touched)."""
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), dpi=100, layout="constrained")


def save_figure(figure, path) -> None:
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", metadata={"Software": None})
    atomic_write_bytes(path, buffer.getvalue())


def summary_lines(result: StudyResult) -> list[str]:
    """A short table for the terminal: the summary numbers, then the targets."""
    lines = [f"{result.title}"]
    width = max((len(k) for k in result.summary), default=0)
    for key, value in result.summary.items():
        if isinstance(value, (dict, list)):
            continue
        lines.append(f"  {key:<{width}}  {fmt(value)}")
    for t in result.targets:
        lines.append(f"  target {t['name']}: {fmt(t['value'])} {t['unit']} {t['comparison']} {t['limit']} "
                     f"{t['unit']}  {'PASS' if t['passed'] else 'MISS'}")
    return lines
