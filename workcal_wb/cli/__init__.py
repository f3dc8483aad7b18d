"""Headless command line: one module per subcommand, each with ``add_parser(subparsers)`` and ``run(args)``.

Exit status: 0 = ok or ambiguous, 1 = the job ran but failed (e.g. a match or calibration failed its
checks), 2 = bad input or usage.  Errors are one line on stderr, never a traceback.
"""
from __future__ import annotations

import argparse
import importlib
import sys

from workcal_wb import __version__

SUBCOMMANDS = ("demo", "calibrate", "toolpath", "simulate", "study", "match", "bench")  # module names in workcal_wb.cli, in the order --help lists them

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python3 -m workcal_wb",
        description="WorkCal: locate a freeform workpiece for a robot or CNC machine from one 3D scan.",
    )
    parser.add_argument("--version", action="version", version=f"WorkCal {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in SUBCOMMANDS:
        module = importlib.import_module(f"workcal_wb.cli.{name}")
        module.add_parser(sub).set_defaults(run=module.run)
    return parser


def main(argv=None) -> int:
    from workcal_wb.core.errors import WorkCalError

    parser = build_parser()
    args = parser.parse_args(argv)
    if not hasattr(args, "run"):
        parser.print_help()
        return EXIT_BAD_INPUT
    try:
        return args.run(args)
    except WorkCalError as exc:
        print(f"workcal {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print(f"workcal {args.command}: interrupted", file=sys.stderr)
        return 130
