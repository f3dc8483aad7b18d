"""Scanner placement (the paper's Table 1 and Fig. 9): W from K scanner positions must be the same.

U = ^S X and V = ^S B change with every scanner position; W = V^-1 U = ^B X must not.  The paper
calibrated its 25 cm car from five positions and found Omega of W varying by about 1.5 degrees.
Each position here is a separate capture from ``scanner_ring`` (tripod jitter, own noise), and each
W is compared with the truth.  The study also checks the calibration's honesty: the predicted
displacement bound at the toolpath must cover the actual displacement of the calibrated toolpath.
"""
from __future__ import annotations

import numpy as np

from .. import frames
from ..errors import InputError
from ..parallel import Runner
from ..simulate.scanner import scanner_ring
from .common import (StudyResult, StudySettings, TARGET_OMEGA_SPREAD_DEG, TARGET_ROTATION_DEG,
                     TARGET_TRANSLATION_MM, accepted, calibrate_scan, fmt, fraction, new_figure, pose_columns,
                     prepared, score, spread, stat, target)

NAME = "placement"
TITLE = "Scanner placement: W from K scanner positions (paper Table 1, Fig. 9)"


def run(out_dir=None, *, positions: int | None = None, workpiece: str = "car", arc_deg: float = 360.0,
        settings: StudySettings = StudySettings(), progress=None, runner=None) -> StudyResult:
    """Calibrate one scene from ``positions`` scanner placements (default 5, quick 2) spread over
    ``arc_deg`` of azimuth around it; ``runner``: where (parallel.Runner; default here, one after the
    other)."""
    k = positions if positions is not None else (2 if settings.quick else 5)
    if k < 1:
        raise InputError(f"placement: need at least one scanner position, got {k}")
    say = progress or (lambda message: None)
    scene, truth = prepared(workpiece, settings.seed)
    ring = scanner_ring(scene, k, seed=settings.seed, arc_deg=arc_deg, **settings.scanner_settings())
    rows, table1 = [], []
    tasks = [(workpiece, settings, scanner, i) for i, scanner in enumerate(ring, start=1)]
    for row in (runner or Runner(workers=1)).map(_run, tasks):
        rows.append(row)
        say(f"{NAME} {row['position']}/{k}: azimuth {row['azimuth_deg']:.0f} deg, {row['status']}, Omega(W) "
            f"{fmt(row['W_omega_deg'])} deg, toolpath error {fmt(row['toolpath_error_mm'])} mm "
            f"(bound {fmt(row['toolpath_bound_mm'])} mm)")
    for name in ("U", "V", "W"):
        for row in rows:
            table1.append({"matrix": f"{name}_{row['position']}",
                           **{k.split("_", 1)[1]: v for k, v in row.items()
                              if k.startswith(f"{name}_") and k.split("_", 1)[1] in
                              ("phi_deg", "theta_deg", "psi_deg", "omega_deg")}})

    ok = accepted(rows)
    tolerance = settings.tolerance_mm
    summary = {
        "workpiece": workpiece, "positions": k, "arc_deg": arc_deg, "accepted": len(ok),
        "refused": sum(r["status"] != "ok" for r in rows),
        "true_W_omega_deg": frames.omega(truth.W),
        "omega_spread_deg": spread(rows, "W_omega_deg"),
        "omega_spread_accepted_deg": spread(ok, "W_omega_deg"),
        "U_omega_spread_deg": spread(rows, "U_omega_deg"),
        "V_omega_spread_deg": spread(rows, "V_omega_deg"),
        "max_rotation_error_deg": stat(rows, "rotation_error_deg", np.max),
        "max_translation_error_mm": stat(rows, "translation_error_mm", np.max),
        "max_rotation_error_accepted_deg": stat(ok, "rotation_error_deg", np.max),
        "max_translation_error_accepted_mm": stat(ok, "translation_error_mm", np.max),
        "max_toolpath_error_accepted_mm": stat(ok, "toolpath_error_mm", np.max),
        "median_toolpath_bound_accepted_mm": stat(ok, "toolpath_bound_mm", np.median),
        "within_bound_fraction": fraction(rows, "within_bound"),
        "within_bound_fraction_accepted": fraction(ok, "within_bound"),
        # The dangerous case: "ok" although the toolpath lands outside the tolerance.
        "accepted_but_wrong": sum(r["toolpath_error_mm"] > tolerance for r in ok),
    }
    targets = [
        target("every position accepted", len(ok) / k, 1.0, "", at_most=False),
        target("rotation error of W (accepted positions)", summary["max_rotation_error_accepted_deg"],
               TARGET_ROTATION_DEG, "deg"),
        target("translation error of W (accepted positions)", summary["max_translation_error_accepted_mm"],
               TARGET_TRANSLATION_MM, "mm"),
        target("spread of Omega of W across positions (accepted)", summary["omega_spread_accepted_deg"],
               TARGET_OMEGA_SPREAD_DEG, "deg"),
        target("predicted bound covers the actual toolpath error (accepted)",
               summary["within_bound_fraction_accepted"], 1.0, "", at_most=False),
        target("accepted calibrations off by more than the tolerance", summary["accepted_but_wrong"], 0, ""),
    ]
    result = StudyResult(NAME, TITLE, {**settings.to_dict(), "positions": k, "workpiece": workpiece,
                                       "arc_deg": arc_deg}, rows, summary, targets, tables={"table1": table1})
    if out_dir is not None:
        result.write(out_dir, figure(result))
    return result


def _run(workpiece: str, settings: StudySettings, scanner, position: int) -> dict:
    """One capture from ``scanner`` calibrated and scored (a task: runs in any process)."""
    scene, truth = prepared(workpiece, settings.seed)
    scan = scanner.scan(scene)
    result, error = calibrate_scan(scan, truth, settings, settings.seed + position)
    away = scanner.position - scanner.look_at
    row = {"position": position,
           "azimuth_deg": float(np.degrees(np.arctan2(away[1], away[0]))),
           "elevation_deg": float(np.degrees(np.arcsin(away[2] / np.linalg.norm(away)))),
           "distance_mm": float(np.linalg.norm(away)),
           "workpiece_points": int(scan.mask("workpiece").sum()),
           "reference_points": int(scan.mask("reference").sum()),
           **score(result, error, truth, scan),
           "rotation_bound_deg": None if result is None else result.uncertainty.get("rotation_bound_deg")}
    for name in ("U", "V", "W"):
        row.update(pose_columns(name, None if result is None else getattr(result, name)))
    row.update(pose_columns("U_true", scan.U))
    row.update(pose_columns("V_true", scan.V))
    return row


def table1_lines(result: StudyResult) -> list[str]:
    """The paper's Table 1: Euler angles and Omega of U, V and W per scanner position."""
    lines = [f"  {'':6} {'phi':>10} {'theta':>10} {'psi':>10} {'Omega':>10}   (deg)"]
    for r in result.tables["table1"]:
        lines.append(f"  {r['matrix']:6} " + " ".join(f"{fmt(r[k], 3):>10}"
                                                       for k in ("phi_deg", "theta_deg", "psi_deg", "omega_deg")))
    return lines


def figure(result: StudyResult):
    """Omega of U, V and W per position (U and V move, W stays), W's rotation error against its
    predicted bound, and the toolpath displacement against its predicted bound."""
    rows = result.rows
    fig = new_figure(14.0, 4.2)
    omegas, rotation, toolpath = fig.subplots(1, 3)
    x = np.array([r["position"] for r in rows])
    for name, marker in (("U", "s"), ("V", "^"), ("W", "o")):
        y = np.array([np.nan if r[f"{name}_omega_deg"] is None else r[f"{name}_omega_deg"] for r in rows])
        omegas.plot(x, y, marker=marker, linestyle="-" if name == "W" else ":", label=f"Omega of {name}")
    omegas.axhline(result.summary["true_W_omega_deg"], color="red", linestyle="--", linewidth=0.8, label="true W")
    omegas.set_xlabel("scanner position")
    omegas.set_ylabel("Omega (deg)")
    omegas.set_xticks(x)
    omegas.set_title(f"spread of Omega(W): {fmt(result.summary['omega_spread_deg'])} deg")
    omegas.legend(fontsize=8)
    _bars(rotation, rows, "rotation_error_deg", "rotation_bound_deg", "deg", "rotation of W")
    toolpath.axhline(result.settings["tolerance_mm"], color="black", linestyle=":", linewidth=0.8, label="tolerance")
    _bars(toolpath, rows, "toolpath_error_mm", "toolpath_bound_mm", "mm", "toolpath displacement")
    return fig


def _bars(ax, rows, actual_key, bound_key, unit, what):
    """Actual error and predicted bound side by side per position, log scale; refused positions hatched."""
    x = np.arange(len(rows))
    actual = np.array([np.nan if r[actual_key] is None else r[actual_key] for r in rows], dtype=float)
    bound = np.array([np.nan if r.get(bound_key) is None else r[bound_key] for r in rows], dtype=float)
    hatch = ["" if r["status"] == "ok" else "//" for r in rows]
    from matplotlib.patches import Patch

    for i in range(len(rows)):
        ax.bar(x[i] - 0.2, actual[i], 0.4, color="tab:red", hatch=hatch[i])
        ax.bar(x[i] + 0.2, bound[i], 0.4, color="tab:blue", hatch=hatch[i])
        if np.isnan(actual[i]):
            ax.annotate("no W", (x[i], 0.03), xycoords=("data", "axes fraction"), ha="center", fontsize=8,
                        color="tab:red")
    ax.set_yscale("log")
    ax.set_xticks(x, [str(r["position"]) for r in rows])
    ax.set_xlabel("scanner position (hatched: not accepted)")
    ax.set_ylabel(f"{what} ({unit})")
    ax.set_title(f"{what}: actual vs predicted")
    handles = [Patch(color="tab:red", label="actual error"), Patch(color="tab:blue", label="predicted bound")]
    ax.legend(handles=handles + ax.get_legend_handles_labels()[0], fontsize=8)
