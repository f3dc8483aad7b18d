"""Headless command line: one module per subcommand, each with ``add_parser(subparsers)`` and ``run(args)``.

Every subcommand ends with one exit status per cause (EXIT_STATUS below, also in ``--help`` and the
README).  Errors are one line on stderr, never a traceback.
"""
from __future__ import annotations

import argparse
import importlib
import os
import re
import signal
import sys
import threading
import traceback

from workcal_wb import __version__

SUBCOMMANDS = ("demo", "calibrate", "choose", "toolpath", "robots", "simulate", "study", "match", "bench")  # module names in workcal_wb.cli, in the order --help lists them

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT, EXIT_CANNOT_WRITE, EXIT_MISSING_DEPENDENCY = 0, 1, 2, 3, 4
EXIT_INTERNAL_ERROR = 70  # EX_SOFTWARE
EXIT_STATUS = f"""exit status (the same for every subcommand):
  {EXIT_OK}    ok, or ambiguous (usable with care: see the reasons)
  {EXIT_FAILED}    failed: the job ran and its result did not pass (calibration or match failed or found
       nothing, a program refused as unsafe, a study or benchmark target missed)
  {EXIT_BAD_INPUT}    bad input: a file or an argument that cannot be used as given
  {EXIT_CANNOT_WRITE}    an output cannot be written (--out not writable, a file in the way, disk full)
  {EXIT_MISSING_DEPENDENCY}    a Python package WorkCal needs is missing (open3d)
  {EXIT_INTERNAL_ERROR}   internal error: a bug in WorkCal (please report it with the command line)
  130  interrupted (SIGINT, Ctrl-C), 143 terminated (SIGTERM): outputs are left as before the run
A run that fails or ends in an error leaves no program and no earlier result in its output folder."""


_NEGATIVE_NUMBER = re.compile(r"-\.?\d|-inf|-nan", re.IGNORECASE)


class _Parser(argparse.ArgumentParser):
    """Every value that starts like a negative number (-1, -.5, -1e3, -1,2,3) is a value, never an
    option (argparse before 3.14 only takes plain -1 and -.5): ``--envelope -1,-1,0,1,1,1`` works."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", _HelpFormatter)
        kwargs.setdefault("epilog", EXIT_STATUS)
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = _NEGATIVE_NUMBER

    def error(self, message):
        """A bad argument: one line, as every other error (argparse would print the usage first)."""
        command = self.prog.split("workcal_wb", 1)[-1].strip()
        self.exit(EXIT_BAD_INPUT, f"workcal{' ' + command if command else ''}: error: {message} "
                                  f"(see: {self.prog} --help)\n")


class _HelpFormatter(argparse.HelpFormatter):
    """Descriptions wrapped as usual; the exit status table kept as written."""

    def _fill_text(self, text, width, indent):
        if text.startswith("exit status"):
            return "".join(indent + line for line in text.splitlines(keepends=True))
        return super()._fill_text(text, width, indent)


class Stopped(KeyboardInterrupt):
    """SIGTERM (or SIGINT) as an exception, so that every ``finally`` and context manager on the way out
    removes its temporary files and a half-staged output set."""

    def __init__(self, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def _stop(signum, frame):
    raise Stopped(signum)


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser of every subcommand, or only of ``command``: a run imports the modules of its own
    subcommand, not those of the others (a match need not load the toolpath exporters)."""
    parser = _Parser(
        prog="python3 -m workcal_wb",
        description="WorkCal: locate a freeform workpiece for a robot or CNC machine from one 3D scan.",
    )
    parser.add_argument("--version", action="version", version=f"WorkCal {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in [command] if command in SUBCOMMANDS else SUBCOMMANDS:
        module = importlib.import_module(f"workcal_wb.cli.{name}")
        module.add_parser(sub).set_defaults(run=module.run)
    return parser


def exit_status(error: BaseException) -> int:
    """The exit status for an exception that ended a run (see EXIT_STATUS)."""
    from workcal_wb.core.errors import Cancelled, MissingDependency, OutputError, WorkCalError
    from workcal_wb.core.toolpath import ExportRefused

    if isinstance(error, KeyboardInterrupt):
        return 128 + getattr(error, "signum", signal.SIGINT)
    for kind, code in ((ExportRefused, EXIT_FAILED), (OutputError, EXIT_CANNOT_WRITE),
                       (MissingDependency, EXIT_MISSING_DEPENDENCY), (Cancelled, 128 + signal.SIGINT),
                       (WorkCalError, EXIT_BAD_INPUT)):
        if isinstance(error, kind):
            return code
    return EXIT_INTERNAL_ERROR


def main(argv=None) -> int:
    from workcal_wb.core.errors import WorkCalError

    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(argv[0] if argv else None)
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, or a bad argument (argparse has said why)
        return exc.code if isinstance(exc.code, int) else EXIT_BAD_INPUT
    if not hasattr(args, "run"):
        parser.print_help()
        return EXIT_BAD_INPUT
    # SIGINT and SIGTERM unwind the run (temporary files removed); past a file-size limit a write fails
    # (exit 3) instead of killing the process.  Set here, not left to the interpreter: FreeCAD 1.0's
    # freecadcmd starts Python with SIGXFSZ at its default (kill) and SIGINT not raising.
    wanted = {signal.SIGTERM: _stop, signal.SIGINT: _stop, signal.SIGXFSZ: signal.SIG_IGN}
    handles_signals = threading.current_thread() is threading.main_thread()
    previous = {signum: signal.signal(signum, handler) for signum, handler in wanted.items()} if handles_signals else {}
    try:
        return args.run(args)
    except KeyboardInterrupt as exc:
        stopped_by = getattr(exc, "signum", signal.SIGINT)
        print(f"workcal {args.command}: {'interrupted' if stopped_by == signal.SIGINT else 'terminated'}; "
              f"{getattr(exc, 'outputs', 'outputs are as before the run')}", file=sys.stderr)
        return exit_status(exc)
    except WorkCalError as exc:
        print(f"workcal {args.command}: error: {exc}", file=sys.stderr)
        return exit_status(exc)
    except Exception as exc:  # a bug: one line, the traceback only on request
        print(f"workcal {args.command}: internal error: {type(exc).__name__}: {exc} (a bug in WorkCal; "
              "set WORKCAL_DEBUG=1 for the traceback and please report it)", file=sys.stderr)
        if os.environ.get("WORKCAL_DEBUG"):
            traceback.print_exc()
        return EXIT_INTERNAL_ERROR
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, signal.SIG_DFL if handler is None else handler)
