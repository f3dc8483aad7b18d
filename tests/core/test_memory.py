"""Memory: a prepared model let go is freed at once (the benchmark and a FreeCAD session drop one model
for the next; a reference cycle kept each until the garbage collector's next full pass)."""
import gc
import weakref

import numpy as np

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
