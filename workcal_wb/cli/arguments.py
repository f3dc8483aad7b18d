"""Argument types shared by the subcommands: every number finite and in range, every input an existing
regular file, checked by argparse before any work starts (a bad value exits 2 naming the option)."""
from __future__ import annotations

import argparse
import math
from pathlib import Path

from workcal_wb.core.errors import InputError
from workcal_wb.core.files import checked_input


def _number(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    return _checked(value, math.isfinite(value), "a finite number", text)


def _whole(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number, got {text!r}") from None


def _checked(value, ok: bool, words: str, text: str):
    if not ok:
        raise argparse.ArgumentTypeError(f"must be {words}, got {text!r}")
    return value


def finite(text: str) -> float:
    """Any finite number (coordinates, angles)."""
    return _number(text)


def positive(text: str) -> float:
    """A finite number > 0 (tolerances, sizes, speeds)."""
    value = _number(text)
    return _checked(value, value > 0, "a number > 0", text)


def non_negative(text: str) -> float:
    """A finite number >= 0 (noise)."""
    value = _number(text)
    return _checked(value, value >= 0, "a number >= 0", text)


def seed(text: str) -> int:
    """A random seed: a whole number from 0 to 2**63 - 1 (what numpy's generators take)."""
    value = _whole(text)
    return _checked(value, 0 <= value < 2**63, "a whole number from 0 to 2**63 - 1", text)


def count(text: str) -> int:
    """A whole number >= 1 (runs, positions)."""
    value = _whole(text)
    return _checked(value, value >= 1, "at least 1", text)


def program_lines(text: str) -> int:
    """Lines per program part: a whole number, at least what one part's frame takes (ExportOptions)."""
    from workcal_wb.core.toolpath.safety import MIN_PART_LINES

    value = _whole(text)
    return _checked(value, value >= MIN_PART_LINES, f"at least {MIN_PART_LINES}", text)


def envelope(text: str):
    """A work envelope "xmin,ymin,zmin,xmax,ymax,zmax" in mm."""
    from workcal_wb.core.toolpath import Envelope

    try:
        return Envelope.parse(text)
    except InputError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def robot(text: str):
    """A built-in robot's id or a robot JSON file (robots.load_robot): every field checked."""
    from workcal_wb.core.robots import load_robot

    try:
        return load_robot(text)
    except InputError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def tool_frame(text: str):
    """A tool as X,Y,Z,A,B,C: the TCP in the robot's flange frame, mm and degrees, R = Rz(A) Ry(B) Rx(C)
    (KUKA's convention); a 4x4 transform."""
    from workcal_wb.core.robots.model import xyzabc_transform

    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 6 or not all(map(math.isfinite, values)):
        raise argparse.ArgumentTypeError(f"expected six numbers X,Y,Z,A,B,C (mm and degrees, the TCP in the flange "
                                         f"frame), got {text!r}")
    return xyzabc_transform(values)


def input_file(text: str) -> str:
    """An existing, readable regular file (not a folder, pipe or device)."""
    try:
        checked_input(text)
    except InputError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


def add_runner_options(parser, what: str) -> None:
    """--workers N / --scheduler ADDRESS: where a batch of ``what`` (e.g. "calibrations") runs
    (core/parallel.py); ``runner_from(args)`` makes the Runner."""
    from workcal_wb.core.parallel import cores

    where = parser.add_mutually_exclusive_group()
    where.add_argument("--workers", type=count, metavar="N",
                       help=f"{what} run at once, each in its own process (default: every core, {cores()} "
                            "here; 1: one after the other in this process)")
    where.add_argument("--scheduler", metavar="ADDRESS",
                       help=f"run the {what} on the Dask cluster whose scheduler listens at ADDRESS "
                            "(e.g. tcp://10.0.0.5:8786; needs python3-distributed here and on the workers)")


def runner_from(args):
    """The parallel.Runner that --workers / --scheduler ask for."""
    from workcal_wb.core.parallel import Runner

    return Runner(args.workers, args.scheduler)


def add_cache_options(parser) -> None:
    """--cache DIR / --no-cache: where prepared models are kept between runs (core/model_cache.py)."""
    from workcal_wb.core.model_cache import default_folder

    group = parser.add_mutually_exclusive_group()
    group.add_argument("--cache", metavar="DIR", type=cache_folder,
                       help=f"folder of prepared models, reused by later runs on the same model files "
                            f"(default {default_folder()})")
    group.add_argument("--no-cache", action="store_true", help="prepare the models anew and keep nothing")


def cache_folder(text: str) -> str:
    """A folder for the model cache (made when first written): not a file."""
    import os

    if os.path.exists(text) and not os.path.isdir(text):
        raise argparse.ArgumentTypeError(f"{text}: is a file, not a folder")
    return text


def model_cache(args):
    """The ModelCache the options ask for."""
    from workcal_wb.core.model_cache import ModelCache, default_folder

    return ModelCache(None if args.no_cache else (args.cache or default_folder()))


def keep_models(cache) -> None:
    """Store what the run prepared (after its outputs); a cache that cannot be written is a warning."""
    import sys

    cache.store()
    for note in cache.notes:
        print(f"warning: {note}", file=sys.stderr)


UNITS = ("mm", "m", "in")
CAD_SUFFIXES = (".step", ".stp", ".iges", ".igs", ".brep", ".brp")


def is_cad_file(path) -> bool:
    """Whether ``path`` is a CAD solid (STEP, IGES, BREP), read only through FreeCAD."""
    return Path(path).suffix.lower() in CAD_SUFFIXES


def read_cad_model(path, units: str):
    """A STEP/IGES/BREP model as a Cloud, tessellated through FreeCAD when the command runs inside it."""
    try:
        from workcal_wb.fc.models import read_model_file
    except ImportError:
        raise InputError(f"{path}: STEP/IGES/BREP models are read through FreeCAD; run this command inside "
                         "freecadcmd (see the README), or export the model as STL") from None
    return read_model_file(path, units)


def read_model(path, units: str, cache, seed: int):
    """A model file, prepared (a SurfaceModel, from ``cache`` when it holds it); CAD solids (STEP,
    IGES, BREP) are tessellated through FreeCAD when it is there."""
    if not is_cad_file(path):
        return cache.model_file(path, units=units, seed=seed, unit_option="--model-units")
    return cache.model(read_cad_model(path, units), seed=seed)
