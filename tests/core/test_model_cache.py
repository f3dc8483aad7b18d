"""The cache of prepared models: a hit is the same model (bit-identical matches), anything that shapes a
model misses, a damaged or foreign file is prepared again, concurrent runs both succeed, the folder
stays bounded."""
import json
import os
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from workcal_wb.cli import main
from workcal_wb.core import frames
from workcal_wb.core.benchmark.cases import zoomed_on_workpiece
from workcal_wb.core.geometry import Cloud
from workcal_wb.core.match import match
from workcal_wb.core.model_cache import MAGIC, SUFFIX, ModelCache, cloud_key, default_folder
from workcal_wb.core.readers import read_cloud
from workcal_wb.core.simulate.scene import build_scene
from workcal_wb.core.surface import SurfaceModel
from workcal_wb.core.writers import write_ply

ROOT = Path(__file__).resolve().parents[2]
# The Python that runs `-m workcal_wb` (inside freecadcmd, sys.executable is FreeCAD itself).
PYTHON = sys.executable if Path(sys.executable).name.startswith("python") else "/usr/bin/python3"


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """The car model (mm) and a scan of it moved to a random pose, and the true U."""
    folder = tmp_path_factory.mktemp("cache")
    scene = build_scene("car", seed=5)
    scan = zoomed_on_workpiece(scene, 40.0, 5, pixel_pitch_mm=0.7).scan(scene)
    motion = frames.random_motion(np.random.default_rng(5))
    write_ply(folder / "scan.ply", Cloud(frames.apply(motion, scan.points[scan.mask("workpiece")])))
    write_ply(folder / "car.ply", scene.workpiece_model())
    return folder, motion @ scan.U


def _same(a, b) -> bool:
    """Two match results equal in every field but their timings."""
    return json.dumps(_timeless(a.to_dict()), sort_keys=True) == json.dumps(_timeless(b.to_dict()), sort_keys=True)


def _timeless(value):
    """A result's JSON without its timings (at any depth), the one part that differs run to run."""
    if isinstance(value, dict):
        return {k: _timeless(v) for k, v in value.items() if k not in ("time_s", "timings_s")}
    if isinstance(value, list):
        return [_timeless(v) for v in value]
    return value


def _entries(folder: Path) -> list:
    return sorted(folder.glob(f"*{SUFFIX}"))


@pytest.mark.slow
def test_a_hit_is_the_same_model_and_gives_a_bit_identical_match(files, tmp_path, monkeypatch):
    folder, U = files
    scan = read_cloud(folder / "scan.ply")
    plain = match(scan, SurfaceModel(read_cloud(folder / "car.ply"), 2), seed=2)
    cold = ModelCache(tmp_path)
    missed_model = cold.model_file(folder / "car.ply", seed=2)
    missed = match(scan, missed_model, seed=2)
    assert (cold.hits, cold.misses) == (0, 1) and cold.store() and len(_entries(tmp_path)) == 1
    warm = ModelCache(tmp_path)
    monkeypatch.setattr(SurfaceModel, "_sample_cover", lambda self: pytest.fail("the sample cover measured again"))
    model = warm.model_file(folder / "car.ply", seed=2)
    assert (warm.hits, warm.misses) == (1, 0) and model.name == "car.ply"
    hit = match(scan, model, seed=2)
    assert _same(plain, missed) and _same(missed, hit)
    assert np.array_equal(hit.matrix, plain.matrix) and frames.rotation_between_deg(hit.matrix, U) < 0.05
    # What the first match computed lazily (its voxel's features, the grid cells it visited) was kept:
    # the same match on the loaded model fills no cell and computes no feature.
    assert all(grid.filled == 0 for grid in model._grids.values())
    assert model.sample_cover == missed_model.sample_cover > 0  # read from the file
    assert not warm.store()  # nothing grew: nothing written again


@pytest.mark.slow
def test_a_loaded_model_is_written_again_when_its_run_filled_a_few_percent_more_cells():
    """Cells a run fills beside the many a cache holds (another view of the part) are written back, or
    every later run of that view fills them again; a handful are not worth the file."""
    from types import SimpleNamespace

    from workcal_wb.core.model_cache import _grew, _held

    grid = SimpleNamespace(known=lambda: 333_000)
    model = SimpleNamespace(_features={1.0: None}, _occupied={}, _grids={0: grid}, _custom_grids={})
    held = _held(model)
    grid.known = lambda: 333_000 + 28_000  # a clean bunny scan's run beside the cells of 50 others
    assert _grew(model, held)
    grid.known = lambda: 333_000 + 4_000
    assert not _grew(model, held)
    model._features[2.0] = None  # features at a voxel not held before
    assert _grew(model, held)


def test_a_changed_model_file_unit_or_option_misses(files, tmp_path):
    folder, _ = files
    ModelCache(tmp_path).model_file(folder / "car.ply")
    cache = ModelCache(tmp_path)
    cache.model_file(folder / "car.ply")
    cache.store()
    changed = read_cloud(folder / "car.ply")
    changed.points[0, 2] += 1e-3  # one vertex moved by a micrometre
    write_ply(tmp_path / "changed.ply", changed)
    for path, units, seed in ((tmp_path / "changed.ply", "mm", 0), (folder / "car.ply", "in", 0),
                              (folder / "car.ply", "mm", 1)):
        other = ModelCache(tmp_path)
        other.model_file(path, units=units, seed=seed)
        assert (other.hits, other.misses) == (0, 1), (path.name, units, seed)
    same = ModelCache(tmp_path)
    same.model_file(folder / "car.ply")
    assert same.hits == 1
    # A model given as points: its content is the key, also for a change in one coordinate.
    cloud = read_cloud(folder / "car.ply")
    first = ModelCache(tmp_path)
    first.model(cloud)
    first.store()
    again, moved = ModelCache(tmp_path), ModelCache(tmp_path)
    again.model(cloud)
    cloud.points[5, 0] += 1e-6
    moved.model(cloud)
    assert again.hits == 1 and moved.misses == 1


@pytest.mark.slow
def test_a_truncated_corrupt_or_foreign_file_is_prepared_again(files, tmp_path):
    folder, _ = files
    scan = read_cloud(folder / "scan.ply")
    first = ModelCache(tmp_path)
    reference = match(scan, first.model_file(folder / "car.ply"))
    first.store()
    (entry,) = _entries(tmp_path)
    good = entry.read_bytes()
    header_length = struct.unpack("<Q", good[len(MAGIC):len(MAGIC) + 8])[0]
    header = json.loads(good[len(MAGIC) + 8:len(MAGIC) + 8 + header_length])
    foreign = dict(header, format=header["format"] + 1)
    flipped = bytearray(good)
    flipped[-100] ^= 0x40  # one bit in the last array
    damaged = {
        "truncated": good[:len(good) // 2],
        "empty": b"",
        "not ours": b"\x80\x04\x95" + os.urandom(200),  # e.g. a pickle: never loaded
        "one bit flipped": bytes(flipped),
        "another format": _with_header(good, header_length, foreign),
        "another model's key": _with_header(good, header_length, dict(header, key="0" * 64)),
    }
    for what, data in damaged.items():
        entry.write_bytes(data)
        cache = ModelCache(tmp_path)
        model = cache.model_file(folder / "car.ply")
        assert (cache.hits, cache.misses) == (0, 1), what
        assert _same(match(scan, model), reference), what
        assert cache.store() == [entry.name], what  # the bad file is replaced by a good one
        again = ModelCache(tmp_path)
        again.model_file(folder / "car.ply")
        assert again.hits == 1, what


def _with_header(data: bytes, length: int, header: dict) -> bytes:
    text = json.dumps(header).encode()
    text += b" " * (length - len(text))  # the same length, so the arrays stay where they were
    assert len(text) == length
    return MAGIC + struct.pack("<Q", length) + text + data[len(MAGIC) + 8 + length:]


@pytest.mark.slow
def test_two_processes_filling_one_entry_both_succeed(files, tmp_path):
    folder, _ = files
    cache = tmp_path / "cache"
    runs = [subprocess.Popen([PYTHON, "-m", "workcal_wb", "match", str(folder / "scan.ply"),
                              str(folder / "car.ply"), "--cache", str(cache), "--json", str(tmp_path / f"{i}.json")],
                             cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for i in range(2)]
    for run in runs:
        out, err = run.communicate(timeout=300)
        assert run.returncode == 0, err
        assert "warning" not in err
    results = [json.loads((tmp_path / f"{i}.json").read_text()) for i in range(2)]
    assert results[0]["matrix"] == results[1]["matrix"] and results[0]["status"] == "ok"
    assert len(_entries(cache)) == 1 and not list(cache.glob("*.part")) and not list(cache.glob(".*"))
    after = ModelCache(cache)
    after.model_file(folder / "car.ply")
    assert after.hits == 1


@pytest.mark.slow
def test_the_folder_stays_bounded_least_recently_used_first(files, tmp_path):
    folder, _ = files
    clouds = []
    for k in range(3):  # three models: the car stretched by 0, 10 and 20 %
        cloud = read_cloud(folder / "car.ply")
        cloud.points[:, 0] *= 1.0 + 0.1 * k
        clouds.append(cloud)
    for cloud in clouds[:2]:
        cache = ModelCache(tmp_path)
        cache.model(cloud)
        cache.store()
    paths = [tmp_path / f"{cloud_key(cloud)}{SUFFIX}" for cloud in clouds]
    size = max(p.stat().st_size for p in paths[:2])
    os.utime(paths[0], (1, 1))  # the first is the older, until ...
    os.utime(paths[1], (2, 2))
    used = ModelCache(tmp_path)
    used.model(clouds[0])  # ... a run uses it again
    assert used.hits == 1
    bounded = ModelCache(tmp_path, max_bytes=2.5 * size)  # room for two models, not three
    bounded.model(clouds[2])
    bounded.store()
    assert [p.exists() for p in paths] == [True, False, True]


def test_the_default_folder_is_the_users_cache_folder(monkeypatch, tmp_path):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert default_folder() == tmp_path / "xdg" / "workcal" / "models"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    if sys.platform != "win32":
        assert default_folder() == tmp_path / "home" / ".cache" / "workcal" / "models"


@pytest.mark.slow
def test_match_command_cache_options(files, tmp_path, capsys, monkeypatch):
    folder, _ = files
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))  # this test's own "user cache folder"
    args = ["match", str(folder / "scan.ply"), str(folder / "car.ply")]
    assert main(args + ["--no-cache"]) == 0
    assert not (tmp_path / "xdg").exists()
    assert main(args) == 0  # the default: the user's cache folder
    assert len(_entries(tmp_path / "xdg" / "workcal" / "models")) == 1
    assert main(args + ["--cache", str(tmp_path / "mine")]) == 0 and len(_entries(tmp_path / "mine")) == 1
    (tmp_path / "a file").write_text("x")
    assert main(args + ["--cache", str(tmp_path / "a file")]) == 2
    assert "is a file" in capsys.readouterr().err
    assert main(args + ["--cache", str(tmp_path), "--no-cache"]) == 2
    assert len(_entries(tmp_path / "xdg" / "workcal" / "models")) == 1  # --cache DIR left the default alone


@pytest.mark.slow
def test_calibrate_gives_the_same_result_cold_warm_and_without_cache(tmp_path):
    """The whole calibrate command, as a user runs it twice, and once with --no-cache: one result.json."""
    from workcal_wb.cli.simulate import write_simulation

    scene = tmp_path / "scene"
    write_simulation(scene, "car", seed=3, pitch=0.8)
    results = {}
    for run, cache in (("cold", ["--cache", str(tmp_path / "cache")]), ("warm", ["--cache", str(tmp_path / "cache")]),
                       ("off", ["--no-cache"])):
        out = tmp_path / run
        assert main(["calibrate", "--scan", str(scene / "scan.ply"), "--workpiece", str(scene / "workpiece.ply"),
                     "--reference", str(scene / "reference.ply"), "--out", str(out), *cache]) == 0
        results[run] = _timeless(json.loads((out / "result.json").read_text()))
    assert len(_entries(tmp_path / "cache")) == 2  # both models kept by the first run
    assert results["cold"]["status"] == "ok"
    assert json.dumps(results["cold"], sort_keys=True) == json.dumps(results["warm"], sort_keys=True)
    assert json.dumps(results["cold"], sort_keys=True) == json.dumps(results["off"], sort_keys=True)


@pytest.mark.slow
def test_a_cache_folder_that_cannot_be_written_is_a_warning_not_a_failure(files, tmp_path, capsys):
    folder, _ = files
    (tmp_path / "a file").write_text("x")
    unwritable = tmp_path / "a file" / "cache"  # no folder can be made inside a file, not even by root
    assert main(["match", str(folder / "scan.ply"), str(folder / "car.ply"), "--cache", str(unwritable),
                 "--json", str(tmp_path / "m.json")]) == 0
    assert "warning: the model cache" in capsys.readouterr().err and (tmp_path / "m.json").exists()
