"""NearestGrid.precompute: every cell of a complete grid holds what a KD-tree query of its centre
gives (the sample nearest it within the bound, else "none"), however the grid was scanned."""
import numpy as np
import pytest
from scipy.spatial import cKDTree

from workcal_wb.core import surface as surface_module
from workcal_wb.core.surface import BRICK, NearestGrid


def _plate(rng):
    """A thin, tilted plate: 2 mm thick at most, so the grid is flat and its edges and corners are
    where only diagonal steps reach the cells near them."""
    u, v = rng.uniform(0.0, 30.0, (2, 900))
    return np.column_stack([u, v, 0.3 * u + rng.uniform(-1.0, 1.0, 900)])


def _shell(rng):
    """A lumpy closed shell: cells near it inside and outside, curved every way."""
    d = rng.normal(size=(1500, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    return d * (10.0 + 2.0 * np.sin(3.0 * d[:, :1])) * [1.0, 0.7, 1.3]


def _every_cell(grid):
    ijk = np.indices(tuple(grid.dims)).reshape(3, -1).T
    return grid._keys(ijk)


@pytest.mark.parametrize("shape", [_plate, _shell])
@pytest.mark.parametrize("slab_cells", [1 << 18, 1])  # the whole grid in one slab; a slab of one brick layer
def test_a_precomputed_grid_holds_in_every_cell_what_a_query_of_its_centre_gives(shape, slab_cells, monkeypatch):
    monkeypatch.setattr(surface_module, "NEAR_SLAB_CELLS", slab_cells)
    monkeypatch.setattr(surface_module, "FILL_CHUNK", 1000)  # several queries per slab
    rng = np.random.default_rng(11)
    points = shape(rng)
    tree = cKDTree(points)
    grid = NearestGrid.around(points, lambda: tree, 1.0, 3.7)
    grid.lookup(points[::50] + 2.0)  # some bricks stored before precompute, as after a lazy match
    grid.precompute()
    keys = _every_cell(grid)
    distance, nearest = tree.query(grid.centres(keys), distance_upper_bound=grid.bound)
    expected = np.where(np.isfinite(distance), nearest + 1, -1)
    assert (expected > 0).any() and (expected == -1).any()
    assert np.array_equal(grid.stored(keys), expected)
    # Rows were allocated for exactly the bricks that hold a near cell (grown on demand, up to half
    # again as many were allocated).
    near_bricks = np.unique(keys[expected > 0] // BRICK**3)
    assert len(grid._rows) == grid._used and grid._used - 2 <= len(near_bricks)


@pytest.mark.slow
def test_prepare_fills_the_grid_levels_a_depth_cameras_gates_ask_for():
    """A depth camera's 2.5 mm tolerance asks for gates of the third grid level: prepare fills it with
    the two finer ones (and a mesh's BVH), so a batch of matches reads those cells instead of filling
    them in each match; a coarser level stays unfilled, and no grid is said filled before prepare."""
    from workcal_wb.core.match import REFINE, prepare
    from workcal_wb.core.simulate import shapes
    from workcal_wb.core.surface import SurfaceModel

    surface = SurfaceModel(shapes.box((60.0, 40.0, 20.0)), 0)
    assert not any(surface.grid_filled(level) for level in range(4))
    prepare(surface)
    assert REFINE.prepared_levels == 3
    assert [surface.grid_filled(level) for level in range(4)] == [True, True, True, False]
    assert "_bvh" in vars(surface)  # built (a cached property)
