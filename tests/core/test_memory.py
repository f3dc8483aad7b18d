"""Memory: a prepared model let go is freed at once (the benchmark and a FreeCAD session drop one model
for the next; a reference cycle kept each until the garbage collector's next full pass)."""
import gc
import weakref

import numpy as np
import pytest

from workcal_wb.core.geometry import Cloud
from workcal_wb.core.surface import SurfaceModel


def test_a_prepared_model_let_go_is_freed_without_the_garbage_collector():
    rng = np.random.default_rng(0)
    u, v = rng.random((2, 1500)) * [[2 * np.pi], [np.pi]]
    points = np.column_stack([30 * np.cos(u) * np.sin(v), 20 * np.sin(u) * np.sin(v), 10 * np.cos(v)])
    model = Cloud(points + rng.normal(0, 0.01, points.shape), name="ellipsoid")
    gc.collect()
    gc.disable()
    try:
        surface = SurfaceModel(model)
        assert (surface.grid_level(0).lookup(points) >= 0).all()  # a grid made and filled, as a match does
        alive = weakref.ref(surface)
        del surface
        assert alive() is None
    finally:
        gc.enable()


def test_a_copied_model_keeps_working_after_the_original_is_let_go():
    """A grid holds the samples' KD-tree holder, not the model (no cycle); a copy of the model (FreeCAD
    copies objects) must not be left with grids that need the original: once that is gone, filling a
    cell still needs the samples (grids holding the model weakly failed here)."""
    import copy

    rng = np.random.default_rng(1)
    u, v = rng.random((2, 1500)) * [[2 * np.pi], [np.pi]]
    points = np.column_stack([30 * np.cos(u) * np.sin(v), 20 * np.sin(u) * np.sin(v), 10 * np.cos(v)])
    surface = SurfaceModel(Cloud(points, name="ellipsoid"))
    grid = surface.grid_level(0)
    copied = copy.deepcopy(surface)
    del surface
    gc.collect()
    query = points[:50] + 0.01
    nearest = copied.tree.query(query)[0]
    for kept in (copied.grid_level(0), grid):  # the copy's grid, and a grid kept without its model
        idx = kept.lookup(query)
        assert (idx >= 0).all()
        # a cell's sample is at most a cell diagonal farther than the point's own nearest sample
        assert (np.linalg.norm(query - copied.points[idx], axis=1) <= nearest + np.sqrt(3) * kept.cell + 1e-9).all()


def _traced_peak_mb(work):
    """(MB work allocated at its peak above what was live when it started, its result), by tracemalloc,
    which counts numpy's buffers exactly (unlike the resident set, deterministic)."""
    import tracemalloc

    tracing = tracemalloc.is_tracing()  # (-X tracemalloc): count from here, and leave it on
    tracemalloc.start()
    tracemalloc.reset_peak()
    try:
        before = tracemalloc.get_traced_memory()[0]
        result = work()
        return (tracemalloc.get_traced_memory()[1] - before) / 1e6, result
    finally:
        if not tracing:
            tracemalloc.stop()


def _large_scan(n=500_000, seed=0):
    return np.random.default_rng(seed).normal(size=(n, 3)) * [100.0, 80.0, 60.0] + 500.0


def test_voxel_keys_of_a_large_scan_hold_no_copy_of_it():
    """The whole scan's cells as floats and as integers were two copies of it (24 MB for 500k points,
    6 columns): now keys (one column) and a block's cells."""
    from workcal_wb.core import pointops

    points = _large_scan()
    column_mb = len(points) * 8 / 1e6
    peak, keys = _traced_peak_mb(lambda: pointops.voxel_keys(points, 2.0))
    assert peak < 1.5 * column_mb
    cells = np.floor((points - points.min(axis=0)) / 2.0).astype(np.int64)
    assert np.array_equal(keys, (cells[:, 0] << 42) | (cells[:, 1] << 21) | cells[:, 2])


def test_voxel_keys_are_the_same_whatever_the_block(monkeypatch):
    """Blocks give the keys of the whole; a cloud wider than 2**21 voxels falls back to ranks even when
    only a later block reaches that far."""
    from workcal_wb.core import pointops

    rng = np.random.default_rng(3)
    points = rng.normal(size=(5000, 3)) * 50
    far = points.copy()
    far[-1] = [1e7, 0, 0]
    whole = {name: pointops.voxel_keys(cloud, 0.5) for name, cloud in (("near", points), ("far", far))}
    monkeypatch.setattr(pointops, "KEY_BLOCK", 64)
    for name, cloud in (("near", points), ("far", far)):
        assert np.array_equal(pointops.voxel_keys(cloud, 0.5), whole[name])
    ranks = pointops.voxel_keys(far, 0.5)
    assert len(np.unique(ranks)) == len(np.unique(np.floor((far - far.min(axis=0)) / 0.5), axis=0))
    assert ranks.max() < len(far)  # ranks, not 21-bit fields the far voxel would overflow


def test_voxel_centroids_are_the_sums_of_each_voxels_points():
    """voxel_downsample sums an axis at a time (no copy of the scan in voxel order): the same centroids,
    bit for bit, as summing the sorted rows whole."""
    from workcal_wb.core import pointops

    points = _large_scan(200_000, seed=1)
    centroids, first, counts = pointops.voxel_downsample(points, 20.0, counts=True)
    keys = pointops.voxel_keys(points, 20.0)
    order = np.argsort(keys)
    starts = np.flatnonzero(np.r_[True, np.diff(keys[order]) != 0])
    assert np.array_equal(centroids, np.add.reduceat(points[order], starts, axis=0) / counts[:, None])
    assert np.array_equal(first, order[starts])


def test_duplicate_points_are_found_without_copies_of_the_scan():
    """The duplicate search of a 500k-point scan (run on every scan a match is given) kept about six
    columns' worth of temporaries (24 MB), then 4.5 (its first bucket counts had twice as many slots
    as points; a large scan's match peaked there); now under four, and the same points are found: the
    first of each repeated point is kept, -0.0 equals 0.0."""
    from workcal_wb.core import geometry

    points = _large_scan().astype(np.float32).astype(float)
    rng = np.random.default_rng(2)
    copies = rng.integers(0, len(points), 5000)
    points[rng.integers(0, len(points), 5000)] = points[copies]
    points[:3] = [0.0, 0.0, 0.0]
    points[3] = [-0.0, 0.0, -0.0]
    peak, duplicate = _traced_peak_mb(lambda: geometry._duplicates(points))
    assert peak < 4 * len(points) * 8 / 1e6
    first = np.zeros(len(points), bool)
    first[np.unique(points + 0.0, axis=0, return_index=True)[1]] = True
    assert np.array_equal(duplicate, ~first)


def test_the_support_plane_is_found_a_block_of_points_at_a_time(monkeypatch):
    """Every coarse point against every candidate plane at once was two (points x 200) float matrices
    (64 MB for 20k points, the largest transient of a match of a scene); now a block at a time, the same
    plane found."""
    from workcal_wb.core import global_search

    rng = np.random.default_rng(4)
    table = np.column_stack([rng.uniform(-300, 300, (15000, 2)), rng.normal(0, 0.1, 15000)])
    part = rng.normal(size=(5000, 3)) * 30 + [0, 0, 40]
    points = np.r_[table, part]
    peak, kept = _traced_peak_mb(lambda: global_search.without_large_plane(points, 2.0, 100.0,
                                                                          np.random.default_rng(1)))
    assert peak < 5.0
    assert len(kept) < len(part) + 200 and np.isin(part[:, 2], kept[:, 2]).mean() > 0.95
    monkeypatch.setattr(global_search, "PLANE_BLOCK", 7)
    assert np.array_equal(global_search.without_large_plane(points, 2.0, 100.0, np.random.default_rng(1)), kept)


def test_sample_cover_of_a_large_mesh_is_found_a_block_of_faces_at_a_time(monkeypatch):
    """A match's first far-off test asks how far the mesh lies from its samples: every face's corners at
    once, and their copies, were 12 MB for 44k faces (57 MB for 200k: the peak of a match against a
    large model).  Faces without area (a segment each) are weighed in whichever block holds them."""
    from workcal_wb.core import surface as surface_module
    from workcal_wb.core.simulate import shapes

    sphere = shapes.sphere(50.0, edge_mm=1.5)  # 43,680 faces
    # A long segment (three corners on a line, across the sphere) in the first and the last block.
    vertices = np.r_[sphere.points, [[-50.0, 0.0, 0.0], [0.0, 0.0, 0.0], [50.0, 0.0, 0.0]]]
    segment = len(vertices) - 3 + np.arange(3)
    triangles = np.r_[[segment], sphere.triangles, [segment[::-1]]]
    surface = SurfaceModel(Cloud(vertices, triangles=triangles, name="sphere"), 0)
    peak, cover = _traced_peak_mb(surface._sample_cover)
    assert peak < 8.0
    assert cover == surface.sample_cover >= 50.0  # half the segment's length: its middle is that far from either end
    monkeypatch.setattr(surface_module, "COVER_BLOCK", 1000)
    assert surface._sample_cover() == cover


def test_shape_kind_of_a_large_scan_holds_no_copy_of_it(monkeypatch):
    """Every match and every scene's region search first asks whether the scan spreads in three
    directions: the scan centred whole was a copy of it (12 MB for 500k points, the largest temporary
    at the start of a match of a large scene); now a block's.  Blocks tell the same kinds."""
    from workcal_wb.core import geometry

    points = _large_scan()
    peak, kind = _traced_peak_mb(lambda: geometry.shape_kind(points))
    assert kind == "solid" and peak < 0.35 * points.nbytes / 1e6  # two blocks at most (12 MB whole)
    plane = points.copy()
    plane[:, 2] = 0.0
    line = np.outer(np.linspace(-1, 1, 100_001), [3.0, 4.0, 5.0]) + 7.0
    kinds = [geometry.shape_kind(cloud) for cloud in (points, plane, line, np.zeros((100_000, 3)))]
    assert kinds == ["solid", "planar", "linear", "point"]
    monkeypatch.setattr(geometry, "SHAPE_BLOCK", 7)
    assert [geometry.shape_kind(cloud) for cloud in (points, plane, line, np.zeros((100_000, 3)))] == kinds


def test_the_freed_heap_is_handed_back_to_the_system():
    """glibc keeps freed arrays smaller than its mmap threshold (which grows to the largest array freed so
    far) in the heap, resident; a process that prepares a model and matches scan after scan carried each
    step's high-water mark into the next.  In a fresh interpreter: 60 arrays of 1 MB freed between
    arrays that stay are still resident until the heap is handed back."""
    import subprocess
    import sys
    from pathlib import Path

    script = """
import os
import numpy as np
from workcal_wb.core import pointops
def resident_mb():
    return int(open("/proc/self/statm").read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20
np.ones(8 * 2**20 // 8).sum()  # an 8 MB array freed: glibc's threshold rises above 1 MB arrays
kept, freed = [], []
for _ in range(60):
    freed.append(np.ones(2**20 // 8))
    kept.append(np.ones(2**14))  # 128 kB between them: too large for a hole the imports left
before = resident_mb()
freed.clear()
after_free = resident_mb()
pointops.hand_back_freed_heap()
print(before, after_free, resident_mb())
"""
    if not Path("/proc/self/statm").exists():
        import pytest
        pytest.skip("no /proc (not Linux)")
    root = Path(__file__).resolve().parents[2]
    out = subprocess.run([sys.executable, "-c", script], cwd=root, capture_output=True, text=True, check=True)
    before, after_free, handed_back = map(float, out.stdout.split())
    assert after_free > before - 10  # freed, but still resident
    assert handed_back < after_free - 40


@pytest.mark.slow
def test_prepare_and_match_hand_back_the_heap_they_leave(monkeypatch):
    """A model's preparation and each match free large temporaries: both hand the heap back when done."""
    from workcal_wb.core import match as match_module
    from workcal_wb.core import pointops

    calls = []
    monkeypatch.setattr(pointops, "hand_back_freed_heap", lambda: calls.append(1))
    rng = np.random.default_rng(5)
    u, v = rng.random((2, 3000)) * [[2 * np.pi], [np.pi]]
    points = np.column_stack([30 * np.cos(u) * np.sin(v), 20 * np.sin(u) * np.sin(v), 10 * np.cos(v)])
    surface = match_module.prepare(SurfaceModel(Cloud(points, name="ellipsoid")))
    assert calls
    calls.clear()
    result = match_module.match(Cloud(points[points[:, 2] > -3] + [5.0, 0.0, 0.0], name="scan"), surface)
    assert result.matrix is not None and calls
