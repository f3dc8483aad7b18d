"""The paper's two shape measures: least-squares closest-point D (ICP) and the mean directed Hausdorff
distance H through the precomputed space binning, minimised by sampled derivatives."""
import numpy as np
import pytest

from workcal_wb.core import frames
from workcal_wb.core.benchmark.cases import bunny_cases, zoomed_on_workpiece
from workcal_wb.core.benchmark.tables import pose_errors
from workcal_wb.core.geometry import Cloud
from workcal_wb.core.match import match
from workcal_wb.core.paper_methods import hausdorff_distances, refine_paper
from workcal_wb.core.simulate.scene import build_scene
from workcal_wb.core.surface import NearestGrid, SurfaceModel


@pytest.fixture(scope="module")
def car():
    scene = build_scene("car", seed=5)
    scan = zoomed_on_workpiece(scene, -40.0, 5).scan(scene)
    motion = frames.random_motion(np.random.default_rng(5))
    points = frames.apply(motion, scan.points[scan.mask("workpiece")])
    return points, SurfaceModel(scene.workpiece_model()), motion @ scan.U


def _mean_distance(points, surface, T, gate):
    """H of the scan placed by T (scan -> model), measured exactly on the mesh and capped at the gate."""
    return np.minimum(surface.exact_distance(frames.apply(T, points)), gate).mean()


@pytest.mark.slow
@pytest.mark.parametrize("method", ["icp", "hausdorff"])
def test_converges_from_a_nearby_start(car, method):
    points, surface, U = car
    start = frames.invert(U @ frames.from_euler_zyz(3.0, 2.0, -2.5, (3.0, -2.0, 2.0)))  # scan -> model
    state = refine_paper(method, points[::4], surface, start)
    rotation, displacement = pose_errors(frames.invert(state.T), U, surface.vertices)
    assert rotation < 0.05 and displacement < 0.15
    assert state.iterations > 5 and state.gate < 2.0  # it iterated and the gate closed in on the noise
    gate = surface.diagonal / 40
    assert _mean_distance(points, surface, state.T, gate) < 0.1 * _mean_distance(points, surface, start, gate)


@pytest.mark.slow
@pytest.mark.parametrize("method", ["icp", "hausdorff"])
def test_selectable_by_name_after_the_global_search(car, method):
    points, surface, U = car
    result = match(Cloud(points), surface, method=method)
    rotation, displacement = pose_errors(result.matrix, U, surface.vertices)
    assert result.method == method and result.status == "ok"
    assert rotation < 0.05 and displacement < 0.15


def test_binning_gives_the_distance_to_the_surface(car):
    _, surface, _ = car
    grid = surface.grid(2 * surface.spacing, 5.0)
    grid.precompute()
    rng = np.random.default_rng(2)
    near = surface.points[rng.choice(len(surface.points), 4000)] + rng.normal(0.0, 1.0, (4000, 3))
    binned = hausdorff_distances(near, surface, grid, gate=5.0)
    exact = np.minimum(surface.exact_distance(near), 5.0)
    error = np.abs(binned - exact)
    assert np.median(error) < 0.01 and np.percentile(error, 95) < 0.1
    # Each filled cell holds the sample nearest its centre, as a KD-tree finds it (stored as index + 1).
    state = grid.state()
    cells = state["cells"][state["values"] > 0][::97]
    centres = grid.centres(cells)
    _, nearest = surface.tree.query(centres)
    assert np.array_equal(grid.stored(cells) - 1, nearest) and np.array_equal(grid.lookup(centres), nearest)
    # Cells far from the model hold "none", also in bricks precompute never stored.
    filled, corner = grid.filled, grid.lo[None] + 0.5 * grid.cell
    assert grid.stored(grid._cells(corner)[0])[0] == -1 and grid.lookup(corner)[0] == -1 and grid.filled == filled


def test_a_grid_keeps_only_the_cells_near_what_it_was_asked(car):
    """Lookups near the surface store the bricks of the cells they visit, not the millions of cells of
    the whole grid (a dense grid held pages of untouched cells: 11 MB of a bunny match)."""
    _, surface, _ = car
    grid = surface.grid(0.5 * surface.spacing, 3.0)
    rng = np.random.default_rng(5)
    near = surface.points[rng.choice(len(surface.points), 1000)] + rng.normal(0.0, 0.5, (1000, 3))
    found = grid.lookup(near)
    _, nearest = surface.tree.query(grid.centres(grid._cells(near)[0]), distance_upper_bound=3.0)
    assert np.array_equal(found, np.where(nearest < len(surface.points), nearest, -1))
    assert grid._rows[:grid._used].nbytes < 0.1 * 4 * np.prod(grid.dims)  # a dense int32 grid's bytes



def test_a_grid_shared_by_two_threads_answers_as_a_grid_used_by_one(car):
    """In FreeCAD one kept model may serve a task panel's worker and a recompute at once: storing a
    brick moves rows and grows the array, so lookups racing it returned wrong samples (or raised)."""
    import sys
    import threading

    _, surface, _ = car
    rng = np.random.default_rng(9)
    batches = [surface.points[rng.choice(len(surface.points), 300)] + rng.normal(0.0, 2.0, (300, 3))
               for _ in range(120)]
    alone, shared = (NearestGrid.around(surface.points, surface._tree, 0.37 * surface.spacing, 4.0) for _ in range(2))
    expected = [alone.lookup(b) for b in batches]
    found, errors = {}, []

    def work(order):
        try:
            for i in order:
                found.setdefault(i, []).append(shared.lookup(batches[i]))
        except Exception as exc:  # noqa: BLE001 - any failure in a thread is the defect
            errors.append(exc)

    switch = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    try:
        threads = [threading.Thread(target=work, args=(order,)) for order in (range(120), range(119, -1, -1))]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    finally:
        sys.setswitchinterval(switch)
    assert not errors
    assert all(np.array_equal(f, expected[i]) for i, fs in found.items() for f in fs)

@pytest.mark.slow
def test_paper_methods_on_a_real_bunny_scan(bunny):
    case = bunny_cases(bunny, seed=4, scans=("bun090.ply",))[0]  # the clean scan
    surface = SurfaceModel(case.model)
    for method in ("icp", "hausdorff"):
        result = match(Cloud(case.scan), surface, method=method)
        rotation, displacement = pose_errors(result.matrix, case.truth, case.model.points)
        assert result.status == "ok" and rotation < 0.5 and displacement < 1.0, method


def test_unknown_paper_method_is_refused(car):
    points, surface, U = car
    with pytest.raises(ValueError, match="paper method"):
        refine_paper("chamfer", points, surface, frames.invert(U))


def test_a_complete_grid_answers_as_one_filled_on_use(car):
    """precompute fills every cell within the bound, also those diagonally off the surface past a
    corner or an edge (its dilation took six neighbours a step and missed them: they said "none"
    where a grid filled on use gives the sample)."""
    _, surface, _ = car
    cell = 2 * surface.spacing
    bound = 5 * cell
    complete, on_use = (NearestGrid.around(surface.points, lambda: surface.tree, cell, bound) for _ in range(2))
    complete.precompute()
    rng = np.random.default_rng(3)
    offsets = rng.normal(size=(20000, 3))
    offsets *= (rng.random(20000) * bound / np.linalg.norm(offsets, axis=1))[:, None]
    near = surface.points[rng.choice(len(surface.points), 20000)] + offsets
    assert np.array_equal(complete.lookup(near), on_use.lookup(near))
