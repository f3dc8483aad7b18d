"""The calibration report: one self-contained HTML page and a JSON file with the same numbers.

report.html has inline CSS, its pictures embedded as base64 PNG and inline SVG (no scripts, no links, nothing
fetched), so it can be mailed or archived on its own.  report.json is ``CalibrationResult.to_dict()``
with the regions as point counts (it loads back with ``CalibrationResult.from_json``) plus the
deviation statistics and the studies.

Both are built completely in memory and then written atomically, report.html last: a failure
leaves the previous report (or none), never half a file.

The deviation map shows the workpiece scan region against its model X-A placed by U: signed
distance to the model surface, positive outside (clay added), negative inside (clay carved), in the
colours of ``deviation.DeviationScale`` (the same as FreeCAD's deviation map).  Given the whole scan,
the report also draws both regions in it; in every view the points of a region its placed model
leaves unexplained are drawn over the rest in OFF_MODEL_COLOUR, and the regions section says how many
there are, where they lie and what to change.
"""
from __future__ import annotations

import base64
import datetime
import html
import json
import math
from pathlib import Path

import numpy as np

from . import frames, picture
from .atomic import atomic_write_text
from .deviation import BEYOND_ADDED, BEYOND_REMOVED, NO_SURFACE, DeviationScale, deviation_stats, signed_deviations
from .errors import OutputError
from .result import AMBIGUOUS, CHOSEN, FAILED, OFF_MODEL_KEYS, OK, CalibrationResult, choice_words

REPORT_FORMAT = "workcal-report"
HTML_NAME, JSON_NAME = "report.html", "report.json"
STUDIES_HTML_NAME = "studies.html"
PERCENTILES = (50, 90, 95, 99)
HISTOGRAM_BINS = 60
# Points drawn in a deviation view (a random subset of larger regions, seeded).
MAX_MAP_POINTS = 60000
MAX_OUTLINE_POINTS = 20000
MODEL_GREY = (0.82, 0.82, 0.82)  # the model's own points behind the scan's
# A region's points off its placed model: magenta, which neither the deviation scale (green, yellow to
# red, cyan to blue, their dark ends, grey) nor the regions' own colours use; drawn larger, over the rest.
OFF_MODEL_COLOUR = (0.95, 0.0, 0.95)
OFF_MODEL_DOT = 3
REGION_COLOURS = {"workpiece": (1.0, 0.62, 0.3), "reference": (0.35, 0.65, 1.0)}  # the 3D view's, lighter
# The two views of a drawing: (horizontal, vertical, depth) principal axes, and their titles.
VIEWS = (((0, 1, 2), "view along the shortest axis"), ((0, 2, 1), "view along the middle axis"))

STATUS_TEXT = {
    OK: ("OK", "W can be used: both matches and every quality gate passed."),
    AMBIGUOUS: ("AMBIGUOUS", "W is not sure: the part is symmetric, another pose fits almost as well, or the scan "
                             "leaves part of the view unexplained (see the reasons). Check before use."),
    FAILED: ("FAILED", "Do not use W: the calibration failed its checks."),
    CHOSEN: ("OK (CHOSEN)", "W can be used: the scan could not tell several poses apart and a person chose one."),
}

# The CSS class of each status's banner: one name each ("ok (chosen)" as it is would be two classes).
STATUS_CLASS = {OK: "ok", AMBIGUOUS: "ambiguous", FAILED: "failed", CHOSEN: "chosen"}

CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Helvetica,Arial,sans-serif;margin:0 auto;max-width:1100px;
padding:1.2em;color:#222;line-height:1.4}
h1{font-size:1.6em;margin:.2em 0}h2{font-size:1.25em;border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:1.6em}
h3{font-size:1.05em;margin:1em 0 .4em}
table{border-collapse:collapse;margin:.4em 0 1em}td,th{border:1px solid #ccc;padding:.25em .6em;text-align:right;
vertical-align:top}th{background:#f2f2f2}td.l,th.l{text-align:left}
table.matrix td{font-family:ui-monospace,Menlo,Consolas,monospace;border:none;padding:.1em .7em}
table.matrix{border-left:2px solid #444;border-right:2px solid #444}
.banner{padding:.8em 1em;border-radius:6px;margin:1em 0;color:#fff}.banner b{font-size:1.3em}
.ok,.chosen{background:#2e7d32}.ambiguous{background:#ef8f00}.failed{background:#c62828}
.pass{color:#2e7d32;font-weight:bold}.miss{color:#c62828;font-weight:bold}
.poses{display:flex;flex-wrap:wrap;gap:1.5em}.note{color:#666;font-size:.9em}
img{max-width:100%;border:1px solid #ddd}code{font-family:ui-monospace,Menlo,Consolas,monospace}
"""


def write_report(calibration: CalibrationResult, out_dir, *, workpiece_points=None, workpiece_model=None,
                 scan_points=None, studies=(), title: str = "WorkCal calibration",
                 deviation_scale: DeviationScale | None = None, robot=None, reach=None) -> dict:
    """Write report.html and report.json into ``out_dir`` (created if missing); return their paths.

    workpiece_points: the workpiece region of the scan (N x 3, mm, in S) for the deviation map;
    workpiece_model: X-A (Cloud or SurfaceModel); scan_points: the whole scan (mm, in S) the result's
    region indices point into, for the views of both regions and the points off their models;
    studies: StudyResults (or their dicts) whose summaries, targets and figures are added;
    deviation_scale: the map's colours (default: the calibration's tolerance); robot (robots.Robot) and
    reach (its robots.reach.ReachReport for the calibrated program): the joint margins along the program.
    Raises OutputError if the folder cannot be written.
    """
    out = Path(out_dir)
    scale = deviation_scale or DeviationScale.for_tolerance(calibration.tolerance_mm)
    deviations = deviation_map(calibration, workpiece_points, workpiece_model)
    deviation = deviation_summary(deviations, calibration.tolerance_mm) if deviations is not None else None
    if deviation is not None:
        deviation["colour_scale"] = scale.to_dict()
    study_dicts = [_study_dict(s) for s in studies]
    generated = datetime.datetime.now().astimezone().isoformat(timespec="seconds")

    data = calibration.to_dict(region_indices=False)
    data["deviation"] = deviation
    data["studies"] = study_dicts
    if robot is not None and reach is not None:
        data["reach"] = reach_summary(robot, reach)
    data["report"] = {"format": REPORT_FORMAT, "version": 1, "title": title, "generated": generated,
                      "files": {"html": HTML_NAME, "json": JSON_NAME}}
    images = {}
    if deviations is not None:
        off = _workpiece_off_model(calibration, len(deviations))
        images["views"] = deviation_views(deviations, calibration, workpiece_points, workpiece_model, scale, off)
        images["legend"] = legend_html(scale, int(off.sum()))
        images["histogram"] = histogram_svg(deviations, scale)
    images["regions"] = region_views(calibration, scan_points)
    page = _page(title, generated, _calibration_body(calibration, deviation, images, workpiece_points is not None
                                                     and workpiece_model is not None)
                 + (_reach_html(robot, reach) if robot is not None and reach is not None else "")
                 + _studies_body(studies, study_dicts))
    paths = {"html": out / HTML_NAME, "json": out / JSON_NAME}
    _write(out, [(paths["json"], json.dumps(data, indent=2, allow_nan=True) + "\n"), (paths["html"], page)])
    return paths


def write_study_report(studies, out_dir, title: str = "WorkCal studies") -> dict:
    """A self-contained studies.html with each study's summary, targets and figure."""
    out = Path(out_dir)
    study_dicts = [_study_dict(s) for s in studies]
    generated = datetime.datetime.now().astimezone().isoformat(timespec="seconds")
    path = out / STUDIES_HTML_NAME
    _write(out, [(path, _page(title, generated, _studies_body(studies, study_dicts)))])
    return {"html": path}


# --- deviation map -----------------------------------------------------------------------------------

def deviation_map(calibration: CalibrationResult, workpiece_points, workpiece_model):
    """Signed deviation (mm) of each workpiece scan point from X-A placed by U, or None when the
    report has no scan points, no model, or no U to place it with."""
    if workpiece_points is None or workpiece_model is None or calibration.U is None:
        return None
    points = np.asarray(workpiece_points, dtype=float).reshape(-1, 3)
    if len(points) == 0:
        return None
    return signed_deviations(points, workpiece_model, calibration.U)


def deviation_summary(deviations: np.ndarray, tolerance_mm: float) -> dict:
    """deviation_stats plus percentiles of |deviation|, the shares above and below the tolerance band
    (added and removed material) and the histogram the report draws."""
    stats = deviation_stats(deviations, tolerance_mm)
    d = deviations[np.isfinite(deviations)]
    if len(d):
        stats["percentiles_abs_mm"] = {str(q): float(np.percentile(np.abs(d), q)) for q in PERCENTILES}
        stats["above_tolerance_pct"] = float(100 * np.mean(d > tolerance_mm))
        stats["below_tolerance_pct"] = float(100 * np.mean(d < -tolerance_mm))
        counts, edges = np.histogram(d, bins=HISTOGRAM_BINS)
        stats["histogram"] = {"edges_mm": edges.tolist(), "counts": counts.tolist()}
    return stats


def _workpiece_off_model(calibration: CalibrationResult, count: int) -> np.ndarray:
    """Which of the workpiece region's ``count`` points (in the order of its indices) lie off its placed
    model; none when the result does not say, or the points given are not its region's."""
    region, off = (calibration.regions.get(key) for key in ("workpiece", OFF_MODEL_KEYS["workpiece"]))
    if region is None or off is None or len(region) != count:
        return np.zeros(count, bool)
    return np.isin(region, off)


def _view_signs(h: int, v: int, depth: int, side: float) -> np.ndarray:
    """The signs that turn principal-axis coordinates into a view along ``depth`` from its ``side``
    (+1, -1): turning the view around flips the horizontal axis with the depth, so it stays a view, not
    a mirror image."""
    sign = np.ones(3)
    sign[[h, depth]] = side
    if (h, v, depth) == (0, 2, 1):  # (x, z) seen along +y is a left-handed view: turn it around
        sign[h] *= -1
    return sign


def deviation_views(deviations, calibration, workpiece_points, workpiece_model, scale: DeviationScale,
                    off_model=None) -> list:
    """Two orthographic views of the workpiece in its model frame (along the model's principal axes:
    seen from above and from the side), scan points coloured by signed deviation over the model in
    grey, those ``off_model`` (a mask, or None) over them in OFF_MODEL_COLOUR: one dict per view with
    its title, axes, PNG bytes and the length of its scale bar (mm)."""
    points = frames.apply(frames.invert(calibration.U), np.asarray(workpiece_points, dtype=float).reshape(-1, 3))
    model_points = getattr(workpiece_model, "points", None)
    model_points = points if model_points is None else np.asarray(model_points)
    centre = model_points.mean(axis=0)
    _, _, axes = np.linalg.svd(model_points - centre, full_matrices=False)  # rows: longest axis first
    if np.linalg.det(axes) < 0:
        axes[2] *= -1  # right-handed, so that no view is a mirror image
    rng = np.random.default_rng(0)
    keep = np.arange(len(points)) if len(points) <= MAX_MAP_POINTS else rng.choice(len(points), MAX_MAP_POINTS, False)
    local, d = (points[keep] - centre) @ axes.T, deviations[keep]
    off = np.zeros(len(keep), bool) if off_model is None else np.asarray(off_model, bool)[keep]
    outline = model_points if len(model_points) <= MAX_OUTLINE_POINTS else \
        model_points[rng.choice(len(model_points), MAX_OUTLINE_POINTS, False)]
    outline = (outline - centre) @ axes.T
    colours = picture.to_bytes(scale.colours(d))
    views = []
    for (h, v, depth), title in VIEWS:
        # Look from the side the scanner saw (the scan points' side of the part).
        sign = _view_signs(h, v, depth, 1.0 if local[:, depth].mean() >= 0 else -1.0)
        seen, model = local * sign, outline * sign
        view = picture.View(np.vstack([model[:, [h, v]], seen[:, [h, v]]]))
        image = picture.canvas(view.width, view.height)
        view.draw(image, model[:, [h, v]], picture.to_bytes(MODEL_GREY))
        order = np.argsort(seen[:, depth])  # painter's order: nearest to the viewer drawn last
        view.draw(image, seen[order][:, [h, v]], colours[order], dot=2)
        view.draw(image, seen[off][:, [h, v]], picture.to_bytes(OFF_MODEL_COLOUR), dot=OFF_MODEL_DOT)
        picture.frame(image)
        bar = view.scale_bar(image)
        views.append({"title": title, "horizontal": h + 1, "vertical": v + 1, "png": picture.png(image),
                      "scale_bar_mm": bar})
    return views


def region_views(calibration: CalibrationResult, scan_points) -> list:
    """Two orthographic views of both regions in the scan (along the principal axes of their points,
    from the scanner's side), each region in its colour (REGION_COLOURS) and its points off its placed
    model over them in OFF_MODEL_COLOUR: one dict per view with its title, PNG bytes and the length of
    its scale bar (mm).  No views without the scan, or when the result's regions do not fit in it (the scan
    changed since): then there is nothing right to draw."""
    if scan_points is None:
        return []
    scan_points = np.asarray(scan_points, dtype=float).reshape(-1, 3)
    rng = np.random.default_rng(0)
    parts, off = [], []
    for role, colour in REGION_COLOURS.items():
        idx, off_idx = (calibration.regions.get(key) for key in (role, OFF_MODEL_KEYS[role]))
        if idx is None or len(idx) == 0:
            continue
        if max(idx.max(), off_idx.max() if off_idx is not None and len(off_idx) else 0) >= len(scan_points):
            return []
        if len(idx) > MAX_MAP_POINTS:
            idx = rng.choice(idx, MAX_MAP_POINTS, replace=False)
        parts.append((scan_points[idx], np.broadcast_to(picture.to_bytes(colour), (len(idx), 3))))
        if off_idx is not None and len(off_idx):
            off.append(scan_points[off_idx if len(off_idx) <= MAX_MAP_POINTS else
                                   rng.choice(off_idx, MAX_MAP_POINTS, replace=False)])
    if not parts:
        return []
    points, colours = np.vstack([p for p, _ in parts]), np.vstack([c for _, c in parts])
    off_points = np.vstack(off) if off else np.empty((0, 3))
    centre = points.mean(axis=0)
    _, _, axes = np.linalg.svd(points - centre, full_matrices=False)  # rows: longest axis first
    if np.linalg.det(axes) < 0:
        axes[2] *= -1  # right-handed, so that no view is a mirror image
    matches = (calibration.workpiece, calibration.reference)
    scanner = next((np.asarray(m.viewpoint["position_mm"], float) for m in matches
                    if m is not None and "position_mm" in (m.viewpoint or {})), np.zeros(3))
    toward_scanner = (scanner - centre) @ axes.T
    local, off_local = (points - centre) @ axes.T, (off_points - centre) @ axes.T
    views = []
    for (h, v, depth), title in VIEWS:
        sign = _view_signs(h, v, depth, 1.0 if toward_scanner[depth] >= 0 else -1.0)
        seen, seen_off = local * sign, off_local * sign
        view = picture.View(seen[:, [h, v]])
        image = picture.canvas(view.width, view.height)
        order = np.argsort(seen[:, depth])  # painter's order: nearest to the viewer drawn last
        view.draw(image, seen[order][:, [h, v]], colours[order], dot=2)
        view.draw(image, seen_off[:, [h, v]], picture.to_bytes(OFF_MODEL_COLOUR), dot=OFF_MODEL_DOT)
        picture.frame(image)
        bar = view.scale_bar(image)
        views.append({"title": title, "png": picture.png(image), "scale_bar_mm": bar})
    return views


def histogram_svg(deviations, scale: DeviationScale) -> str:
    """Histogram of signed deviations (log count) as inline SVG: bars coloured like the map, the
    tolerance band dotted, axes labelled."""
    d = deviations[np.isfinite(deviations)]
    if not len(d):
        return ""
    width, height, left, right, top, bottom = 720, 260, 64, 16, 10, 46
    counts, edges = np.histogram(d, bins=HISTOGRAM_BINS)
    lo, hi = min(edges[0], -scale.tolerance_mm), max(edges[-1], scale.tolerance_mm)
    span = hi - lo if hi > lo else 1.0
    decades = max(1.0, np.log10(counts.max()) + 1)  # a count of 1 is a bar of one decade's height

    def x(value):
        return left + (value - lo) / span * (width - left - right)

    def y(decade):
        return height - bottom - decade / decades * (height - top - bottom)

    middles = 0.5 * (edges[1:] + edges[:-1])
    out = [f'<svg width="{width}" height="{height}" role="img" '
           'aria-label="deviation histogram" font-family="sans-serif" font-size="11">']
    for count, left_edge, right_edge, colour in zip(counts, edges[:-1], edges[1:], picture.to_bytes(scale.colours(middles))):
        if count:
            top_y = y(np.log10(count) + 1)
            out.append(f'<rect x="{x(left_edge):.1f}" y="{top_y:.1f}" width="{max(x(right_edge) - x(left_edge), 0.5):.1f}" '
                       f'height="{y(0) - top_y:.1f}" fill="rgb{tuple(int(c) for c in colour)}" stroke="#555" '
                       'stroke-width="0.3"/>')
    out.append(f'<path d="M{left},{top}V{y(0):.1f}H{width - right}" fill="none" stroke="#222"/>')
    for k in range(int(decades)):
        out.append(f'<text x="{left - 4}" y="{y(k + 1) + 4:.1f}" text-anchor="end">{10 ** k:g}</text>'
                   f'<path d="M{left - 3},{y(k + 1):.1f}h3" stroke="#222"/>')
    ticks = [t for t in scale.ticks() if lo <= t <= hi]
    ends = [e for e in (edges[0], edges[-1]) if all(abs(x(e) - x(t)) > 36 for t in ticks)]  # no labels on labels
    for value in ticks + ends:
        out.append(f'<text x="{x(value):.1f}" y="{y(0) + 14:.1f}" text-anchor="middle">{value:.3g}</text>'
                   f'<path d="M{x(value):.1f},{y(0):.1f}v3" stroke="#222"/>')
    for value in (-scale.tolerance_mm, scale.tolerance_mm):
        out.append(f'<path d="M{x(value):.1f},{top}V{y(0):.1f}" stroke="#000" stroke-dasharray="2,3"/>')
    out.append(f'<text x="{(left + width - right) / 2:.0f}" y="{height - 6}" text-anchor="middle">signed deviation (mm); '
               f'dotted: tolerance +/- {scale.tolerance_mm:g} mm</text>'
               f'<text transform="translate(14,{(top + height - bottom) / 2:.0f}) rotate(-90)" text-anchor="middle">'
               'scan points (log scale)</text></svg>')
    return "".join(out)


def _figure(png: bytes, alt: str, caption: str) -> str:
    """A PNG view inline, side by side with the next, with its caption (both texts escaped here)."""
    return (f"<figure style='display:inline-block;margin:.4em 1em .4em 0'><img alt=\"{_e(alt)}\" "
            f"src=\"data:image/png;base64,{base64.b64encode(png).decode('ascii')}\">"
            f"<figcaption class='note'>{_e(caption)}</figcaption></figure>")


def _rgb(colour) -> str:
    return "rgb({},{},{})".format(*picture.to_bytes(colour))


# --- joint margins along the program -------------------------------------------------------------------

# The six joints' colours in the margin plot (the Tableau 10 palette: told apart also in print).
JOINT_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b")
# Most robot targets a margin line is drawn through; a longer program keeps, per stretch of targets and
# per joint, the target nearest the limit, so that no dip towards a limit is lost and the page stays small.
MAX_PLOTTED_TARGETS = 2000


def reach_summary(robot, reach) -> dict:
    """What report.json says of the robot's reach: the robot, whether it follows the program (else why),
    the smallest joint margin and where."""
    from .robots.reach import joint_name

    margin = reach.margin
    return {"robot": robot.id, "robot_name": robot.name, "targets": reach.targets, "problem": reach.problem,
            "reason": reach.reason,
            "smallest_margin": None if margin is None else {
                "joint": joint_name(robot, margin.joint), "deg": margin.value, "target": margin.where.target + 1,
                "line": margin.where.line, "on_the_way": margin.where.on_the_way}}


def target_margins(robot, reach) -> np.ndarray:
    """(N, 6) each joint's margin to its nearer limit (deg) at every robot target, NaN past a problem."""
    from .robots.kinematics import joint_margins_deg

    return joint_margins_deg(robot, reach.joints)


def _plotted_targets(margins: np.ndarray) -> list:
    """Per joint, the 0-based targets its line is drawn through: every target the robot reaches, or for a
    longer program than MAX_PLOTTED_TARGETS the one nearest the limit in each of that many stretches."""
    reached = np.flatnonzero(~np.isnan(margins).any(axis=1))
    if len(reached) <= MAX_PLOTTED_TARGETS:
        return [reached] * margins.shape[1]
    stretches = np.array_split(reached, MAX_PLOTTED_TARGETS)
    return [np.array([stretch[np.argmin(margins[stretch, joint])] for stretch in stretches])
            for joint in range(margins.shape[1])]


def joint_margins_svg(robot, reach) -> str:
    """Each joint's margin to its nearer limit (deg) over the program's robot targets as inline SVG: one
    polyline per joint (``data-joint``, its points in data units: target number from 1, margin in deg,
    drawn through a transform), the limit at 0 dashed, the smallest margin marked, and where a refused
    program fails."""
    from .robots.reach import joint_name

    margins = target_margins(robot, reach)
    plotted = _plotted_targets(margins)
    if not any(len(p) for p in plotted):
        return ""
    width, height, left, right, top, bottom = 720, 300, 64, 16, 34, 46
    count = max(reach.targets, 2)
    values = np.concatenate([margins[p, j] for j, p in enumerate(plotted)])
    low = min(0.0, float(np.min(values)), reach.margin.value if reach.margin is not None else 0.0)
    high = max(float(np.max(values)), low + 1.0)
    low, high = low - 0.04 * (high - low), high + 0.04 * (high - low)
    scale_x = (width - left - right) / (count - 1)
    scale_y = (height - top - bottom) / (high - low)

    def x(target_number):
        return left + (target_number - 1) * scale_x

    def y(deg):
        return height - bottom - (deg - low) * scale_y

    out = [f'<svg width="{width}" height="{height}" role="img" aria-label="joint margins along the program" '
           'font-family="sans-serif" font-size="11">']
    out.append(f'<path d="M{left},{top}V{y(low):.1f}H{width - right}" fill="none" stroke="#222"/>')
    for tick in _ticks(low, high):
        out.append(f'<text x="{left - 4}" y="{y(tick) + 4:.1f}" text-anchor="end">{tick:g}</text>'
                   f'<path d="M{left - 3},{y(tick):.1f}h3" stroke="#222"/>')
    for tick in _ticks(1, count, whole=True):
        out.append(f'<text x="{x(tick):.1f}" y="{y(low) + 14:.1f}" text-anchor="middle">{tick:g}</text>'
                   f'<path d="M{x(tick):.1f},{y(low):.1f}v3" stroke="#222"/>')
    out.append(f'<path d="M{left},{y(0):.1f}H{width - right}" stroke="#c62828" stroke-dasharray="5,3"/>'
               f'<text x="{left + 4}" y="{y(0) - 4:.1f}" fill="#c62828">joint limit</text>')
    # Data units inside: x the target number, y the margin in degrees (up), so the points are the values.
    out.append(f'<g transform="matrix({scale_x:.6g} 0 0 {-scale_y:.6g} {left - scale_x:.6g} '
               f'{height - bottom + low * scale_y:.6g})">')
    for joint, targets in enumerate(plotted):
        points = " ".join(f"{t + 1},{margins[t, joint]:.3f}" for t in targets)
        out.append(f'<polyline data-joint="{_e(joint_name(robot, joint))}" points="{points}" fill="none" '
                   f'stroke="{JOINT_COLOURS[joint]}" stroke-width="1.5" vector-effect="non-scaling-stroke"/>')
    out.append("</g>")
    for joint in range(6):
        out.append(f'<rect x="{left + 8 + 70 * joint}" y="8" width="14" height="4" fill="{JOINT_COLOURS[joint]}"/>'
                   f'<text x="{left + 26 + 70 * joint}" y="14">{_e(joint_name(robot, joint))}</text>')
    if reach.margin is not None:
        m = reach.margin
        at = m.where.target + 1 - (0.5 if m.where.on_the_way else 0.0)
        anchor = "end" if x(at) > width / 2 else "start"
        shift = -8 if anchor == "end" else 8
        out.append(f'<circle class="worst" cx="{x(at):.1f}" cy="{y(m.value):.1f}" r="4.5" fill="none" '
                   f'stroke="#000" stroke-width="1.5"/><text x="{x(at) + shift:.1f}" y="{y(m.value) - 6:.1f}" '
                   f'text-anchor="{anchor}">smallest: {_e(joint_name(robot, m.joint))} {m.value:.1f} deg '
                   f'{_e(m.where.on())}</text>')
    if reach.problem_at is not None:
        at = reach.problem_at.target + 1 - (0.5 if reach.problem_at.on_the_way else 0.0)
        anchor = "end" if x(at) > width / 2 else "start"
        out.append(f'<path class="problem" d="M{x(at):.1f},{top}V{y(low):.1f}" stroke="#c62828" stroke-width="2"/>'
                   f'<text x="{x(at) + (-4 if anchor == "end" else 4):.1f}" y="{top + 12}" text-anchor="{anchor}" '
                   f'fill="#c62828">fails {_e(reach.problem_at.on())}</text>')
    out.append(f'<text x="{(left + width - right) / 2:.0f}" y="{height - 6}" text-anchor="middle">robot target '
               f'(in program order)</text><text transform="translate(14,{(top + height - bottom) / 2:.0f}) '
               'rotate(-90)" text-anchor="middle">margin to the joint limit (deg)</text></svg>')
    return "".join(out)


def _ticks(low: float, high: float, whole: bool = False) -> list:
    """About five round values between ``low`` and ``high`` (whole numbers only when ``whole``)."""
    span = high - low
    step = 10 ** math.floor(math.log10(span / 5)) if span > 0 else 1.0
    for factor in (1, 2, 5, 10):
        if span / (step * factor) <= 6:
            step *= factor
            break
    if whole:
        step = max(1.0, round(step))
    first = math.ceil(low / step) * step
    return [float(v) for v in np.arange(first, high + 1e-9 * step, step)]


def _reach_html(robot, reach) -> str:
    from .robots.reach import joint_name

    if reach.reachable:
        verdict = (f"{_e(robot.name)} ({_e(robot.id)}) follows the calibrated program, all {reach.targets} robot "
                   "targets.")
    else:
        verdict = f"{_e(robot.name)} ({_e(robot.id)}) cannot follow the calibrated program: {_e(reach.reason)}."
    rows = []
    if reach.margin is not None:
        m = reach.margin
        rows.append(["smallest joint-limit margin" + ("" if reach.reachable else " (up to the failure)"),
                     f"{m.value:.1f} deg", f"{_e(joint_name(robot, m.joint))} {_e(m.where.on())}"])
    for name, extreme, unit, what in (("wrist", reach.wrist, "deg", "joint 5 from 0 or 180 deg"),
                                      ("elbow", reach.elbow, "deg", "from stretched or folded"),
                                      ("shoulder", reach.shoulder, "mm", "wrist point from axis 1")):
        if extreme is not None:
            rows.append([f"closest to the {name} singularity ({what})", f"{extreme.value:.1f} {unit}",
                         _e(extreme.where.on())])
    plot = joint_margins_svg(robot, reach)
    note = ("<p class='note'>Each joint's distance to its nearer limit at every robot target of the program, in "
            "the configuration the check solved; the dashed line is the limit, the circle the smallest margin "
            "(which may lie on a linear move between two targets)"
            + ("; longer programs show, per stretch of targets, the one nearest the limit" if reach.targets >
               MAX_PLOTTED_TARGETS else "") + ".</p>")
    return (f"<h2>Robot reach</h2><p>{verdict}</p>" + (_table(rows, ["", "value", "where"]) if rows else "")
            + (plot + note if plot else "<p class='note'>The robot reaches none of the program's targets.</p>"))


# A colour swatch in a legend line (its background the colour).
SWATCH = "display:inline-block;width:1.2em;height:1em;vertical-align:middle;border:1px solid #999;background:"


def _off_model_swatch(count: int) -> str:
    return f"<span style='{SWATCH}{_rgb(OFF_MODEL_COLOUR)}'></span> {count} points off the placed model"


def legend_html(scale: DeviationScale, off_model: int = 0) -> str:
    """The map's colour scale as HTML: a gradient from -limit to +limit with its ticks, the colours
    past the limit, the grey of points with no model surface near them and, when there are
    ``off_model`` of them, the colour of the region's points off its placed model."""
    values = np.linspace(-scale.limit_mm, scale.limit_mm, 61)
    stops = ",".join(f"{_rgb(c)} {100 * i / (len(values) - 1):.2f}%" for i, c in enumerate(scale.colours(values)))
    ticks = "".join(f"<span style='position:absolute;left:{50 * (1 + t / scale.limit_mm):.1f}%;"
                    f"transform:translateX(-50%)'>{t:+.3g}</span>" for t in scale.ticks())
    return ("<div class='note' style='margin:.5em 0 1em'>"
            f"<span style='{SWATCH}{_rgb(BEYOND_REMOVED)}'></span> removed past {-scale.limit_mm:g} mm "
            f"<span style='display:inline-block;width:320px;vertical-align:middle;margin:0 .6em'>"
            f"<span style='display:block;height:1em;border:1px solid #999;background:linear-gradient(to right,{stops})'>"
            f"</span><span style='display:block;position:relative;height:1.2em'>{ticks}</span></span>"
            f"<span style='{SWATCH}{_rgb(BEYOND_ADDED)}'></span> added past +{scale.limit_mm:g} mm "
            f"&nbsp; <span style='{SWATCH}{_rgb(NO_SURFACE)}'></span> no model surface near "
            f"&nbsp; <span style='{SWATCH}{_rgb(MODEL_GREY)}'></span> the model X-A"
            + (f" &nbsp; {_off_model_swatch(off_model)} (drawn over the rest)" if off_model else "")
            + "<br>signed deviation (mm): + clay added, - clay removed; green within +/- "
            f"{scale.tolerance_mm:g} mm</div>")


# --- HTML ----------------------------------------------------------------------------------------------

def _e(value) -> str:
    return html.escape(str(value), quote=True)


def fmt(value, digits: int = 4) -> str:
    """A number for a terminal or HTML table; '-' for nothing."""
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, (int, np.integer)):
        return str(value)
    if isinstance(value, (float, np.floating)):
        if not math.isfinite(value):
            return "-"
        return f"{value:.{digits}f}" if abs(value) >= 10 ** -digits or value == 0 else f"{value:.2e}"
    return str(value)


def _num(value, digits: int = 4) -> str:
    """A number as the terminal summaries print it; text escaped."""
    return _e(value) if isinstance(value, str) else fmt(value, digits)


def _table(rows, header=None, left_columns=1) -> str:
    out = ["<table>"]
    if header:
        out.append("<tr>" + "".join(f'<th class="{"l" if i < left_columns else ""}">{_e(h)}</th>'
                                    for i, h in enumerate(header)) + "</tr>")
    for row in rows:
        out.append("<tr>" + "".join(f'<td class="{"l" if i < left_columns else ""}">{cell}</td>'
                                    for i, cell in enumerate(row)) + "</tr>")
    return "".join(out) + "</table>"


def _matrix_html(T) -> str:
    return '<table class="matrix">' + "".join(
        "<tr>" + "".join(f"<td>{v:.6f}</td>" for v in row) + "</tr>" for row in np.asarray(T)) + "</table>"


def _pose_html(name: str, meaning: str, T) -> str:
    if T is None:
        return f"<div><h3>{_e(name)}</h3><p class='note'>{_e(meaning)}: not determined.</p></div>"
    phi, theta, psi = frames.euler_zyz(T)
    t = np.asarray(T)[:3, 3]
    rows = [["Euler Z-Y-Z (phi, theta, psi)", f"{phi:.4f}, {theta:.4f}, {psi:.4f} deg"],
            ["Omega (principal-axis rotation)", f"{frames.omega(T):.4f} deg"],
            ["translation (x, y, z)", f"{t[0]:.4f}, {t[1]:.4f}, {t[2]:.4f} mm"]]
    return (f"<div><h3>{_e(name)}</h3><p class='note'>{_e(meaning)}</p>{_matrix_html(T)}"
            + _table([[_e(a), _e(b)] for a, b in rows]) + "</div>")


def _banner(calibration: CalibrationResult) -> str:
    label, text = STATUS_TEXT[calibration.status]
    reasons = "".join(f"<li>{_e(r)}</li>" for r in calibration.reasons)
    if calibration.choice is not None:
        reasons += f"<li>{_e(choice_words(calibration.choice))}</li>"
    return (f'<div class="banner {STATUS_CLASS[calibration.status]}" id="status"><b>{label}</b> &nbsp; {_e(text)}'
            + (f"<ul>{reasons}</ul>" if reasons else "") + "</div>")


def _matches_html(calibration: CalibrationResult) -> str:
    matches = [("workpiece: U", calibration.workpiece), ("reference: V", calibration.reference)]
    fields = [
        ("status", lambda m: _e(m.status)), ("method", lambda m: _e(m.method)),
        ("scan points", lambda m: _num(m.n_scan_points)), ("inliers", lambda m: _num(m.n_inliers)),
        ("fitness (points on the model)", lambda m: f"{100 * m.fitness:.1f} %"),
        ("coverage of the model", lambda m: f"{100 * m.coverage:.1f} %"),
        ("RMS (mm)", lambda m: _num(m.rms_mm)),
        ("mean directed Hausdorff (mm)", lambda m: _num(m.mean_directed_hausdorff_mm)),
        ("max deviation (mm)", lambda m: _num(m.max_deviation_mm)),
        *[(f"{q}th percentile |deviation| (mm)", lambda m, q=q: _num(m.percentiles_mm.get(str(q))))
          for q in PERCENTILES],
        ("within tolerance", lambda m: f"{m.within_tolerance_pct:.1f} % (of inliers, {m.tolerance_mm:g} mm)"),
        ("scan noise (mm, on the part)", lambda m: _num(m.noise_mm)),
        ("viewpoint", lambda m: _e(m.viewpoint.get("source", "-")) if m.viewpoint else "-"),
        ("view contradicted by the pose", lambda m: f"{m.view['contradicted_pct']:.1f} %"
         if "contradicted_pct" in m.view else "-"),
        ("final gate (mm)", lambda m: _num(m.gate_mm)), ("iterations", lambda m: _num(m.iterations)),
        ("time (s)", lambda m: _num(m.time_s, 2)),
    ]
    rows = [[_e(label)] + [("-" if m is None else getter(m)) for _, m in matches] for label, getter in fields]
    notes = [calibration.off_model(role) for role in ("workpiece", "reference")]
    if any(notes):
        rows.append([_e("region points off the placed model")]
                    + ["-" if n is None else _num(n["count"]) for n in notes])
    return _table(rows, ["", *(name for name, _ in matches)])


def _regions_html(calibration: CalibrationResult, images) -> str:
    """What each region holds that its placed model does not explain, where it lies and what to change,
    and both regions drawn in the scan with those points over them (when the report has the scan)."""
    sentences = []
    for role in ("workpiece", "reference"):
        note = calibration.off_model(role)
        if note is None:
            continue
        if note["count"]:
            sentences.append(f"The {role} region: {note['count']} points off its placed model, {note['where']}. "
                             f"{note['change']}.")
        else:
            sentences.append(f"The {role} region: every point lies on its placed model.")
    if not sentences:
        return ""
    out = "<h2>Regions</h2><ul>" + "".join(f"<li>{_e(s)}</li>" for s in sentences) + "</ul>"
    for view in images.get("regions", ()):
        out += _figure(view["png"], f"regions and the points off their models, {view['title']}",
                       f"{view['title']} of both regions, from the scanner's side; the bar at the lower left is "
                       f"{view['scale_bar_mm']:g} mm")
    if images.get("regions"):
        count = sum(calibration.off_model(role)["count"] for role in ("workpiece", "reference")
                    if calibration.off_model(role) is not None)
        out += ("<div class='note' style='margin:.5em 0 1em'>"
                + " &nbsp; ".join(f"<span style='{SWATCH}{_rgb(colour)}'></span> the {role} region"
                                  for role, colour in REGION_COLOURS.items())
                + f" &nbsp; {_off_model_swatch(count)} (of either region, drawn over the rest)</div>")
    return out


def _symmetry_sentences(calibration: CalibrationResult) -> list[str]:
    """One sentence per model symmetry of either match: "The workpiece model is symmetric: turning the
    part 90 degrees about its axis ... gives the same surface." """
    out = []
    for role, m in (("workpiece", calibration.workpiece), ("reference", calibration.reference)):
        for symmetry in (m.symmetries if m is not None else []):
            out.append(f"The {role} model is symmetric: {symmetry['description']} (axis in the model's frame), so "
                       f"no scan can tell those poses apart.")
    return out


def _symmetry_html(calibration: CalibrationResult) -> str:
    sentences = _symmetry_sentences(calibration)
    if not sentences:
        return ""
    return "<h2>Symmetry</h2><ul>" + "".join(f"<li>{_e(s)}</li>" for s in sentences) + "</ul>"


def _gates_html(calibration: CalibrationResult) -> str:
    if not calibration.quality_gates:
        return "<p class='note'>No quality gates were evaluated.</p>"
    rows = []
    for g in calibration.quality_gates:
        value = g["value"] if isinstance(g["value"], str) else _num(g["value"])
        verdict = '<span class="pass">pass</span>' if g["passed"] else '<span class="miss">FAIL</span>'
        rows.append([_e(g["name"]), value, _e(g["limit"]), _e(g.get("unit", "")), verdict])
    return _table(rows, ["gate", "value", "limit", "unit", "result"])


# What the bound means, as measured against exact truth (docs/studies.md): its level.
BOUND_LEVEL = ("The bound is meant to hold the true displacement at least 95 times in 100; against exact truth "
               "it held in 98 % of the simulated cell scenes, mixed pixels and edge-held blocks included")


def _uncertainty_html(calibration: CalibrationResult) -> str:
    u = calibration.uncertainty
    if not u:
        return "<p class='note'>No uncertainty was estimated (the calibration did not get that far).</p>"
    labels = [("toolpath_bound_mm", "bound at the toolpath (largest over its points)", "mm"),
              ("toolpath_median_mm", "median at the toolpath", "mm"),
              ("surface_bound_mm", "bound at the workpiece surface (largest)", "mm"),
              ("surface_median_mm", "median at the workpiece surface", "mm"),
              ("toolpath_edge_bias_mm", "of the bound at the toolpath: a pose centred between edges off", "mm"),
              ("surface_edge_bias_mm", "of the bound at the surface: a pose centred between edges off", "mm"),
              ("rotation_bound_deg", "rotation bound", "deg"),
              ("distortion_shift_mm", "shift of W by the scan's distortion (largest)", "mm"),
              ("distortion_scale_pct", "the scan's scale against the models", "%"),
              ("distortion_strain_pct", "the scan's largest strain against the models", "%")]
    rows = [[_e(text), _num(u[key]), unit] for key, text, unit in labels if key in u]
    rows += [[_e(k), _num(v), ""] for k, v in u.items() if k not in {key for key, _, _ in labels} | {"method"}]
    note = f"<p class='note'>{_e(u['method'])}. {_e(BOUND_LEVEL)}</p>" if "method" in u else ""
    return _table(rows, ["", "value", "unit"]) + note


def _inputs_html(calibration: CalibrationResult) -> str:
    rows = [[_e(k), _e(v)] for k, v in calibration.inputs.items()]
    regions = calibration.regions or {}
    for role in ("workpiece", "reference", "platform"):
        if role in regions:
            rows.append([_e(f"{role} region"), f"{len(regions[role])} scan points"])
    if "source" in regions:
        rows.append(["regions from", _e("automatic" if regions["source"] == "auto" else "the user")])
    rows += [["tolerance", f"{calibration.tolerance_mm:g} mm"], ["seed", _e(calibration.seed)],
             ["time", f"{calibration.time_s:.2f} s"]]
    return _table(rows, left_columns=2)


def _deviation_html(deviation, images, asked: bool) -> str:
    if deviation is None:
        why = ("the calibration found no U to place the model with" if asked
               else "no workpiece scan points or model were given to the report")
        return f"<p class='note'>No deviation map: {_e(why)}.</p>"
    rows = [["points compared", _num(deviation.get("n_points"))],
            ["points far from the model (not compared)", _num(deviation.get("n_far"))]]
    if deviation.get("n_points"):
        rows += [["mean (mm)", _num(deviation["mean_mm"])], ["RMS (mm)", _num(deviation["rms_mm"])],
                 ["min (mm)", _num(deviation["min_mm"])], ["max (mm)", _num(deviation["max_mm"])],
                 *[[f"{q}th percentile |deviation| (mm)", _num(v)] for q, v in deviation["percentiles_abs_mm"].items()],
                 [f"within +/- {deviation['tolerance_mm']:g} mm", f"{deviation['within_tolerance_pct']:.1f} %"],
                 ["above the tolerance (added)", f"{deviation['above_tolerance_pct']:.2f} %"],
                 ["below the tolerance (removed)", f"{deviation['below_tolerance_pct']:.2f} %"]]
    scale = deviation.get("colour_scale") or {}
    out = ("<p>Signed distance of the workpiece scan points to the model X-A placed by U: green within the tolerance, "
           "yellow to red outside the model (clay added since the model was made), cyan to blue inside (clay "
           f"removed), full colour at +/- {_num(scale.get('limit_mm'))} mm; grey points have no model surface "
           "near them. FreeCAD's deviation map uses the same colours.</p>"
           + _table(rows))
    for view in images.get("views", ()):
        out += _figure(view["png"], f"deviation colour map, {view['title']}",
                       f"{view['title']}: principal axis {view['horizontal']} of X-A to the right, axis "
                       f"{view['vertical']} up; the bar at the lower left is {view['scale_bar_mm']:g} mm")
    out += images.get("legend", "") + images.get("histogram", "")
    return out


def _calibration_body(calibration: CalibrationResult, deviation, images, asked: bool) -> str:
    warnings = "".join(f"<li>{_e(w)}</li>" for w in calibration.warnings) or "<li>none</li>"
    poses = "".join([
        _pose_html("W = ^B X", "the workpiece frame X in the robot base frame B (W = V^-1 U): the toolpath "
                   "goes to the robot as B-m = W X-m", calibration.W),
        _pose_html("U = ^S X", "the workpiece model frame in the scanner frame (workpiece match)", calibration.U),
        _pose_html("V = ^S B", "the robot base frame in the scanner frame (reference match)", calibration.V),
    ])
    return (_banner(calibration)
            + f"<h2>Transformations</h2><div class='poses'>{poses}</div>"
            + "<p class='note'>Lengths in mm, angles in degrees; matrices act on column vectors (p_B = W p_X). "
              "The paper's Table 1 prints the inverse of W (U^-1 V), which has the same Omega.</p>"
            + _symmetry_html(calibration)
            + "<h2>Residuals of the matches</h2>" + _matches_html(calibration)
            + _regions_html(calibration, images)
            + "<h2>Quality gates</h2>" + _gates_html(calibration)
            + "<h2>Uncertainty</h2>" + _uncertainty_html(calibration)
            + "<h2>Deviation of the workpiece from its model</h2>" + _deviation_html(deviation, images, asked)
            + f"<h2>Warnings</h2><ul>{warnings}</ul>"
            + "<h2>Inputs</h2>" + _inputs_html(calibration))


def _study_dict(study) -> dict:
    return study.to_dict() if hasattr(study, "to_dict") else dict(study)


def _study_figure(study) -> str | None:
    files = getattr(study, "files", None) or (study.get("files") if isinstance(study, dict) else None) or {}
    path = files.get("figure")
    if path is None or not Path(path).is_file():
        return None
    return base64.b64encode(Path(path).read_bytes()).decode("ascii")


def _studies_body(studies, study_dicts) -> str:
    if not study_dicts:
        return ""
    out = ["<h2>Studies</h2>"]
    for study, data in zip(studies, study_dicts):
        out.append(f"<h3>{_e(data.get('title', data.get('name', 'study')))}</h3>")
        summary = [[_e(k), _num(v)] for k, v in data.get("summary", {}).items() if not isinstance(v, (dict, list))]
        out.append(_table(summary))
        targets = data.get("targets", [])
        if targets:
            out.append(_table([[_e(t["name"]), _num(t["value"]), f"{_e(t['comparison'])} {_e(t['limit'])}",
                                _e(t["unit"]), '<span class="pass">met</span>' if t["passed"]
                                else '<span class="miss">missed</span>'] for t in targets],
                              ["target", "value", "limit", "unit", "result"]))
        figure = _study_figure(study)
        if figure:
            out.append(f'<img alt="{_e(data.get("name", "study"))} figure" src="data:image/png;base64,{figure}">')
        settings = ", ".join(f"{k} = {v}" for k, v in data.get("settings", {}).items() if not isinstance(v, dict))
        out.append(f"<p class='note'>Settings: {_e(settings)}</p>")
    return "".join(out)


def _page(title: str, generated: str, body: str) -> str:
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{_e(title)}</title>'
            f"<style>{CSS}</style></head><body><h1>{_e(title)}</h1>"
            f"<p class='note'>Written {_e(generated)} by WorkCal.</p>{body}</body></html>\n")


def _write(out: Path, files) -> None:
    """Each file atomically, in order (the HTML last, so its presence means the report is complete)."""
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"{out}: cannot write the report ({exc.strerror or exc})") from None
    for path, text in files:
        atomic_write_text(path, text)
