"""The benchmark's cases carry the right truth and realistic clutter; its table flags missed targets."""
import numpy as np

from workcal_wb.core import frames
from workcal_wb.core.benchmark.cases import BUNNY_UP, bunny_cases, simulated_cases, with_clutter
from workcal_wb.core.benchmark.run import STOCK, WORKCAL, Row, _table
from workcal_wb.core.surface import SurfaceModel


def _on_model(case, surface, gate=2.0):
    """Fraction of the scan that lies within ``gate`` mm of the model placed by the case's truth."""
    _, _, found = surface.nearest(frames.apply(frames.invert(case.truth), case.scan), gate)
    return found.mean()


def test_simulated_cases_sit_on_their_model_at_the_truth():
    cases = simulated_cases(seed=1, quick=True)
    surfaces = {}
    for case in cases:
        surface = surfaces.setdefault(id(case.model), SurfaceModel(case.model))
        share = _on_model(case, surface, gate=1.5)  # the model sample spacing
        assert (share > 0.99) if "region" in case.name else (0.05 < share < 0.5), case.name
    assert {c.group for c in cases} == {"simulated car, region", "simulated car, whole scene",
                                       "simulated figurine, region"}


def test_bunny_reference_poses_and_realistic_clutter(bunny):
    cases = {c.name: c for c in bunny_cases(bunny, seed=2, scans=("bun000.ply",))}
    surface = SurfaceModel(cases["bun000 clean"].model)
    assert _on_model(cases["bun000 clean"], surface) > 0.97
    clean, cluttered = cases["bun000 clean"], cases["bun000 table, box, 20 % stray"]
    # As many table and box points as scan points, then a fifth of the whole is stray.
    assert 2.4 * len(clean.scan) < len(cluttered.scan) < 2.6 * len(clean.scan)
    assert 0.35 < _on_model(cluttered, surface) < 0.45
    # The table lies under the part: its plane passes through the model's lowest point along "up".
    in_model = frames.apply(frames.invert(cluttered.truth), cluttered.scan[len(clean.scan):])
    heights = in_model @ BUNNY_UP
    lowest = clean.model.points @ BUNNY_UP
    assert np.mean(np.abs(heights - lowest.min()) < 1.0) > 0.45


def test_with_clutter_is_deterministic_for_a_seed():
    scan = np.random.default_rng(0).normal(size=(500, 3)) * [30, 20, 10]
    from workcal_wb.core.geometry import Cloud

    model = Cloud(scan)
    a, b = (with_clutter(scan, np.eye(4), model, np.array([0, 0, 1.0]), np.random.default_rng(3)) for _ in range(2))
    assert np.array_equal(a, b)


def _rows(method, success=True, time_s=0.1, group="bunny clean"):
    return [Row(f"case {i}", group, method, 40000, 0.05 if success or i else 5.0, 0.1, time_s, "ok", False)
            for i in range(4)]


def test_table_reports_met_and_missed_targets():
    good = _table({WORKCAL: (_rows(WORKCAL, time_s=0.1), 300.0), STOCK: (_rows(STOCK, time_s=0.3), 400.0)},
                  [], seed=0, quick=True, rounds=1, note=None)
    assert not good.missed and "all met" in good.text and "| 0.33 |" in good.text
    slow_and_wrong = _table({WORKCAL: (_rows(WORKCAL, success=False, time_s=0.2), 300.0),
                             STOCK: (_rows(STOCK, time_s=0.3), 400.0)}, [], seed=0, quick=True, rounds=1, note=None)
    assert any("success 75%" in m for m in slow_and_wrong.missed)
    assert any("0.67 x stock" in m for m in slow_and_wrong.missed)
