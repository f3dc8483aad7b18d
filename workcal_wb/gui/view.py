"""The 3D view brought to what a step is about, at once.

FreeCAD 1.x animates camera changes by default: ``setCameraOrientation`` then ``fitAll`` fits the
scene as seen from the old orientation while the turn is still under way, and the turn then ends
with the objects off screen.  Turning the animation off for the change makes it one step, as on
FreeCAD 0.20.
"""
from __future__ import annotations

from contextlib import contextmanager


@contextmanager
def without_animation(view):
    """Camera changes inside the block take effect immediately; the user's setting comes back after."""
    animated = bool(view.isAnimationEnabled())
    view.setAnimationEnabled(False)
    try:
        yield view
    finally:
        view.setAnimationEnabled(animated)


def look(view, orientation=None) -> None:
    """Turn the camera to ``orientation`` (a FreeCAD.Rotation; None keeps it) and fit everything shown."""
    with without_animation(view):
        if orientation is not None:
            view.setCameraOrientation(orientation)
        view.fitAll()
