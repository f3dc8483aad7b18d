"""The two result types: one match (U or V) and one calibration (W = V^-1 U).

Both serialise to JSON with lengths in mm and angles in degrees.  Derived numbers (inverse, Euler
angles, Omega) are written for the reader but never stored: they are recomputed from the matrix.
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass, field, fields

import numpy as np

from . import frames
from .errors import InputError

OK, AMBIGUOUS, FAILED = "ok", "ambiguous", "failed"
STATUSES = (OK, AMBIGUOUS, FAILED)


def _jsonable(value):
    """numpy scalars and arrays -> plain Python, recursively."""
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


def _matrix(value, name):
    return None if value is None else frames.as_transform(value, name)


@dataclass
class MatchResult:
    """U = ^S X: the transform that places the model (X) into the scan (S), with its quality."""

    status: str
    method: str
    matrix: np.ndarray | None
    scan_name: str = ""
    model_name: str = ""
    fitness: float = 0.0  # fraction of scan points within the final gate of the placed model
    coverage: float = 0.0  # fraction of the model surface that has scan points on it
    rms_mm: float = float("nan")  # RMS point-to-surface distance of the inliers
    mean_directed_hausdorff_mm: float = float("nan")  # the paper's H over the inliers
    max_deviation_mm: float = float("nan")
    percentiles_mm: dict = field(default_factory=dict)  # "50", "90", "95", "99" of |deviation|
    within_tolerance_pct: float = 0.0  # of the inliers, % within tolerance_mm
    tolerance_mm: float = 0.3
    gate_mm: float = float("nan")
    n_scan_points: int = 0
    n_inliers: int = 0
    iterations: int = 0
    time_s: float = 0.0
    timings_s: dict = field(default_factory=dict)  # wall time per phase
    stability: dict = field(default_factory=dict)
    candidates: list = field(default_factory=list)
    warnings: list = field(default_factory=list)
    reasons: list = field(default_factory=list)
    seed: int = 0

    def __post_init__(self):
        if self.status not in STATUSES:
            raise ValueError(f"match status must be one of {STATUSES}, not {self.status!r}")
        self.matrix = _matrix(self.matrix, "match matrix")

    @property
    def ok(self) -> bool:
        return self.status == OK

    def to_dict(self) -> dict:
        out = _jsonable(asdict(self))
        if self.matrix is not None:
            out["inverse"] = frames.invert(self.matrix).tolist()
            out.update({k: v for k, v in frames.describe(self.matrix).items() if k != "matrix"})
        out["units"] = {"length": "mm", "angle": "deg"}
        return out

    @classmethod
    def from_dict(cls, data: dict) -> "MatchResult":
        names = {f.name for f in fields(cls)}
        return cls(**{k: v for k, v in data.items() if k in names})

    def summary(self) -> str:
        """A few lines for a terminal or the Report view."""
        lines = [f"{self.status.upper()}  {self.model_name} -> {self.scan_name}  ({self.method}, {self.time_s:.2f} s)"]
        if self.matrix is not None:
            phi, theta, psi = frames.euler_zyz(self.matrix)
            t = self.matrix[:3, 3]
            lines.append(f"  Euler ZYZ {phi:.3f} {theta:.3f} {psi:.3f} deg, Omega {frames.omega(self.matrix):.3f} deg, "
                         f"translation {t[0]:.3f} {t[1]:.3f} {t[2]:.3f} mm")
            lines.append(f"  RMS {self.rms_mm:.3f} mm, mean Hausdorff {self.mean_directed_hausdorff_mm:.3f} mm, "
                         f"fitness {self.fitness:.1%}, coverage {self.coverage:.1%}, "
                         f"{self.within_tolerance_pct:.1f}% within {self.tolerance_mm} mm")
        lines += [f"  reason: {r}" for r in self.reasons] + [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)


@dataclass
class CalibrationResult:
    """W = ^B X = V^-1 U, the workpiece frame in the robot base frame, and what it rests on."""

    status: str
    W: np.ndarray | None
    U: np.ndarray | None = None
    V: np.ndarray | None = None
    workpiece: MatchResult | None = None
    reference: MatchResult | None = None
    uncertainty: dict = field(default_factory=dict)
    quality_gates: list = field(default_factory=list)  # {"name", "value", "limit", "passed", "unit"}
    tolerance_mm: float = 0.3
    inputs: dict = field(default_factory=dict)
    regions: dict = field(default_factory=dict)  # scan point indices per role and how they were found
    warnings: list = field(default_factory=list)
    reasons: list = field(default_factory=list)
    time_s: float = 0.0
    seed: int = 0

    def __post_init__(self):
        if self.status not in STATUSES:
            raise ValueError(f"calibration status must be one of {STATUSES}, not {self.status!r}")
        self.W, self.U, self.V = (_matrix(m, n) for m, n in ((self.W, "W"), (self.U, "U"), (self.V, "V")))
        if isinstance(self.workpiece, dict):
            self.workpiece = MatchResult.from_dict(self.workpiece)
        if isinstance(self.reference, dict):
            self.reference = MatchResult.from_dict(self.reference)

    @property
    def ok(self) -> bool:
        return self.status == OK

    def summary(self) -> str:
        """W, its angles, both matches and the uncertainty in a few lines (terminal, Report view)."""
        lines = [f"calibration {self.status.upper()} in {self.time_s:.2f} s"]
        lines += [f"  reason: {r}" for r in self.reasons]
        if self.W is not None:
            phi, theta, psi = frames.euler_zyz(self.W)
            lines.append("W = ^B X (workpiece frame in the robot base frame, mm):")
            lines += ["  " + " ".join(f"{v:12.5f}" for v in row) for row in self.W]
            lines.append(f"  Euler ZYZ {phi:.4f} {theta:.4f} {psi:.4f} deg, Omega {frames.omega(self.W):.4f} deg")
        for role, m in (("workpiece", self.workpiece), ("reference", self.reference)):
            if m is not None and m.matrix is not None:
                lines.append(f"  {role}: {m.status}, RMS {m.rms_mm:.3f} mm, mean Hausdorff "
                             f"{m.mean_directed_hausdorff_mm:.3f} mm, {m.within_tolerance_pct:.1f}% within "
                             f"{m.tolerance_mm} mm, {m.n_inliers} points")
        for key, words in (("toolpath_bound_mm", "at the toolpath"), ("surface_bound_mm", "at the workpiece surface")):
            if key in self.uncertainty:
                lines.append(f"  uncertainty {words}: {self.uncertainty[key]:.4f} mm "
                             f"(tolerance {self.tolerance_mm} mm)")
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        out = {"format": "workcal-calibration", "version": 1, "units": {"length": "mm", "angle": "deg"}}
        for f in fields(self):
            value = getattr(self, f.name)
            out[f.name] = value.to_dict() if isinstance(value, MatchResult) else _jsonable(value)
        for name in ("W", "U", "V"):
            M = getattr(self, name)
            out[f"{name}_pose"] = None if M is None else frames.describe(M)
        out["W_inverse"] = None if self.W is None else frames.invert(self.W).tolist()
        return out

    @classmethod
    def from_dict(cls, data: dict, source: str = "calibration") -> "CalibrationResult":
        if data.get("format") != "workcal-calibration":
            raise InputError(f"{source}: not a WorkCal calibration (missing \"format\": \"workcal-calibration\")")
        names = {f.name for f in fields(cls)}
        try:
            return cls(**{k: v for k, v in data.items() if k in names})
        except (TypeError, ValueError) as exc:
            raise InputError(f"{source}: {exc}") from exc

    def to_json_text(self) -> str:
        """The text ``to_json`` writes (``result_fingerprint`` hashes it)."""
        return json.dumps(self.to_dict(), indent=2, allow_nan=True)

    def to_json(self, path) -> None:
        from .atomic import atomic_write_text

        atomic_write_text(path, self.to_json_text())

    @classmethod
    def from_json(cls, path) -> "CalibrationResult":
        try:
            with open(path, encoding="utf-8") as fh:
                data = json.load(fh)
        except OSError as exc:
            raise InputError(f"{path}: cannot read calibration ({exc.strerror})") from exc
        except json.JSONDecodeError as exc:
            raise InputError(f"{path}: not valid JSON ({exc})") from exc
        return cls.from_dict(data, str(path))


def result_fingerprint(result: CalibrationResult) -> str:
    """The first 16 hex digits of the SHA-256 of the result's JSON: of result.json's bytes as ``to_json``
    writes them, so every exported program names the result it came from."""
    return hashlib.sha256(result.to_json_text().encode("utf-8")).hexdigest()[:16]
