"""The reach-check table: ``robots.reach.check_reach`` on a program of a million poses, for an OPW arm
(KUKA KR 16-2) and a Universal Robots arm (UR5e), beside py-opw-kinematics' batch inverse kinematics on
the same poses where it applies (OPW arms only).

The poses are the forward kinematics of a smooth joint path (every pose reachable, one configuration,
clear of singularities), the TCP 150 mm out along the flange's z, one linear move after another a few
tenths of a millimetre long, as a finishing raster gives them.  Each robot is measured in a process of
its own, ``ROUNDS`` times; the table keeps the fastest round.  py-opw-kinematics (Rust, a test and
benchmark peer, never a runtime dependency) is looked for where ``make test`` puts it ($WORKCAL_TEST_PEERS,
which make sets to its build folder's test-peers/pyXY, else build/test-peers/pyXY in this checkout), then in
build/peers and on sys.path; without it its columns say so.
"""
from __future__ import annotations

import glob
import importlib.machinery
import importlib.util
import multiprocessing
import os
import sys
import time
from pathlib import Path

import numpy as np

from .tables import in_child

HEADING = "## Reach check"

POSES = 1_000_000
ROBOTS = ("kuka_kr16_2", "ur5e")
ROUNDS = 2
TOOL_Z_MM = 150.0
ROOT = Path(__file__).resolve().parents[3]
# The environment variable through which make tells where it installed the test peers for this Python
# (its BUILD folder need not be this checkout's build/, as in the other-Debian chroot).
TEST_PEERS_VARIABLE = "WORKCAL_TEST_PEERS"


def trajectory(robot, count: int = POSES) -> np.ndarray:
    """(count, 6) joints of a smooth path about a posture 60 % out in front of the robot."""
    from ..robots import inverse
    from .. import frames

    if robot.opw is not None:
        p = robot.opw
        reach, height = p.a1 + p.c2 + np.hypot(p.a2, p.c3), p.c1
    else:
        reach, height = -robot.ur.a2 - robot.ur.a3, robot.ur.d1
    model = frames.rigid(np.diag([1.0, -1.0, -1.0]), (0.6 * reach, 0.0, height))
    solutions = inverse(robot, frames.invert(robot.base_transform) @ model @ robot.flange_transform)
    centre = solutions[~np.isnan(solutions).any(axis=1)][0]
    if abs(centre[4]) < 40:
        centre[4] += 50 * np.sign(centre[4] or 1)
    t = np.linspace(0.0, 1.0, count)[:, None]
    return centre + np.array([20, 8, 8, 40, 15, 90]) * np.sin(2 * np.pi * t * np.array([1, 2, 3, 1, 2, 1]))


def py_opw_kinematics():
    """py-opw-kinematics' compiled module, or None: a build for this Python where ``make test`` or
    ``make bench`` installs it (``TEST_PEERS_VARIABLE`` names that folder when make runs us), else an
    importable one."""
    tag = f"py{sys.version_info[0]}{sys.version_info[1]}"
    suffixes = [s for s in importlib.machinery.EXTENSION_SUFFIXES if s != ".so"]
    told = [Path(os.environ[TEST_PEERS_VARIABLE])] if os.environ.get(TEST_PEERS_VARIABLE) else []
    for folder in (*told, ROOT / "build" / "test-peers" / tag, ROOT / "build" / "peers", *map(Path, sys.path)):
        found = [so for so in glob.glob(str(folder / "py_opw_kinematics" / "_internal*"))
                 if any(so.endswith(s) for s in suffixes)]
        if found:
            loader = importlib.machinery.ExtensionFileLoader("py_opw_kinematics._internal", found[0])
            spec = importlib.util.spec_from_file_location("py_opw_kinematics._internal", found[0], loader=loader)
            module = importlib.util.module_from_spec(spec)
            loader.exec_module(module)
            return module
    return None


def measure(robot_id: str, count: int = POSES) -> dict:
    """Times (s) of check_reach, of WorkCal's inverse alone and of the peer's batch inverse on ``count`` poses."""
    from .. import frames
    from ..robots import forward, inverse, load_robot
    from ..robots.reach import check_reach

    robot = load_robot(robot_id)
    tool = frames.rigid(None, (0.0, 0.0, TOOL_Z_MM))
    poses = forward(robot, trajectory(robot, count)) @ tool
    row = {"robot": robot.name, "poses": count, "opw": robot.opw is not None}
    t0 = time.perf_counter()
    report = check_reach(robot, poses, tool)
    row["check_s"] = time.perf_counter() - t0
    row["reachable"] = report.reachable
    row["samples"] = report.samples
    flange = poses @ frames.invert(tool)
    t0 = time.perf_counter()
    inverse(robot, flange)
    row["inverse_s"] = time.perf_counter() - t0
    peer = py_opw_kinematics() if robot.opw is not None and not robot.opw.j23_factor else None
    row["peer"] = peer is not None
    if peer is not None:
        p = robot.opw
        model = peer.KinematicModel(a1=p.a1, a2=p.a2, b=p.b, c1=p.c1, c2=p.c2, c3=p.c3, c4=p.c4,
                                    offsets=tuple(p.offsets_deg), flip_axes=tuple(s < 0 for s in p.signs))
        solver = peer.Robot(model, True)
        model_poses = np.ascontiguousarray((robot.base_transform @ flange @ frames.invert(robot.flange_transform))
                                           .reshape(-1, 16))
        t0 = time.perf_counter()
        solver.batch_inverse(model_poses, None, None)
        row["peer_batch_s"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        solver.reach(model_poses, [tuple(limit) for limit in robot.joint_limits_deg], None, 1)
        row["peer_reach_s"] = time.perf_counter() - t0
    return row


def _measure_in_child(robot_id: str, count: int, queue) -> None:
    queue.put(measure(robot_id, count))


def run(log=print, count: int = POSES) -> tuple[str, list]:
    """The section (Markdown) and the targets missed (none: the table is for reading)."""
    started = os.getloadavg()[0]
    rows = []
    for robot_id in ROBOTS:
        best = None
        for round_ in range(ROUNDS):
            log(f"benchmark: reach check, {robot_id}, round {round_ + 1} of {ROUNDS} ...")
            row = in_child(_measure_in_child, robot_id, count)
            if best is None:
                best = row
            else:
                for key in ("check_s", "inverse_s", "peer_batch_s", "peer_reach_s"):
                    if key in row:
                        best[key] = min(best[key], row[key])
        rows.append(best)
    slowest = max(row["check_s"] for row in rows)
    missed = [f"reach check: {slowest:.2f} s for {count:,} poses (target {TARGET_S:g} s)"] if slowest >= TARGET_S else []
    return table(rows, (started, os.getloadavg()[0])), missed


# The target: a million path poses checked in under this (s), so that checking a program never holds up its export.
TARGET_S = 2.0


def table(rows: list, load: tuple = ()) -> str:
    def peer(row, key):
        if row["peer"]:
            return f"{row[key]:.2f}"
        return "not installed (make test-peers)" if row["opw"] else "n/a (not an OPW arm)"

    lines = [HEADING, "",
             f"`robots.reach.check_reach` on {rows[0]['poses']:,} TCP poses of one program (the forward kinematics of "
             f"a smooth joint path, a {TOOL_Z_MM:g} mm tool, a joint move to the first pose and linear moves after "
             "it): the inverse kinematics of every pose in all eight configurations, each configuration followed "
             "along the program (turns unwrapped, joint limits, jumps between poses), one chosen, margins and "
             "singularity distances. Beside it WorkCal's inverse kinematics alone, and py-opw-kinematics (Rust) on "
             "the same flange poses: `batch_inverse` (one solution per pose, continuous from the previous) and "
             "`reach` (all eight branches with limit margins, one thread). Wall-clock seconds, the fastest of "
             f"{ROUNDS} rounds, each robot in a fresh process, on a machine shared with other jobs.", "",
             "| robot | poses | check_reach (s) | WorkCal inverse alone (s) | py-opw-kinematics batch_inverse (s) | "
             "py-opw-kinematics reach (s) | reachable |",
             "|---|---|---|---|---|---|---|"]
    for row in rows:
        lines.append(f"| {row['robot']} | {row['poses']:,} | {row['check_s']:.2f} | {row['inverse_s']:.2f} | "
                     f"{peer(row, 'peer_batch_s')} | {peer(row, 'peer_reach_s')} | "
                     f"{'yes' if row['reachable'] else 'NO'} |")
    slowest = max(row["check_s"] for row in rows)
    lines += ["", f"Target: {rows[0]['poses']:,} poses checked in under {TARGET_S:g} s: "
                  f"{'met' if slowest < TARGET_S else 'missed'} (slowest {slowest:.2f} s)."]
    if load:
        lines.append(f"Load average (1 min) on the {multiprocessing.cpu_count()} cores, shared with other jobs: "
                     f"{load[0]:.1f} at the start, {load[1]:.1f} at the end.")
    return "\n".join(lines + [""])
