"""A robot as WorkCal checks programs against it: geometry, joint limits and frames, read from a JSON file.

A robot file (the built-in ones are ``library/<id>.json``) holds::

    {"id": "kuka_kr6_r700_sixx", "name": "KUKA KR 6 R700 sixx", "controller": "kuka", "kinematics": "opw",
     "opw": {"a1": 25.0, "a2": -35.0, "b": 0.0, "c1": 400.0, "c2": 315.0, "c3": 365.0, "c4": 80.0,
             "offsets_deg": [0, -90, 0, 0, 0, 0], "signs": [-1, 1, 1, -1, 1, -1]},
     "joint_limits_deg": [[-170, 170], ...],
     "base": [0, 0, 0, 0, 0, 0], "flange": [0, 0, 0, 0, 0, 0],
     "sources": {"geometry": "...", "joint_limits": "...", "frames": "..."}}

* ``opw``: the seven lengths (mm) of Brandstötter, Angerer and Hofbaur's ortho-parallel-wrist model and
  the joint offsets and sign corrections exactly as ROS-Industrial's opw_kinematics defines them
  (``joint_offsets`` and ``sign_corrections``, here in degrees): the model angle of joint i is
  ``signs[i] * joint[i] - offsets[i]``, so ``joint[i] = signs[i] * (model angle + offsets[i])``.
  Optional ``j23_factor`` (-1, 0 or 1, default 0) is for controllers whose J3 is the forearm's angle
  rather than the joint's (the J2/J3 interaction): the model's joint 3 is ``J3 + j23_factor * J2`` before
  offsets and signs apply, as ROS-Industrial's drivers convert it (fanuc_driver ``J23_factor`` = 1 for
  FANUC arms; abb_driver's ``J23_coupled`` arms such as the IRB 2400 are -1).
* ``ur`` (instead of ``opw`` when ``kinematics`` is "ur"): UR's published DH lengths d1, a2, a3, d4, d5, d6
  in mm, a2 and a3 negative as UR publishes them; the joint values are the DH angles.
* ``joint_limits_deg``: six [low, high] pairs in the controller's joint values (what the pendant shows).
* ``base``: the controller's base frame in the model's base frame; ``flange``: the controller's flange
  frame (from which a tool is measured) in the model's end frame (z along joint 6, out of the flange).
  Both are x, y, z in mm and A, B, C in degrees with R = Rz(A) Ry(B) Rx(C), KUKA's convention.

Joint values everywhere are the controller's, in degrees.
"""
from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from .. import frames
from ..errors import InputError

# The built-in robot files, one <id>.json each.
LIBRARY = Path(__file__).resolve().parent / "library"
# The controllers whose programs WorkCal exports, and so the ones a robot file may name.
CONTROLLERS = ("kuka", "abb", "fanuc", "ur")
# The kinematic models solved in closed form: opw.py and ur.py.
KINEMATICS = ("opw", "ur")
# The keys of the "opw" and "ur" sections, lengths in mm (the names of the OPW paper and of UR's DH table).
OPW_LENGTHS = ("a1", "a2", "b", "c1", "c2", "c3", "c4")
UR_LENGTHS = ("d1", "a2", "a3", "d4", "d5", "d6")
# Every field a robot file may have; any other is refused, so that a misspelt one is not silently ignored.
TOP_LEVEL_FIELDS = ("id", "name", "controller", "kinematics", "opw", "ur", "joint_limits_deg", "base",
                    "flange", "sources")
# A robot id names its file in the library, so it is kept to characters every file system accepts.
_ID_PATTERN = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")


@dataclass(frozen=True)
class OpwParameters:
    """Ortho-parallel-wrist geometry (mm) with opw_kinematics' joint offsets (degrees) and sign corrections."""

    a1: float
    a2: float
    b: float
    c1: float
    c2: float
    c3: float
    c4: float
    offsets_deg: tuple[float, ...] = (0.0,) * 6
    signs: tuple[int, ...] = (1,) * 6
    j23_factor: int = 0


@dataclass(frozen=True)
class UrParameters:
    """Universal Robots DH lengths in mm as UR publishes them (a2, a3 negative)."""

    d1: float
    a2: float
    a3: float
    d4: float
    d5: float
    d6: float


@dataclass(frozen=True)
class Robot:
    """One robot arm: which controller runs it, its kinematic model, joint limits and frames."""

    id: str
    name: str
    controller: str
    kinematics: str
    opw: OpwParameters | None
    ur: UrParameters | None
    joint_limits_deg: tuple[tuple[float, float], ...]
    base: tuple[float, ...] = (0.0,) * 6
    flange: tuple[float, ...] = (0.0,) * 6
    sources: tuple[tuple[str, str], ...] = ()

    @property
    def parameters(self) -> OpwParameters | UrParameters:
        """The kinematic model's parameters (OPW or UR)."""
        return self.opw if self.kinematics == "opw" else self.ur

    @cached_property
    def limits(self) -> np.ndarray:
        """(6, 2) joint limits in degrees, read-only."""
        return _read_only(np.array(self.joint_limits_deg, dtype=float))

    @cached_property
    def base_transform(self) -> np.ndarray:
        """4x4 pose of the controller's base frame in the model's base frame, read-only."""
        return _read_only(xyzabc_transform(self.base))

    @cached_property
    def flange_transform(self) -> np.ndarray:
        """4x4 pose of the controller's flange frame in the model's end frame, read-only."""
        return _read_only(xyzabc_transform(self.flange))


def parameters_of(robot_or_params, kind: type):
    """``robot_or_params`` as ``kind`` (OpwParameters or UrParameters): a Robot's own, or the parameters given."""
    if isinstance(robot_or_params, Robot):
        if not isinstance(robot_or_params.parameters, kind):
            raise ValueError(f"robot {robot_or_params.id} has {robot_or_params.kinematics} kinematics, not "
                             f"{_KIND_NAMES[kind]}")
        return robot_or_params.parameters
    if isinstance(robot_or_params, kind):
        return robot_or_params
    raise TypeError(f"expected a Robot or {kind.__name__}, got {type(robot_or_params).__name__}")


_KIND_NAMES = {OpwParameters: "OPW", UrParameters: "UR"}


def xyzabc_transform(xyzabc) -> np.ndarray:
    """4x4 transform of x, y, z (mm) and A, B, C (degrees), R = Rz(A) Ry(B) Rx(C)."""
    x, y, z, a, b, c = (float(v) for v in xyzabc)
    return frames.rigid(frames.rot_z(a) @ frames.rot_y(b) @ frames.rot_x(c), (x, y, z))


def builtin_robots() -> list[str]:
    """Ids of the robots shipped in the library folder, sorted."""
    return sorted(path.stem for path in LIBRARY.glob("*.json"))


def load_robot(name_or_path) -> Robot:
    """A built-in robot by id, or a robot file by path; every field is checked (InputError says which)."""
    text = str(name_or_path)
    if not isinstance(name_or_path, Path) and text in builtin_robots():
        return read_robot_file(LIBRARY / f"{text}.json", builtin=True)
    path = Path(text).expanduser()
    if path.is_file():
        return read_robot_file(path)
    raise InputError(f"{text}: no built-in robot of that id and no such file "
                     f"(built-in robots: {', '.join(builtin_robots()) or 'none'})")


def read_robot_file(path: Path, builtin: bool = False) -> Robot:
    """Read and check one robot file."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as exc:
        raise InputError(f"{path}: cannot read the robot file ({exc.strerror or exc})") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(f"{path}: not a JSON robot file ({exc})") from None
    return robot_from_dict(data, str(path), expected_id=Path(path).stem if builtin else None)


def robot_from_dict(data, where: str = "robot", expected_id: str | None = None) -> Robot:
    """A checked Robot from the parsed JSON of a robot file; ``where`` names the file in messages."""
    check = _Checker(where)
    if not isinstance(data, dict):
        raise InputError(f"{where}: a robot file holds one JSON object, not {type(data).__name__}")
    unknown = sorted(set(data) - set(TOP_LEVEL_FIELDS))
    if unknown:
        raise InputError(f"{where}: unknown field(s) {', '.join(map(repr, unknown))}; "
                         f"a robot file has {', '.join(TOP_LEVEL_FIELDS)}")
    robot_id = check.text(data, "id")
    if not _ID_PATTERN.match(robot_id):
        raise InputError(f"{where}: field 'id' must be letters, digits, '_', '-' or '.', got {robot_id!r}")
    if expected_id is not None and robot_id != expected_id:
        raise InputError(f"{where}: field 'id' is {robot_id!r} but the file is named {expected_id}.json")
    name = check.text(data, "name")
    controller = check.choice(data, "controller", CONTROLLERS)
    kinematics = check.choice(data, "kinematics", KINEMATICS)
    if (controller == "ur") != (kinematics == "ur"):
        raise InputError(f"{where}: field 'kinematics' is {kinematics!r} for controller {controller!r}; "
                         "Universal Robots arms use 'ur', the others 'opw'")
    other = "ur" if kinematics == "opw" else "opw"
    if other in data:
        raise InputError(f"{where}: field {other!r} given but 'kinematics' is {kinematics!r}")
    opw = _opw_parameters(check, data) if kinematics == "opw" else None
    ur = _ur_parameters(check, data) if kinematics == "ur" else None
    limits = _joint_limits(check, data)
    base = check.pose(data, "base")
    flange = check.pose(data, "flange")
    sources = _sources(check, data)
    return Robot(robot_id, name, controller, kinematics, opw, ur, limits, base, flange, sources)


def _opw_parameters(check: "_Checker", data: dict) -> OpwParameters:
    section = check.section(data, "opw", OPW_LENGTHS + ("offsets_deg", "signs", "j23_factor"))
    lengths = {key: check.number(section, key, f"opw.{key}") for key in OPW_LENGTHS}
    for key in ("c2", "c3"):
        if lengths[key] <= 0:
            raise InputError(f"{check.where}: field 'opw.{key}' must be a positive length in mm, got {lengths[key]:g}")
    if lengths["c4"] < 0:
        raise InputError(f"{check.where}: field 'opw.c4' (wrist centre to flange) must not be negative, "
                         f"got {lengths['c4']:g}")
    offsets = check.numbers(section, "offsets_deg", 6, "opw.offsets_deg")
    signs = check.numbers(section, "signs", 6, "opw.signs")
    if any(s not in (-1, 1) for s in signs):
        raise InputError(f"{check.where}: field 'opw.signs' must hold six values of 1 or -1, got {list(signs)}")
    j23_factor = check.number(section, "j23_factor", "opw.j23_factor") if "j23_factor" in section else 0
    if j23_factor not in (-1, 0, 1):
        raise InputError(f"{check.where}: field 'opw.j23_factor' must be -1, 0 or 1 (model joint 3 = "
                         f"J3 + j23_factor * J2), got {j23_factor:g}")
    return OpwParameters(**lengths, offsets_deg=offsets, signs=tuple(int(s) for s in signs),
                         j23_factor=int(j23_factor))


def _ur_parameters(check: "_Checker", data: dict) -> UrParameters:
    section = check.section(data, "ur", UR_LENGTHS)
    lengths = {key: check.number(section, key, f"ur.{key}") for key in UR_LENGTHS}
    for key in ("d1", "d4", "d5", "d6"):
        if lengths[key] <= 0:
            raise InputError(f"{check.where}: field 'ur.{key}' must be a positive length in mm, got {lengths[key]:g}")
    for key in ("a2", "a3"):
        if lengths[key] >= 0:
            raise InputError(f"{check.where}: field 'ur.{key}' must be negative, as Universal Robots publishes "
                             f"it, got {lengths[key]:g}")
    return UrParameters(**lengths)


def _joint_limits(check: "_Checker", data: dict) -> tuple[tuple[float, float], ...]:
    field = "joint_limits_deg"
    value = check.required(data, field)
    if not isinstance(value, list) or len(value) != 6:
        raise InputError(f"{check.where}: field '{field}' must be a list of six [low, high] pairs in degrees")
    limits = []
    for axis, pair in enumerate(value, 1):
        low, high = check.numbers({field: pair}, field, 2, f"{field}[{axis - 1}] (axis {axis})")
        if not low < high:
            raise InputError(f"{check.where}: field '{field}[{axis - 1}]' (axis {axis}) must have low < high, "
                             f"got [{low:g}, {high:g}]")
        limits.append((low, high))
    return tuple(limits)


def _sources(check: "_Checker", data: dict) -> tuple[tuple[str, str], ...]:
    value = data.get("sources", {})
    if not isinstance(value, dict) or not all(isinstance(v, str) for v in value.values()):
        raise InputError(f"{check.where}: field 'sources' must be an object of texts "
                         "(where the geometry, joint limits and frames come from)")
    return tuple(sorted(value.items()))


class _Checker:
    """Reads one field at a time and raises InputError naming the file and the field."""

    def __init__(self, where: str):
        self.where = where

    def required(self, data: dict, field: str, label: str | None = None):
        if field not in data:
            raise InputError(f"{self.where}: field '{label or field}' is missing")
        return data[field]

    def text(self, data: dict, field: str) -> str:
        value = self.required(data, field)
        if not isinstance(value, str) or not value.strip():
            raise InputError(f"{self.where}: field '{field}' must be a non-empty text, got {value!r}")
        return value

    def choice(self, data: dict, field: str, allowed: tuple[str, ...]) -> str:
        value = self.required(data, field)
        if value not in allowed:
            raise InputError(f"{self.where}: field '{field}' must be one of {', '.join(allowed)}, got {value!r}")
        return value

    def section(self, data: dict, field: str, keys: tuple[str, ...]) -> dict:
        value = self.required(data, field)
        if not isinstance(value, dict):
            raise InputError(f"{self.where}: field '{field}' must be an object with {', '.join(keys)}")
        unknown = sorted(set(value) - set(keys))
        if unknown:
            raise InputError(f"{self.where}: field '{field}' has unknown key(s) {', '.join(map(repr, unknown))}; "
                             f"it takes {', '.join(keys)}")
        return value

    def number(self, data: dict, field: str, label: str | None = None) -> float:
        value = self.required(data, field, label)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise InputError(f"{self.where}: field '{label or field}' must be a finite number, got {value!r}")
        return float(value)

    def numbers(self, data: dict, field: str, count: int, label: str | None = None) -> tuple[float, ...]:
        label = label or field
        value = self.required(data, field, label)
        if not isinstance(value, list) or len(value) != count:
            raise InputError(f"{self.where}: field '{label}' must be a list of {count} numbers, got {value!r}")
        return tuple(self.number({label: v}, label) for v in value)

    def pose(self, data: dict, field: str) -> tuple[float, ...]:
        if field not in data:
            return (0.0,) * 6
        return self.numbers(data, field, 6, f"{field} (x, y, z in mm, A, B, C in degrees)")


def _read_only(array: np.ndarray) -> np.ndarray:
    array.flags.writeable = False
    return array
