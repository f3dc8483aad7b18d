"""Rays cast against triangle meshes by open3d's RaycastingScene, where its ray casting works.

open3d 0.16 (Debian 12) builds a RaycastingScene whose ``cast_rays`` returns no hits at all; 0.19
(Debian 13) casts them correctly (Embree, single precision: a scan of the simulated cell, 90k to 280k
rays on 55k to 100k triangles, takes half the time of our numpy z-buffer, with the same pixels).
``works()`` casts two rays at one triangle once per process, one that must hit it at a known distance
and one that must miss, and caches the answer: callers cast rays where it works and keep their own
z-buffer (simulate.raster) where it does not.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

# The probe: a ray down the z axis hits the triangle at this distance; a ray beside it misses.
_PROBE_TRIANGLE = np.array([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]])
_PROBE_RAYS = np.array([[0.0, 0.0, 5.0, 0.0, 0.0, -1.0], [3.0, 3.0, 5.0, 0.0, 0.0, -1.0]])
_PROBE_DISTANCE = 5.0


@lru_cache(maxsize=1)
def works() -> bool:
    """Whether this open3d casts rays correctly (probed once per process)."""
    try:
        import open3d
    except ImportError:
        return False
    return casts_correctly(open3d)


def casts_correctly(open3d) -> bool:
    """Whether ``open3d`` (the module) hits the probe triangle where it lies and misses beside it;
    any error counts as not working."""
    try:
        t_hit, _ = _cast(open3d, _PROBE_TRIANGLE, np.array([[0, 1, 2]]), _PROBE_RAYS)
    except Exception:  # an open3d without the tensor API, or one that fails in its own way
        return False
    return bool(abs(t_hit[0] - _PROBE_DISTANCE) < 1e-4 and not np.isfinite(t_hit[1]))


def cast(vertices: np.ndarray, triangles: np.ndarray, origins: np.ndarray, directions: np.ndarray):
    """(t, triangle index) of the first hit of each ray origin + t * direction (t in units of the
    direction's length; inf and -1 where the ray hits nothing).  Only where ``works()``."""
    rays = np.hstack([np.broadcast_to(origins, directions.shape), directions])
    import open3d

    return _cast(open3d, vertices, triangles, rays)


def _cast(open3d, vertices, triangles, rays):
    scene = open3d.t.geometry.RaycastingScene()
    scene.add_triangles(open3d.core.Tensor(np.ascontiguousarray(vertices, dtype=np.float32)),
                        open3d.core.Tensor(np.ascontiguousarray(triangles, dtype=np.uint32)))
    hits = scene.cast_rays(open3d.core.Tensor(np.ascontiguousarray(rays, dtype=np.float32)))
    t_hit = hits["t_hit"].numpy().astype(float)
    index = hits["primitive_ids"].numpy().astype(np.int64)
    missed = ~np.isfinite(t_hit)
    index[missed] = -1
    return t_hit, index
