"""Repeatability (the paper's Fig. 7): one scan pair matched N times, each a global search from scratch.

The paper repeated the matching of one pair of sets S-a, S-p ten times and found Omega of W varying
by about 1 degree.  Here each run calibrates the same capture with another seed (its own RANSAC
draws, refinement subsets and bootstrap), so the spread shows what the search itself adds; the
error against the true W shows whether the runs agree on the right answer.
"""
from __future__ import annotations

import numpy as np

from .. import frames
from ..errors import InputError
from ..parallel import Runner
from .common import (StudyResult, StudySettings, TARGET_ROTATION_DEG, TARGET_TRANSLATION_MM, accepted,
                     calibrate_scan, capture, fmt, fraction, new_figure, pose_columns, prepared, score, spread,
                     stat, target)

NAME = "repeatability"
TITLE = "Repeatability: one scan pair, N matches from scratch (paper Fig. 7)"
# Runs whose Omega lies this far from the median are shown in the overview panel only.
ZOOM_WINDOW_DEG = 1.0


def run(out_dir=None, *, n: int | None = None, workpiece: str = "car", settings: StudySettings = StudySettings(),
        progress=None, runner=None) -> StudyResult:
    """N calibrations (default 10, quick 3) of one simulated capture of ``workpiece`` (``runner``:
    where they run, parallel.Runner; default here, one after the other)."""
    n = n if n is not None else (3 if settings.quick else 10)
    if n < 1:
        raise InputError(f"repeatability: need at least one match, got n = {n}")
    say = progress or (lambda message: None)
    _, truth = prepared(workpiece, settings.seed)
    scan = capture(workpiece, settings)
    rows = []
    tasks = [(workpiece, settings, settings.seed + 1000 * (i + 1)) for i in range(n)]
    for i, row in enumerate((runner or Runner(workers=1)).map(_run, tasks), start=1):
        rows.append({"run": i, **row})
        say(f"{NAME} {i}/{n}: {row['status']}, Omega(W) {fmt(row['W_omega_deg'])} deg, "
            f"rotation error {fmt(row['rotation_error_deg'])} deg")

    ok = accepted(rows)
    true_omega = frames.omega(truth.W)
    summary = {
        "workpiece": workpiece, "runs": n, "accepted": len(ok),
        "scan_points": len(scan.points), "workpiece_points": int(scan.mask("workpiece").sum()),
        "reference_points": int(scan.mask("reference").sum()),
        "true_omega_deg": true_omega,
        "omega_mean_deg": stat(rows, "W_omega_deg", np.mean),
        "omega_std_deg": stat(rows, "W_omega_deg", np.std),
        "omega_spread_deg": spread(rows, "W_omega_deg"),
        "omega_spread_accepted_deg": spread(ok, "W_omega_deg"),
        "max_rotation_error_deg": stat(rows, "rotation_error_deg", np.max),
        "max_translation_error_mm": stat(rows, "translation_error_mm", np.max),
        "max_toolpath_error_mm": stat(rows, "toolpath_error_mm", np.max),
        "max_rotation_error_accepted_deg": stat(ok, "rotation_error_deg", np.max),
        "max_translation_error_accepted_mm": stat(ok, "translation_error_mm", np.max),
        "within_bound_fraction": fraction(rows, "within_bound"),
    }
    targets = [
        target("every run accepted", len(ok) / n, 1.0, "", at_most=False),
        target("rotation error of W (all runs)", summary["max_rotation_error_deg"], TARGET_ROTATION_DEG, "deg"),
        target("translation error of W (all runs)", summary["max_translation_error_mm"], TARGET_TRANSLATION_MM, "mm"),
    ]
    result = StudyResult(NAME, TITLE, {**settings.to_dict(), "n": n, "workpiece": workpiece,
                                       "scanner": scan.scanner.to_dict()}, rows, summary, targets)
    if out_dir is not None:
        result.write(out_dir, figure(result))
    return result


def _run(workpiece: str, settings: StudySettings, seed: int) -> dict:
    """One run: the capture calibrated from scratch with ``seed`` (a task: runs in any process)."""
    _, truth = prepared(workpiece, settings.seed)
    scan = capture(workpiece, settings)
    result, error = calibrate_scan(scan, truth, settings, seed)
    return {"seed": seed, **score(result, error, truth, scan), **pose_columns("W", None if result is None else result.W)}


def figure(result: StudyResult):
    """Left: Omega of W per 0.5 deg bin, as in the paper's Fig. 7; right: the runs near the median,
    finely binned, with the true Omega."""
    omegas = np.array([r["W_omega_deg"] for r in result.rows if r["W_omega_deg"] is not None])
    true_omega = result.summary["true_omega_deg"]
    fig = new_figure()
    overview, zoom = fig.subplots(1, 2)
    if len(omegas):
        lo, hi = np.floor(min(omegas.min(), true_omega) * 2) / 2, np.ceil(max(omegas.max(), true_omega) * 2) / 2
        overview.hist(omegas, bins=np.arange(lo, hi + 0.5, 0.5) if hi > lo else [lo - 0.5, lo + 0.5],
                      color="tab:blue", edgecolor="black")
        near = omegas[np.abs(omegas - np.median(omegas)) <= ZOOM_WINDOW_DEG]
        offsets = 1000 * (near - true_omega)
        zoom.hist(offsets, bins=max(5, min(20, len(near))), color="tab:green", edgecolor="black")
        zoom.axvline(0.0, color="red", linestyle="--", label="true Omega")
        zoom.legend(loc="upper right")
    overview.axvline(true_omega, color="red", linestyle="--")
    overview.set_xlabel("principal-axis rotation Omega of W (deg), 0.5 deg bins")
    overview.set_ylabel("number of matches")
    overview.set_title(f"{result.summary['runs']} matches of one scan pair")
    zoom.set_xlabel("Omega of W minus true Omega (millidegrees)")
    zoom.set_ylabel("number of matches")
    zoom.set_title(f"runs within {ZOOM_WINDOW_DEG:g} deg of the median")
    return fig
