"""Where to put the part instead: a move on the platform that brings a program the robot cannot follow
within its reach.

The part may be moved in the platform's plane (the robot base frame's XY: the platform's normal is its
z) and turned about z around the toolpath's centre; every pose of the program moves with it.  The
search tries every turn of ``TURN_STEP_DEG`` and every position of the centre on a ``GRID_MM`` grid
over the robot's reach, cheapest first (distance moved plus ``TURN_COST_MM_PER_DEG`` per degree
turned):

1. a map of where the robot's wrist point can be (its distance from axis 1 and its height, from the
   forward kinematics of joints drawn within the limits, ``MAP_CELL_MM`` cells) rules out at once every
   placement that puts a wrist point of ``SEARCH_POSES`` poses of the program where it never is;
2. the placements left, in batches, solve those poses: some configuration must reach all of them with
   ``MARGIN_DEG`` to every joint limit;
3. the first placement that passes is confirmed with ``reach.check_reach`` on every pose of the
   program: reachable, and the same margin.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from .. import frames
from .kinematics import forward, inverse
from .model import Robot
from .reach import JOINT_MOVE, TURN_SHIFTS_DEG, ReachReport, check_reach, wrist_points

# Joint margin (deg) a suggested placement leaves at every pose: room for the part not lying exactly
# where it is put.
MARGIN_DEG = 5.0
# The grid of the toolpath centre's new position on the platform (mm) and of the turns (deg).
GRID_MM = 50.0
TURN_STEP_DEG = 15.0
# A degree of turn is weighed like this many mm of move when placements are ranked (a turn of 30 deg
# moves the far end of a 600 mm part about 300 mm).
TURN_COST_MM_PER_DEG = 5.0
# Poses of the program the search solves (spread along it, with its extremes); the confirmation solves all.
SEARCH_POSES = 48
# Placements solved at a time, the most placements solved, and the most confirmed with the whole program.
BATCH = 256
MAX_SOLVED = 16_384
MAX_CONFIRMED = 4
# The wrist-point map: cell size (mm), joint sets drawn for it, and the seed (the map is the same every run).
MAP_CELL_MM = 25.0
MAP_SAMPLES = 200_000
MAP_SEED = 20240521


@dataclass(frozen=True)
class PartMove:
    """Turn the part ``turn_deg`` about the vertical through ``centre_mm`` (x, y in the robot base frame),
    then move it by ``translation_mm`` (x, y): ``transform`` (4x4) maps where it is to where it goes
    (a pose P becomes transform @ P).  ``report``: the whole program checked there."""

    translation_mm: tuple
    turn_deg: float
    centre_mm: tuple
    transform: np.ndarray = field(compare=False, repr=False)
    report: ReachReport = field(compare=False, repr=False)

    def describe(self) -> str:
        """'move the part 120 mm along -X of the robot base (towards the robot) and turn it 30 deg about Z ...'"""
        dx, dy = self.translation_mm
        words = []
        steps = [f"{abs(v):.0f} mm along {'+' if v > 0 else '-'}{axis}" for v, axis in ((dx, "X"), (dy, "Y"))
                 if round(abs(v)) > 0]
        if steps:
            cx, cy = self.centre_mm
            closer = math.hypot(cx + dx, cy + dy) < math.hypot(cx, cy)
            words.append(f"move the part {' and '.join(steps)} of the robot base "
                         f"({'towards' if closer else 'away from'} the robot)")
        if round(self.turn_deg):
            sense = "counter-clockwise" if self.turn_deg > 0 else "clockwise"
            words.append(f"{'turn it' if steps else 'turn the part'} {abs(self.turn_deg):.0f} deg about Z ({sense} "
                         f"seen from above, about the toolpath's centre)")
        return " and ".join(words) or "leave the part where it is"


def part_move(translation_xy, turn_deg: float, centre_xy) -> np.ndarray:
    """4x4: turn ``turn_deg`` about the vertical through ``centre_xy``, then move by ``translation_xy`` (mm)."""
    cx, cy = centre_xy
    dx, dy = translation_xy
    return frames.compose(frames.rigid(None, (cx + dx, cy + dy, 0.0)), frames.rigid(frames.rot_z(turn_deg)),
                          frames.rigid(None, (-cx, -cy, 0.0)))


def suggest_placement(robot: Robot, tcp_poses, tool=None, move_kinds=None, source_lines=None) -> PartMove | None:
    """The cheapest move of the part on the platform after which ``robot`` follows the program with
    MARGIN_DEG to its limits (None when the search finds none); arguments as ``reach.check_reach``."""
    poses = np.asarray(tcp_poses, dtype=float)
    tool = np.eye(4) if tool is None else np.asarray(tool, dtype=float)
    flange = poses @ frames.invert(tool)
    chosen = _spread(robot, flange)
    centre = poses[chosen, :2, 3].mean(axis=0)
    for move, turn, translation in _candidates(robot, flange[chosen], centre):
        report = check_reach(robot, move @ poses, tool, move_kinds, source_lines)
        if report.reachable and report.margin.value >= MARGIN_DEG:
            return PartMove(tuple(float(v) for v in translation), float(turn), tuple(float(v) for v in centre),
                            move, report)
    return None


def _spread(robot: Robot, flange: np.ndarray) -> np.ndarray:
    """Indices of up to SEARCH_POSES poses: evenly along the program, and those whose wrist points are
    furthest out, in, up and down."""
    count = len(flange)
    chosen = set(np.linspace(0, count - 1, min(count, SEARCH_POSES - 6)).round().astype(int).tolist())
    points = wrist_points(robot, flange)
    radius = np.hypot(points[:, 0], points[:, 1])
    for values in (radius, points[:, 2]):
        chosen |= {int(np.argmin(values)), int(np.argmax(values))}
    chosen |= {int(np.argmin(points[:, 0])), int(np.argmax(points[:, 0]))}
    return np.array(sorted(chosen))


def _candidates(robot: Robot, flange: np.ndarray, centre: np.ndarray):
    """(transform, turn, translation) of the placements whose chosen poses some configuration reaches
    with MARGIN_DEG to the limits, cheapest first (at most MAX_CONFIRMED of them)."""
    radius_max, inside = _wrist_map(robot)
    steps = [GRID_MM * np.arange(math.ceil((-radius_max - c) / GRID_MM), math.floor((radius_max - c) / GRID_MM) + 1)
             for c in centre]
    gx, gy = np.meshgrid(*steps, indexing="ij")
    spots = centre + np.column_stack([gx.ravel(), gy.ravel()])  # where the centre may go (B's XY), whole grid steps
    spots = spots[np.hypot(spots[:, 0], spots[:, 1]) <= radius_max]
    turns = TURN_STEP_DEG * np.arange(-math.floor(180 / TURN_STEP_DEG) + 1, math.floor(180 / TURN_STEP_DEG) + 1)
    base = robot.base_transform
    points_b = _wrist_points_b(robot, flange) - [centre[0], centre[1], 0.0]  # about the centre
    kept_turn, kept_spot = [], []
    for turn in turns:  # one pass per turn over every spot at once
        c, s = math.cos(math.radians(turn)), math.sin(math.radians(turn))
        turned = points_b @ np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
        moved = turned[None, :, :] + np.column_stack([spots, np.zeros(len(spots))])[:, None, :]
        in_model = moved @ base[:3, :3].T + base[:3, 3]
        fits = inside(in_model).all(axis=1)
        kept_spot.append(spots[fits])
        kept_turn.append(np.full(int(fits.sum()), turn))
    spots, turn_of = np.concatenate(kept_spot), np.concatenate(kept_turn)
    translation = spots - centre
    cost = np.hypot(translation[:, 0], translation[:, 1]) + TURN_COST_MM_PER_DEG * np.abs(turn_of)
    order = np.argsort(cost, kind="stable")[:MAX_SOLVED]
    confirmed = 0
    for start in range(0, len(order), BATCH):
        batch = order[start:start + BATCH]
        moves = np.stack([part_move(translation[i], turn_of[i], centre) for i in batch])
        ok = _reached_with_margin(robot, moves[:, None] @ flange[None])
        for i, move in zip(batch[ok], moves[ok]):
            yield move, turn_of[i], translation[i]
            confirmed += 1
            if confirmed >= MAX_CONFIRMED:
                return


def _reached_with_margin(robot: Robot, flange: np.ndarray) -> np.ndarray:
    """(P,) for (P, S, 4, 4) flange poses: some configuration reaches all S poses with every joint, at its
    best whole turn, MARGIN_DEG inside its limits."""
    joints = inverse(robot, flange)  # (P, S, 8, 6)
    low, high = robot.limits[:, 0], robot.limits[:, 1]
    turned = joints[..., None] + TURN_SHIFTS_DEG
    with np.errstate(invalid="ignore"):
        room = np.minimum(turned - low[:, None], high[:, None] - turned).max(axis=-1).min(axis=-1)  # (P, S, 8)
        return np.any(np.all(room >= MARGIN_DEG, axis=1), axis=-1)


def _wrist_points_b(robot: Robot, flange: np.ndarray) -> np.ndarray:
    """Wrist points of flange poses in the controller's base frame B."""
    return frames.apply(frames.invert(robot.base_transform), wrist_points(robot, flange))


@lru_cache(maxsize=16)
def _wrist_map(robot: Robot):
    """(largest distance of the wrist point from axis 1 in B, inside(points (..., 3) in the model's base
    frame) -> bool): where the wrist point can be, from joints drawn within the limits, one cell of
    slack all round."""
    rng = np.random.default_rng(MAP_SEED)
    low, high = robot.limits[:, 0], robot.limits[:, 1]
    joints = rng.uniform(low, high, (MAP_SAMPLES, 6))
    points = wrist_points(robot, forward(robot, joints))
    radius, height = np.hypot(points[:, 0], points[:, 1]), points[:, 2]
    z0 = height.min() - 2 * MAP_CELL_MM
    shape = (int(radius.max() // MAP_CELL_MM) + 3, int((height.max() - z0) // MAP_CELL_MM) + 3)
    grid = np.zeros(shape, dtype=bool)
    grid[(radius // MAP_CELL_MM).astype(int), ((height - z0) // MAP_CELL_MM).astype(int)] = True
    padded = grid.copy()  # one cell of slack: the draw leaves holes at the edges
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            padded |= np.roll(np.roll(grid, di, axis=0), dj, axis=1)

    def inside(points_model: np.ndarray) -> np.ndarray:
        i = (np.hypot(points_model[..., 0], points_model[..., 1]) // MAP_CELL_MM).astype(int)
        j = ((points_model[..., 2] - z0) // MAP_CELL_MM).astype(int)
        valid = (i < shape[0]) & (j >= 0) & (j < shape[1])
        return valid & padded[np.minimum(i, shape[0] - 1), np.clip(j, 0, shape[1] - 1)]

    base_xy = np.linalg.norm(frames.invert(robot.base_transform)[:2, 3])
    return float(radius.max() + base_xy + MAP_CELL_MM), inside
