"""Object size: the 2 cm figurine against the 25 cm car (the paper's A1 and A2).

The paper found that below about 2 cm the spread of Omega exceeds 1 degree (about 0.2 mm at the
surface), while 10-50 cm objects calibrate well.  Each object stands in its own scene and is
scanned from K positions by the same scanner (zoomed to fit workpiece and reference, so the small
object gets few points, as in the paper's Fig. 5).  Errors are reported absolute and relative to
the object's size (largest surface displacement / model diagonal).
"""
from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..parallel import Runner
from ..simulate.scanner import scanner_ring
from .common import (StudyResult, StudySettings, TARGET_ROTATION_DEG, TARGET_TRANSLATION_MM, accepted,
                     calibrate_scan, fmt, fraction, new_figure, pose_columns, prepared, score, spread, stat, target)

NAME = "object-size"
TITLE = "Object size: 2 cm figurine against 25 cm car"
WORKPIECES = ("figurine", "car")


def run(out_dir=None, *, positions: int | None = None, workpieces=WORKPIECES, settings: StudySettings = StudySettings(),
        progress=None, runner=None) -> StudyResult:
    """Each workpiece calibrated from ``positions`` scanner placements (default 5, quick 2); ``runner``:
    where (parallel.Runner; default here, one after the other)."""
    k = positions if positions is not None else (2 if settings.quick else 5)
    if k < 1 or not workpieces:
        raise InputError(f"object-size: need at least one workpiece and one position, got {workpieces}, {k}")
    say = progress or (lambda message: None)
    tasks = []
    for workpiece in workpieces:
        scene, _ = prepared(workpiece, settings.seed)
        ring = scanner_ring(scene, k, seed=settings.seed, **settings.scanner_settings())
        tasks += [(workpiece, settings, scanner, i) for i, scanner in enumerate(ring, start=1)]
    rows = []
    for row in (runner or Runner(workers=1)).map(_run, tasks):
        rows.append(row)
        say(f"{NAME} {row['workpiece']} {row['position']}/{k}: {row['workpiece_points']} points, {row['status']}, "
            f"rotation error {fmt(row['rotation_error_deg'])} deg, surface error {fmt(row['surface_error_mm'])} mm")

    by_object = []
    for workpiece in workpieces:
        group = [r for r in rows if r["workpiece"] == workpiece]
        ok = accepted(group)
        by_object.append({
            "workpiece": workpiece, "diagonal_mm": group[0]["diagonal_mm"], "positions": len(group),
            "accepted": len(ok), "median_workpiece_points": float(np.median([r["workpiece_points"] for r in group])),
            "max_rotation_error_deg": stat(group, "rotation_error_deg", np.max),
            "max_rotation_error_accepted_deg": stat(ok, "rotation_error_deg", np.max),
            "max_translation_error_accepted_mm": stat(ok, "translation_error_mm", np.max),
            "max_surface_error_accepted_mm": stat(ok, "surface_error_mm", np.max),
            "max_relative_surface_error_accepted": stat(ok, "relative_surface_error", np.max),
            "omega_spread_accepted_deg": spread(ok, "W_omega_deg"),
            "median_toolpath_bound_mm": stat(group, "toolpath_bound_mm", np.median),
            "within_bound_fraction_accepted": fraction(ok, "within_bound"),
        })
    summary = {"positions": k, "workpieces": len(workpieces)}
    for entry in by_object:
        for key in ("accepted", "max_rotation_error_accepted_deg", "max_translation_error_accepted_mm",
                    "max_surface_error_accepted_mm", "max_relative_surface_error_accepted",
                    "omega_spread_accepted_deg", "median_toolpath_bound_mm"):
            summary[f"{entry['workpiece']}_{key}"] = entry[key]
    ok = accepted(rows)
    summary["within_bound_fraction_accepted"] = fraction(ok, "within_bound")
    summary["accepted_but_wrong"] = sum(r["toolpath_error_mm"] > settings.tolerance_mm for r in ok)
    targets = []
    if "car" in workpieces:
        targets += [target("car: rotation error of W (accepted)", summary["car_max_rotation_error_accepted_deg"],
                           TARGET_ROTATION_DEG, "deg"),
                    target("car: translation error of W (accepted)", summary["car_max_translation_error_accepted_mm"],
                           TARGET_TRANSLATION_MM, "mm")]
    targets += [target("predicted bound covers the actual toolpath error (accepted)",
                       summary["within_bound_fraction_accepted"], 1.0, "", at_most=False),
                target("accepted calibrations off by more than the tolerance", summary["accepted_but_wrong"], 0, "")]
    result = StudyResult(NAME, TITLE, {**settings.to_dict(), "positions": k, "workpieces": list(workpieces)},
                         rows, summary, targets, tables={"by_object": by_object})
    if out_dir is not None:
        result.write(out_dir, figure(result))
    return result


def _run(workpiece: str, settings: StudySettings, scanner, position: int) -> dict:
    """One capture from ``scanner`` calibrated and scored (a task: runs in any process)."""
    scene, truth = prepared(workpiece, settings.seed)
    scan = scanner.scan(scene)
    result, error = calibrate_scan(scan, truth, settings, settings.seed + position)
    row = {"workpiece": workpiece, "diagonal_mm": truth.diagonal, "position": position,
           "workpiece_points": int(scan.mask("workpiece").sum()),
           "reference_points": int(scan.mask("reference").sum()),
           **score(result, error, truth, scan), **pose_columns("W", None if result is None else result.W)}
    row["relative_surface_error"] = (None if row["surface_error_mm"] is None
                                     else row["surface_error_mm"] / truth.diagonal)
    return row


def figure(result: StudyResult):
    """Per object: rotation error of W and largest surface displacement (absolute and relative to
    the object's diagonal), one dot per scanner position."""
    fig = new_figure(14.0, 4.2)
    axes = fig.subplots(1, 3)
    names = [o["workpiece"] for o in result.tables["by_object"]]
    labels = [f"{o['workpiece']}\n({o['diagonal_mm']:.0f} mm, ~{o['median_workpiece_points']:.0f} pts)"
              for o in result.tables["by_object"]]
    for ax, key, ylabel in zip(axes, ("rotation_error_deg", "surface_error_mm", "relative_surface_error"),
                               ("rotation error of W (deg)", "largest surface displacement (mm)",
                                "surface displacement / object diagonal")):
        for j, name in enumerate(names):
            for r in result.rows:
                if r["workpiece"] == name and r[key] is not None:
                    ax.scatter(j, max(r[key], 1e-7), color="tab:blue" if r["status"] == "ok" else "tab:red",
                               alpha=0.7)
            missing = sum(r["workpiece"] == name and r[key] is None for r in result.rows)
            if missing:
                ax.annotate(f"{missing} without W", (j, 0.02), xycoords=("data", "axes fraction"), ha="center",
                            fontsize=8, color="tab:red")
        ax.set_yscale("log")
        ax.set_xticks(range(len(names)), labels)
        ax.set_xlim(-0.6, len(names) - 0.4)
        ax.set_ylabel(ylabel)
    axes[0].axhline(TARGET_ROTATION_DEG, color="black", linestyle=":", linewidth=0.8)
    axes[1].axhline(result.settings["tolerance_mm"], color="black", linestyle=":", linewidth=0.8)
    axes[0].set_title("rotation error (blue: accepted, red: refused)")
    axes[1].set_title("displacement at the surface")
    axes[2].set_title("relative to size")
    return fig
