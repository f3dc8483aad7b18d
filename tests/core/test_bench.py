"""The benchmark's cases carry the right truth and realistic clutter; its table flags missed targets."""
import numpy as np
import pytest

from workcal_wb.core import frames
from workcal_wb.core.benchmark.cases import BUNNY_UP, bunny_cases, simulated_cases, with_clutter
from workcal_wb.core.benchmark.run import STOCK, WORKCAL, Row, _table
from workcal_wb.core.surface import SurfaceModel


def _on_model(case, surface, gate=2.0):
    """Fraction of the scan that lies within ``gate`` mm of the model placed by the case's truth."""
    _, _, found = surface.nearest(frames.apply(frames.invert(case.truth), case.scan), gate)
    return found.mean()


@pytest.mark.slow
def test_simulated_cases_sit_on_their_model_at_the_truth():
    cases = simulated_cases(seed=1, quick=True)
    surfaces = {}
    for case in cases:
        surface = surfaces.setdefault(id(case.model), SurfaceModel(case.model))
        share = _on_model(case, surface, gate=1.5)  # the model sample spacing
        assert (share > 0.99) if "region" in case.name else (0.05 < share < 0.5), case.name
    assert {c.group for c in cases} == {"simulated car, region", "simulated car, whole scene",
                                       "simulated figurine, region"}


@pytest.mark.slow
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


def _rows(method, success=True, time_s=0.1, group="bunny clean", cpu_s=0.1):
    return [Row(f"case {i}", group, method, 40000, 0.05 if success or i else 5.0, 0.1, time_s, "ok", False, cpu_s)
            for i in range(4)]


def test_table_reports_met_and_missed_targets():
    good = _table({WORKCAL: (_rows(WORKCAL, time_s=0.1), 300.0), STOCK: (_rows(STOCK, time_s=0.3, cpu_s=0.55), 400.0)},
                  seed=0, quick=True, rounds=1, note=None)
    assert not good.missed and "all met" in good.text
    assert "| 0.100 | 0.33 | 0.100 |" in good.text and "| 0.300 | 1.00 | 0.550 |" in good.text  # time, ratio, CPU
    assert "WorkCal 300 MB, Open3D stock 400 MB" in good.text
    slow_and_wrong = _table({WORKCAL: (_rows(WORKCAL, success=False, time_s=0.2), 500.0),
                             STOCK: (_rows(STOCK, time_s=0.3), 400.0)}, seed=0, quick=True, rounds=1, note=None)
    assert any("success 75%" in m for m in slow_and_wrong.missed)
    assert any("0.67 x stock" in m for m in slow_and_wrong.missed)
    assert any("WorkCal 500 MB above stock's 400 MB" in m for m in slow_and_wrong.missed)


def test_large_scan_table_flags_missed_targets():
    from workcal_wb.core.benchmark.large import table

    def row(scan, run, time_s, peak_mb, status="ok", rotation=0.001, command="match"):
        return {"scan": scan, "command": command, "run": run, "file_points": 5_003_516, "file_mb": 60.0,
                "used_points": 5_003_516, "status": status, "rotation_error_deg": rotation, "displacement_mm": 0.01,
                "time_s": time_s, "peak_mb": peak_mb, "thinned": []}

    text, missed = table([row("5M", "cold", 9.0, 700), row("5M", "warm", 3.9, 700),
                          row("20M", "warm", 30.0, 900), row("5M", "warm", 4.5, 900, command="calibrate")], (1.0, 2.0))
    assert not missed and "All met." in text and "| match | 5M | 5,003,516 | 60 | warm | 5,003,516 | ok |" in text
    assert "| calibrate | 5M | 5,003,516 | 60 | warm | 5,003,516 | ok |" in text
    text, missed = table([row("5M", "warm", 5.2, 700), row("20M", "cold", 30.0, 1600, "ambiguous", 2.0),
                          row("5M", "warm", 14.0, 1200, "failed", command="calibrate")], ())
    assert missed == ["large scans: match 5M warm: 5.20 s (target under 5 s)",
                      "large scans: match 20M cold: peak memory 1600 MB (target under 1500 MB)",
                      "large scans: match 20M cold: ambiguous, 2.0000 deg, 0.010 mm from the truth",
                      "large scans: calibrate 5M warm: 14.00 s (target under 5 s)",
                      "large scans: calibrate 5M warm: failed, 0.0010 deg, 0.010 mm from the truth"]
    drawn = "5M drawn to 1M #1"  # a sensor of lower resolution: its pose must be found; no time target
    text, missed = table([row(drawn, "warm", 9.0, 700, command="calibrate"),
                          row(drawn, "warm", 9.0, 700, "ambiguous", command="calibrate")], ())
    assert missed == [f"large scans: calibrate {drawn} warm: ambiguous, 0.0010 deg, 0.010 mm from the truth"]
    assert "random draws of its points (3 of 1M, 3 of 2M, 3 of 3M)" in text
    assert "random draws" not in table([row("5M", "warm", 3.9, 700)], ())[0]


def test_the_large_scans_draws_are_random_points_of_the_scan_written_once(tmp_path, monkeypatch):
    from workcal_wb.core.benchmark import cases, large
    from workcal_wb.core.geometry import Cloud
    from workcal_wb.core.readers import read_cloud
    from workcal_wb.core.writers import write_ply

    monkeypatch.setattr(large, "FOLDER", tmp_path)
    monkeypatch.setattr(large, "DRAWS", ((300, 2), (600, 1)))
    points = np.random.default_rng(0).uniform(0, 100, (1000, 3)).astype(np.float32).astype(float)
    scan = tmp_path / "scan.ply"
    write_ply(scan, Cloud(points))
    files = large.draw_files(scan, 0, lambda message: None)
    assert [label for label, _ in files] == ["5M drawn to 0.0003M #1", "5M drawn to 0.0003M #2",
                                             "5M drawn to 0.0006M #1"]
    drawn = [read_cloud(path).points for _, path in files]
    assert [len(p) for p in drawn] == [300, 300, 600]
    scanned = {tuple(x) for x in points}
    for path, p in zip((path for _, path in files), drawn):  # points of the scan, each once, as float32
        assert all(tuple(x) in scanned for x in p) and len(np.unique(p, axis=0)) == len(p)
        assert b"property float x" in path.read_bytes()[:400]
    assert not np.array_equal(drawn[0], drawn[1])
    written = []
    monkeypatch.setattr(cases, "write_float32_ply", lambda *args: written.append(args))
    assert large.draw_files(scan, 0, lambda message: None) == files and not written  # reused
    assert not list(tmp_path.glob("*.part"))


@pytest.fixture(scope="module")
def dragon_set():
    """The verdicts table's dragon cases (seed 0), made once for the tests that use them."""
    from workcal_wb.core.benchmark.verdicts import dragon_cases

    return dragon_cases(seed=0)


@pytest.mark.slow
def test_dragon_scans_lie_on_the_other_scans_at_their_truth(dragon_set):
    """The real-data set in the repository: each decimated dragon scan, moved by its .conf truth,
    lies on the other 14 scans aligned the same way (the model it is matched against)."""
    cases = dragon_set
    assert len(cases) == 15
    for case in cases[::7]:
        surface = SurfaceModel(case.model)
        assert 0.85 < _on_model(case, surface, gate=1.0) <= 1.0, case.name
        wrong = frames.apply(frames.invert(case.truth), case.scan) @ frames.rot_z(90.0).T
        assert surface.nearest(wrong, 1.0)[2].mean() < 0.3


def test_verdict_table_counts_statuses_and_wrong_oks():
    from workcal_wb.core.benchmark.verdicts import VerdictRow, goals, table

    rows = [VerdictRow("a", "g", 100, 0.3, 0.1, False, "ok", True, ""),
            VerdictRow("b", "g", 100, 0.3, 0.1, False, "ok", False, ""),
            VerdictRow("c", "g", 100, 0.3, 0.1, False, "ambiguous", True, "the part may be nearly symmetric"),
            VerdictRow("d", "h", 100, 0.3, 0.5, False, "failed", True, "the scan's own noise is 0.50 mm"),
            VerdictRow("e", "h", 100, 0.3, 0.1, True, "ambiguous", True, "the model is symmetric")]
    wrong_ok, missed = goals(rows)
    assert [r.case for r in wrong_ok] == ["b"]
    assert [r.case for r in missed] == ["c"]  # d's noise is above its tolerance, e is symmetric
    text, wrong = table(rows, seed=0)
    assert wrong == ["b"]
    assert "| g | 3 | 1 / 1 | 1 / 0 | 0 / 0 |" in text and "| h | 2 | 0 / 0 | 1 / 0 | 1 / 0 |" in text
    assert "wrong poses reported \"ok\": **1** (goal 0): b" in text
    assert "not reported \"ok\": **1 of 2** (goal 0)" in text


def test_each_checks_refusals_are_counted_on_right_and_wrong_poses():
    """The cost table: a code's right poses refused (alone: nothing else refused them) and wrong poses
    it stopped (alone: no other check did), most costly first; "ok" rows do not count."""
    from workcal_wb.core.benchmark.verdicts import VerdictRow, table

    def row(name, status, right, codes):
        return VerdictRow(name, "g", 100, 0.3, 0.1, False, status, right, "", codes)

    rows = [row("a", "ok", True, ()), row("b", "ambiguous", True, ("rival",)),
            row("c", "ambiguous", True, ("rival", "outline_continued")), row("d", "ambiguous", False, ("rival",)),
            row("e", "failed", False, ("misfit", "rival")), row("f", "failed", True, ("rms",))]
    text, _ = table(rows, seed=0)
    costs = text[text.index("| code | right poses refused"):].split("\n")
    assert costs[2:5] == ["| `rival` | 2 | 1 | 2 | 1 |", "| `rms` | 1 | 1 | 0 | 0 |",
                          "| `outline_continued` | 1 | 0 | 0 | 0 |"]
    assert costs[5] == "| `misfit` | 0 | 0 | 1 | 0 |"


def test_whole_process_peak_memory_is_the_processs_own(tmp_path):
    """A command's peak memory is its own, not that of the (large) process that measures it."""
    from workcal_wb.core.benchmark.processes import PYTHON, timed

    ballast = np.ones(40_000_000)  # 320 MB in the measuring process
    _, small, _ = timed([PYTHON, "-c", "import numpy"])
    _, large, cpu = timed([PYTHON, "-c", "import numpy; a = numpy.ones(25_000_000)"])  # 200 MB more
    assert small < 150 < 190 < large < 320 and ballast[-1] == 1
    assert 0 < cpu  # the child's own CPU time, filling 200 MB


def test_whole_process_table_flags_missed_targets():
    from workcal_wb.core.benchmark.processes import (BUNNY_CLEAN, COLD, IN_PROCESS, KISS, STOCK as PEER, WARM, Run,
                                                     table)

    def runs(command, method, time_s, peak, success=True, n=4, family=BUNNY_CLEAN):
        return [Run(command, method, f"case {i}", time_s, peak, success or i > 0,
                    family if command == "match" else "demo scene", time_s / 2) for i in range(n)]

    good = (runs("match", COLD, 0.8, 300) + runs("match", WARM, 0.2, 300) + runs("match", PEER, 1.0, 400)
            + runs("match", KISS, 0.8, 200) + runs("match", WARM, 0.4, 90, family="depth camera")
            + runs("match", PEER, 0.9, 90, family="depth camera") + runs("calibrate", WARM, 0.9, 350)
            + runs("calibrate", IN_PROCESS, 0.25, 350))
    text, missed = table(good, [PEER, KISS], None)
    assert not missed and "All met." in text
    # vs stock (1.0 s) and vs the faster peer (0.8 s)
    assert "| match | bunny clean | WorkCal warm | 4 | 100% | 0.200 | 0.20 | 0.25 | 0.100 | 300 | 300 |" in text
    assert "| match | depth camera | WorkCal warm | 4 | 100% | 0.400 | 0.44 | 0.44 | 0.200 | 90 | 90 |" in text
    bad = (runs("match", WARM, 0.3, 500, success=False) + runs("match", PEER, 1.0, 400)
           + runs("match", KISS, 0.6, 200) + runs("match", WARM, 0.5, 95, family="depth camera")
           + runs("match", PEER, 0.9, 90, family="depth camera") + runs("calibrate", WARM, 1.2, 350)
           + runs("calibrate", IN_PROCESS, 0.4, 350))
    text, missed = table(bad, [PEER, KISS], "a note")
    assert len(missed) == 7 and "Note: a note" in text
    assert missed[0].startswith("whole processes: bunny clean: warm match 0.300 s (0.30 x Open3D stock")
    assert "success 75% vs 100%" in missed[0]
    assert "500 MB above stock Open3D's 400 MB" in missed[1]  # match against match: calibrate's 350 MB not counted
    assert "depth camera: warm match 0.500 s (0.56 x Open3D stock's 0.900 s, target 0.5)" in missed[2]
    assert "depth camera: WorkCal match peak memory 95 MB above stock Open3D's 90 MB" in missed[3]
    assert "0.50 x KISS-Matcher" in missed[4]
    assert "1.20 s as a process" in missed[5] and "0.40 s in-process" in missed[6]


def test_the_whole_process_cases_are_the_match_tables_written_as_files(tmp_path, bunny):
    """Each case's scan and model files read back as the case's points, one model file per group,
    each case with its own name, family and tolerance (the depth camera's above the others); the quick
    subset keeps the first case of each family."""
    from workcal_wb.core.benchmark.cases import BUNNY_SCANS, iter_bunny_cases, iter_depth_camera_groups
    from workcal_wb.core.benchmark.processes import write_match_files
    from workcal_wb.core.readers import read_cloud

    def groups():
        return [list(iter_bunny_cases(bunny, 0, scans=BUNNY_SCANS[:2])), next(iter_depth_camera_groups(0, quick=True))]

    made = groups()
    written = list(write_match_files(tmp_path, iter(groups())))
    assert len(written) == 2 and written[0][0].model != written[1][0].model
    for files, cases in zip(written, made):
        assert [(f.name, f.family, f.tolerance_mm) for f in files] == [(c.name, c.group, c.tolerance_mm) for c in cases]
        assert len({f.model for f in files}) == 1
        assert np.allclose(read_cloud(files[0].model).points, cases[0].model.points, atol=1e-9)
        for file, case in zip(files, cases):
            assert np.allclose(read_cloud(file.scan).points, case.scan, atol=1e-9)
            assert np.array_equal(file.truth, case.truth)
    assert written[1][0].tolerance_mm > written[0][0].tolerance_mm
    (tmp_path / "quick").mkdir()
    quick = [f for files in write_match_files(tmp_path / "quick", iter(groups()), one_per_family=True) for f in files]
    assert [f.name for f in quick] == [c.name for c in made[0][:5]] + [made[1][0].name]
    assert len({f.family for f in quick}) == len(quick)


def test_a_section_replaces_its_old_version_and_keeps_the_rest():
    from workcal_wb.core.benchmark.run import _with_section

    page = "# Benchmark\n\n## Summary\n\nold table\n\n## Verdicts\n\nverdicts\n\n## Scenes\n\nscenes\n"
    added = _with_section(page, "## Whole processes\n\nfirst\n")
    assert added == ("# Benchmark\n\n## Summary\n\nold table\n\n## Whole processes\n\nfirst\n\n## Verdicts\n\n"
                     "verdicts\n\n## Scenes\n\nscenes\n")
    replaced = _with_section(added, "## Whole processes\n\nsecond\n")
    assert replaced == added.replace("first", "second")
    assert _with_section(replaced, "## Scenes\n\nnew\n") == replaced.replace("\nscenes\n", "\nnew\n")
    assert _with_section("", "## Scenes\n\nonly\n") == "## Scenes\n\nonly\n"
    assert _with_section(replaced, "# Benchmark\n\nnew table\n") == replaced.replace("## Summary\n\nold table", "new table")
    assert _with_section(replaced, "## Large scans\n\nbig\n") == replaced.replace(
        "## Whole processes", "## Large scans\n\nbig\n\n## Whole processes")


def test_peers_read_the_files_workcal_writes(tmp_path):
    from workcal_wb.core.benchmark.peers import read_vertices
    from workcal_wb.core.geometry import Cloud
    from workcal_wb.core.writers import write_ply

    points = np.random.default_rng(1).normal(size=(100, 3)) * 50
    write_ply(tmp_path / "mesh.ply", Cloud(points, triangles=np.array([[0, 1, 2], [2, 3, 4]])))
    write_ply(tmp_path / "normals.ply", Cloud(points, normals=np.tile([0.0, 0.0, 1.0], (100, 1))))
    for name in ("mesh.ply", "normals.ply"):
        assert np.array_equal(read_vertices(tmp_path / name), points)


@pytest.mark.slow
def test_real_scan_whose_first_search_misses_is_searched_again(dragon_set, monkeypatch):
    """Dragon stand scan 144 against the other 14 (verdicts table, seed 0): on Debian 12's stack the
    first feature search's best leaves the model 2 mm and more off the scan; the match searches once
    more and finds the right pose, "ok".  Whether the first search misses depends on the
    libraries' rounding (on Debian 13's it finds the pose at once), so a first search made to miss
    (its poses turned and moved off) shows the second one on every stack."""
    from workcal_wb.core import match as match_module
    from workcal_wb.core.benchmark.verdicts import right
    from workcal_wb.core.geometry import Cloud

    case = next(c for c in dragon_set if c.name == "dragon dragonStandRight_144")
    surface = SurfaceModel(case.model)
    result = match_module.match(Cloud(case.scan, name=case.name), surface)
    assert result.status == "ok" and right(surface, result.matrix, case.truth), result.reasons

    searches = match_module._global_candidates
    off = frames.from_euler_zyz(30.0, 100.0, -60.0, (40.0, -30.0, 20.0))  # a pose the refinement cannot bring back
    calls = []

    def first_misses(*args, **kwargs):
        calls.append(1)
        found = searches(*args, **kwargs)
        return [(off @ T, score) for T, score in found] if len(calls) == 1 else found

    monkeypatch.setattr(match_module, "_global_candidates", first_misses)
    result = match_module.match(Cloud(case.scan, name=case.name), surface)
    assert "search again" in result.timings_s and len(calls) == 2
    assert result.status == "ok" and right(surface, result.matrix, case.truth), result.reasons


@pytest.mark.slow
def test_verdicts_batch_on_a_process_pool_gives_the_serial_rows():
    """The verdicts' matches, one task per model, on two worker processes: the same rows, in the same
    order, as one after the other here (the scenes' calibrations go through the same parallel.Runner,
    whose pooled calibrations test_studies checks)."""
    import numpy as np

    from workcal_wb.core.benchmark.verdicts import VerdictCase, run, simulated_parts, simulated_view
    from workcal_wb.core.parallel import Runner

    parts = simulated_parts()
    cases = []
    for seed, name in enumerate(("rebated plate", "curved tile")):
        points, truth = simulated_view(parts[name], np.random.default_rng(seed), 0.05, samples=3000)
        cases.append(VerdictCase(name, name, points, parts[name], truth, 0.3))
    serial = run(None, seed=0, log=lambda message: None, runner=Runner(workers=1), cases=cases)
    pooled = run(None, seed=0, log=lambda message: None, runner=Runner(workers=2), cases=cases)
    assert [r.case for r in serial] == [c.name for c in cases]
    assert pooled == serial


@pytest.mark.slow
def test_the_l_block_on_its_foot_section_has_its_hundred_scenes_and_counts_a_wrong_ok():
    """The section's scenes: at least a hundred over seeds and two noise levels (the figurine stands in
    for the bunny without the shared data); its table and its one goal, no wrong W reported ok; and one
    scene calibrated into a row."""
    from workcal_wb.core.benchmark.scenes import SceneRow, goals, scene_row, table, upright_l_variants

    specs = upright_l_variants(0, bunny=False)
    scenes = [spec for group in specs.values() for spec in group]
    assert len(scenes) >= 100 and len({(s.seed, s.noise_mm) for s in scenes}) == len(scenes)
    assert {s.workpiece for s in scenes} == {"figurine"} and {s.noise_mm for s in scenes} == {0.1, 0.2}
    rows = [SceneRow("0.1 mm noise", "0.1 mm noise #0", 1000, "ok", 180.0, 400.0, 3.0, ""),
            SceneRow("0.1 mm noise", "0.1 mm noise #1", 1000, "ambiguous", 180.0, 400.0, 5.0, "a rival")]
    text = table(rows, 0, upright_l=True)
    assert text.startswith("## L-block on its foot\n") and "| **all** | 2 | 0 | 1 | 0 | 1 | 4.0 | 5.0 |" in text
    covered = [SceneRow("v", f"v #{i}", 1000, "ok", 0.01, error, 3.0, "", (), 0.1) for i, error in enumerate((0.05, 0.2))]
    assert "covers the true error (largest displacement of a workpiece model point) in **1 of 2** scenes" in table(
        covered, 0)
    assert goals(rows, None, "L-block on its foot") == [
        "L-block on its foot: a wrong W reported ok in 1 scene(s): 0.1 mm noise #0"]
    row = scene_row("0.1 mm noise", scenes[2], None, 0)
    assert row.status in ("ok", "ambiguous", "failed") and row.points > 10000 and row.time_s > 0
    assert row.outcome != "wrong", row


def test_the_scenes_table_holds_warm_processes_to_their_targets():
    """Beside the in-process times, the scenes table holds `workcal calibrate` as a warm whole process to
    its targets: its median, 95th percentile and slowest per variant, and the goals missed when the
    tail is over twice the median or a variant's median 3 s or more."""
    from workcal_wb.core.benchmark.scenes import SceneRow, goals, table

    def row(variant, k, warm):
        return SceneRow(variant, f"{variant} #{k}", 1000, "ok", 0.01, 0.02, 3.0, "", (), 0.1, warm, "ok")

    quick = [row("plain", k, 2.0 + 0.1 * k) for k in range(10)] + [row("touching", k, 2.5) for k in range(10)]
    text = table(quick, 0)
    assert "| plain | 10 | 10 | 0 | 0 | 0 | 3.0 | 3.0 | 2.5 | 2.9 | 2.9 |" in text
    assert "(1.1 x: met); variants with a median of 3 s or more: none." in text and not goals(quick)
    slow = quick[:10] + [row("touching", k, 4.0 + k) for k in range(10)]
    assert goals(slow) == ["scenes: warm calibrate's 95th percentile 12.1 s is 3.5 x its median (target 2)",
                           "scenes: warm calibrate's median 3 s or more in touching (8.5 s)"]


@pytest.mark.slow
def test_a_scene_calibrated_as_a_warm_process_comes_to_the_same_status():
    """A scene's files calibrated by `workcal calibrate` twice with one model cache: the second, timed,
    run's status is the in-process one."""
    from workcal_wb.core.benchmark.scenes import scene_row, variants

    row = scene_row("sensor frame", variants(0, bunny=False)["sensor frame"][0], None, 0, processes=True)
    assert row.status == "ok" and row.warm_status == row.status and 0 < row.warm_s < 60
