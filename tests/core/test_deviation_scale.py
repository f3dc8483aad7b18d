"""One deviation colour scale, read against the tolerance, shared by FreeCAD's 3D view and the report."""
import json
import zlib

import numpy as np
import pytest

from workcal_wb.core import frames
from workcal_wb.core.deviation import BEYOND_ADDED, BEYOND_REMOVED, NO_SURFACE, WITHIN, DeviationScale
from workcal_wb.core.errors import InputError
from workcal_wb.core.geometry import Cloud
from workcal_wb.core import picture
from workcal_wb.core.report import MODEL_GREY, deviation_views, legend_html, write_report
from workcal_wb.core.result import CalibrationResult

TOL = 0.3


def read_png(data: bytes) -> np.ndarray:
    """The pixels of a PNG as picture.png writes it (8-bit RGB, every row unfiltered)."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    chunks, at = {}, 8
    while at < len(data):
        length = int.from_bytes(data[at:at + 4], "big")
        kind = data[at + 4:at + 8]
        chunks[kind] = chunks.get(kind, b"") + data[at + 8:at + 8 + length]
        at += 12 + length
    width, height = int.from_bytes(chunks[b"IHDR"][:4], "big"), int.from_bytes(chunks[b"IHDR"][4:8], "big")
    rows = np.frombuffer(zlib.decompress(chunks[b"IDAT"]), np.uint8).reshape(height, 3 * width + 1)
    assert not rows[:, 0].any()
    return rows[:, 1:].reshape(height, width, 3)


def distance(a, b):
    return float(np.linalg.norm(np.asarray(a) - np.asarray(b)))


def test_colours_are_read_against_the_tolerance():
    scale = DeviationScale.for_tolerance(TOL)
    assert scale.limit_mm == pytest.approx(3 * TOL)  # the tolerance, not the data's extremes, sets the scale
    c = scale.colours([0.0, 0.99 * TOL, -0.99 * TOL, 1.5 * TOL, -1.5 * TOL, 3 * TOL, 5.0, -5.0, np.nan])
    np.testing.assert_allclose(c[:3], [WITHIN] * 3)
    assert distance(c[3], WITHIN) > 0.5 and distance(c[4], WITHIN) > 0.5  # just out of tolerance: plainly not green
    assert c[3][0] > c[3][2] and c[4][2] > c[4][0]  # added warm, removed cold
    assert distance(c[5], (0.86, 0.05, 0.0)) < 1e-6  # full red at the limit
    np.testing.assert_allclose(c[6:], [BEYOND_ADDED, BEYOND_REMOVED, NO_SURFACE])
    assert scale.ticks() == [pytest.approx(v) for v in (0.9, 0.3, 0.0, -0.3, -0.9)]


@pytest.mark.parametrize("limit", [0.2, 0.3, -1.0, np.inf])
def test_a_limit_inside_the_tolerance_is_refused(limit):
    with pytest.raises(InputError, match="past the tolerance|must lie past"):
        DeviationScale.for_tolerance(TOL, limit)


def test_the_report_uses_the_same_colours(tmp_path):
    """The report's map colours every point as the 3D view's scale does, and says which scale it used."""
    rng = np.random.default_rng(1)
    u, v = rng.uniform(-1, 1, (2, 4000))
    model = Cloud(np.column_stack([50 * u, 30 * v, 5 * np.cos(2 * u)]), name="model")
    U = frames.rigid(frames.rot_z(20.0), (10.0, 0.0, 300.0))
    lift = np.where(np.hypot(u, v) < 0.3, 0.8, 0.0)  # a lump 0.8 mm high: between tolerance and limit
    points = frames.apply(U, model.points + np.column_stack([np.zeros_like(u), np.zeros_like(u), lift]))
    calibration = CalibrationResult("ok", np.eye(4), U=U, V=np.eye(4), tolerance_mm=TOL)
    scale = DeviationScale.for_tolerance(TOL, 1.2)
    from workcal_wb.core.report import deviation_map

    d = deviation_map(calibration, points, model)
    views = deviation_views(d, calibration, points, model, scale)
    assert [v["title"] for v in views] == ["view along the shortest axis", "view along the middle axis"]
    expected = {tuple(c) for c in picture.to_bytes(scale.colours(d))}
    lump = tuple(picture.to_bytes(scale.colours([0.8]))[0])
    for view in views:
        image = read_png(view["png"])
        drawn = {tuple(c) for c in image.reshape(-1, 3)} - {(255, 255, 255), (200, 200, 200), (0, 0, 0),
                                                            tuple(picture.to_bytes(MODEL_GREY))}
        assert drawn <= expected and lump in drawn  # every point in its scale colour; the lump is seen
        assert view["scale_bar_mm"] in (10.0, 20.0)  # a round length, about a fifth of the 100 mm part
    legend = legend_html(scale)
    assert "rgb({},{},{})".format(*picture.to_bytes(BEYOND_ADDED)) in legend and "+1.2" in legend
    paths = write_report(calibration, tmp_path, workpiece_points=points, workpiece_model=model, deviation_scale=scale)
    data = json.loads(paths["json"].read_text())
    assert data["deviation"]["colour_scale"] == {"tolerance_mm": TOL, "limit_mm": 1.2}
