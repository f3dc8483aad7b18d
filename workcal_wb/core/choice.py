"""Choosing one pose of an ambiguous calibration, as a person looking at them does.

``poses(result, role)`` lists the poses of a match the scan could not tell apart (the best, the rivals
the match found that nothing ruled out, the turns the model's symmetries give when the match says it is
symmetric), ``difference`` says in words how one differs from the best (a turn about one of the part's
axes, a shift along one, in mm and degrees), and ``choose`` gives the result with that pose as U (or V),
W = V^-1 U again, the status "ok (chosen)" and the record of the choice (``result.Choice``).

A choice settles a tie and nothing else: only a match ambiguous by tie codes alone (result.TIE_CODES),
beside a match that is ok, offers one (``why_not`` says in words why another does not).
"""
from __future__ import annotations

import getpass
from dataclasses import dataclass, replace
from datetime import datetime, timezone

import numpy as np
from scipy.spatial.transform import Rotation

from . import frames
from .errors import InputError
from .result import (AMBIGUOUS, CHOSEN, OK, SYMMETRIC, TIE_CODES, Candidate, CalibrationResult, Choice, choice_words,
                     codes, status_gate_code)
from .symmetry import turn

ROLES = ("workpiece", "reference")
PRINCIPAL_NAMES = ("long", "middle", "short")
FRAME_NAMES = ("X", "Y", "Z")
# A direction within this angle of one of the part's axes is said to be along it; else given as a vector.
ALONG_AXIS_DEG = 10.0
# Principal axes along which the part's extents differ by less than this fraction (a round or square
# part) are not told apart by name: the frame's axis is named instead.
DISTINCT_EXTENT = 0.1
# Turns and shifts below these are left unsaid: the words round them to 0, and they are far below what
# tells two poses apart on a scan.
SAID_TURN_DEG, SAID_SHIFT_MM = 0.05, 0.05
# A turn of the model, shown for a symmetry of any angle (order 0): a quarter turn shows it.
ANY_ANGLE_TURN_DEG = 90.0


@dataclass(frozen=True)
class PartAxes:
    """The model's centre and principal axes (columns, long first, each signed to its largest
    component positive), in the model's frame X, and which of them are told apart by their extent."""

    centre: np.ndarray
    axes: np.ndarray
    distinct: tuple


def part_axes(points) -> PartAxes:
    """The principal axes of the model's points (mm, frame X), named long, middle and short by the
    model's extent along them, and its centre: the middle of that extent (where its points lie thickest
    does not move it)."""
    points = np.asarray(points, dtype=float)
    mean = points.mean(axis=0)
    _, vectors = np.linalg.eigh(np.cov((points - mean).T))
    along = (points - mean) @ vectors
    extent = along.max(axis=0) - along.min(axis=0)
    centre = mean + vectors @ ((along.max(axis=0) + along.min(axis=0)) / 2)
    order = np.argsort(extent)[::-1]
    extent, axes = extent[order], vectors[:, order]
    axes = axes * np.sign(axes[np.argmax(np.abs(axes), axis=0), range(3)])
    apart = {(i, j): abs(extent[i] - extent[j]) > DISTINCT_EXTENT * extent[i] for i, j in ((0, 1), (0, 2), (1, 2))}
    distinct = (apart[0, 1] and apart[0, 2], apart[0, 1] and apart[1, 2], apart[0, 2] and apart[1, 2])
    return PartAxes(centre, axes, distinct)


@dataclass(frozen=True)
class Difference:
    """How a pose differs from the best, in the model's frame X: the turn (degrees about a unit axis)
    about the part's centre, then the centre's shift (mm), and both in words."""

    angle_deg: float
    axis: np.ndarray
    shift_mm: np.ndarray
    words: str


def _number(value: float) -> str:
    """To 0.1, without a trailing ".0" or a "-0"."""
    text = f"{value:.1f}".rstrip("0").rstrip(".")
    return "0" if text == "-0" else text


def _along(direction, axes: PartAxes) -> tuple[str, float]:
    """(the name of the part's axis ``direction`` lies along, the sign it has along it), or (its
    components in the part's frame, 1) when it lies along none."""
    direction = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
    near = np.cos(np.radians(ALONG_AXIS_DEG))
    frame = int(np.argmax(np.abs(direction)))
    frame_name = FRAME_NAMES[frame] if abs(direction[frame]) >= near else ""
    principal = int(np.argmax(np.abs(axes.axes.T @ direction)))
    along = axes.axes[:, principal] @ direction
    if axes.distinct[principal] and abs(along) >= near:
        aligned = abs(axes.axes[frame, principal]) >= near and frame_name
        return f"the part's {PRINCIPAL_NAMES[principal]} axis" + (f" ({frame_name})" if aligned else ""), np.sign(along)
    if frame_name:
        return f"the part's {frame_name} axis", np.sign(direction[frame])
    return "({}) in the part's frame".format(", ".join(f"{v:.2f}" for v in direction)), 1.0


def difference(best, other, axes: PartAxes) -> Difference:
    """How the pose ``other`` (model -> scan) differs from ``best``: the motion best^-1 other of the
    model in its own frame, as a turn about the part's centre and a shift of that centre."""
    D = frames.invert(best) @ other
    rotvec = Rotation.from_matrix(D[:3, :3]).as_rotvec()
    angle = float(np.degrees(np.linalg.norm(rotvec)))
    axis = rotvec / np.linalg.norm(rotvec) if angle > 0 else np.array([0.0, 0.0, 1.0])
    shift = frames.apply(D, axes.centre[None])[0] - axes.centre
    words = []
    if angle >= SAID_TURN_DEG:
        name, sign = _along(axis, axes)
        signed = angle if angle > 180.0 - SAID_TURN_DEG else sign * angle
        words.append(f"turned {_number(signed)} deg about {name}")
    distance = float(np.linalg.norm(shift))
    if distance >= SAID_SHIFT_MM:
        name, sign = _along(shift, axes)
        words.append(f"shifted {_number(sign * distance)} mm along {name}")
    return Difference(angle, axis, shift, ", ".join(words) or "the same pose")


@dataclass(frozen=True)
class Pose:
    """One pose of a match (model -> scan), with what the match weighed of it (``candidate``) or the
    model symmetry that gives it (``symmetry``); the best has the match's first candidate, if any."""

    matrix: np.ndarray
    candidate: Candidate | None = None
    symmetry: dict | None = None


def _match(result: CalibrationResult, role: str):
    return result.workpiece if role == "workpiece" else result.reference


def _other(role: str) -> str:
    return ROLES[1 - ROLES.index(role)]


def poses(result: CalibrationResult, role: str) -> list[Pose]:
    """The poses of ``role``'s model the calibration could not tell apart, best first: the pose the
    calibration found (kept first after a choice), the rivals its match found that nothing ruled out
    and, when the match says the model is symmetric, the turns the model's symmetries give."""
    if result.choice is not None and result.choice.role == role:
        best = result.choice.best
    else:
        best = result.U if role == "workpiece" else result.V
    if best is None:
        return []
    match = _match(result, role)
    found = list(getattr(match, "candidates", None) or [])
    out = [Pose(best, found[0] if found else None)]
    out += [Pose(c.matrix, c) for c in found[1:] if c.rival and not c.ruled_out_by]
    if SYMMETRIC in codes(getattr(match, "reasons", None) or []):
        for symmetry in match.symmetries:
            angle = 360.0 / symmetry["order"] if symmetry["order"] >= 2 else ANY_ANGLE_TURN_DEG
            out.append(Pose(best @ turn(symmetry["axis"], angle, symmetry["point_mm"]), symmetry=symmetry))
    return out


def workpiece_placements(result: CalibrationResult, role: str) -> list[np.ndarray]:
    """Where the workpiece frame X lies in the scan for each pose of ``role`` (as ``poses`` lists them):
    where the robot would take it were that pose chosen, seen through the best reference pose (as the
    scan shows the robot base).  A workpiece pose U_k places it itself; a reference pose V_k gives
    W_k = V_k^-1 U, so the workpiece at V_0 V_k^-1 U."""
    found = poses(result, role)
    if role == "workpiece" or not found or result.U is None:
        return [p.matrix for p in found]
    best = found[0].matrix
    return [best @ frames.invert(p.matrix) @ result.U for p in found]


def why_not(result: CalibrationResult, role: str) -> str | None:
    """Why a person cannot settle ``role``'s doubt by choosing one of its poses, in plain words; None
    when they can: the calibration and that match are ambiguous only because poses tie (every reason
    a tie code), the other match is ok and no quality gate but that match's status failed."""
    if role not in ROLES:
        return f"a choice is of the workpiece or the reference match, not of {role!r}"
    if result.status != AMBIGUOUS:
        return f"only an ambiguous calibration's poses can be chosen; this one is {result.status!r}"
    match, other = _match(result, role), _match(result, _other(role))
    if match is None or match.status != AMBIGUOUS:
        return (f"the {role} match is {getattr(match, 'status', 'missing')!r}, not ambiguous: it has no tie "
                "between poses to choose from")
    beyond = [r for r in match.reasons if r.code not in TIE_CODES]
    if beyond or not match.reasons:
        said = f": {beyond[0]}" if beyond else ""
        return (f"the {role} match is in doubt for more than a tie between poses the scan cannot tell apart"
                f"{said}; choosing a pose cannot settle that: calibrate again")
    if other is None or other.status != OK:
        return (f"the {_other(role)} match is {getattr(other, 'status', 'missing')!r}: choosing a {role} pose "
                f"cannot settle that; calibrate again")
    failed = [g for g in result.quality_gates if g.get("passed") is False and g.get("code") != status_gate_code(role)]
    if failed:
        return f"the calibration's {failed[0].get('name', 'quality gate')} failed: choosing a pose cannot settle that"
    if len(poses(result, role)) < 2:
        return f"the {role} match lists no other pose tied with the best to choose from"
    return None


def chosen_role(result: CalibrationResult) -> str | None:
    """The match a person may choose a pose of (or chose one of): the one whose poses tie, when that
    is all that keeps the calibration ambiguous; None otherwise."""
    if result.choice is not None:
        return result.choice.role
    return next((role for role in ROLES if why_not(result, role) is None), None)


def role_to_choose(result: CalibrationResult) -> str:
    """The match whose poses a person may choose among now; InputError saying why there is none (a pose
    was chosen already, the calibration is ambiguous by more than a tie, or it is not ambiguous)."""
    if result.choice is not None:
        raise InputError(f"a pose was chosen already ({choice_words(result.choice)}); only an ambiguous "
                         "calibration's poses can be chosen: choose anew from the result it was chosen from")
    role = chosen_role(result)
    if role is None and result.status == AMBIGUOUS:
        raise InputError(f"ambiguous, with no tie between poses to choose from: {no_choice_words(result)}")
    if role is None:
        raise InputError(f"its status is {result.status!r}; only an ambiguous calibration's poses can be chosen")
    return role


def no_choice_words(result: CalibrationResult) -> str:
    """Why an ambiguous calibration offers no pose to choose, in plain words (for each match in doubt)."""
    said = [why_not(result, role) for role in ROLES if getattr(_match(result, role), "status", OK) != OK]
    return "; ".join(w for w in said if w) or "no match lists poses tied with its best"


def evidence(pose: Pose, index: int, named: Difference) -> dict:
    """What was shown of a pose when choosing: its difference from the best and the match's numbers."""
    out = {"index": index, "difference": named.words}
    if pose.candidate is not None:
        out.update({key: getattr(pose.candidate, key) for key in ("score", "score_ratio",
                                                                 "standard_errors_below_best")})
    if pose.symmetry is not None:
        out["symmetry"] = pose.symmetry.get("description", "")
    return out


def user_name() -> str:
    """The OS user's name, who a choice is recorded as made by ("unknown" where the OS has none)."""
    try:
        return getpass.getuser()
    except (OSError, KeyError, ImportError):  # no login name, no passwd entry (containers)
        return "unknown"


def choose(result: CalibrationResult, role: str, index: int, axes: PartAxes, who: str,
           when: str | None = None) -> CalibrationResult:
    """The ambiguous ``result`` with pose ``index`` of ``role``'s match chosen by ``who`` (the OS user
    name) at ``when`` (ISO 8601; default now): that pose as U (or V), W = V^-1 U, status "ok (chosen)"
    and the record.  Only a tie between poses is settled so (``why_not`` says why else not); choosing
    the best (0) is a person confirming it.  ``axes``: the ``role`` model's (part_axes), to name each pose's difference."""
    refused = why_not(result, role)
    if refused:
        raise InputError(refused)
    found = poses(result, role)
    if not 0 <= index < len(found):
        raise InputError(f"the {role} match has {len(found)} poses (0 to {len(found) - 1}), no pose {index}")
    best, chosen = found[0].matrix, found[index].matrix
    shown = [evidence(p, i, difference(best, p.matrix, axes)) for i, p in enumerate(found)]
    record = Choice(str(who), when or datetime.now(timezone.utc).isoformat(timespec="seconds"), role, index,
                    len(found), chosen, best, shown)
    U, V = (chosen, result.V) if role == "workpiece" else (result.U, chosen)
    warnings = list(result.warnings)
    if index:
        warnings.append("the uncertainty was estimated at the pose found best, not at the chosen one")
    return replace(result, status=CHOSEN, U=U, V=V, W=frames.invert(V) @ U, choice=record, warnings=warnings)
