"""``workcal robots``: the built-in robots that --robot takes by id."""
from __future__ import annotations

from workcal_wb.cli import EXIT_OK


def add_parser(subparsers):
    return subparsers.add_parser(
        "robots", help="list the built-in robots (ids for --robot)",
        description="List the built-in robots: the id --robot takes, the robot, the controller that runs its "
                    "programs and its joint limits. A robot of your own is a JSON file in the same form "
                    "(docs/robots.md), given to --robot by its path.")


def run(args) -> int:
    from workcal_wb.core.robots import builtin_robots, load_robot
    from workcal_wb.core.toolpath.reach import MAKERS

    for robot_id in builtin_robots():
        robot = load_robot(robot_id)
        limits = ", ".join(f"[{low:g}, {high:g}]" for low, high in robot.joint_limits_deg)
        print(f"{robot.id:22s} {robot.name:32s} {MAKERS[robot.controller]:16s} limits (deg) {limits}")
    return EXIT_OK
