"""The calibration report: self-contained HTML, JSON with the calibration's numbers, a deviation map
that shows clay changes where they are, and atomic writing."""
import base64
import json
import math
import re

import numpy as np
import pytest

from workcal_wb.core import atomic, frames
from workcal_wb.core.calibration import CalibrationOptions, calibrate
from workcal_wb.core.errors import OutputError
from workcal_wb.core.report import deviation_map, write_report, write_study_report
from workcal_wb.core.result import FAILED, CalibrationResult
from workcal_wb.core.simulate.scanner import Scanner
from workcal_wb.core.simulate.scene import build_scene
from workcal_wb.core.studies.common import StudyResult, new_figure, save_figure

PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def lumpy():
    """A car with a clay lump and a carved patch added after its model was made, calibrated."""
    scene = build_scene("car", seed=2, clay_change=["lump", "carve"])
    scan = Scanner.aimed_at(scene, seed=2, image_size=(368, 276)).scan(scene)
    regions = {role: np.flatnonzero(scan.mask(role)) for role in ("workpiece", "reference")}
    result = calibrate(scan.cloud(), scene.workpiece_model(), scene.reference_model(), regions=regions,
                       options=CalibrationOptions(resamples=2))
    assert result.W is not None, result.reasons
    return scene, scan, result


@pytest.fixture(scope="module")
def written(lumpy, tmp_path_factory):
    scene, scan, result = lumpy
    out = tmp_path_factory.mktemp("report")
    paths = write_report(result, out, workpiece_points=scan.points[scan.mask("workpiece")],
                         workpiece_model=scene.workpiece_model(), title="Lump <test> & report")
    return paths, paths["html"].read_text(encoding="utf-8"), json.loads(paths["json"].read_text(encoding="utf-8"))


@pytest.mark.slow
def test_report_files_are_written_and_self_contained(written):
    paths, page, _ = written
    assert set(paths) == {"html", "json"} and all(p.is_file() for p in paths.values())
    assert page.startswith("<!DOCTYPE html>") and page.rstrip().endswith("</html>")
    assert "http://" not in page and "https://" not in page and "<link" not in page and "<script" not in page
    sources = re.findall(r'src="([^"]*)"', page)
    assert len(sources) >= 2  # the deviation map's two views
    for src in sources:
        assert src.startswith("data:image/png;base64,")
        assert base64.b64decode(src.split(",", 1)[1])[:8] == PNG
    assert page.count('aria-label="deviation histogram"') == 1 and "<svg" in page  # drawn inline
    assert "Lump &lt;test&gt; &amp; report" in page  # text is escaped, not injected


def _same(a, b):
    """Equal as JSON values, NaN equal to NaN."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return isinstance(b, list) and len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, float) and math.isnan(a):
        return isinstance(b, float) and math.isnan(b)
    return a == b


@pytest.mark.slow
def test_report_json_holds_the_calibration_numbers(written, lumpy):
    _, _, data = written
    result = lumpy[2]
    expected = json.loads(json.dumps(result.to_dict(region_indices=False), allow_nan=True))
    for key, value in expected.items():
        assert _same(data[key], value), key
    assert data["regions"]["counts"]["workpiece"] == len(result.regions["workpiece"])  # no index lists
    back = CalibrationResult.from_dict(data)  # report.json is also a calibration file
    assert np.array_equal(back.W, result.W) and back.status == result.status
    assert data["report"]["format"] == "workcal-report"
    deviation = data["deviation"]
    assert deviation["n_points"] + deviation["n_far"] == int(lumpy[1].mask("workpiece").sum())
    assert sum(deviation["histogram"]["counts"]) == deviation["n_points"]


@pytest.mark.slow
def test_html_shows_status_matrices_and_residuals(written, lumpy):
    _, page, _ = written
    result = lumpy[2]
    assert re.search(rf'class="banner {result.status}"', page)
    for name in ("W", "U", "V"):
        for value in getattr(result, name).ravel():
            assert f"<td>{value:.6f}</td>" in page, (name, value)
    phi, theta, psi = frames.euler_zyz(result.W)
    assert f"{phi:.4f}, {theta:.4f}, {psi:.4f} deg" in page and f"{frames.omega(result.W):.4f} deg" in page
    assert f"{result.workpiece.rms_mm:.4f}" in page and f"{result.reference.rms_mm:.4f}" in page
    for gate in result.quality_gates:
        assert gate["name"] in page
    assert f"{result.uncertainty['surface_bound_mm']:.4f}" in page
    # the bound's parts and its level, as measured against the truth
    assert f"{result.uncertainty['surface_edge_bias_mm']:.4f}" in page and "at least 95 times in 100" in page


@pytest.mark.slow
def test_deviation_map_shows_the_lump_and_the_carving(lumpy):
    scene, scan, result = lumpy
    points = scan.points[scan.mask("workpiece")]
    deviations = deviation_map(result, points, scene.workpiece_model())
    reshaped = scene.reshaped
    mesh = scene.workpiece.mesh  # the clay as scanned, in X
    for pick, sign in ((np.argmax, 1.0), (np.argmin, -1.0)):
        apex = mesh.points[pick(reshaped.displacement_mm)]
        height = abs(reshaped.displacement_mm).max() if sign > 0 else -reshaped.displacement_mm.min()
        near = np.linalg.norm(points - frames.apply(scan.U, apex[None])[0], axis=1) < 3.0
        assert near.sum() > 10
        assert np.all(sign * deviations[near] > 0.6 * height), (sign, height, deviations[near].min())
    changed = mesh.points[reshaped.changed]
    in_X = frames.apply(frames.invert(scan.U), points)
    untouched = np.min(np.linalg.norm(in_X[:, None, :] - changed[None, ::25, :], axis=2), axis=1) > 10.0
    assert np.nanmedian(np.abs(deviations[untouched])) < 0.1
    assert np.nanpercentile(np.abs(deviations[untouched]), 95) < result.tolerance_mm


@pytest.mark.slow
def test_report_json_deviation_statistics_show_the_lump(written, lumpy):
    _, _, data = written
    lump_height = lumpy[0].reshaped.displacement_mm.max()
    assert data["deviation"]["max_mm"] > 0.6 * lump_height
    assert data["deviation"]["above_tolerance_pct"] > 0 and data["deviation"]["below_tolerance_pct"] > 0


def _failing_fsync(calls_before_failure):
    calls = []
    real = atomic.os.fsync

    def fsync(fd):
        calls.append(fd)
        if len(calls) > calls_before_failure:
            raise OSError(28, "No space left on device")
        return real(fd)
    return fsync


def stored_result() -> CalibrationResult:
    """A calibration's result built directly, for the tests of how the report's files are written."""
    return CalibrationResult("ok", np.eye(4), U=np.eye(4), V=np.eye(4), tolerance_mm=0.3)


@pytest.mark.parametrize("calls_before_failure", [0, 1])  # failing while writing report.json / report.html
def test_a_failure_while_writing_leaves_no_report(tmp_path, monkeypatch, calls_before_failure):
    result = stored_result()
    monkeypatch.setattr(atomic.os, "fsync", _failing_fsync(calls_before_failure))
    with pytest.raises(OutputError, match=r"report\.(json|html): cannot be written \(No space left"):
        write_report(result, tmp_path)
    assert not (tmp_path / "report.html").exists()
    assert not list(tmp_path.glob("*.part")) and not list(tmp_path.glob(".*.part"))


def test_a_failed_rewrite_keeps_the_previous_report(tmp_path, monkeypatch):
    result = stored_result()
    write_report(result, tmp_path, title="first")
    before = (tmp_path / "report.html").read_bytes()
    monkeypatch.setattr(atomic.os, "fsync", _failing_fsync(1))
    with pytest.raises(OutputError):
        write_report(result, tmp_path, title="second")
    assert (tmp_path / "report.html").read_bytes() == before
    assert not list(tmp_path.glob(".*.part"))


def test_failed_calibration_report_says_why(tmp_path):
    failed = CalibrationResult(FAILED, W=None, reasons=["reference match failed: the scan points are planar"],
                               warnings=["scan: 12 points with NaN"])
    paths = write_report(failed, tmp_path)
    page = paths["html"].read_text(encoding="utf-8")
    assert 'class="banner failed"' in page and "FAILED" in page
    assert "the scan points are planar" in page and "12 points with NaN" in page
    assert "not determined" in page and "No deviation map" in page
    data = json.loads(paths["json"].read_text(encoding="utf-8"))
    assert data["status"] == "failed" and data["W"] is None and data["deviation"] is None


@pytest.mark.slow
def test_studies_are_embedded_in_the_report(lumpy, tmp_path):
    fig = new_figure(3, 2)
    fig.subplots().plot([0, 1], [1, 0])
    save_figure(fig, tmp_path / "made_up.png")
    study = StudyResult("made-up", "A made-up study", {"quick": True}, rows=[{"run": 1, "error": 0.5}],
                        summary={"max_error_mm": 0.5}, targets=[{"name": "error", "value": 0.5, "limit": 0.3,
                                                                  "unit": "mm", "passed": False,
                                                                  "comparison": "<="}],
                        files={"figure": tmp_path / "made_up.png"})
    figure = base64.b64encode((tmp_path / "made_up.png").read_bytes()).decode("ascii")
    page = write_report(lumpy[2], tmp_path, studies=[study])["html"].read_text(encoding="utf-8")
    assert "A made-up study" in page and figure in page and "missed" in page
    alone = write_study_report([study], tmp_path / "studies")["html"].read_text(encoding="utf-8")
    assert figure in alone and "http://" not in alone and "https://" not in alone
    assert 'class="banner' not in alone  # no calibration in a studies page
    data = json.loads((tmp_path / "report.json").read_text(encoding="utf-8"))
    assert data["studies"][0]["name"] == "made-up" and data["studies"][0]["passed"] is False


@pytest.mark.slow
def test_report_names_the_symmetry_of_a_symmetric_workpiece(tmp_path):
    """A workpiece with a four-fold symmetry (a square plate with a square boss): the calibration is
    ambiguous and the report says which turn gives the same surface, in words."""
    from workcal_wb.core.simulate import shapes

    scene = build_scene(shapes.boss_plate(), seed=4)
    scan = Scanner.aimed_at(scene, seed=4, image_size=(368, 276)).scan(scene)
    regions = {role: np.flatnonzero(scan.mask(role)) for role in ("workpiece", "reference")}
    result = calibrate(scan.cloud(), scene.workpiece_model(), scene.reference_model(), regions=regions,
                       options=CalibrationOptions(resamples=2))
    assert result.status == "ambiguous"
    page = write_report(result, tmp_path)["html"].read_text(encoding="utf-8")
    assert "<h2>Symmetry</h2>" in page
    assert "The workpiece model is symmetric: turning the part 90 degrees about its axis" in page
    assert "The reference model is symmetric" not in page  # the L-block has no symmetry
    assert "workpiece model symmetry: turning the part 90 degrees" in result.summary()


@pytest.mark.slow
def test_a_report_is_written_without_matplotlib_the_studies_or_the_simulator(tmp_path):
    """The report's pictures are drawn with numpy (picture.py): writing one imports no matplotlib,
    whose import and rendering cost a calibrate process more than a second, and neither the studies
    nor the scene simulator they bring (a calibrate process paid ~15 ms for them to format numbers)."""
    import subprocess
    import sys
    from pathlib import Path

    code = f"""
import sys
import numpy as np
from workcal_wb.core import frames
from workcal_wb.core.geometry import Cloud
from workcal_wb.core.report import write_report
from workcal_wb.core.result import CalibrationResult
u, v = np.random.default_rng(1).uniform(-1, 1, (2, 3000))
model = Cloud(np.column_stack([50 * u, 30 * v, 5 * np.cos(2 * u)]), name="model")
U = frames.rigid(frames.rot_z(20.0), (10.0, 0.0, 300.0))
write_report(CalibrationResult("ok", np.eye(4), U=U, V=np.eye(4), tolerance_mm=0.3), {str(tmp_path)!r},
             workpiece_points=frames.apply(U, model.points), workpiece_model=model)
print(sorted(m for m in sys.modules if m.split(".")[0] == "matplotlib"
             or m.startswith(("workcal_wb.core.studies", "workcal_wb.core.simulate"))))
"""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=Path(__file__).resolve().parents[2])
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip() == "[]" and (tmp_path / "report.html").is_file()


def test_the_scale_bar_is_a_round_length_under_a_fifth_of_the_width_at_any_scale():
    """A width whose fifth lies just under a power of ten made log10 round up and left no round
    length to choose (ValueError while writing the report)."""
    from workcal_wb.core.picture import View

    view = View(np.array([[0.0, 0.0], [1.0, 1.0]]))
    image = np.zeros((100, 520, 3), np.uint8)
    for decade in range(-4, 5):
        for target in (np.nextafter(10.0**decade, 0.0), 10.0**decade, 3.0 * 10.0**decade):
            view.mm_per_pixel = target / (0.2 * (image.shape[1] - 2 * view.margin))
            length = view.scale_bar(image)
            assert 0.39 * target <= length <= target * (1 + 1e-12), (decade, target, length)
            assert np.isclose(length / 10.0 ** np.floor(np.log10(length) + 1e-9), [1, 2, 5]).any()


def test_where_dots_overlap_the_point_painted_last_wins():
    """``View.draw`` against painting dot after dot in a loop: many points on few pixels, dots of
    one and two pixels, some off the image."""
    from workcal_wb.core.picture import View, canvas

    rng = np.random.default_rng(3)
    points = rng.uniform(-1, 11, (3000, 2))
    colours = rng.integers(0, 256, (len(points), 3), dtype=np.uint8)
    view = View(np.array([[0.0, 0.0], [10.0, 10.0]]), size=40, margin=2)
    for dot in (1, 2):
        image = canvas(view.width, view.height)
        view.draw(image, points, colours, dot=dot)
        expected = canvas(view.width, view.height)
        column, row = view.pixels(points)
        for c, r, colour in zip(column, row, colours):
            for dr in np.arange(dot) - dot // 2:
                for dc in np.arange(dot) - dot // 2:
                    if 0 <= r + dr < expected.shape[0] and 0 <= c + dc < expected.shape[1]:
                        expected[r + dr, c + dc] = colour
        assert np.array_equal(image, expected), dot


def test_the_last_painted_by_sort_agrees_with_painting_in_turn():
    """``sorted_last_painted``, what ``last_painted`` falls back on should numpy ever scatter out of order."""
    from workcal_wb.core.picture import last_painted, sorted_last_painted

    rng = np.random.default_rng(4)
    pixel = rng.integers(0, 50, 400)
    order = np.sort(rng.choice(1000, 400, replace=False))
    expected = np.full(60, -1)
    for p, o in zip(pixel, order):
        expected[p] = o
    assert np.array_equal(sorted_last_painted(pixel, order, 60), expected)
    assert np.array_equal(last_painted(pixel, order, 60), expected)
    assert np.array_equal(sorted_last_painted(pixel[:0], order[:0], 60), np.full(60, -1))


def _pixels(png: bytes) -> np.ndarray:
    """An (height, width, 3) image from the PNG bytes picture.png writes (8-bit RGB, every row unfiltered)."""
    import struct
    import zlib

    width, height = struct.unpack(">II", png[16:24])
    data, at = b"", 8
    while at < len(png):
        length, kind = struct.unpack(">I4s", png[at:at + 8])
        if kind == b"IDAT":
            data += png[at + 8:at + 8 + length]
        at += 12 + length
    rows = np.frombuffer(zlib.decompress(data), np.uint8).reshape(height, 1 + 3 * width)
    assert not rows[:, 0].any(), "a filtered row"
    return rows[:, 1:].reshape(height, width, 3)


def _figures(page: str, alt_start: str) -> list:
    return [_pixels(base64.b64decode(src)) for src in
            re.findall(rf'<img alt="{re.escape(alt_start)}[^"]*" src="data:image/png;base64,([^"]+)"', page)]


@pytest.mark.slow
def test_the_report_says_and_draws_the_points_a_region_s_model_leaves_unexplained(tmp_path):
    """A reference box drawn loosely around the block and a band of the platform beside it: the regions
    section says how many of its points lie off the block's placed model, where and what to change; the
    views of both regions draw those points in the off-model colour (the deviation views of the clean
    workpiece have none), with a legend line."""
    import html

    from loose_regions import platform_band_beside_the_block
    from workcal_wb.core.picture import to_bytes
    from workcal_wb.core.report import OFF_MODEL_COLOUR

    scene = platform_band_beside_the_block()
    result = calibrate(scene.cloud, scene.workpiece_model, scene.reference_model, regions=scene.regions,
                       options=CalibrationOptions(resamples=2))
    note = result.off_model("reference")
    assert result.status == FAILED and note["count"] > 1000
    region = result.regions["workpiece"]
    page = write_report(result, tmp_path, workpiece_points=scene.cloud.points[region],
                        workpiece_model=scene.workpiece_model,
                        scan_points=scene.cloud.points)["html"].read_text(encoding="utf-8")
    said = f"The reference region: {note['count']} points off its placed model, {note['where']}. {note['change']}."
    assert html.escape(said) in page
    assert "The workpiece region: every point lies on its placed model." in page
    assert re.search(rf"region points off the placed model</td><td[^>]*>0</td><td[^>]*>{note['count']}</td>", page)
    assert f"{note['count']} points off the placed model (of either region" in page
    magenta = to_bytes(OFF_MODEL_COLOUR)
    regions = _figures(page, "regions and the points off their models")
    deviation = _figures(page, "deviation colour map")
    assert len(regions) == 2 and len(deviation) == 2
    for image in regions:
        assert np.all(image == magenta, axis=2).sum() > 300  # the band, in 3 x 3 dots
    for image in deviation:
        assert not np.all(image == magenta, axis=2).any()


@pytest.mark.slow
def test_a_report_without_the_scan_says_the_regions_but_draws_none(written):
    """Without the scan there is nothing to draw the regions in: the regions section still says what
    lies off each model."""
    _, page, _ = written
    assert "<h2>Regions</h2>" in page and "The reference region: " in page
    assert not _figures(page, "regions and the points off their models")


# --------------------------------------------------------------------------- joint margins along the program

POLYLINE = re.compile(r'<polyline data-joint="([^"]+)" points="([^"]+)"')


def margin_report(end_x: float):
    """A KR 16-2 checked along a line of 40 targets pointing down, from x 900 mm to ``end_x``, lines 11 on."""
    from workcal_wb.core.robots import load_robot
    from workcal_wb.core.robots.model import xyzabc_transform
    from workcal_wb.core.robots.reach import check_reach

    robot = load_robot("kuka_kr16_2")
    poses = np.tile(np.eye(4), (40, 1, 1))
    poses[:, :3, :3] = frames.rot_y(180.0)
    poses[:, :3, 3] = np.linspace((900.0, -400.0, 300.0), (end_x, 400.0, 300.0), 40)
    tool = xyzabc_transform([0.0, 0.0, 150.0, 0.0, 0.0, 0.0])
    return robot, check_reach(robot, poses, tool, source_lines=np.arange(40) + 11)


def plotted_lines(page: str) -> dict:
    """Joint name -> {target number: margin (deg)} of the margin plot's polylines."""
    return {joint: {int(float(x)): float(y) for x, y in (pair.split(",") for pair in points.split())}
            for joint, points in POLYLINE.findall(page)}


def test_the_report_plots_each_joints_margin_along_the_program(tmp_path):
    """Six polylines, one per joint, their points (target number, margin in deg) the ReachReport's margins
    at the targets; the limit line, the smallest margin marked; report.json says where it is."""
    from workcal_wb.core.robots import joint_margins_deg

    robot, reach = margin_report(1300.0)
    assert reach.reachable
    paths = write_report(CalibrationResult("ok", np.eye(4)), tmp_path, robot=robot, reach=reach)
    page = paths["html"].read_text(encoding="utf-8")
    lines = plotted_lines(page)
    assert list(lines) == ["A1", "A2", "A3", "A4", "A5", "A6"] and page.count("<polyline") == 6
    margins = joint_margins_deg(robot, reach.joints)  # (40, 6)
    for joint, name in enumerate(lines):
        assert sorted(lines[name]) == list(range(1, 41))
        for target in (1, 17, 40):
            assert lines[name][target] == pytest.approx(margins[target - 1, joint], abs=1e-3)
    m = reach.margin
    assert "joint limit</text>" in page and page.count('class="worst"') == 1
    assert f"smallest: A{m.joint + 1} {m.value:.1f} deg {m.where.on()}" in page
    assert "<h2>Robot reach</h2>" in page and "follows the calibrated program, all 40 robot targets" in page
    data = json.loads(paths["json"].read_text(encoding="utf-8"))["reach"]
    assert data["robot"] == "kuka_kr16_2" and data["problem"] is None
    assert data["smallest_margin"]["joint"] == f"A{m.joint + 1}" and data["smallest_margin"]["deg"] == m.value


def test_a_program_the_robot_cannot_follow_is_plotted_up_to_where_it_fails(tmp_path):
    robot, reach = margin_report(2600.0)
    assert reach.problem == "out_of_reach"
    page = write_report(CalibrationResult("ok", np.eye(4)), tmp_path, robot=robot, reach=reach)["html"].read_text(
        encoding="utf-8")
    followed = int(np.flatnonzero(~np.isnan(reach.joints[:, 0]))[-1]) + 1
    assert all(max(line) == followed < 40 for line in plotted_lines(page).values())
    assert f"fails {reach.problem_at.on()}" in page and "cannot follow the calibrated program" in page


def test_a_long_program_keeps_every_dip_towards_a_limit(tmp_path, monkeypatch):
    """Past MAX_PLOTTED_TARGETS a line keeps, per stretch of targets, the one nearest the limit: the
    smallest margin of each joint is still drawn."""
    from workcal_wb.core import report
    from workcal_wb.core.robots import joint_margins_deg

    monkeypatch.setattr(report, "MAX_PLOTTED_TARGETS", 7)
    robot, reach = margin_report(1300.0)
    lines = plotted_lines(report.joint_margins_svg(robot, reach))
    margins = joint_margins_deg(robot, reach.joints)
    for joint, name in enumerate(lines):
        assert len(lines[name]) == 7
        assert min(lines[name].values()) == pytest.approx(margins[:, joint].min(), abs=1e-3)
