"""The two result types: one match (U or V) and one calibration (W = V^-1 U).

Both serialise to JSON with lengths in mm and angles in degrees.  Derived numbers (inverse, Euler
angles, Omega) are written for the reader but never stored: they are recomputed from the matrix.

A result file is input like any other: ``from_dict`` checks every field's type (a result.json that
is an array, or has gates that are not a list of gates, is an InputError naming the file, never a
traceback in whoever reads it next).  ``to_json`` writes the scan's region indices (millions for a
large scan), and those of each region's points off its placed model, to a binary side file beside
result.json, ``<stem>.regions.npz``, and result.json records their counts, which ``from_json``
checks both ways.  A file without off-model points (written before they were kept) reads as before.
"""
from __future__ import annotations

import hashlib
import io
import json
import math
import zipfile
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np

from . import frames
from .errors import InputError
from .files import read_bytes

OK, AMBIGUOUS, FAILED = "ok", "ambiguous", "failed"
# An ambiguous calibration whose pose a person chose among those the scan could not tell apart: usable
# as "ok" is, and only with the record of that choice (Choice).
CHOSEN = "ok (chosen)"
STATUSES = (OK, AMBIGUOUS, FAILED, CHOSEN)
USABLE = (OK, CHOSEN)  # the statuses whose W may be used without forcing
# Version 2: region indices in a side file; 3: each reason a code with its sentence; 4: a person's choice.
CALIBRATION_FORMAT, CALIBRATION_VERSION = "workcal-calibration", 4
REGION_ROLES = ("workpiece", "reference", "platform")  # the regions that are scan point indices
# Per matched region, the scan indices of its points off its placed model, kept as the regions are;
# regions["off_model"] says of each how many there are, where they lie and what to change.
OFF_MODEL_KEYS = {"workpiece": "workpiece_off_model", "reference": "reference_off_model"}
INDEX_KEYS = REGION_ROLES + tuple(OFF_MODEL_KEYS.values())  # every scan index list a result keeps
_OFF_MODEL_WORDS = ("where", "change")  # a region's off_model note: "count" and these sentences
REGIONS_SUFFIX = ".regions.npz"
_REGION_FILE_KEYS = ("counts", "indices_file")  # what result.json says of the side file


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


# --- why a result is not "ok" -------------------------------------------------------------------

# The codes of Reason, stable across versions (decisions and tests compare them; the sentences may change).
# A match:
SCAN_NOT_SOLID = "scan_not_solid"  # the scan points lie on a line or a plane, or are too few
NOT_A_SURFACE = "not_a_surface"  # they scatter like a volume
NO_POSE = "no_pose"  # the global search found no consistent pose
NOISE_ABOVE_TOLERANCE = "noise_above_tolerance"  # the scan's own noise exceeds the tolerance
FEW_POINTS = "few_points"  # too few scan points on the model
LOW_COVERAGE = "low_coverage"  # the matched points cover too little of the model
MISFIT = "misfit"  # the model does not fit the scan within its noise
RMS = "rms"  # the fit's RMS exceeds the tolerance
WITHIN_TOLERANCE = "within_tolerance"  # too few matched points lie within the tolerance
VIEW_CONTRADICTED = "view_contradicted"  # the placed model contradicts much of the view
SYMMETRIC = "symmetric"  # the model is symmetric
OTHER_SIDE = "other_side"  # a pose seen from the other side fits about as well
RIVAL = "rival"  # a clearly different pose explains the view about as well
BEHIND_SURFACE = "behind_surface"  # much of the view inside the outline lies behind the placed surface
THIN_WALL = "thin_wall"  # the wall seen is too thin for the noise
OUTLINE_CONTINUED = "outline_continued"  # the scanned surface goes on past the placed outline
FACE_CONTINUED = "face_continued"  # scan points run on in the plane of a face past its edge
THROUGH_SUPPORT = "through_support"  # the placed model reaches through the plane the scan stands on
UNDER_CONSTRAINED = "under_constrained"  # a motion the matched surface does not fix
# Weighing a match by the scene (physics, regions, surroundings):
SINKS = "sinks"  # the placed model sinks through the platform
MANY_WAYS = "many_ways"  # the view fits the object in more ways than the constraints can weigh
TIE_UNBROKEN = "tie_unbroken"  # nothing in the scene tells the poses apart
SPLIT_UNEXPLAINED = "split_unexplained"  # touching objects split leaving much on neither model
SEARCH_DOUBT = "search_doubt"  # refined from a first pose whose search was in doubt
# A calibration (and its quality gates' codes, also <role>_status, <role>_rms, <role>_within_tolerance and
# <role>_explained for "workpiece" and "reference"):
NOT_FOUND = "not_found"  # an object the scan does not show (or its model is not the one scanned)
UNCERTAINTY = "uncertainty"  # the uncertainty bound exceeds the tolerance
DISTORTION = "distortion"  # the scan's distortion moves W more than the uncertainty leaves of the tolerance
ERROR = "error"  # an input the calibration could not use (the message names it)
UNKNOWN = "unknown"  # a reason read from a file written before reasons had codes
# The codes that say another pose explains the scan as well as the one found (a symmetry of the model, a
# pose seen from the other side, a rival, a tie the scene leaves unbroken): the only doubt a person's
# choice among the poses settles.  MANY_WAYS is not one: the poses that fit may not all be listed.
TIE_CODES = (SYMMETRIC, OTHER_SIDE, RIVAL, TIE_UNBROKEN)


def status_gate_code(role: str) -> str:
    """The code of the quality gate that a match's status is "ok" (role: "workpiece" or "reference")."""
    return f"{role}_status"


@dataclass(frozen=True)
class Reason:
    """Why a result is not "ok": a stable ``code`` (the module's constants above) that decisions and
    tests compare, the sentence people read (``str(reason)``), and the object it is about when it is
    said of a whole (a calibration's "reference match: ...")."""

    code: str
    text: str
    subject: str = ""

    def __str__(self) -> str:
        return self.text

    def within(self, words: str, subject: str = "") -> "Reason":
        """The same reason said within a whole, after ``words`` ("reference match", "with the scan beside
        its region"), of ``subject`` when it is one object's ("reference")."""
        return Reason(self.code, f"{words}: {self.text}", subject or self.subject)

    def to_dict(self) -> dict:
        return {"code": self.code, "text": self.text, **({"subject": self.subject} if self.subject else {})}

    @classmethod
    def from_value(cls, value, source: str, name: str) -> "Reason":
        """A reason as a file gives it: {"code", "text"[, "subject"]}, or a bare sentence (UNKNOWN code)."""
        if isinstance(value, cls):
            return value
        if _is(value, _TEXT):
            return cls(UNKNOWN, value)
        if (isinstance(value, dict) and _is(value.get("code"), _TEXT) and _is(value.get("text"), _TEXT)
                and _is(value.get("subject", ""), _TEXT)):
            return cls(value["code"], value["text"], value.get("subject", ""))
        raise InputError(f"{source}: every entry of {name} must be a reason (an object with code and text) or a "
                         f"string, found {_json_kind(value)}")


def codes(reasons) -> list[str]:
    """The codes of ``reasons`` in order."""
    return [r.code for r in reasons]


@dataclass
class Candidate:
    """A pose a match weighed, as its result lists it (the best first): U (model -> scan) and how it
    compares with the best by the view evidence and by the scan points it leaves far off, whether it
    is refined like the best (``turn_of_best``: a turn of it, or a rival near it by the view), fits the
    scan within the noise, is a rival, or was ruled out by a physical constraint.  ``evidence``
    (visibility.Evidence) is kept while the match judges it."""

    matrix: np.ndarray
    score: float = 0.0
    score_ratio: float = 1.0
    standard_errors_below_best: float = 0.0
    far_off_standard_errors: float = 0.0  # NaN where not weighed (a result that could not be "ok")
    from_the_other_side: bool = False
    turn_of_best: bool = False
    fits: bool = True
    hidden_points: int = 0
    missing_cells: int = 0
    rotation_from_best_deg: float = 0.0
    shift_from_best_mm: float = 0.0
    rival: bool = False
    ruled_out_by: str | None = None
    evidence: object = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        self.matrix = frames.as_transform(self.matrix, "candidate matrix")

    @property
    def to_model(self) -> np.ndarray:
        """T = U^-1: scan -> model."""
        return frames.invert(self.matrix)

    def __eq__(self, other) -> bool:  # as listed: a matrix by its elements, NaN (not weighed) equal to NaN
        return isinstance(other, Candidate) and json.dumps(self.to_dict()) == json.dumps(other.to_dict())

    def to_dict(self) -> dict:
        return _jsonable({f.name: getattr(self, f.name) for f in fields(self) if f.name != "evidence"})

    @classmethod
    def from_dict(cls, data, source: str) -> "Candidate":
        values = _checked_fields(cls, data, source)
        for name in ("score", "score_ratio", "standard_errors_below_best", "far_off_standard_errors",
                     "rotation_from_best_deg", "shift_from_best_mm", "hidden_points", "missing_cells"):
            if name in values and not _is(values[name], _NUMBER):
                raise InputError(f"{source}: {name} must be a number, found {_json_kind(values[name])}")
        for name in ("from_the_other_side", "turn_of_best", "fits", "rival"):
            if name in values and not isinstance(values[name], bool):
                raise InputError(f"{source}: {name} must be true or false, found {_json_kind(values[name])}")
        if values.get("ruled_out_by") is not None and not _is(values["ruled_out_by"], _TEXT):
            raise InputError(f"{source}: ruled_out_by must be a string or null")
        values.pop("evidence", None)
        try:
            return cls(**values)
        except (TypeError, ValueError, InputError) as exc:
            raise InputError(f"{source}: {exc}") from None


# The match's numbers a choice's evidence keeps of a pose (Candidate fields).
_EVIDENCE_NUMBERS = ("score", "score_ratio", "standard_errors_below_best")


@dataclass
class Choice:
    """A person's choice of one pose among those an ambiguous calibration could not tell apart: who
    (the OS user name) and when (ISO 8601), which match (``role``) and which of its ``count`` poses
    (``index``, 0 the best), that pose (``matrix``, U or V) and the best it replaced (``best``), and
    the evidence shown for each pose ({"index", "difference" in words, and the match's "score",
    "score_ratio", "standard_errors_below_best" or the "symmetry" that gives it})."""

    who: str
    when: str
    role: str
    index: int
    count: int
    matrix: np.ndarray
    best: np.ndarray
    evidence: list = field(default_factory=list)

    def __post_init__(self):
        self.matrix, self.best = frames.as_transform(self.matrix, "chosen pose"), frames.as_transform(self.best, "best pose")
        if self.role not in ("workpiece", "reference") or not 0 <= self.index < self.count:
            raise ValueError(f"a choice names the workpiece or reference match and one of its poses, not "
                             f"{self.role!r} pose {self.index} of {self.count}")

    def __eq__(self, other) -> bool:
        return isinstance(other, Choice) and json.dumps(self.to_dict()) == json.dumps(other.to_dict())

    @property
    def difference(self) -> str:
        """How the chosen pose differs from the best, in words (as shown when it was chosen)."""
        return next((e.get("difference", "") for e in self.evidence if e.get("index") == self.index), "")

    def to_dict(self) -> dict:
        return _jsonable({f.name: getattr(self, f.name) for f in fields(self)})

    @classmethod
    def from_dict(cls, data, source: str) -> "Choice":
        values = _checked_fields(cls, data, source)
        missing = [f.name for f in fields(cls) if f.name not in values and f.name != "evidence"]
        if missing:
            raise InputError(f"{source}: the choice has no {missing[0]}")
        _check_items(values.get("evidence", []), (dict,), source, "choice evidence")
        for entry in values.get("evidence", []):
            if not (_is(entry.get("index"), (int,)) and _is(entry.get("difference", ""), _TEXT)
                    and _is(entry.get("symmetry", ""), _TEXT)
                    and all(_is(entry.get(key, 0), _NUMBER) for key in _EVIDENCE_NUMBERS)):
                raise InputError(f"{source}: every entry of the choice evidence needs index (a whole number), "
                                 f"difference and symmetry as strings and {', '.join(_EVIDENCE_NUMBERS)} as numbers")
        try:
            return cls(**values)
        except (TypeError, ValueError, InputError) as exc:
            raise InputError(f"{source}: {exc}") from None


# --- checking what a file says ------------------------------------------------------------------

_NUMBER, _TEXT = (int, float), (str,)
_KINDS = {"str": _TEXT, "float": _NUMBER, "int": (int,), "list": (list,), "dict": (dict,)}


def _is(value, kinds) -> bool:
    return isinstance(value, kinds) and not isinstance(value, bool)


def _checked_fields(cls, data, source: str) -> dict:
    """The fields of ``cls`` found in ``data``, each of the type its annotation names (str, float, int,
    list, dict; others are checked by the class itself); a wrong type is an InputError."""
    if not isinstance(data, dict):
        raise InputError(f"{source}: expected a JSON object, found {_json_kind(data)}")
    out = {}
    for f in fields(cls):
        if f.name not in data:
            continue
        value, kinds = data[f.name], _KINDS.get(f.type)
        if kinds is not None and not _is(value, kinds):
            raise InputError(f"{source}: {f.name} must be {_kind_words(kinds)}, found {_json_kind(value)}")
        out[f.name] = value
    return out


def _json_kind(value) -> str:
    if value is None:
        return "null"
    return {bool: "true/false", int: "a number", float: "a number", str: "a string", list: "an array",
            dict: "an object"}.get(type(value), type(value).__name__)


def _kind_words(kinds) -> str:
    return {_NUMBER: "a number", _TEXT: "a string", (int,): "a whole number", (list,): "an array",
            (dict,): "an object"}[kinds]


def _check_items(values: list, kinds, source: str, name: str) -> None:
    for value in values:
        if not _is(value, kinds):
            raise InputError(f"{source}: every entry of {name} must be {_kind_words(kinds)}, found {_json_kind(value)}")


def _check_numbers(mapping: dict, source: str, name: str, keys=None) -> None:
    """Values that must be numbers (all of them, or those whose key ``keys`` accepts)."""
    for key, value in mapping.items():
        if (keys is None or keys(key)) and not _is(value, _NUMBER):
            raise InputError(f"{source}: {name}[{key!r}] must be a number, found {_json_kind(value)}")


def _check_gates(gates: list, source: str) -> None:
    _check_items(gates, (dict,), source, "quality_gates")
    for gate in gates:
        if not _is(gate.get("name", ""), _TEXT) or not isinstance(gate.get("passed", False), bool):
            raise InputError(f"{source}: a quality gate needs a name (string) and passed (true/false)")
        for key in ("value", "limit"):
            if key in gate and not _is(gate[key], _NUMBER + _TEXT):
                raise InputError(f"{source}: quality gate {gate.get('name')!r}: {key} must be a number or a string")
        if not _is(gate.get("why", ""), _TEXT) or not _is(gate.get("code", ""), _TEXT):
            raise InputError(f"{source}: quality gate {gate.get('name')!r}: why and code must be strings")


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
    candidates: list = field(default_factory=list)  # Candidates weighed, best first, distinct under the model's symmetries
    warnings: list = field(default_factory=list)
    reasons: list = field(default_factory=list)  # Reasons
    seed: int = 0
    noise_mm: float = float("nan")  # the scan's own noise (scatter about local surface fits)
    viewpoint: dict = field(default_factory=dict)  # the sensor position the view was judged from, and its source
    view: dict = field(default_factory=dict)  # the best pose's view evidence: cells, hidden points, missing cells
    symmetries: list = field(default_factory=list)  # the model's own: axis, point_mm, order (0: any angle), description
    ties: list = field(default_factory=list)  # the Reasons that come from rival poses (physics.decide may break them)
    constraints: list = field(default_factory=list)  # poses ruled out by contact with the platform or free space

    def __post_init__(self):
        if self.status not in STATUSES:
            raise ValueError(f"match status must be one of {STATUSES}, not {self.status!r}")
        self.matrix = _matrix(self.matrix, "match matrix")
        self.reasons = [Reason.from_value(r, "match", "reasons") for r in self.reasons]
        self.ties = [Reason.from_value(r, "match", "ties") for r in self.ties]
        self.candidates = [c if isinstance(c, Candidate) else Candidate.from_dict(c, "match candidate")
                           for c in self.candidates]

    @property
    def ok(self) -> bool:
        return self.status == OK

    def to_dict(self) -> dict:
        out = _jsonable({f.name: getattr(self, f.name) for f in fields(self)
                         if f.name not in ("candidates", "reasons", "ties")})
        out["candidates"] = [c.to_dict() for c in self.candidates]
        out["reasons"], out["ties"] = [r.to_dict() for r in self.reasons], [r.to_dict() for r in self.ties]
        if self.matrix is not None:
            out["inverse"] = frames.invert(self.matrix).tolist()
            out.update({k: v for k, v in frames.describe(self.matrix).items() if k != "matrix"})
        out["units"] = {"length": "mm", "angle": "deg"}
        return out

    @classmethod
    def from_dict(cls, data: dict, source: str = "match") -> "MatchResult":
        values = _checked_fields(cls, data, source)
        for name in ("percentiles_mm", "timings_s"):
            _check_numbers(values.get(name, {}), source, name)
        for name in ("warnings", "constraints"):
            _check_items(values.get(name, []), _TEXT, source, name)
        for name in ("reasons", "ties"):
            values[name] = [Reason.from_value(r, source, name) for r in values.get(name, [])]
        _check_items(values.get("candidates", []), (dict,), source, "candidates")
        values["candidates"] = [Candidate.from_dict(c, f"{source}: candidate {k}")
                                for k, c in enumerate(values.get("candidates", []))]
        try:
            return cls(**values)
        except (TypeError, ValueError) as exc:
            raise InputError(f"{source}: {exc}") from None

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
                         f"{self.within_tolerance_pct:.1f}% within {self.tolerance_mm} mm, scan noise {self.noise_mm:.3f} mm")
        lines += [f"  symmetry: {s['description']}" for s in self.symmetries]
        lines += [f"  decided: {c}" for c in self.constraints]
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
    quality_gates: list = field(default_factory=list)  # {"name", "value", "limit", "passed", "unit"[, "why"]}
    tolerance_mm: float = 0.3
    inputs: dict = field(default_factory=dict)
    # Scan point indices per role, and per matched region of its points off its placed model, and how
    # they were found (source, trimmed, off_model)
    regions: dict = field(default_factory=dict)
    warnings: list = field(default_factory=list)
    reasons: list = field(default_factory=list)  # Reasons
    time_s: float = 0.0
    seed: int = 0
    choice: Choice | None = None  # the pose a person chose, when the status is CHOSEN

    def __post_init__(self):
        if self.status not in STATUSES:
            raise ValueError(f"calibration status must be one of {STATUSES}, not {self.status!r}")
        if isinstance(self.choice, dict):
            self.choice = Choice.from_dict(self.choice, "calibration")
        if (self.status == CHOSEN) != (self.choice is not None):
            raise ValueError(f"calibration status {CHOSEN!r} needs the record of who chose the pose, and only it has "
                             f"one (status {self.status!r}, {'a' if self.choice else 'no'} choice recorded)")
        self.reasons = [Reason.from_value(r, "calibration", "reasons") for r in self.reasons]
        self.W, self.U, self.V = (_matrix(m, n) for m, n in ((self.W, "W"), (self.U, "U"), (self.V, "V")))
        if isinstance(self.workpiece, dict):
            self.workpiece = MatchResult.from_dict(self.workpiece, "workpiece match")
        if isinstance(self.reference, dict):
            self.reference = MatchResult.from_dict(self.reference, "reference match")
        self.regions = {k: np.asarray(v, dtype=np.int64) if k in INDEX_KEYS and v is not None else v
                        for k, v in self.regions.items()}

    @property
    def ok(self) -> bool:
        """W may be used: "ok", or "ok (chosen)" by a person among poses the scan could not tell apart."""
        return self.status in USABLE

    def off_model(self, role: str) -> dict | None:
        """What the result says of the ``role`` region's points off its placed model: "count", "where"
        and "change" (sentences, empty when there are none) and their scan "indices" (None when read
        without the side file); None when it says nothing (no pose to measure them from, or a file
        written before they were kept)."""
        note = (self.regions.get("off_model") or {}).get(role)
        return None if note is None else {**note, "indices": self.regions.get(OFF_MODEL_KEYS[role])}

    def summary(self) -> str:
        """W, its angles, both matches and the uncertainty in a few lines (terminal, Report view)."""
        lines = [f"calibration {self.status.upper()} in {self.time_s:.2f} s"]
        lines += [f"  reason: {r}" for r in self.reasons]
        if self.choice is not None:
            lines.append(f"  {choice_words(self.choice)}")
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
                lines += [f"  {role} model symmetry: {s['description']}" for s in m.symmetries]
                lines += [f"  {role}: {c}" for c in m.constraints]
        for key, words in (("toolpath_bound_mm", "at the toolpath"), ("surface_bound_mm", "at the workpiece surface")):
            if key in self.uncertainty:
                lines.append(f"  uncertainty {words}: {self.uncertainty[key]:.4f} mm "
                             f"(tolerance {self.tolerance_mm} mm)")
        u = self.uncertainty
        if all(f"distortion_{key}" in u for key in ("scale_pct", "strain_pct", "shift_mm")):
            lines.append(f"  scan distortion: scale {u['distortion_scale_pct']:+.3f} %, strain up to "
                         f"{u['distortion_strain_pct']:.3f} %, moving W up to {u['distortion_shift_mm']:.4f} mm")
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def to_dict(self, region_indices: bool = True) -> dict:
        """Everything as JSON values; ``region_indices=False`` gives only how many points each region has."""
        out = {"format": CALIBRATION_FORMAT, "version": CALIBRATION_VERSION, "units": {"length": "mm", "angle": "deg"}}
        for f in fields(self):
            value = getattr(self, f.name)
            out[f.name] = value.to_dict() if isinstance(value, (MatchResult, Choice)) else _jsonable(value)
        out["reasons"] = [r.to_dict() for r in self.reasons]
        roles = {k: v for k, v in self.regions.items() if k in INDEX_KEYS and v is not None}
        out["regions"] = {k: v for k, v in out["regions"].items() if k not in _REGION_FILE_KEYS + INDEX_KEYS}
        if region_indices:
            out["regions"].update(_jsonable(roles))
        else:  # read without its side file, a result still knows the counts
            out["regions"]["counts"] = {k: len(v) for k, v in roles.items()} or self.regions.get("counts", {})
        for name in ("W", "U", "V"):
            M = getattr(self, name)
            out[f"{name}_pose"] = None if M is None else frames.describe(M)
        out["W_inverse"] = None if self.W is None else frames.invert(self.W).tolist()
        return out

    @classmethod
    def from_dict(cls, data: dict, source: str = "calibration", regions_folder=None) -> "CalibrationResult":
        """A result from JSON values, every field checked; region indices kept in a side file are read
        from ``regions_folder`` (None: not read, the regions keep only their counts)."""
        if not isinstance(data, dict) or data.get("format") != CALIBRATION_FORMAT:
            raise InputError(f"{source}: not a WorkCal calibration (missing \"format\": \"{CALIBRATION_FORMAT}\")")
        version = data.get("version", 1)
        if not _is(version, (int,)) or not 1 <= version <= CALIBRATION_VERSION:
            raise InputError(f"{source}: calibration format version {version!r}; this WorkCal reads versions "
                             f"1 to {CALIBRATION_VERSION} (a newer WorkCal wrote it?)")
        if "status" not in data:
            raise InputError(f"{source}: has no status")
        values = _checked_fields(cls, data, source)
        _check_numbers(values.get("uncertainty", {}), source, "uncertainty",
                       lambda key: key.endswith(("_mm", "_deg", "_pct")))
        _check_items(values.get("warnings", []), _TEXT, source, "warnings")
        values["reasons"] = [Reason.from_value(r, source, "reasons") for r in values.get("reasons", [])]
        _check_gates(values.get("quality_gates", []), source)
        if not math.isfinite(values.get("tolerance_mm", 1.0)) or values.get("tolerance_mm", 1.0) <= 0:
            raise InputError(f"{source}: tolerance_mm must be a positive number of mm")
        for role in ("workpiece", "reference"):
            if values.get(role) is not None and not isinstance(values[role], dict):
                raise InputError(f"{source}: {role} must be a match (an object) or null, found {_json_kind(values[role])}")
            if values.get(role) is not None:
                values[role] = MatchResult.from_dict(values[role], f"{source}: {role} match")
        if values.get("choice") is not None:
            values["choice"] = Choice.from_dict(values["choice"], f"{source}: choice")
        scan_points = values.get("inputs", {}).get("scan_points")
        values["regions"] = _read_regions(values.get("regions", {}), source, regions_folder,
                                          scan_points if _is(scan_points, (int,)) else None)
        try:
            result = cls(**values)
        except (TypeError, ValueError) as exc:
            raise InputError(f"{source}: {exc}") from None
        if result.choice is not None:
            _check_choice(result, version, source)
        return result

    def to_json_text(self, indices_file: str | None = None) -> str:
        """The text ``to_json`` writes (``result_fingerprint`` hashes it): the regions as counts and the
        name of the side file that holds their indices (``indices_file``; default: the name the result
        was read with, else result.regions.npz), so a result read back gives the same text."""
        data = self.to_dict(region_indices=False)
        if data["regions"]["counts"]:
            data["regions"]["indices_file"] = (indices_file or self.regions.get("indices_file")
                                               or "result" + REGIONS_SUFFIX)
        return json.dumps(data, indent=2, allow_nan=True)

    def to_json(self, path) -> None:
        """result.json, and the region indices beside it in ``<stem>.regions.npz`` (written first)."""
        from .atomic import atomic_write_bytes, atomic_write_text

        path = Path(path)
        side = path.with_name(path.stem + REGIONS_SUFFIX)
        indices = {k: v for k, v in self.regions.items() if k in INDEX_KEYS and v is not None}
        if indices:
            atomic_write_bytes(side, _npz_bytes(indices))
        atomic_write_text(path, self.to_json_text(side.name))

    @classmethod
    def from_json(cls, path, with_regions: bool = True) -> "CalibrationResult":
        """Read a result file (and its region indices, unless ``with_regions`` is False: W alone)."""
        path = Path(path)
        return cls.from_text(read_bytes(path, "calibration file"), str(path),
                             regions_folder=path.parent if with_regions else None)

    @classmethod
    def from_text(cls, text, source: str, regions_folder=None) -> "CalibrationResult":
        """From JSON text (a file's bytes, or what a FreeCAD object stores)."""
        try:
            data = json.loads(text)
        except (ValueError, RecursionError) as exc:  # JSONDecodeError, bad UTF-8, absurd nesting
            raise InputError(f"{source}: not valid JSON ({exc})") from None
        return cls.from_dict(data, source, regions_folder)


# How far a chosen result's matrices may be from what they must be (mm, and a rotation's elements): JSON
# keeps numbers exactly, so this leaves only the rounding of V^-1 U; any edit is far beyond it.
SAME_POSE_TOLERANCE = 1e-6


def _check_choice(result: CalibrationResult, version: int, source: str) -> None:
    """A result with a person's choice, as ``choice.choose`` writes it: version 4 or later, who and when
    said, the chosen match ambiguous only by a tie (TIE_CODES) and the other ok, the chosen pose its U
    (or V) and W = V^-1 U; else an InputError naming ``source``."""
    record = result.choice
    other_role = "reference" if record.role == "workpiece" else "workpiece"
    match, other = getattr(result, record.role), getattr(result, other_role)
    pose = result.U if record.role == "workpiece" else result.V

    def same(a, b) -> bool:
        return a is not None and b is not None and bool(np.allclose(a, b, rtol=0.0, atol=SAME_POSE_TOLERANCE))

    if version < 4:
        said = f"the file is version {version} (a person's choice is recorded from version 4)"
    elif not (record.who.strip() and record.when.strip()):
        said = "its choice does not say who made it and when"
    elif match is None or match.status != AMBIGUOUS:
        said = f"the {record.role} match it chose a pose of is {getattr(match, 'status', 'missing')!r}, not ambiguous"
    elif other is None or other.status != OK:
        said = f"the {other_role} match is {getattr(other, 'status', 'missing')!r}, not ok"
    elif not match.reasons or any(r.code not in TIE_CODES for r in match.reasons):
        said = f"the {record.role} match is in doubt for more than a tie between poses"
    elif not same(record.matrix, pose):
        said = f"the chosen pose is not its {'U' if record.role == 'workpiece' else 'V'}"
    elif not (result.U is not None and result.V is not None and same(result.W, frames.invert(result.V) @ result.U)):
        said = "its W is not V^-1 U"
    else:
        return
    raise InputError(f"{source}: status {CHOSEN!r} while {said}: the file contradicts itself (edited, or not "
                     "written by WorkCal); calibrate again")


def choice_words(choice: Choice) -> str:
    """The choice in one sentence (the summary, the programs' headers)."""
    return (f"pose chosen by the user {choice.who} on {choice.when} among {choice.count} candidate poses of the "
            f"{choice.role} match: pose {choice.index + 1}, {choice.difference or 'the best'}")


def result_fingerprint(result: CalibrationResult) -> str:
    """The first 16 hex digits of the SHA-256 of the result's JSON: of result.json's bytes as ``to_json``
    writes them, so every exported program names the result it came from."""
    return hashlib.sha256(result.to_json_text().encode("utf-8")).hexdigest()[:16]


# --- region indices -----------------------------------------------------------------------------

def _npz_bytes(indices: dict) -> bytes:
    """The index arrays as a compressed .npz, 32-bit where they fit.  Written as np.savez_compressed
    does, at zlib's fastest level: as small for these rising indices and ~9x faster (0.14 s to 0.016 s
    for the demo scene's 266k indices)."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as archive:
        for role, v in indices.items():
            v = np.asarray(v, dtype=np.int64)
            with archive.open(f"{role}.npy", "w", force_zip64=True) as member:
                np.lib.format.write_array(member, v.astype(np.int32) if v.size == 0 or v.max() < 2**31 else v)
    return buffer.getvalue()


def _read_regions(regions, source: str, folder, scan_points: int | None) -> dict:
    """Regions as {role: int64 indices, other keys as they are}: inline lists (version 1, FreeCAD
    documents) or the side file a version 2 result.json names, with its counts checked both ways."""
    if not isinstance(regions, dict):
        raise InputError(f"{source}: regions must be an object, found {_json_kind(regions)}")
    regions = dict(regions)
    counts, name = regions.get("counts"), regions.get("indices_file")
    if name is not None and not (_is(name, _TEXT) and Path(name).name == name and isinstance(counts, dict)):
        raise InputError(f"{source}: regions.indices_file must be a file name beside it, with regions.counts")
    if name is not None and folder is not None:
        regions.update(_side_file_indices(Path(folder) / name, counts, source))
        del regions["counts"]  # the arrays say it now
    for key in INDEX_KEYS:
        if key in regions:
            regions[key] = _indices(regions[key], source, scan_points, key)
    _check_off_model(regions, source)
    return regions


def _index_words(key: str) -> str:
    """An index list of the regions in words: "workpiece", "reference off-model"."""
    return key.replace("_off_model", " off-model")


def _indices(values, source: str, scan_points: int | None, key: str) -> np.ndarray:
    try:
        array = np.asarray(values)
    except (ValueError, TypeError, OverflowError):  # ragged lists, absurd numbers
        array = None
    if array is None or array.ndim != 1 or (len(array) and array.dtype.kind not in "iu"):
        what = f"the {key} region" if key in REGION_ROLES else f"the {_index_words(key)} points"
        raise InputError(f"{source}: {what} must be a list of whole point indices")
    array = array.astype(np.int64)
    if len(array) and (array.min() < 0 or (scan_points is not None and array.max() >= scan_points)):
        raise InputError(f"{source}: {_index_words(key)} indices outside the scan's {scan_points} points")
    return array


def _check_off_model(regions: dict, source: str) -> None:
    """regions["off_model"], when there: per matched role, {"count": whole number, "where": text,
    "change": text}, its count that of the role's off-model indices when they are read too."""
    notes = regions.get("off_model")
    if notes is None:
        return
    if not isinstance(notes, dict) or not set(notes) <= set(OFF_MODEL_KEYS):
        raise InputError(f"{source}: regions.off_model must be an object with a note per region "
                         f"({' and '.join(OFF_MODEL_KEYS)})")
    for role, note in notes.items():
        if not (isinstance(note, dict) and _is(note.get("count"), (int,)) and note["count"] >= 0
                and all(_is(note.get(key), _TEXT) for key in _OFF_MODEL_WORDS)):
            raise InputError(f"{source}: regions.off_model.{role} must hold count (a whole number) and "
                             f"{' and '.join(_OFF_MODEL_WORDS)} (strings)")
        indices = regions.get(OFF_MODEL_KEYS[role])
        if isinstance(indices, np.ndarray) and len(indices) != note["count"]:
            raise InputError(f"{source}: regions.off_model.{role} counts {note['count']} points, its "
                             f"{_index_words(OFF_MODEL_KEYS[role])} indices are {len(indices)}")


def _side_file_indices(path: Path, counts: dict, source: str) -> dict:
    data = read_bytes(path, "region index file")
    try:
        with np.load(io.BytesIO(data), allow_pickle=False) as archive:
            arrays = {role: archive[role] for role in archive.files}
    except Exception as exc:  # numpy's npz/npy parsing raises many kinds on corrupt data
        raise InputError(f"{path}: cannot be read as region indices ({type(exc).__name__}: {exc})") from None
    unlisted = sorted(arrays.keys() - counts.keys())
    if unlisted:
        raise InputError(f"{path}: holds {unlisted[0]} indices that result.json does not list")
    for role, count in counts.items():
        if role not in arrays:
            raise InputError(f"{path}: has no {role} indices; {source} says {count}")
        if len(arrays[role]) != count:
            raise InputError(f"{path}: holds {len(arrays[role])} {role} indices, result.json says {count}")
    return arrays
