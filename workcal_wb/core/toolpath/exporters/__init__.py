"""One module per target format, each with NAME, EXTENSION, MACHINES and ``render(job)``; ``export`` runs them.

Each module also says which robots' controllers run its programs (``CONTROLLERS``, robots.model's
codes; none for G-code).
``render(job)`` yields the files of the program, ``(path, chunks)``: for a program over the controller's
size limit its numbered parts first, then the main program at ``job.out``.
``export`` is the only way a program reaches the disk: checks first (``checked_export``: calibration gates,
sanity bound, finite numbers, work envelope in B, the machine's axes, the path on the workpiece model, the
robot's reach), then each file is written atomically in plain
ASCII (``common.ascii_text``), parts
first and the main program last; a failure removes what this export wrote, and parts left by an
earlier, longer export of the same program are removed.
"""
from __future__ import annotations

import re
from pathlib import Path

from ...atomic import atomic_open
from ...errors import InputError
from ...result import CalibrationResult
from ..model import Toolpath
from ..reach import check_controller, checked_reach
from ..safety import ExportOptions, Placement, checked_placement
from . import common, csv, fanuc, gcode, krl, rapid, urscript

FORMATS = {"krl": krl, "rapid": rapid, "urscript": urscript, "fanuc": fanuc, "gcode": gcode, "csv": csv}


def format_for(path) -> str:
    """The format whose usual extension ``path`` has."""
    suffix = Path(path).suffix.lower()
    for name, module in FORMATS.items():
        if module.EXTENSION == suffix:
            return name
    known = ", ".join(f"{m.EXTENSION} ({n})" for n, m in FORMATS.items())
    raise InputError(f"{path}: cannot tell the output format from the extension; use one of {known} or name the format")


def machine_for(fmt: str, machine: str | None) -> str:
    """The machine a format writes for: the one asked, if the format can; otherwise its first."""
    module = FORMATS[fmt]
    if machine is None:
        return module.MACHINES[0]
    if machine not in module.MACHINES:
        raise InputError(f"{module.NAME} is written for {' or '.join(module.MACHINES)}, not --machine {machine}")
    return machine


def checked_export(toolpath: Toolpath, calibration: CalibrationResult, fmt: str, options: ExportOptions) -> Placement:
    """Every check ``export`` makes before it writes, in one place (FreeCAD checks with it before it
    records an export): ``safety.checked_placement``, then for a robot program the robot's reach
    (``reach.checked_reach``); refuses (ExportRefused, InputError) as ``export`` would."""
    if fmt not in FORMATS:
        raise InputError(f"unknown output format {fmt!r}; use one of {', '.join(FORMATS)}")
    machine = machine_for(fmt, options.machine)
    check_controller(options.robot, FORMATS[fmt])
    checked = checked_placement(toolpath, calibration, options, machine)
    if machine != "robot":
        return checked
    return checked_reach(toolpath, calibration, checked, options)


def export(toolpath: Toolpath, calibration: CalibrationResult, fmt: str, out, options: ExportOptions | None = None,
           **settings) -> common.ExportJob:
    """Write ``toolpath`` (workpiece frame, mm) as ``fmt`` to ``out``; refuses (ExportRefused) before writing.

    ``settings`` are ``ExportOptions`` fields (force, envelope, machine, ...), for callers without one."""
    options = options or ExportOptions(**settings)
    checked = checked_export(toolpath, calibration, fmt, options)
    job = common.ExportJob(toolpath, calibration, checked.transform, checked.forced, Path(out), options,
                           machine_for(fmt, options.machine), notes=list(checked.notes), banner=list(checked.banner),
                           reach=checked.reach)
    files = FORMATS[fmt].render(job)
    written = []
    try:
        for path, chunks in files:  # parts first, the main program last
            with atomic_open(path) as fh:
                for chunk in chunks:
                    fh.write(common.ascii_text(chunk))
            written.append(Path(path))
    except BaseException:
        for path in written:
            path.unlink(missing_ok=True)
        raise
    _remove_stale_parts(job.out, written)
    return job


def _remove_stale_parts(out: Path, written: list) -> None:
    """Parts ``<name>_NNN<ext>`` of an earlier export of this program that this one did not write."""
    pattern = re.compile(re.escape(out.stem) + r"_\d{3}" + re.escape(out.suffix) + "$", re.IGNORECASE)
    keep = {p.name.lower() for p in written}
    for path in out.parent.iterdir():
        if pattern.match(path.name) and path.name.lower() not in keep:
            with open(path, "rb") as fh:
                ours = b"WorkCal" in fh.read(4096)
            if ours:
                path.unlink()
