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
