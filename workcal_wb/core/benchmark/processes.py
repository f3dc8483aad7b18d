"""The whole-process table: the ``match`` and ``calibrate`` commands as a cell runs them, scan after
scan, each a fresh process, against the peers run the same way on the same files (peers.py).

Every figure is one whole process from start to exit, measured from outside: interpreter start,
imports (from bytecode compiled beforehand, as an installed package has it: ``compile_bytecode``),
reading both files, preparing (or, warm, loading) the model, the match and writing the result.
The cases are the match table's (cases.py), every family of them, written as files a model at a
time.  Cold: an empty model cache (on the clean bunny scans); warm: the model's cache filled before
(see match_runs).  The peers keep nothing between runs.  Peak memory is each process's own maximum
resident set (wait4).  The methods alternate case by case, ROUNDS times, and a case's time is its
fastest round, so a burst of load from other jobs does not land on one method only.  In-process:
``calibrate`` alone with models kept as FreeCAD keeps them (``_in_process``).
"""
from __future__ import annotations

import json
import multiprocessing
import os
import shutil
import statistics
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .cases import DEPTH_CAMERA_TOLERANCE_MM, Case, match_case_groups
from .tables import SUCCESS_DEG, SUCCESS_MM, TIME_RATIO_TARGET, in_child, pose_errors

HEADING = "## Whole processes"

ROUNDS = 2
WARM, COLD = "WorkCal warm", "WorkCal cold"
STOCK, KISS = "Open3D stock", "KISS-Matcher + small_gicp"
IN_PROCESS = "WorkCal in-process (kept models)"
PEER_NAMES = {STOCK: "open3d", KISS: "kiss"}
# The family the cold runs and the faster peer's target are measured on, and calibrate's one case.
BUNNY_CLEAN, DEMO = "bunny clean", "demo scene"
# Targets: warm match at most tables.TIME_RATIO_TARGET of stock Open3D's median time in every case
# family, and on the clean bunny scans at most this fraction of the faster peer's (each with at least its
# success rate); warm calibrate of the demo scene under these seconds as a process and in-process; no
# WorkCal match process above stock Open3D's peak memory on the same files.
MATCH_RATIO_TARGET = 0.4
CALIBRATE_PROCESS_S, CALIBRATE_IN_PROCESS_S = 1.0, 0.3
PYTHON = sys.executable if Path(sys.executable).name.startswith("python") else "/usr/bin/python3"
ROOT = Path(__file__).resolve().parents[3]


@dataclass
class Run:
    command: str  # "match" or "calibrate"
    method: str
    case: str
    time_s: float
    peak_mb: float
    success: bool
    family: str  # a match's case family (the match table's rows); calibrate's scene
    cpu_s: float = float("nan")  # user + system time of the process, all its threads


# Runs one command and prints its wall time, peak resident memory (kB), exit status and CPU time, forked from
# a small process of its own: Linux keeps the forking process's high-water mark in the child's across exec.
LAUNCHER = """import os, sys, time
started = time.perf_counter()
pid = os.fork()
if pid == 0:
    os.dup2(os.open(os.devnull, os.O_WRONLY), 1)
    os.execv(sys.argv[1], sys.argv[1:])
_, status, usage = os.wait4(pid, 0)
print(time.perf_counter() - started, usage.ru_maxrss, os.waitstatus_to_exitcode(status),
      usage.ru_utime + usage.ru_stime)
"""


def timed(argv: list) -> tuple[float, float, float]:
    """Wall time (s), peak resident memory (MB) and CPU time (s) of one process; RuntimeError when it fails."""
    done = subprocess.run([PYTHON, "-I", "-S", "-c", LAUNCHER, *map(str, argv)], cwd=ROOT, capture_output=True,
                          text=True)
    elapsed, peak_kb, code, cpu = done.stdout.split()
    if int(code) not in (0, 1):  # 1: a calibration that ran and is not "ok"
        raise RuntimeError(f"{' '.join(map(str, argv))} exited with {code}: {done.stderr[-400:]}")
    return float(elapsed), int(peak_kb) / 1024, float(cpu)


def compile_bytecode() -> None:
    """Compile the package's modules to bytecode first, as an installed package has them (pip and
    Debian's packaging compile them; a checkout writes them on its first run): otherwise a run with
    PYTHONDONTWRITEBYTECODE set, as in CI, would compile every module it imports, every time (~0.1 s)."""
    import compileall

    compileall.compile_dir(ROOT / "workcal_wb", quiet=1)


def peers_available() -> list:
    """The peers that can run here (KISS-Matcher needs ``make bench``'s private install)."""
    from .peers import PEERS_DIR

    installed = (PEERS_DIR / "kiss_matcher").is_dir() and any(PEERS_DIR.glob("small_gicp*.so"))
    return [STOCK, KISS] if installed else [STOCK]


@dataclass
class MatchFiles:
    """One case of the match table written as files: its scan and its model's file, the true U and
    the model's points (to measure the found pose against), and the tolerance the match is told."""

    family: str
    name: str
    scan: Path
    model: Path
    truth: np.ndarray
    model_points: np.ndarray
    tolerance_mm: float


def write_match_files(folder: Path, groups, one_per_family: bool = False):
    """The cases of ``groups`` (cases.match_case_groups: a model's cases each), one group at a time,
    written as binary PLY in mm: yields the MatchFiles of one group, its model file written once;
    with ``one_per_family`` only the first case of each family (the quick subset)."""
    from ..geometry import Cloud
    from ..writers import write_ply

    families = set()
    for number, group in enumerate(groups):
        model, files = folder / f"model-{number}.ply", []
        for case in group:
            if one_per_family and case.group in families:
                continue
            families.add(case.group)
            if not model.exists():
                write_ply(model, case.model)
            scan = folder / f"scan-{number}-{len(files)}.ply"
            write_ply(scan, Cloud(case.scan))
            files.append(MatchFiles(case.group, case.name, scan, model, case.truth, case.model.points,
                                    case.tolerance_mm))
        if files:
            yield files


def match_runs(folder: Path, bunny: Path | None, seed: int, quick: bool, log) -> tuple[list, list]:
    """Every case of the match table (quick: one a family) matched as a whole process by each method, a
    model's cases at a time: WorkCal cold on the clean bunny scans (an empty cache of its own), and warm
    on every case (the model's cache, filled first by an untimed run matching the model's own points, so
    no case finds it filled by its own scan first, then by what each run adds to it, as scan after scan
    against one model does); (runs, peers used)."""
    peers = peers_available()
    best: dict = {}
    result = folder / "result.json"
    for files in write_match_files(folder, match_case_groups(bunny, seed, quick), one_per_family=quick):
        model = files[0].model
        cache, empty = folder / f"cache-{model.stem}", folder / "cache-cold"
        for r in range(1 if quick else ROUNDS):
            for case in files:
                log(f"whole processes: match {case.name}, round {r + 1}")
                runs = ({COLD: _workcal_match(case.scan, model, case.tolerance_mm, result, empty)}
                        if case.family == BUNNY_CLEAN else {})
                runs[WARM] = _workcal_match(case.scan, model, case.tolerance_mm, result, cache)
                runs.update({peer: [PYTHON, "-m", "workcal_wb.core.benchmark.peers", PEER_NAMES[peer],
                                    str(case.scan), str(model), str(result)] for peer in peers})
                for method, argv in runs.items():
                    if method == COLD:
                        shutil.rmtree(empty, ignore_errors=True)
                    elif method == WARM and not cache.is_dir():
                        timed(_workcal_match(model, model, case.tolerance_mm, result, cache))
                    result.unlink(missing_ok=True)
                    elapsed, peak, cpu = timed(argv)
                    matrix = json.loads(result.read_text())["matrix"]
                    rotation, displacement = pose_errors(None if matrix is None else np.array(matrix), case.truth,
                                                         case.model_points)
                    success = rotation < SUCCESS_DEG and displacement < SUCCESS_MM
                    _keep_fastest(best, Run("match", method, case.name, elapsed, peak, success, case.family, cpu))
        for case in files:
            case.scan.unlink()
        model.unlink()
        for folder_used in (cache, empty):
            shutil.rmtree(folder_used, ignore_errors=True)
    return list(best.values()), peers


def _workcal_match(scan: Path, model: Path, tolerance_mm: float, result: Path, cache: Path) -> list:
    """The command line of one ``workcal match`` of ``scan`` (mm) against ``model`` with its model cache."""
    return [PYTHON, "-m", "workcal_wb", "match", str(scan), str(model), "--units", "mm", "--tolerance",
            str(tolerance_mm), "--json", str(result), "--cache", str(cache)]


def _keep_fastest(best: dict, run: Run) -> None:
    """Fold ``run`` into ``best``, one entry per method and case: the first round's outcome, the
    fastest round's wall and CPU times, the largest memory."""
    kept = best.setdefault((run.method, run.case), run)
    if kept is not run:
        kept.time_s, kept.cpu_s = min(kept.time_s, run.time_s), min(kept.cpu_s, run.cpu_s)
        kept.peak_mb = max(kept.peak_mb, run.peak_mb)


def calibrate_runs(folder: Path, seed: int, quick: bool, log) -> list:
    """The demo scene calibrated as a whole process, cold and warm, and in-process with warm models."""
    scene = folder / "demo"
    subprocess.run([PYTHON, "-m", "workcal_wb", "simulate", "--out", str(scene), "--seed", str(seed), "--lump"],
                   cwd=ROOT, stdout=subprocess.DEVNULL, check=True)  # the scene `make demo` calibrates
    cache = folder / "calibrate-cache"
    argv = [PYTHON, "-m", "workcal_wb", "calibrate", "--scan", str(scene / "scan.ply"), "--workpiece",
            str(scene / "workpiece.ply"), "--reference", str(scene / "reference.ply"), "--toolpath",
            str(scene / "toolpath.nc"), "--machine", "5axis-tcp", "--seed", str(seed), "--cache", str(cache)]
    best: dict = {}
    for r in range(1 if quick else ROUNDS):
        log(f"whole processes: calibrate the demo scene, round {r + 1}")
        shutil.rmtree(cache, ignore_errors=True)
        for method in (COLD, WARM):
            out = folder / f"calibrate-{r}-{method.split()[1]}"
            elapsed, peak, cpu = timed(argv + ["--out", str(out)])
            ok = json.loads((out / "result.json").read_text())["status"] == "ok"
            _keep_fastest(best, Run("calibrate", method, DEMO, elapsed, peak, ok, DEMO, cpu))
    # In a fresh process of its own (its memory its own).
    for run in in_child(_in_process, scene, cache, seed, 1 if quick else 3):
        _keep_fastest(best, run)
    return list(best.values())


def _in_process(scene: Path, cache: Path, seed: int, repeats: int, queue) -> None:
    """``calibrate()`` with the models kept as the FreeCAD workbench keeps them (headless options: BLAS on
    one thread, where FreeCAD's worker thread leaves BLAS as it is): the models loaded from the warm cache once and
    kept, one untimed first run (it fills what the models build on first use, as a document's first
    calibration does), then ``repeats`` timed runs against the same kept models."""
    import resource

    from ..calibration import CalibrationOptions, calibrate
    from ..model_cache import ModelCache
    from ..readers import read_cloud
    from ..toolpath import path_points, read_gcode

    scan = read_cloud(scene / "scan.ply")
    toolpath = path_points(read_gcode(scene / "toolpath.nc"))[0]
    models = ModelCache(cache)
    workpiece, reference = (models.model_file(scene / name, seed=seed) for name in ("workpiece.ply", "reference.ply"))
    runs = []
    for repeat in range(repeats + 1):
        started, cpu = time.perf_counter(), time.process_time()
        result = calibrate(scan, workpiece, reference, toolpath_points=toolpath, options=CalibrationOptions(seed=seed))
        elapsed, cpu = time.perf_counter() - started, time.process_time() - cpu
        if repeat:
            runs.append(Run("calibrate", IN_PROCESS, DEMO, elapsed,
                            resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, result.status == "ok", DEMO, cpu))
    queue.put(runs)


def table(runs: list, peers: list, note: str | None, load: tuple = ()) -> tuple[str, list]:
    """The section's Markdown and the targets missed; ``load``: the machine's load average (1 min) at
    the start and the end of the runs."""
    def median(values):
        return statistics.median(values) if values else float("nan")

    stats = {}
    for key in dict.fromkeys((r.command, r.family, r.method) for r in runs):
        members = [r for r in runs if (r.command, r.family, r.method) == key]
        stats[key] = {"n": len(members), "success": sum(r.success for r in members) / len(members),
                      "time": median([r.time_s for r in members]), "cpu": median([r.cpu_s for r in members]),
                      "peak": median([r.peak_mb for r in members]), "max_peak": max(r.peak_mb for r in members)}
    families = list(dict.fromkeys(family for command, family, _ in stats if command == "match"))

    def faster_peer(family):
        times = {p: stats[("match", family, p)]["time"] for p in peers if ("match", family, p) in stats}
        return min(times, key=times.get) if times else None

    lines = [HEADING, "",
             "Written by `make bench` (or `make bench-processes`). The `match` and `calibrate` commands as whole "
             "processes, as a cell runs them scan after scan (`core/benchmark/processes.py`), beside the peers run "
             "the same way on the same files (`core/benchmark/peers.py`): every case of the match table above "
             "(each real Stanford bunny scan and its degradations against `bun_zipper.ply`, the simulated car and "
             "figurine, the depth camera's parts on their table, the same cases from the same seed), written as "
             "binary PLY in mm, no initial guess, WorkCal told the case's tolerance (`--tolerance`: "
             f"{DEPTH_CAMERA_TOLERANCE_MM:g} mm on the depth camera's scans, {Case.tolerance_mm:g} mm elsewhere). "
             "Each figure is a whole process measured from outside: interpreter start, imports "
             "(the package compiled to bytecode first, as installed), "
             "reading both files, preparing the model (cold: an empty model cache, measured on the clean bunny "
             "scans; the peers always) or loading it (warm: the model's cache, filled first by an untimed run "
             "matching the model's own points, so that no case finds it filled by its own scan first, then by what "
             "each run adds to it, as scan after scan against one model does), the match and writing the "
             "result JSON (when the verdict weighs a rival by the points it leaves far off, or a fit is taken to "
             "the exact surface, a mesh model's exact distances go through open3d's BVH, whose import takes "
             "0.2-0.4 s and ~45 MB, as in the peers). "
             "calibrate: the demo "
             "scene (`make demo`'s car with a clay lump, automatic regions, 6 bootstrap refits, the toolpath "
             "exported). After result.json and the program are written, the process goes on and is timed to its exit: "
             "the report (the workpiece region's exact distances to its mesh through open3d's BVH; two "
             "PNG views drawn with numpy; an SVG histogram; report.html and report.json) and, when the run grew "
             "them, the prepared models written back to the cache. In-process: "
             "`calibrate()` alone with the models prepared once and kept as the FreeCAD workbench keeps them "
             "(headless options: BLAS on one thread; FreeCAD's worker leaves BLAS as it is): the scan read and "
             "the models loaded from the warm cache before the clock starts, one untimed first run (it fills the "
             "nearest-sample grids the models build on first use), then 3 timed runs against the same models, "
             "the fastest kept. "
             f"Times: medians over the cases of each case's fastest of {ROUNDS} alternating rounds; CPU time: the "
             "process's user and system time, all its threads, taken like the wall time (each case's least over "
             "its rounds; the wall time waits for the cores other jobs hold, the CPU time much less so); peak memory: "
             "each process's own maximum resident set (Python and libraries included). KISS-Matcher is given the "
             "stock pipeline's voxel (model diagonal / 50) in mm, noise bounds not clamped, then small_gicp "
             "point-to-plane ICP (clouds thinned at voxel / 4, correspondences within 0.4 voxel as in stock's "
             "ICP, up to 100 iterations).", ""]
    if load:
        lines += [f"Load average (1 min) on the {multiprocessing.cpu_count()} cores, shared with other jobs: "
                  + " at the start, ".join(f"{x:.1f}" for x in load) + " at the end: compare ratios, not "
                  "absolute times.", ""]
    if note:
        lines += [f"Note: {note}", ""]
    lines += ["| command | cases | method | n | success | median time (s) | time vs stock | time vs faster peer "
              "| median CPU time (s) | median peak memory (MB) | max peak memory (MB) |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
    for (command, family, method), s in stats.items():
        stock, faster = stats.get((command, family, STOCK)), faster_peer(family)
        versus_stock = f"{s['time'] / stock['time']:.2f}" if command == "match" and stock else "-"
        versus_faster = (f"{s['time'] / stats[(command, family, faster)]['time']:.2f}" if command == "match" and faster
                         else "-")
        lines.append(f"| {command} | {family} | {method} | {s['n']} | {s['success']:.0%} | {s['time']:.3f} | "
                     f"{versus_stock} | {versus_faster} | {s['cpu']:.3f} | {s['peak']:.0f} | {s['max_peak']:.0f} |")
    def slower(family: str, peer: str, target: float) -> None:
        """Note a miss where the family's warm match takes more than ``target`` x the peer's median time
        or finds less often."""
        warm, theirs = stats.get(("match", family, WARM)), stats.get(("match", family, peer))
        if warm and theirs and (warm["time"] > target * theirs["time"] or warm["success"] < theirs["success"]):
            missed.append(f"whole processes: {family}: warm match {warm['time']:.3f} s ({warm['time'] / theirs['time']:.2f} "
                          f"x {peer}'s {theirs['time']:.3f} s, target {target}), success "
                          f"{warm['success']:.0%} vs {theirs['success']:.0%}")

    missed = []
    for family in families:
        slower(family, STOCK, TIME_RATIO_TARGET)
        stock = stats.get(("match", family, STOCK))
        ours = max((stats[("match", family, m)]["max_peak"] for m in (COLD, WARM) if ("match", family, m) in stats),
                   default=0)
        if stock and ours > stock["max_peak"]:
            missed.append(f"whole processes: {family}: WorkCal match peak memory {ours:.0f} MB above stock Open3D's "
                          f"{stock['max_peak']:.0f} MB on the same files")
    faster = faster_peer(BUNNY_CLEAN)
    if faster:
        slower(BUNNY_CLEAN, faster, MATCH_RATIO_TARGET)
    calibrate_warm = stats.get(("calibrate", DEMO, WARM))
    if calibrate_warm and calibrate_warm["time"] >= CALIBRATE_PROCESS_S:
        missed.append(f"whole processes: warm calibrate of the demo scene {calibrate_warm['time']:.2f} s as a process "
                      f"(target under {CALIBRATE_PROCESS_S} s)")
    inside = stats.get(("calibrate", DEMO, IN_PROCESS))
    if inside and inside["time"] >= CALIBRATE_IN_PROCESS_S:
        missed.append(f"whole processes: warm calibrate of the demo scene {inside['time']:.2f} s in-process "
                      f"(target under {CALIBRATE_IN_PROCESS_S} s)")
    lines += ["", f"Targets: warm `match` at most {TIME_RATIO_TARGET} x stock Open3D's median time in every case "
              f"family, and on the clean bunny scans at most {MATCH_RATIO_TARGET} x the faster peer's, each with at "
              f"least its success rate; warm `calibrate` of the demo scene under {CALIBRATE_PROCESS_S} s as a process "
              f"and under {CALIBRATE_IN_PROCESS_S} s in-process; no WorkCal `match` process above stock Open3D's peak "
              "memory on the same files. "
              + ("Missed: " + "; ".join(m.removeprefix("whole processes: ") for m in missed) + "."
                 if missed else "All met."), ""]
    return "\n".join(lines), missed


def run(bunny: Path | None, seed: int, quick: bool, folder: Path, log=print) -> tuple[str, list]:
    """The whole-process section and the targets it missed (files and caches under ``folder``)."""
    started = os.getloadavg()[0]
    compile_bytecode()
    runs, peers = match_runs(folder, bunny, seed, quick, log)
    notes = ["Stanford bunny data not found: the bunny rows were skipped."] if bunny is None else []
    if KISS not in peers:
        notes.append("KISS-Matcher + small_gicp not installed under build/peers (`make bench` installs them): skipped.")
    runs += calibrate_runs(folder, seed, quick, log)
    return table(runs, peers, " ".join(notes) or None, (started, os.getloadavg()[0]))
