"""Clay that changed between modelling and scanning: local lumps and carved patches.

The paper assumes the workpiece is unchanged since its model X-A was made and names local changes
as the open problem.  Here the scanner sees a reshaped copy while the model stays as it was; the
vertex mask and per-vertex displacement say where and by how much, so deviation maps can be checked.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import frames
from ..errors import InputError
from ..geometry import Cloud
from ..pointops import vertex_normals
from .raster import heights_above

KINDS = ("lump", "carve")


@dataclass(frozen=True)
class ClayEdit:
    """One change: a smooth lump of ``height`` mm or a carving ``height`` mm deep, ``radius`` mm wide,
    centred on the mesh vertex nearest ``centre`` (mm, in the mesh's frame)."""

    kind: str
    centre: tuple
    radius: float
    height: float

    def __post_init__(self):
        if self.kind not in KINDS:
            raise InputError(f"clay edit: kind must be one of {KINDS}, not {self.kind!r}")
        if self.radius <= 0 or self.height < 0:
            raise InputError(f"clay edit: radius must be > 0 and height >= 0 mm, got {self.radius}, {self.height}")


@dataclass
class Reshaped:
    """The reshaped mesh, which vertices moved, and how far each moved along its outward normal (mm)."""

    mesh: Cloud
    changed: np.ndarray
    displacement_mm: np.ndarray


def reshape(mesh: Cloud, edits) -> Reshaped:
    """Apply the edits together, each along the original surface's vertex normals.

    The bump is (1 - (d / radius)^2)^3 of the distance d from the centre: full height at the centre,
    flat and smooth at the rim, so the surface stays smooth and only vertices within ``radius`` move.
    A radius larger than the local thickness of the part would also move the far side.
    """
    displacement = np.zeros(len(mesh.points))
    for edit in edits:
        centre = mesh.points[np.argmin(np.linalg.norm(mesh.points - np.asarray(edit.centre, float), axis=1))]
        d = np.linalg.norm(mesh.points - centre, axis=1) / edit.radius
        bump = np.clip(1.0 - d * d, 0.0, None) ** 3
        displacement += (edit.height if edit.kind == "lump" else -edit.height) * bump
    moved = mesh.points + displacement[:, None] * vertex_normals(mesh.points, mesh.triangles)
    return Reshaped(Cloud(moved, triangles=mesh.triangles, name=mesh.name), displacement != 0, displacement)


def add_lump(mesh: Cloud, centre, radius: float, height: float) -> Reshaped:
    """Clay pressed on after the model was made: ``height`` mm outward at ``centre``, ``radius`` mm wide."""
    return reshape(mesh, [ClayEdit("lump", tuple(centre), radius, height)])


def carve_patch(mesh: Cloud, centre, radius: float, depth: float) -> Reshaped:
    """Clay scraped off after the model was made: ``depth`` mm inward at ``centre``, ``radius`` mm wide."""
    return reshape(mesh, [ClayEdit("carve", tuple(centre), radius, depth)])


def on_top(kind: str, mesh: Cloud, upright: np.ndarray, at=(0.0, 0.0), radius: float = 10.0,
           height: float = 2.0) -> ClayEdit:
    """An edit on the upper surface above ``at`` = (x, y) of the upright frame ``upright`` (^M N: z up):
    where a modeller adds or carves clay, and where a scanner from above sees it."""
    local = frames.apply(frames.invert(upright), mesh.points)
    x, y = (np.array([v]) for v in at)
    z = heights_above(local, mesh.triangles, x, y)[0, 0]
    if np.isnan(z):
        raise InputError(f"{mesh.name}: no surface above ({at[0]}, {at[1]}) mm to put a {kind} on")
    return ClayEdit(kind, tuple(frames.apply(upright, np.array([[x[0], y[0], z]]))[0]), radius, height)


def suggested(kind: str, mesh: Cloud, upright: np.ndarray) -> ClayEdit:
    """A visible, plausible edit scaled to the workpiece: a lump on the front top, a carving at the back."""
    local = frames.apply(frames.invert(upright), mesh.points)
    lo, hi = local.min(axis=0), local.max(axis=0)
    size = float(np.linalg.norm(hi - lo))
    centre = 0.5 * (lo + hi)
    forward = 0.25 * (hi[0] - lo[0]) * (1 if kind == "lump" else -1)
    return on_top(kind, mesh, upright, (centre[0] + forward, centre[1]), 0.07 * size,
                  (0.02 if kind == "lump" else 0.012) * size)
