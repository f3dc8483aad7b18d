"""Point count: accuracy of W against the size of the point clouds (the paper's section 4 question).

One capture is subsampled at random to a given number of points per region (workpiece and
reference each), several times per size, and each subsample is calibrated.  With regions "auto"
the whole scan is thinned by the same fraction instead, so the region finder works on it too.
The predicted bound must grow as the points thin out, and still cover the actual error.
"""
from __future__ import annotations

import numpy as np

from .. import pointops
from ..errors import InputError
from ..parallel import Runner
from .common import (StudyResult, StudySettings, TARGET_ROTATION_DEG, TARGET_TRANSLATION_MM, accepted,
                     calibrate_scan, capture, fmt, fraction, new_figure, pose_columns, prepared, score, stat,
                     target)

NAME = "point-count"
TITLE = "Point count: accuracy of W against the number of scan points per region"
SIZES = (250, 500, 1000, 2000, 5000, 10000, 20000, None)  # None: every point of the capture
QUICK_SIZES = (500, None)


def run(out_dir=None, *, sizes=None, n: int | None = None, workpiece: str = "car",
        settings: StudySettings = StudySettings(), progress=None, runner=None) -> StudyResult:
    """``n`` random subsamples (default 3, quick 1) at each size in ``sizes`` (points per region);
    ``runner``: where they are calibrated (parallel.Runner; default here, one after the other)."""
    sizes = tuple(sizes) if sizes is not None else (QUICK_SIZES if settings.quick else SIZES)
    n = n if n is not None else (1 if settings.quick else 3)
    if n < 1 or not sizes or any(s is not None and s < 1 for s in sizes):
        raise InputError(f"point-count: need n >= 1 and sizes >= 1 point, got n = {n}, sizes = {sizes}")
    say = progress or (lambda message: None)
    scan = capture(workpiece, settings)
    masks = {role: np.flatnonzero(scan.mask(role)) for role in ("workpiece", "reference")}
    rng = np.random.default_rng(settings.seed)  # the subsamples drawn here, in order, whatever runs them
    tasks = [(workpiece, settings, size, repeat, _subsample(scan, masks, size, settings.regions, rng))
             for size in sizes for repeat in range(1, n + 1)]
    rows = []
    for row in (runner or Runner(workers=1)).map(_run, tasks):
        rows.append(row)
        say(f"{NAME} {row['points_per_region']} points, run {row['repeat']}/{n}: {row['status']}, rotation error "
            f"{fmt(row['rotation_error_deg'])} deg, toolpath error {fmt(row['toolpath_error_mm'])} mm "
            f"(bound {fmt(row['toolpath_bound_mm'])} mm)")

    by_size = []
    for size in dict.fromkeys(r["points_per_region"] for r in rows):
        group = [r for r in rows if r["points_per_region"] == size]
        ok = accepted(group)
        by_size.append({
            "points_per_region": size, "runs": len(group), "accepted": len(ok),
            "workpiece_points": int(np.median([r["workpiece_points"] for r in group])),
            "reference_points": int(np.median([r["reference_points"] for r in group])),
            "median_rotation_error_deg": stat(group, "rotation_error_deg", np.median),
            "max_rotation_error_deg": stat(group, "rotation_error_deg", np.max),
            "median_translation_error_mm": stat(group, "translation_error_mm", np.median),
            "median_toolpath_error_mm": stat(group, "toolpath_error_mm", np.median),
            "max_toolpath_error_mm": stat(group, "toolpath_error_mm", np.max),
            "median_toolpath_bound_mm": stat(group, "toolpath_bound_mm", np.median),
            "within_bound_fraction": fraction(group, "within_bound"),
            "within_bound_fraction_accepted": fraction(ok, "within_bound"),
        })
    full = [r for r in rows if r["points_per_region"] == by_size[-1]["points_per_region"]]
    ok = accepted(rows)
    summary = {
        "workpiece": workpiece, "sizes": len(by_size), "runs_per_size": n, "accepted": len(ok), "runs": len(rows),
        "largest_size": by_size[-1]["points_per_region"],
        "max_rotation_error_largest_deg": stat(full, "rotation_error_deg", np.max),
        "max_translation_error_largest_mm": stat(full, "translation_error_mm", np.max),
        "smallest_size_all_accepted_within_tolerance": _smallest_good(by_size, rows, settings.tolerance_mm),
        "within_bound_fraction_accepted": fraction(ok, "within_bound"),
        "accepted_but_wrong": sum(r["toolpath_error_mm"] > settings.tolerance_mm for r in ok),
    }
    targets = [
        target(f"rotation error of W at {summary['largest_size']} points", summary["max_rotation_error_largest_deg"],
               TARGET_ROTATION_DEG, "deg"),
        target(f"translation error of W at {summary['largest_size']} points",
               summary["max_translation_error_largest_mm"], TARGET_TRANSLATION_MM, "mm"),
        target("predicted bound covers the actual toolpath error (accepted, all sizes)",
               summary["within_bound_fraction_accepted"], 1.0, "", at_most=False),
        target("accepted calibrations off by more than the tolerance", summary["accepted_but_wrong"], 0, ""),
    ]
    result = StudyResult(NAME, TITLE, {**settings.to_dict(), "n": n, "workpiece": workpiece,
                                       "sizes": ["all" if s is None else s for s in sizes],
                                       "scanner": scan.scanner.to_dict()},
                         rows, summary, targets, tables={"by_size": by_size})
    if out_dir is not None:
        result.write(out_dir, figure(result))
    return result


def _run(workpiece: str, settings: StudySettings, size, repeat: int, keep) -> dict:
    """One subsample calibrated and scored (a task: runs in any process)."""
    _, truth = prepared(workpiece, settings.seed)
    scan = capture(workpiece, settings)
    result, error = calibrate_scan(scan, truth, settings, settings.seed + repeat, keep=keep)
    return {"points_per_region": "all" if size is None else size, "repeat": repeat,
            "workpiece_points": int(scan.mask("workpiece")[keep].sum()),
            "reference_points": int(scan.mask("reference")[keep].sum()),
            "scan_points": len(keep), **score(result, error, truth, scan),
            **pose_columns("W", None if result is None else result.W)}


def _subsample(scan, masks, size, regions, rng) -> np.ndarray:
    """Indices of the points kept: ``size`` per region (truth regions), or the whole scan thinned by
    the fraction that leaves ``size`` workpiece points (automatic regions)."""
    if size is None:
        return np.arange(len(scan.points))
    if regions == "truth":
        keep = [pointops.random_subset(idx, size, rng) for idx in masks.values()]
        return np.sort(np.concatenate(keep))
    share = min(1.0, size / max(1, len(masks["workpiece"])))
    return np.sort(rng.choice(len(scan.points), max(1, int(round(share * len(scan.points)))), replace=False))


def _smallest_good(by_size, rows, tolerance):
    """The smallest size at which every run was accepted and landed the toolpath within the tolerance."""
    good = [s["points_per_region"] for s in by_size
            if s["accepted"] == s["runs"] and all(r["toolpath_error_mm"] <= tolerance for r in rows
                                                   if r["points_per_region"] == s["points_per_region"])]
    return good[0] if good else None


def figure(result: StudyResult):
    """Rotation error and toolpath displacement against points per region (log-log), every run as a
    dot, the median as a line, and the predicted bound."""
    by_size = result.tables["by_size"]
    x = np.array([s["workpiece_points"] for s in by_size], dtype=float)
    fig = new_figure()
    rotation, toolpath = fig.subplots(1, 2)
    for ax, key, label in ((rotation, "rotation_error_deg", "rotation error of W (deg)"),
                           (toolpath, "toolpath_error_mm", "largest toolpath displacement (mm)")):
        for r in result.rows:
            if r[key] is not None:
                ax.scatter(r["workpiece_points"], max(r[key], 1e-6), s=14, alpha=0.6,
                           color="tab:blue" if r["status"] == "ok" else "tab:red")
        medians = [np.nan if s[f"median_{key}"] is None else s[f"median_{key}"] for s in by_size]
        ax.plot(x, medians, color="tab:blue", label="median error (red dots: not accepted)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("workpiece points used")
        ax.set_ylabel(label)
    bound = [np.nan if s["median_toolpath_bound_mm"] is None else s["median_toolpath_bound_mm"] for s in by_size]
    toolpath.plot(x, bound, color="tab:orange", linestyle="--", label="median predicted bound")
    toolpath.axhline(result.settings["tolerance_mm"], color="black", linestyle=":", linewidth=0.8, label="tolerance")
    rotation.axhline(TARGET_ROTATION_DEG, color="black", linestyle=":", linewidth=0.8, label="target")
    rotation.set_title("rotation error of W")
    toolpath.set_title("displacement at the toolpath")
    rotation.legend(fontsize=8)
    toolpath.legend(fontsize=8)
    return fig
