"""Geometric stability of a point-to-plane fit (Gelfand et al. 2003): which motions the data pin down.

The 6x6 matrix C = sum [p x n; n][p x n; n]^T over the matched points (centred, p scaled by the RMS
radius so rotations and translations are commensurate) has a small eigenvalue for every motion that
slides the surface along itself: a plane leaves three, a cylinder two, a sphere three rotations.
"""
from __future__ import annotations

import numpy as np

# min/max eigenvalue ratio below which a motion counts as free (too weakly held to trust): above
# surfaces that leave a motion free (cylinder, sphere, plane), below real partial scans of freeform parts.
FREE_MOTION_RATIO = 5e-3
# A free twist whose rotation axis passes within this many RMS radii of the points is described
# as a rotation (a sphere seen from one side turns about its centre, behind the points).
ROTATION_REACH = 4.0


def stability(points: np.ndarray, normals: np.ndarray, threshold: float = FREE_MOTION_RATIO) -> dict:
    """Eigenvalues (normalised to the largest), condition ratio and the free motions, described in
    the frame of ``points``; JSON-ready."""
    if len(points) < 6:
        return {"ratio": 0.0, "eigenvalues": [], "free_motions": ["too few matched points"], "constrained": False}
    vals, vecs, centre, radius = gelfand(points, normals)
    free = [describe_motion(vecs[:, i], centre, radius) for i in range(6) if vals[i] < threshold]
    return {"ratio": float(vals[0]), "eigenvalues": vals.tolist(), "free_motions": free,
            "constrained": not free}


def gelfand(points: np.ndarray, normals: np.ndarray):
    """(eigenvalues normalised to the largest, ascending; eigenvectors [rotation x radius,
    translation] as columns; centre; RMS radius) of the point-to-plane constraint matrix."""
    centre = points.mean(axis=0)
    p = points - centre
    radius = np.sqrt((p**2).sum(axis=1).mean()) or 1.0
    J = np.hstack([np.cross(p / radius, normals), normals])
    vals, vecs = np.linalg.eigh(J.T @ J)
    return np.maximum(vals, 0) / max(vals[-1], 1e-300), vecs, centre, radius


def describe_motion(v: np.ndarray, centre: np.ndarray, radius: float) -> str:
    """A free motion as words: a rotation about an axis through a point (the screw axis of the
    twist, nearest the centre) unless its axis lies more than ROTATION_REACH radii away, where it
    is as good as a translation."""
    rot, trans = v[:3], v[3:]
    if ROTATION_REACH * np.linalg.norm(rot) >= np.linalg.norm(trans):
        omega = rot / radius  # undo the scaling of the rotation columns
        through = centre + np.cross(omega, trans) / (omega @ omega)
        axis = rot / np.linalg.norm(rot)
        return (f"rotation about axis ({axis[0]:.2f}, {axis[1]:.2f}, {axis[2]:.2f}) through "
                f"({through[0]:.1f}, {through[1]:.1f}, {through[2]:.1f}) mm")
    direction = trans / np.linalg.norm(trans)
    return f"translation along ({direction[0]:.2f}, {direction[1]:.2f}, {direction[2]:.2f})"
