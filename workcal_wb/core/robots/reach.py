"""Can this robot follow this program?  Every pose a program commands, solved on the robot's kinematics.

A program's poses are the TCP in the controller's base frame (the robot base frame B of W = ^B X), one
per robot target, each reached by a joint move (PTP, MoveJ, J, movej: the controller may choose any
configuration there) or a linear move (LIN, MoveL, L, movel: the controller interpolates the pose and
cannot change configuration, nor unwind a joint by a whole turn, on the way).  ``check_reach``:

* solves the flange (TCP times the inverse of the tool) of every target and of points along every
  linear move, at most ``SAMPLE_STEP_MM`` and ``SAMPLE_STEP_DEG`` apart (position interpolated
  linearly, orientation along the shortest rotation, as the controllers do);
* follows each of the eight configurations (``kinematics.inverse``'s branches) from joint move to
  joint move, its joints unwrapped into one continuous turn each and then moved by whole turns to
  leave the most room to the limits; a stretch of linear moves is reachable in a configuration when
  every point of it is reachable, within the joint limits and without a joint turning more than
  ``MAX_JOINT_STEP_DEG`` per sample step (a flip through a singularity);
* keeps the configuration of the previous stretch where it can, else takes the one with the most
  room to the joint limits; the first stretch no configuration follows is the program's problem:
  out of reach, a joint limit, a configuration change inside a linear move, or a wrist, elbow or
  shoulder singularity, with the first robot target (and source line) where it happens;
* reports the smallest joint-limit margin and how close the path comes to each singularity, with
  the joints (and configuration) at every target for the exporters.

Everything is vectorised over poses: the samples are solved and followed a chunk (``SOLVE_CHUNK``) at a
time, all eight configurations at once, and Python loops run over those chunks and over the stretches
between joint moves only.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from .. import frames
from .kinematics import inverse_by_joint, joint_margins_deg, wrap_into_limits
from .model import Robot
from .opw import model_angle

# The move kinds ``check_reach`` takes: at a joint move the controller may change configuration.
JOINT_MOVE, LINEAR_MOVE = 0, 1

# A linear move is checked at points this far apart along it (mm) and in tool rotation (deg): over
# such a step no joint of an arm away from its singularities turns more than a few degrees.
SAMPLE_STEP_MM = 5.0
SAMPLE_STEP_DEG = 2.0
# Most any joint may turn over one full sample step (past a singularity joints turn up to 180 deg at once);
# shorter steps allow proportionally less, as a fine raster near a singularity is as fast for the joints.
MAX_JOINT_STEP_DEG = 20.0
# What a step shorter than this share of a sample step is still allowed (so that repeated points and
# rounding never count as a flip): MAX_JOINT_STEP_DEG times it, 0.2 deg.
MIN_STEP_SHARE = 0.01
# Closer than these the header warns: axes 4 and 6 nearly in line (wrist), the arm nearly stretched
# or folded (elbow), the wrist point nearly on axis 1 (shoulder): there small moves of the tool
# need large, fast joint moves, and controllers slow down or stop.
WRIST_NEAR_DEG = 5.0
ELBOW_NEAR_DEG = 5.0
SHOULDER_NEAR_MM = 50.0
# The arm posture (OPW branch modulo 4) taken where it follows the program: wrist centre in front of axis 1,
# elbow up, as robots are homed, so the first joint move does not swing the arm over its base or under its elbow.
USUAL_ARM = 0
# Samples solved and followed at a time: a chunk's joints (3 MB) are unwrapped while still in the caches,
# and the temporaries stay under glibc's mmap threshold and are reused rather than faulted in afresh.
SOLVE_CHUNK = 1 << 13
# Whole turns tried when a joint is moved into its limits: no robot joint spans more than +-540 deg.
TURN_SHIFTS_DEG = 360.0 * np.arange(-2, 3)

# What ``ReachReport.problem`` says (None: the robot follows the program).
OUT_OF_REACH = "out_of_reach"
JOINT_LIMIT = "joint_limit"
CONFIGURATION_CHANGE = "configuration_change"
WRIST_SINGULARITY = "wrist_singularity"
ELBOW_SINGULARITY = "elbow_singularity"
SHOULDER_SINGULARITY = "shoulder_singularity"
PROBLEMS = (OUT_OF_REACH, JOINT_LIMIT, CONFIGURATION_CHANGE, WRIST_SINGULARITY, ELBOW_SINGULARITY,
            SHOULDER_SINGULARITY)
# The singularity a joint that jumps belongs to (0-based joints 0..5).
_JUMP_SINGULARITY = (SHOULDER_SINGULARITY, ELBOW_SINGULARITY, ELBOW_SINGULARITY, WRIST_SINGULARITY,
                     WRIST_SINGULARITY, WRIST_SINGULARITY)
# How each controller names its joints.
JOINT_NAMES = {"kuka": tuple(f"A{i}" for i in range(1, 7)), "abb": tuple(f"axis {i}" for i in range(1, 7)),
               "fanuc": tuple(f"J{i}" for i in range(1, 7)),
               "ur": ("base", "shoulder", "elbow", "wrist 1", "wrist 2", "wrist 3")}


@dataclass(frozen=True)
class Where:
    """A place along the program: robot target ``target`` (0-based), its source line (0: unknown), and
    whether it lies on the linear move to that target rather than at it."""

    target: int
    line: int = 0
    on_the_way: bool = False

    def text(self) -> str:
        """'robot target 5 (line 12)', or 'the linear move to robot target 5 (line 12)'."""
        what = f"robot target {self.target + 1}" + (f" (line {self.line})" if self.line else "")
        return f"the linear move to {what}" if self.on_the_way else what

    def on(self) -> str:
        """'at robot target 5 (line 12)', or 'on the linear move to robot target 5 (line 12)'."""
        return ("on " if self.on_the_way else "at ") + self.text()


@dataclass(frozen=True)
class Extreme:
    """The smallest value of a measure along the program, where it is, and (margins) which joint (0-based)."""

    value: float
    where: Where
    joint: int | None = None


@dataclass(frozen=True)
class PoseOnPath:
    """The robot's joints at one place along the program: the controller's values in degrees, each joint
    at the turn the program runs it at; ``past_limit``: a joint is past its limit there (a refused program's
    problem)."""

    where: Where
    joints: tuple
    past_limit: bool = False


@dataclass(frozen=True)
class ReachReport:
    """What ``check_reach`` found.  ``problem`` is None when the robot follows the whole program, else
    one of PROBLEMS, with ``reason`` in words and ``problem_at`` the first robot target it concerns.
    Measures cover the program up to the problem: ``margin`` (deg, the joint nearest its limit),
    ``wrist`` (deg, joint 5 from 0 or 180), ``elbow`` (deg, the arm from stretched or folded),
    ``shoulder`` (mm, the wrist point from axis 1); ``near`` lists the singularities the path comes
    closer to than WRIST_NEAR_DEG, ELBOW_NEAR_DEG, SHOULDER_NEAR_MM.  ``joints`` (N, 6) and
    ``branches`` (N,) are the solution at every target (NaN and -1 past a problem).  ``margin_pose`` is the
    robot where its margin is smallest; ``problem_pose`` where the problem shows: past its limit in the
    configuration that goes furthest for a joint limit, else the last pose the robot follows before the
    problem (None when it follows nothing)."""

    robot_id: str
    targets: int
    samples: int
    problem: str | None
    reason: str
    problem_at: Where | None
    problem_joint: int | None
    unreachable_at: Where | None
    margin: Extreme | None
    wrist: Extreme | None
    elbow: Extreme | None
    shoulder: Extreme | None
    near: tuple = ()
    configuration_changes: tuple = ()
    first_branch: int | None = None
    first_joints: tuple | None = None
    joints: np.ndarray = field(default=None, compare=False, repr=False)
    branches: np.ndarray = field(default=None, compare=False, repr=False)
    margin_pose: PoseOnPath | None = None
    problem_pose: PoseOnPath | None = None

    @property
    def reachable(self) -> bool:
        return self.problem is None


def joint_name(robot: Robot, joint: int) -> str:
    """The controller's name of joint ``joint`` (0-based): A1, axis 1, J1, base."""
    return JOINT_NAMES.get(robot.controller, JOINT_NAMES["fanuc"])[joint]


def check_reach(robot: Robot, tcp_poses, tool=None, move_kinds=None, source_lines=None) -> ReachReport:
    """Whether ``robot`` follows a program: ``tcp_poses`` (N, 4, 4) the TCP at every robot target in the
    controller's base frame (mm), ``tool`` the TCP in the flange frame (4x4, default the flange),
    ``move_kinds`` (N,) JOINT_MOVE or LINEAR_MOVE (default: a joint move to the first target, linear
    moves after it; the first move is always a joint move, its start being unknown), ``source_lines``
    (N,) the source line of each target, for messages (0: unknown)."""
    poses = np.asarray(tcp_poses, dtype=float)
    if poses.ndim != 3 or poses.shape[1:] != (4, 4) or not len(poses):
        raise ValueError(f"tcp_poses must have shape (N, 4, 4) with N >= 1, got {poses.shape}")
    count = len(poses)
    tool = np.eye(4) if tool is None else np.asarray(tool, dtype=float)
    kinds = np.full(count, LINEAR_MOVE, dtype=np.int8) if move_kinds is None else np.array(move_kinds, dtype=np.int8)
    kinds[0] = JOINT_MOVE
    lines = np.zeros(count, dtype=np.int64) if source_lines is None else np.asarray(source_lines, dtype=np.int64)
    if kinds.shape != (count,) or lines.shape != (count,):
        raise ValueError(f"move_kinds and source_lines must have one entry per pose ({count})")
    path = _Samples(poses @ frames.invert(tool), kinds, lines)
    followed, branches = _Follower(robot, path).follow()
    choice = _choose(robot, branches, path)
    return _report(robot, path, followed, branches, choice)


class _Samples:
    """The flange poses the check solves: every target, and points along each linear move to it."""

    def __init__(self, flange: np.ndarray, kinds: np.ndarray, lines: np.ndarray):
        count = len(flange)
        position, rotation = flange[:, :3, 3], flange[:, :3, :3]
        length, turn = np.zeros(count), np.zeros(count)
        length[1:] = np.linalg.norm(np.diff(position, axis=0), axis=1)
        cosine = (np.einsum("nij,nij->n", rotation[:-1], rotation[1:]) - 1.0) / 2.0
        turn[1:] = np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))
        linear = kinds == LINEAR_MOVE
        extent = np.where(linear, np.maximum(length / SAMPLE_STEP_MM, turn / SAMPLE_STEP_DEG), 0.0)
        pieces = np.maximum(1, np.ceil(extent - 1e-9)).astype(np.int64)
        owner = np.repeat(np.arange(count), pieces)
        first = np.cumsum(pieces) - pieces
        k = np.arange(len(owner)) - first[owner] + 1
        self.at_target = k == pieces[owner]
        inner = np.flatnonzero(~self.at_target)
        self.poses = flange[owner] if inner.size else flange  # (no sample between targets: no copy)
        if inner.size:
            target = owner[inner]
            share = (k[inner] / pieces[target])[:, None]
            self.poses[inner, :3, 3] = position[target - 1] + share * (position[target] - position[target - 1])
            split = np.flatnonzero(pieces > 1)
            relative = Rotation.from_matrix(np.swapaxes(rotation[split - 1], 1, 2) @ rotation[split]).as_rotvec()
            turned = Rotation.from_rotvec(relative[np.searchsorted(split, target)] * share).as_matrix()
            self.poses[inner, :3, :3] = rotation[target - 1] @ turned
        # How far each sample lies from the one before: mm, deg, and in sample steps (inf after a joint
        # move: not checked).
        self.length = (length / pieces)[owner]
        self.turn = (turn / pieces)[owner]
        self.step = np.where(linear, extent / pieces, np.inf)[owner]
        self.owner, self.kinds, self.lines = owner, kinds, lines
        starts = self.at_target & (kinds[owner] == JOINT_MOVE)
        self.starts = np.flatnonzero(starts)  # samples where a stretch between joint moves begins
        self.run = np.cumsum(starts) - 1  # the stretch of every sample
        self.ends = np.append(self.starts[1:], len(owner))
        self.lengths = self.ends - self.starts

    def __len__(self) -> int:
        return len(self.owner)

    def where(self, sample: int) -> Where:
        target = int(self.owner[sample])
        return Where(target, int(self.lines[target]), not bool(self.at_target[sample]))


@dataclass
class _Branches:
    """The eight configurations followed along the program, per configuration and stretch (8, runs): the
    first sample where it fails (``len(samples)`` when it does not), how (``_MISSING``, ``_JUMP``,
    ``_LIMIT``, ``_NONE``) and its room to the limits before that."""

    fail: np.ndarray
    how: np.ndarray
    room: np.ndarray


_MISSING, _JUMP, _LIMIT, _NONE = 0, 1, 2, 3


def _least_margin(joints_by_joint: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """(..., n) for joints (..., 6, n), one row per joint: the smallest distance in degrees of any joint to
    its nearer limit (``low``, ``high``: (6,)), negative past it, NaN where the joints are NaN."""
    rows = np.moveaxis(joints_by_joint, -2, 0)
    with np.errstate(invalid="ignore"):
        out = np.subtract(rows[0], low[0])
        np.minimum(out, high[0] - rows[0], out=out)
        for joint in range(1, 6):
            np.minimum(out, rows[joint] - low[joint], out=out)
            np.minimum(out, high[joint] - rows[joint], out=out)
    return out


class _Follower:
    """Solves the program's samples chunk by chunk and follows the eight configurations along them: each
    chunk is unwrapped and checked for jumps while it is fresh in the caches, then every stretch is
    moved by the whole turns that leave the most room to the limits."""

    def __init__(self, robot: Robot, path: _Samples):
        self.robot = robot
        self.low, self.high = robot.limits[:, 0], robot.limits[:, 1]
        self.path = path
        self.allowed = MAX_JOINT_STEP_DEG * np.maximum(path.step, MIN_STEP_SHARE)
        self.start_of = path.starts[path.run]  # the first sample of every sample's stretch

    def follow(self) -> tuple[np.ndarray, _Branches]:
        """(8, 6, M) the joints of every configuration at every sample, each joint continuous along a
        stretch and at the turn that leaves the most room to its limits, and what each configuration
        does per stretch."""
        path, count = self.path, len(self.path)
        runs = len(path.starts)
        followed = np.empty((8, 6, count))
        first_bad = np.full((8, runs), count)  # per stretch, the first sample missing or jumping
        low = np.full((8, 6, runs), np.nan)  # per stretch, the extremes of the samples before it
        high = np.full((8, 6, runs), np.nan)
        previous = np.full((8, 6), np.nan)  # the last sample of the chunk before, as solved
        turns = np.zeros((8, 6))  # the whole turns unwound since the stretch began, at that sample
        for start, stop in self._chunks():
            block = inverse_by_joint(self.robot, path.poses[start:stop], out=followed[:, :, start:stop])
            jump = np.empty((8, stop - start), dtype=bool)
            previous, turns = self._unwrap(block, start, previous, turns, jump)
            bad = np.isnan(block[:, 0])
            bad |= jump
            self._note_first(bad, start, first_bad)
            valid = np.arange(start, stop) < self._per_sample(first_bad, start, stop)
            self._extend(low, high, block, valid, start, stop)

        with np.errstate(invalid="ignore"):
            room = np.minimum(low[..., None] + TURN_SHIFTS_DEG - self.low[:, None, None],
                              self.high[:, None, None] - high[..., None] - TURN_SHIFTS_DEG)
        room = np.nan_to_num(room, nan=-np.inf)
        best = np.argmax(room, axis=-1)  # (8, 6, runs)
        most = np.take_along_axis(room, best[..., None], axis=-1)[..., 0]
        for branch, joint in np.argwhere((np.isfinite(most) & (most < 0)).any(axis=2)):
            # a joint no whole turn fits: the turn that keeps it inside its limits longest
            valid = np.arange(count) < self._per_sample(first_bad[branch], 0, count)
            values = np.where(valid, followed[branch, joint], np.nan)
            best[branch, joint] = self._longest_inside(values, joint, room[branch, joint])
        shift = TURN_SHIFTS_DEG[best]

        first_outside = np.full((8, runs), count)  # per stretch, the first sample before first_bad past a limit
        least = np.full((8, 1, runs), np.nan)  # per stretch, the smallest margin before it fails
        for start, stop in self._chunks():
            block = followed[:, :, start:stop]
            block += self._per_sample(shift, start, stop)
            margin = _least_margin(block, self.low, self.high)
            index = np.arange(start, stop)
            with np.errstate(invalid="ignore"):
                outside = margin < 0
            outside &= index < self._per_sample(first_bad, start, stop)
            self._note_first(outside, start, first_outside)
            before_fail = index < self._per_sample(np.minimum(first_bad, first_outside), start, stop)
            self._extend(least, None, margin[:, None], before_fail, start, stop)
        fail = np.minimum(first_bad, first_outside)
        failed = fail < path.ends
        at = np.minimum(fail, count - 1)
        missing = np.isnan(np.take_along_axis(followed[:, 0], at, axis=1))
        how = np.where(~failed, _NONE, np.where(missing, _MISSING, np.where(at == first_bad, _JUMP, _LIMIT)))
        return followed, _Branches(fail, how, least[:, 0])

    def _chunks(self):
        """(start, stop) of the chunks of samples solved and followed at a time."""
        count = len(self.path)
        return [(start, min(start + SOLVE_CHUNK, count)) for start in range(0, count, SOLVE_CHUNK)]

    def _per_sample(self, per_stretch: np.ndarray, start: int, stop: int) -> np.ndarray:
        """(..., n) or (..., 1) the value of every sample start .. stop - 1 from (..., runs) per stretch."""
        run = self.path.run
        if run[start] == run[stop - 1]:
            return per_stretch[..., run[start], None]
        return per_stretch[..., run[start:stop]]

    def _note_first(self, flags: np.ndarray, start: int, first: np.ndarray) -> None:
        """Lowers ``first`` (rows, runs) to the first set sample per row and stretch of ``flags`` (rows, n),
        the samples start .. start + n - 1 (chunks come in order, so a stretch's first is its earliest)."""
        run = self.path.run
        stop = start + flags.shape[-1]
        if run[start] == run[stop - 1]:  # within one stretch: the first set sample at all
            stretch = run[start]
            for row, set_in_row in zip(first, flags):
                at = int(np.argmax(set_in_row))
                if set_in_row[at]:
                    row[stretch] = min(row[stretch], start + at)
            return
        for row, set_in_row in zip(first, flags):
            hits = np.flatnonzero(set_in_row)
            if hits.size:
                stretches = run[start + hits]  # ascending
                earliest = np.flatnonzero(np.diff(stretches, prepend=-1))
                row[stretches[earliest]] = np.minimum(row[stretches[earliest]], start + hits[earliest])

    def _extend(self, low: np.ndarray, high: np.ndarray | None, block: np.ndarray, valid: np.ndarray, start: int,
                stop: int) -> None:
        """Extends ``low`` and ``high`` (rows, k, runs) by the valid samples of ``block`` (rows, k, n), the
        samples start .. stop - 1, per stretch (NaN-ignoring; ``high`` may be None)."""
        run = self.path.run[start:stop]
        masked = block if valid.all() else np.where(valid[:, None], block, np.nan)
        bounds = np.concatenate([[0], np.flatnonzero(run[1:] != run[:-1]) + 1])
        stretches = run[bounds]
        with np.errstate(invalid="ignore"):
            low[:, :, stretches] = np.fmin(low[:, :, stretches], np.fmin.reduceat(masked, bounds, axis=2))
            if high is not None:
                high[:, :, stretches] = np.fmax(high[:, :, stretches], np.fmax.reduceat(masked, bounds, axis=2))

    def _unwrap(self, block: np.ndarray, start: int, previous: np.ndarray, turns: np.ndarray,
                jump: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Unwinds whole turns between consecutive samples of ``block`` (8, 6, n), the solutions of samples
        start .. start + n - 1, in place, and sets ``jump`` (8, n) where a joint still turns more than
        allowed; ``previous`` and ``turns`` carry the sample before (as solved) and the turns unwound in its
        stretch.  Returns them for the next chunk."""
        path = self.path
        stop = start + block.shape[2]
        step = np.empty_like(block)
        np.subtract(block[:, :, :1], previous[:, :, None], out=step[:, :, :1])
        np.subtract(block[:, :, 1:], block[:, :, :-1], out=step[:, :, 1:])
        last_solved = block[:, :, -1].copy()
        magnitude = np.abs(step)
        largest = magnitude.max(axis=1)  # (8, n): NaN only where the configuration is missing
        starts_here = path.starts[(path.starts >= start) & (path.starts < stop)] - start
        if (largest > 180.0).any():  # a joint passes +-180: unwind the turn
            unwind = np.round(step / 360.0)
            unwind *= 360.0
            unwind[:, :, starts_here] = 0.0  # no continuity into a joint move
            unwind = np.nan_to_num(unwind, copy=False)
            total = np.cumsum(unwind, axis=2)
            total += turns[:, :, None]
            if starts_here.size:  # turns count from the start of each stretch
                own = self.start_of[start:stop] - start
                begun = own >= 0
                total[:, :, begun] -= total[:, :, own[begun]]
            block -= total
            step -= unwind
            np.abs(step, out=magnitude)
            magnitude.max(axis=1, out=largest)
            turns = total[:, :, -1].copy()
        elif turns.any():
            if starts_here.size:
                total = np.broadcast_to(turns[:, :, None], block.shape).copy()
                total[:, :, starts_here[0]:] = 0.0
                block -= total
            else:
                block -= turns[:, :, None]
            if starts_here.size:
                turns = np.zeros_like(turns)
        with np.errstate(invalid="ignore"):
            np.greater(largest, self.allowed[start:stop], out=jump)
        if start == 0:
            jump[:, 0] = False
        return last_solved, turns

    def _longest_inside(self, values: np.ndarray, joint: int, room: np.ndarray) -> np.ndarray:
        """(runs,) index into TURN_SHIFTS_DEG: per stretch, the whole turn after which ``values`` (M,) of
        ``joint`` first leave its limits latest (then the one with the most room)."""
        latest = np.empty((len(self.path.starts), len(TURN_SHIFTS_DEG)))
        shifted = np.empty_like(values)
        out, above = np.empty(len(values), dtype=bool), np.empty(len(values), dtype=bool)
        for k, shift in enumerate(TURN_SHIFTS_DEG):  # a handful of turns, each over every sample at once
            np.add(values, shift, out=shifted)
            with np.errstate(invalid="ignore"):
                np.less(shifted, self.low[joint], out=out)
                np.greater(shifted, self.high[joint], out=above)
            out |= above
            first = np.full((1, len(self.path.starts)), len(values))
            self._note_first(out[None], 0, first)
            latest[:, k] = first[0]
        return np.lexsort((room, latest), axis=-1)[:, -1]


@dataclass
class _Choice:
    branch_of_run: np.ndarray  # -1 for stretches after the problem
    stop: int  # the first sample past what the chosen configurations follow (len(samples): all)
    failed_run: int | None
    best: int | None  # the configuration that goes furthest in the failed stretch


def _choose(robot: Robot, branches: _Branches, path: _Samples) -> _Choice:
    """One configuration per stretch: the previous one where it follows the stretch, else (OPW arms)
    the usual posture where it does (``USUAL_ARM``), else the one with the most room to the limits;
    the first stretch none follows stops the choice."""
    fail = branches.fail  # (8, runs)
    room = np.nan_to_num(branches.room, nan=-np.inf)
    follows = fail >= path.ends
    usual = (np.arange(len(fail)) % 4 == USUAL_ARM) if robot.opw is not None else np.ones(len(fail), bool)
    chosen = np.full(len(path.starts), -1, dtype=np.int64)
    previous = None
    for run in range(len(path.starts)):  # one pass over the stretches between joint moves
        if previous is not None and follows[previous, run]:
            chosen[run] = previous
        elif follows[:, run].any():
            pick = follows[:, run] & usual if (follows[:, run] & usual).any() else follows[:, run]
            chosen[run] = int(np.argmax(np.where(pick, room[:, run], -np.inf)))
        else:
            order = np.lexsort((room[:, run], fail[:, run]))  # furthest, then most room
            best = int(order[-1])
            chosen[run] = best  # followed up to where it fails
            return _Choice(chosen, int(fail[best, run]), run, best)
        previous = chosen[run]
    return _Choice(chosen, len(path), None, None)


def _report(robot: Robot, path: _Samples, followed: np.ndarray, branches: _Branches, choice: _Choice) -> ReachReport:
    solutions = followed.transpose(2, 0, 1)  # (M, 8, 6)
    stop = choice.stop
    samples = np.arange(stop)
    branch = choice.branch_of_run[path.run[:stop]]
    one = int(branch[0]) if stop and (branch == branch[0]).all() else None  # one configuration all along
    # (stop, 6) the joints the robot runs at every sample it follows, and each sample's joint margin
    joints = followed[one, :, :stop].T if one is not None else solutions[samples, branch]
    margins = _least_margin(joints.T, robot.limits[:, 0], robot.limits[:, 1])
    reached = np.zeros(len(path), dtype=bool)
    reached[:stop] = True
    target_rows = np.flatnonzero(path.at_target & reached)
    count = len(path.kinds)
    target_joints = np.full((count, 6), np.nan)
    target_branch = np.full(count, -1, dtype=np.int8)
    target_joints[path.owner[target_rows]] = joints[target_rows]
    target_branch[path.owner[target_rows]] = branch[target_rows]

    margin = wrist = elbow = shoulder = margin_pose = None
    near = []
    if stop:
        at = int(np.argmin(margins))
        per_joint = np.minimum(joints[at] - robot.limits[:, 0], robot.limits[:, 1] - joints[at])
        margin = Extreme(float(per_joint.min()), path.where(at), int(np.argmin(per_joint)))
        margin_pose = PoseOnPath(path.where(at), tuple(float(v) for v in joints[at]))
        wrist_deg, elbow_deg = singular_angles(robot, joints)
        shoulder_mm = shoulder_distance(robot, path.poses[:stop])
        for values, threshold, name in ((wrist_deg, WRIST_NEAR_DEG, WRIST_SINGULARITY),
                                        (elbow_deg, ELBOW_NEAR_DEG, ELBOW_SINGULARITY),
                                        (shoulder_mm, SHOULDER_NEAR_MM, SHOULDER_SINGULARITY)):
            at = int(np.argmin(values))
            extreme = Extreme(float(values[at]), path.where(at))
            if extreme.value < threshold:
                near.append(name)
            if name == WRIST_SINGULARITY:
                wrist = extreme
            elif name == ELBOW_SINGULARITY:
                elbow = extreme
            else:
                shoulder = extreme
    runs = choice.branch_of_run
    changes = tuple(int(path.owner[path.starts[r]]) for r in range(1, len(runs))
                    if runs[r] >= 0 and runs[r - 1] >= 0 and runs[r] != runs[r - 1])
    problem, reason, problem_at, problem_joint, problem_pose = None, "", None, None, None
    if choice.failed_run is not None:
        problem, reason, problem_joint = _problem(robot, path, solutions, branches, choice)
        problem_at = path.where(stop)
        past_limit = solutions[stop, choice.best]
        if branches.how[choice.best, choice.failed_run] == _LIMIT and not np.isnan(past_limit).any():
            problem_pose = PoseOnPath(problem_at, tuple(float(v) for v in past_limit), past_limit=True)
        elif stop:
            problem_pose = PoseOnPath(path.where(stop - 1), tuple(float(v) for v in joints[stop - 1]))
    unreachable = np.flatnonzero(path.at_target & np.isnan(solutions[:, :, 0]).all(axis=1))
    first_joints = tuple(float(v) for v in target_joints[0]) if target_branch[0] >= 0 else None
    return ReachReport(robot.id, count, len(path), problem, reason, problem_at, problem_joint,
                       path.where(int(unreachable[0])) if unreachable.size else None, margin, wrist, elbow, shoulder,
                       tuple(near), changes, int(target_branch[0]) if first_joints else None, first_joints,
                       target_joints, target_branch, margin_pose, problem_pose)


def _problem(robot: Robot, path: _Samples, solutions: np.ndarray, branches: _Branches, choice: _Choice):
    """(code, reason, joint) for the stretch no configuration follows, at the sample where the
    configuration that goes furthest fails."""
    at, best = choice.stop, choice.best
    where, on = path.where(at).text(), path.where(at).on()
    here = solutions[at]  # (8, 6), this sample's joints in every configuration as followed
    reaches = ~np.isnan(here[:, 0])
    if not reaches.any():
        flange = path.poses[at]
        x, y, z = flange[:3, 3]
        return OUT_OF_REACH, (f"{where} is out of the robot's reach: no configuration puts the flange at "
                              f"({x:.1f}, {y:.1f}, {z:.1f}) mm in the robot base frame, "
                              f"{np.linalg.norm(flange[:3, 3]):.0f} mm from its origin"), None
    how = branches.how[best, choice.failed_run]
    start = path.where(int(path.starts[choice.failed_run])).text()
    if how == _JUMP:
        turned = np.abs(here[best] - solutions[at - 1, best])
        joint = int(np.argmax(turned))
        code = _JUMP_SINGULARITY[joint]
        words = {WRIST_SINGULARITY: "the wrist passes its singularity (axes 4 and 6 in line)",
                 ELBOW_SINGULARITY: "the arm passes its stretched or folded position (elbow singularity)",
                 SHOULDER_SINGULARITY: "the wrist point passes over axis 1 (shoulder singularity)"}[code]
        wrist = [j for j in (3, 5) if turned[j] > MAX_JOINT_STEP_DEG] if code == WRIST_SINGULARITY else []
        names = " and ".join(joint_name(robot, j) for j in (wrist or [joint]))
        flip = code == WRIST_SINGULARITY and turned[joint] >= 90.0
        return code, (f"{on}, {words}: {names} would turn {turned[joint]:.0f} deg while the flange moves "
                      f"{path.length[at]:.2g} mm and turns {path.turn[at]:.2g} deg"
                      + (" (a wrist flip)" if flip else "")), joint
    in_limits = ~np.isnan(wrap_into_limits(robot, here)[:, 0])
    if how == _MISSING:
        others = np.flatnonzero(reaches)
        if in_limits.any():
            return CONFIGURATION_CHANGE, (
                f"{where} is out of reach in the configuration the robot takes at {start} "
                f"({configuration_words(robot, best, solutions[path.starts[choice.failed_run], best])}); "
                f"another configuration ({_words_at(robot, here, in_limits)}) reaches it, but a robot cannot "
                "change configuration inside a linear move"), None
        joint, value, limit = _worst_joint(robot, here[others])
        return JOINT_LIMIT, (f"{where} needs {joint_name(robot, joint)} at {value:.1f} deg, past its limit "
                             f"{limit:g} deg, in every configuration that reaches it"), joint
    joints = here[best]
    margin = np.minimum(joints - robot.limits[:, 0], robot.limits[:, 1] - joints)
    joint = int(np.argmin(margin))
    limit = robot.limits[joint, 0] if joints[joint] < robot.limits[joint, 0] else robot.limits[joint, 1]
    passing = f"{joint_name(robot, joint)} would pass its limit {limit:g} deg (to {joints[joint]:.1f} deg)"
    if in_limits[best]:
        return JOINT_LIMIT, (f"{on}, {passing}: the robot reaches that pose only with "
                             f"{joint_name(robot, joint)} a whole turn away, and it cannot unwind a turn inside a "
                             "linear move"), joint
    if in_limits.any():
        return CONFIGURATION_CHANGE, (
            f"{on}, {passing} in the configuration the robot takes at {start} "
            f"({configuration_words(robot, best, solutions[path.starts[choice.failed_run], best])}); another "
            f"configuration ({_words_at(robot, here, in_limits)}) reaches it, but a robot cannot change "
            "configuration inside a linear move"), joint
    return JOINT_LIMIT, f"{on}, {passing}, and no other configuration reaches it within the limits", joint


def _worst_joint(robot: Robot, joints: np.ndarray) -> tuple[int, float, float]:
    """Of (K, 6) joints, each joint at its best whole turn: the joint furthest past its limit in the row
    that is least so, as (joint, value, limit)."""
    low, high = robot.limits[:, 0], robot.limits[:, 1]
    turned = joints[..., None] + TURN_SHIFTS_DEG  # (K, 6, turns)
    room = np.minimum(turned - low[:, None], high[:, None] - turned)
    best = np.argmax(room, axis=-1)
    value = np.take_along_axis(turned, best[..., None], axis=-1)[..., 0]
    margin = np.take_along_axis(room, best[..., None], axis=-1)[..., 0]
    row = int(np.argmax(margin.min(axis=1)))
    joint = int(np.argmin(margin[row]))
    limit = float(low[joint] if value[row, joint] < low[joint] else high[joint])
    return joint, float(value[row, joint]), limit


def _words_at(robot: Robot, here: np.ndarray, in_limits: np.ndarray) -> str:
    branch = int(np.flatnonzero(in_limits)[0])
    return configuration_words(robot, branch, wrap_into_limits(robot, here[branch]))


def configuration_words(robot: Robot, branch: int, joints) -> str:
    """A configuration as the controller names it: KUKA Status, ABB cfx, Fanuc 'N U T', UR signs."""
    from .configuration import abb_confdata, fanuc_config, kuka_status_turn

    joints = np.asarray(joints, dtype=float)
    if robot.controller == "kuka":
        status = int(kuka_status_turn(robot, joints)[0])
        return f"Status {status} ('B{status:03b}')"
    if robot.controller == "abb":
        return f"cfx {int(abb_confdata(robot, joints)[3])}"
    if robot.controller == "fanuc":
        return f"'{str(fanuc_config(robot, joints)).split(',')[0]}'"
    shoulder = "first" if branch % 4 < 2 else "second"
    return (f"{shoulder} shoulder solution, elbow {'positive' if joints[2] >= 0 else 'negative'}, "
            f"wrist 2 {'positive' if joints[4] >= 0 else 'negative'}")


def _from_singular(angle_deg) -> np.ndarray:
    """Degrees from the nearest multiple of 180 (0 or 180: where the axes line up)."""
    rest = np.remainder(angle_deg, 180.0)
    return np.minimum(rest, 180.0 - rest)


def singular_angles(robot: Robot, joints_deg) -> tuple[np.ndarray, np.ndarray]:
    """(wrist, elbow) in degrees from their singularities for (..., 6) controller joints: joint 5 from 0
    or 180 (axes 4 and 6 in line), the elbow from the arm stretched or folded."""
    joints = np.asarray(joints_deg, dtype=float)
    if robot.opw is not None:
        wrist = np.degrees(model_angle(robot.opw, joints, 4))
        elbow = np.degrees(model_angle(robot.opw, joints, 2)) + np.degrees(np.arctan2(robot.opw.a2, robot.opw.c3))
        return _from_singular(wrist), _from_singular(elbow)
    return _from_singular(joints[..., 4]), _from_singular(joints[..., 2])


def wrist_points(robot: Robot, flange_poses) -> np.ndarray:
    """(..., 3) the wrist point of (..., 4, 4) flange poses (controller frames), in the model's base frame:
    the OPW wrist centre, or the UR joint-5 origin (where axes 5 and 6 cross)."""
    model = np.asarray(flange_poses, dtype=float)
    if not np.array_equal(robot.base_transform, np.eye(4)):
        model = robot.base_transform @ model
    if not np.array_equal(robot.flange_transform, np.eye(4)):
        model = model @ frames.invert(robot.flange_transform)
    offset = robot.opw.c4 if robot.opw is not None else robot.ur.d6
    return model[..., :3, 3] - offset * model[..., :3, 2]


def shoulder_distance(robot: Robot, flange_poses) -> np.ndarray:
    """(...) mm from the shoulder singularity: the wrist point's distance from axis 1 in the arm's plane
    (beside the OPW offset b; beside UR's shoulder offset d4)."""
    point = wrist_points(robot, flange_poses)
    side = robot.opw.b if robot.opw is not None else robot.ur.d4
    return np.sqrt(np.maximum(point[..., 0] ** 2 + point[..., 1] ** 2 - side ** 2, 0.0))


# How a pose's title names the problem that comes right after the last pose the robot follows.
PROBLEM_WORDS = {OUT_OF_REACH: "going out of reach", JOINT_LIMIT: "passing a joint limit",
                 CONFIGURATION_CHANGE: "having to change configuration inside a linear move",
                 WRIST_SINGULARITY: "passing the wrist singularity", ELBOW_SINGULARITY: "passing the elbow singularity",
                 SHOULDER_SINGULARITY: "passing the shoulder singularity"}


@dataclass(frozen=True)
class WorstPose:
    """The pose of a program to look at: ``joints`` (the controller's, degrees), ``where`` along the program,
    and ``text``, where it is and why it is the one: 'at line 120 (A5 2.1 deg from its limit)'."""

    joints: tuple
    where: Where
    text: str


def worst_pose(robot: Robot, report: ReachReport) -> WorstPose | None:
    """Where the robot comes nearest a joint limit along a program it follows, or where a program it cannot
    follow fails (past the limit, or the last pose it follows before the problem); None when it follows
    none of the program."""
    if report.reachable:
        if report.margin_pose is None:
            return None
        pose, margin = report.margin_pose, report.margin
        return WorstPose(pose.joints, pose.where, f"{_place(pose.where)} ({joint_name(robot, margin.joint)} "
                                                  f"{margin.value:.1f} deg from its limit)")
    pose = report.problem_pose
    if pose is None:
        return None
    if pose.past_limit:
        margins = joint_margins_deg(robot, pose.joints)
        joint = int(np.argmin(margins))
        return WorstPose(pose.joints, pose.where, f"{_place(pose.where)} ({joint_name(robot, joint)} "
                                                  f"{-margins[joint]:.1f} deg past its limit)")
    problem = report.problem_at
    there = "" if (problem.target, problem.on_the_way) == (pose.where.target, pose.where.on_the_way) \
        else f" {_place(problem)}"
    return WorstPose(pose.joints, pose.where, f"{_place(pose.where)}, just before "
                                              f"{PROBLEM_WORDS[report.problem]}{there}")


def _target(where: Where) -> str:
    """'line 12', or 'robot target 5' when the source line is unknown."""
    return f"line {where.line}" if where.line else f"robot target {where.target + 1}"


def _place(where: Where) -> str:
    """'at line 12', or 'on the way to line 12' for a point on the linear move to it."""
    return ("on the way to " if where.on_the_way else "at ") + _target(where)
