"""4x4 numpy transforms (mm, column convention) to and from FreeCAD's Matrix and Placement."""
from __future__ import annotations

import numpy as np

import FreeCAD


def freecad_matrix(T) -> "FreeCAD.Matrix":
    return FreeCAD.Matrix(*[float(v) for v in np.asarray(T, dtype=float).reshape(-1)])


def placement(T) -> "FreeCAD.Placement":
    """A FreeCAD Placement from a 4x4 rigid transform."""
    return FreeCAD.Placement(freecad_matrix(T))


def matrix_of(value) -> np.ndarray:
    """4x4 numpy array of a FreeCAD Placement or Matrix."""
    if hasattr(value, "toMatrix"):
        value = value.toMatrix()
    return np.array(value.A, dtype=float).reshape(4, 4)


def container_matrix(obj) -> np.ndarray | None:
    """The placement of the containers (App::Part) holding ``obj`` as a 4x4, None when it is the
    identity or ``obj`` has no Placement.  Points and Mesh kernels apply only the object's own
    Placement, so their coordinates need this to be where the document shows them."""
    try:
        extra = obj.getGlobalPlacement().multiply(obj.Placement.inverse())
    except Exception:  # objects without Placement
        return None
    return None if extra.isIdentity() else matrix_of(extra)
