"""Procedural, deterministic test objects as closed, outward-wound triangle meshes (mm).

Four builders make every shape watertight by construction: a pole-to-pole (theta, phi) grid for
smooth star-shaped or parametric bodies, a revolved profile for surfaces of revolution (corners kept
as sharp edges), the boundary of a union of grid cells for flat-faced blocks (exactly planar
faces, sharp edges, vertices shared along every edge), and a straight prism over a star-shaped
outline (round or slanted walls with sharp edges).  A block can also be bent into a shell.  ``edge_mm`` sets the mesh resolution: the
typical triangle edge; the meshes are accurate surfaces, not just point sets.

The workpieces (car, figurine) are returned in an arbitrary model frame X (rotated and off-origin,
so nothing can pass by accident with an identity pose); ``CAR_BODY_IN_X`` / ``FIGURINE_BODY_IN_X`` give
their upright body frame (x forward, y left, z up) in X.  The other shapes are in their natural frame.
"""
from __future__ import annotations

import numpy as np

from ..frames import apply, from_euler_zyz
from ..geometry import Cloud

CAR_BODY_IN_X = from_euler_zyz(35.0, 70.0, -20.0, (120.0, -45.0, 210.0))
FIGURINE_BODY_IN_X = from_euler_zyz(-60.0, 110.0, 15.0, (12.0, 30.0, -8.0))

# Fine sampling used to place grid lines at equal arc length before the final grid is built.
_FINE_SAMPLES = 512


def _smoothstep(t):
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


# ----------------------------------------------------------------------------------------------
# Builders
# ----------------------------------------------------------------------------------------------

def _closed_grid(grid: np.ndarray, name: str) -> Cloud:
    """Mesh of a (rows, cols, 3) grid whose first and last rows are poles and whose columns wrap.

    The grid must run like a sphere's (theta from the north pole, phi counter-clockwise seen from
    outside at the north pole); every orientation-preserving deformation of it then winds outward.
    """
    rows, cols = grid.shape[:2]
    ring = grid[1:-1].reshape(-1, 3)
    points = np.vstack([grid[0].mean(axis=0), ring, grid[-1].mean(axis=0)])
    north, south = 0, len(points) - 1

    def vid(r, c):  # vertex id of ring row r (0-based among the inner rows), column c (wrapping)
        return 1 + r * cols + c % cols

    c = np.arange(cols)
    fans_north = np.column_stack([np.full(cols, north), vid(0, c), vid(0, c + 1)])
    fans_south = np.column_stack([np.full(cols, south), vid(rows - 3, c + 1), vid(rows - 3, c)])
    r, c = np.meshgrid(np.arange(rows - 3), np.arange(cols), indexing="ij")
    r, c = r.ravel(), c.ravel()
    a, b, d, e = vid(r, c), vid(r + 1, c), vid(r + 1, c + 1), vid(r, c + 1)
    quads = np.vstack([np.column_stack([a, b, d]), np.column_stack([a, d, e])])
    return Cloud(points, triangles=np.vstack([fans_north, quads, fans_south]), name=name)


def _equal_arc_parameters(curves: np.ndarray, params: np.ndarray, edge_mm: float, closed: bool) -> np.ndarray:
    """Parameter values that cut the curves into pieces about ``edge_mm`` long.

    ``curves`` is (n_curves, n_params, 3) sampled at ``params``; the mean arc length over the curves
    places the cuts, the longest curve sets their number (so no edge is much longer than edge_mm).
    """
    seg = np.linalg.norm(np.diff(curves, axis=1), axis=2)
    arc = np.concatenate([[0.0], np.cumsum(seg.mean(axis=0))])
    count = max(3, int(np.ceil(seg.sum(axis=1).max() / edge_mm)))
    cuts = np.interp(np.linspace(0.0, arc[-1], count + 1), arc, params)
    return cuts[:-1] if closed else cuts


def _parametric(surface, edge_mm: float, name: str) -> Cloud:
    """Mesh of a closed surface p(theta, phi), theta in [0, pi] pole to pole, phi in [0, 2 pi)."""
    theta = np.linspace(0.0, np.pi, _FINE_SAMPLES)
    phi = np.linspace(0.0, 2 * np.pi, _FINE_SAMPLES)
    fine = surface(*np.meshgrid(theta, phi, indexing="ij"))
    theta_cuts = _equal_arc_parameters(fine.transpose(1, 0, 2), theta, edge_mm, closed=False)
    phi_cuts = _equal_arc_parameters(fine, phi, edge_mm, closed=True)
    return _closed_grid(surface(*np.meshgrid(theta_cuts, phi_cuts, indexing="ij")), name)


def _revolve(pieces: list, edge_mm: float, name: str) -> Cloud:
    """Surface of revolution about z of a profile from the top pole to the bottom pole.

    ``pieces`` are (n, 2) polylines of (radius, z), each smooth; the joints between pieces are kept
    as exact grid rows, so corners of the profile become sharp edges and flat caps stay planar.
    """
    rows = []
    for piece in pieces:
        piece = np.asarray(piece, dtype=float)
        seg = np.linalg.norm(np.diff(piece, axis=0), axis=1)
        arc = np.concatenate([[0.0], np.cumsum(seg)])
        at = np.linspace(0.0, arc[-1], max(1, int(np.ceil(arc[-1] / edge_mm))) + 1)
        samples = np.column_stack([np.interp(at, arc, piece[:, 0]), np.interp(at, arc, piece[:, 1])])
        rows.append(samples if not rows else samples[1:])
    profile = np.vstack(rows)
    profile[[0, -1], 0] = 0.0
    cols = max(8, int(np.ceil(2 * np.pi * profile[:, 0].max() / edge_mm)))
    phi = np.linspace(0.0, 2 * np.pi, cols, endpoint=False)
    radius, z = profile[:, :1], profile[:, 1:]
    grid = np.stack([radius * np.cos(phi), radius * np.sin(phi), np.broadcast_to(z, (len(z), cols))], axis=-1)
    return _closed_grid(grid, name)


def _cell_union(breaks: list, inside, edge_mm: float, name: str) -> Cloud:
    """Boundary of a union of axis-aligned cells: exactly planar faces and sharp edges.

    ``breaks`` holds, per axis, the coordinates where the solid's faces may lie; every interval is
    cut into equal steps of at most ``edge_mm``, and ``inside(x, y, z)`` says which cells (by their
    centres) are solid.  Faces between a solid and an empty cell become two triangles each, sharing
    the grid's vertices, so the surface is watertight wherever the solid is a manifold.
    """
    axes = []
    for b in breaks:
        steps = [np.linspace(lo, hi, max(1, int(np.ceil((hi - lo) / edge_mm))) + 1)[:-1]
                 for lo, hi in zip(b[:-1], b[1:])]
        axes.append(np.concatenate(steps + [[b[-1]]]))
    centres = [0.5 * (a[1:] + a[:-1]) for a in axes]
    solid = np.pad(inside(*np.meshgrid(*centres, indexing="ij")), 1)  # empty cells around
    shape = np.array([len(a) for a in axes])
    faces = []
    for axis in range(3):
        other, third = (axis + 1) % 3, (axis + 2) % 3
        step = np.zeros(3, dtype=int)
        step[axis] = 1
        below = solid[tuple(slice(0, -1) if k == axis else slice(1, -1) for k in range(3))]
        above = solid[tuple(slice(1, None) if k == axis else slice(1, -1) for k in range(3))]
        for change, outward in ((below & ~above, True), (~below & above, False)):
            corner = np.argwhere(change)  # vertex-grid index of the face's lowest corner
            e_other, e_third = np.eye(3, dtype=int)[other], np.eye(3, dtype=int)[third]
            loop = [corner, corner + e_other, corner + e_other + e_third, corner + e_third]
            if not outward:
                loop = loop[::-1]
            ids = [np.ravel_multi_index(v.T, shape) for v in loop]
            faces += [np.column_stack([ids[0], ids[1], ids[2]]), np.column_stack([ids[0], ids[2], ids[3]])]
    triangles = np.vstack(faces)
    used, triangles = np.unique(triangles, return_inverse=True)
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    return Cloud(grid[used], triangles=triangles.reshape(-1, 3), name=name)


def _prism(outline, length: float, edge_mm: float, name: str) -> Cloud:
    """A straight prism along z, from 0 to ``length``, over a closed outline in the xy plane.

    ``outline`` is a counter-clockwise polygon (n, 2), star-shaped about the mean of its vertices:
    its edges are cut into pieces of at most ``edge_mm``, the walls into rows of that height, and each
    cap is a fan from that mean, so the caps are exactly planar and meet the walls in sharp edges.
    """
    outline = np.asarray(outline, dtype=float)
    ring = np.vstack([a + np.outer(np.arange(k) / k, b - a) for a, b in zip(outline, np.roll(outline, -1, axis=0))
                      for k in [max(1, int(np.ceil(np.linalg.norm(b - a) / edge_mm)))]])
    centre = ring.mean(axis=0)
    spokes = ring - centre
    if (spokes[:, 0] * np.roll(spokes[:, 1], -1) - spokes[:, 1] * np.roll(spokes[:, 0], -1)).min() <= 0:
        raise ValueError(f"{name}: the outline must run counter-clockwise and be star-shaped about its middle")
    n = len(ring)
    levels = np.linspace(0.0, length, max(1, int(np.ceil(length / edge_mm))) + 1)
    points = np.vstack([np.column_stack([np.tile(ring, (len(levels), 1)), np.repeat(levels, n)]),
                        [[*centre, 0.0], [*centre, length]]])
    i = np.arange(n)
    j = (i + 1) % n
    faces = []
    for row in range(len(levels) - 1):  # wall quads, outward for a counter-clockwise outline
        a, b, c, d = row * n + i, row * n + j, (row + 1) * n + j, (row + 1) * n + i
        faces += [np.column_stack([a, b, c]), np.column_stack([a, c, d])]
    top = (len(levels) - 1) * n
    faces += [np.column_stack([np.full(n, len(points) - 2), j, i]),  # bottom cap, facing -z
              np.column_stack([np.full(n, len(points) - 1), top + i, top + j])]
    return Cloud(points, triangles=np.vstack(faces), name=name)


def _bent(mesh: Cloud, radius: float, name: str) -> Cloud:
    """The mesh bent about an axis parallel to y, ``radius`` mm below z = 0: x becomes arc length
    along the bend, z the distance outside it (an orientation-preserving map, so it stays closed and
    outward; faces must be small against the radius)."""
    x, y, z = mesh.points.T
    angle, reach = x / radius, radius + z
    points = np.column_stack([reach * np.sin(angle), y, reach * np.cos(angle) - radius])
    return Cloud(points, triangles=mesh.triangles, name=name)


def _ellipsoid_radius(d: np.ndarray, centre, radii) -> np.ndarray:
    """Distance along unit directions d (..., 3) from the origin to an ellipsoid that contains it."""
    q = d / radii
    c = np.asarray(centre) / radii
    a, b, cc = (q * q).sum(-1), (q * c).sum(-1), (c * c).sum() - 1.0
    return (b + np.sqrt(b * b - a * cc)) / a


def _angular_bump(d: np.ndarray, axis, height: float, width_rad: float) -> np.ndarray:
    """A smooth radial bump of ``height`` mm around the unit direction ``axis``."""
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    angle = np.arccos(np.clip(d @ axis, -1.0, 1.0))
    return height * np.exp(-(angle / width_rad) ** 2)


# ----------------------------------------------------------------------------------------------
# Workpieces (returned in their model frame X)
# ----------------------------------------------------------------------------------------------

def car_body(edge_mm: float = 1.75) -> Cloud:
    """The car in its body frame (x forward, y left, z up, origin on the ground under its middle).

    250 x 104 x 80 mm: a rounded box with a low bonnet, a cabin set towards the back and narrower
    than the body, a higher boot, and dents over the four wheels.  Smooth everywhere and mirror-
    symmetric left/right only.  About 30k vertices at 1.75 mm.
    """
    half_length, half_width = 125.0, 52.0

    def plateau(x, rise_from, rise_to, fall_from, fall_to):
        return _smoothstep((x - rise_from) / (rise_to - rise_from)) * (1 - _smoothstep((x - fall_from) / (fall_to - fall_from)))

    def surface(theta, phi):
        # A rounded box in [-1, 1]^3 (superellipse sections, so smooth), then stretched into the car.
        along = (np.abs(np.cos(theta)) ** 3 + np.abs(np.sin(theta)) ** 3) ** (-1 / 3)
        across = (np.abs(np.cos(phi)) ** 4 + np.abs(np.sin(phi)) ** 4) ** (-1 / 4)
        section = along * np.sin(theta) * across
        x = half_length * along * np.cos(theta)
        roof = 42.0 + 38.0 * plateau(x, -105.0, -70.0, 5.0, 55.0) - 12.0 * _smoothstep((x - 20.0) / 105.0)
        z = 0.5 * (1.0 + section * np.sin(phi)) * roof
        cabin_taper = 1.0 - 0.3 * _smoothstep((z - 40.0) / 25.0)
        y = half_width * section * np.cos(phi) * cabin_taper * (1.0 - 0.1 * _smoothstep((x - 30.0) / 95.0))
        arches = sum(7.0 * np.exp(-((x - wheel) ** 2 + (z - 8.0) ** 2) / 24.0 ** 2) for wheel in (78.0, -80.0))
        return np.stack([x, y - arches * np.tanh(y / 15.0), z], axis=-1)

    return _parametric(surface, edge_mm, "car")


def car(edge_mm: float = 1.75) -> Cloud:
    """The ~25 cm car model X-A in its model frame X (see ``car_body`` for the shape)."""
    body = car_body(edge_mm)
    return Cloud(apply(CAR_BODY_IN_X, body.points), triangles=body.triangles, name="car")


def figurine_body(edge_mm: float = 0.3) -> Cloud:
    """The ~2 cm puppet in its body frame (x forward, y left, z up): 11 x 14 x 21 mm, freeform.

    Torso and a large head (a smooth union, so there is a neck), arms at different heights, a nose:
    no symmetry at all.  Star-shaped around the neck, so a radial function closes it.  About 11k
    vertices at 0.3 mm.
    """
    torso, head = ((0.0, 0.0, -5.0), (4.5, 5.5, 6.5)), ((0.5, 0.0, 4.5), (4.8, 4.8, 4.8))

    def surface(theta, phi):
        d = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)
        r_torso, r_head = (_ellipsoid_radius(d, c, np.asarray(s)) for c, s in (torso, head))
        r = (r_torso ** 8 + r_head ** 8) ** (1 / 8)
        r = r + _angular_bump(d, (0.1, 1.0, -0.35), 3.5, 0.3)  # left arm, hanging
        r = r + _angular_bump(d, (0.3, -1.0, 0.25), 3.5, 0.28)  # right arm, raised
        r = r + _angular_bump(d, (1.0, 0.0, 0.75), 0.9, 0.12)  # nose
        return d * r[..., None]

    return _parametric(surface, edge_mm, "figurine")


def figurine(edge_mm: float = 0.3) -> Cloud:
    """The ~2 cm puppet X-A in its model frame X (see ``figurine_body``)."""
    body = figurine_body(edge_mm)
    return Cloud(apply(FIGURINE_BODY_IN_X, body.points), triangles=body.triangles, name="figurine")


# ----------------------------------------------------------------------------------------------
# Reference block, platform, clutter
# ----------------------------------------------------------------------------------------------

def l_block(length: float = 120.0, width: float = 80.0, height: float = 60.0, thickness: float = 30.0,
            edge_mm: float = 2.0) -> Cloud:
    """The L-shaped reference P: two arms ``thickness`` wide, outer corner at the origin, on z = 0.

    Default 120 x 80 x 60 mm with 30 mm arms: eight flat rectangular faces and sharp edges, the
    features that make the reference easy to match.  About 7k vertices at 2 mm.
    """
    def inside(x, y, z):
        return (x < thickness) | (y < thickness)

    return _cell_union([[0.0, thickness, length], [0.0, thickness, width], [0.0, height]], inside, edge_mm,
                       "L-block")


def box(size=(600.0, 600.0, 20.0), edge_mm: float = 10.0, name: str = "box") -> Cloud:
    """A box centred in x and y with its top face at z = 0 (the platform by default: 600 x 600 x 20 mm)."""
    sx, sy, sz = size
    return _cell_union([[-sx / 2, sx / 2], [-sy / 2, sy / 2], [-sz, 0.0]],
                       lambda x, y, z: np.ones(x.shape, dtype=bool), edge_mm, name)


def platform(edge_mm: float = 10.0) -> Cloud:
    """The robot's platform, 600 x 600 x 20 mm, top face at z = 0 (coarse: it is never matched)."""
    return box((600.0, 600.0, 20.0), edge_mm, "platform")


# ----------------------------------------------------------------------------------------------
# Shapes for matcher tests (natural frames, symmetry axis z)
# ----------------------------------------------------------------------------------------------

def cylinder(radius: float = 30.0, height: float = 80.0, edge_mm: float = 2.0, name: str = "cylinder") -> Cloud:
    """Cylinder on z = 0 with flat caps and sharp rims: symmetric under every rotation about z."""
    return _revolve([[(0.0, height), (radius, height)], [(radius, height), (radius, 0.0)],
                     [(radius, 0.0), (0.0, 0.0)]], edge_mm, name)


def sphere(radius: float = 40.0, edge_mm: float = 2.0) -> Cloud:
    """Sphere centred at the origin: no orientation can be recovered from it."""
    t = np.linspace(0.0, np.pi, _FINE_SAMPLES)
    return _revolve([np.column_stack([radius * np.sin(t), radius * np.cos(t)])], edge_mm, "sphere")


def vase(edge_mm: float = 2.0) -> Cloud:
    """A closed vase, 120 mm tall, 77 mm across the belly, flat base and lid: a surface of revolution."""
    z = np.linspace(120.0, 0.0, _FINE_SAMPLES)
    t = z / 120.0
    radius = 24.0 + 12.0 * np.sin(np.pi * t) ** 2 * (1 - t) * 2.2 - 6.0 * np.exp(-((t - 0.85) / 0.08) ** 2)
    wall = np.column_stack([radius, z])
    return _revolve([[(0.0, 120.0), wall[0]], wall, [wall[-1], (0.0, 0.0)]], edge_mm, "vase")


def ellipsoid(radii=(60.0, 40.0, 25.0), edge_mm: float = 2.0) -> Cloud:
    """Ellipsoid centred at the origin: three 180-degree rotations map it onto itself."""
    a, b, c = radii

    def surface(theta, phi):
        return np.stack([a * np.sin(theta) * np.cos(phi), b * np.sin(theta) * np.sin(phi),
                         c * np.cos(theta)], axis=-1)

    return _parametric(surface, edge_mm, "ellipsoid")


# ----------------------------------------------------------------------------------------------
# Near-symmetric and symmetric parts for the verdict (natural frames)
# ----------------------------------------------------------------------------------------------

def plate(length: float = 120.0, width: float = 80.0, thickness: float = 6.0, notch=(24.0, 10.0),
          notch_offset: float = 14.0, rebate=None, edge_mm: float = 2.0, name: str = "plate") -> Cloud:
    """A flat plate, centred in x and y on z = 0, whose outline is nearly mirror symmetric.

    ``notch`` (length, depth) is cut into the +y long edge with its middle ``notch_offset`` mm off the
    plate's middle; ``rebate`` (width, depth), if given, is a step along the -y edge of the top face,
    so front and back outlines differ only there.  Turned over or turned about its normal the plate
    covers nearly the same rectangle: the near-symmetric flips a scan of one side must tell apart.
    """
    hx, hy = length / 2, width / 2
    x = [-hx, hx]
    y = [-hy, hy]
    z = [0.0, thickness]
    if notch is not None:
        x = [-hx, notch_offset - notch[0] / 2, notch_offset + notch[0] / 2, hx]
        y = [-hy, hy - notch[1], hy]
    if rebate is not None:
        y = sorted(set(y) | {-hy + rebate[0]})
        z = [0.0, thickness - rebate[1], thickness]

    def inside(px, py, pz):
        solid = np.ones(px.shape, dtype=bool)
        if notch is not None:
            solid &= ~((np.abs(px - notch_offset) < notch[0] / 2) & (py > hy - notch[1]))
        if rebate is not None:
            solid &= ~((py < -hy + rebate[0]) & (pz > thickness - rebate[1]))
        return solid

    return _cell_union([x, y, z], inside, edge_mm, name)


def boss_plate(size: float = 80.0, thickness: float = 8.0, boss: float = 30.0, boss_height: float = 6.0,
               edge_mm: float = 2.0) -> Cloud:
    """A square plate (centred, on z = 0) with a square boss in the middle of its top: a quarter turn
    about its normal maps it onto itself (4-fold symmetry); turning it over does not."""
    h, b = size / 2, boss / 2
    return _cell_union([[-h, -b, b, h], [-h, -b, b, h], [0.0, thickness, thickness + boss_height]],
                       lambda x, y, z: (z < thickness) | ((np.abs(x) < b) & (np.abs(y) < b)), edge_mm, "boss plate")


def peg(radius: float = 10.0, length: float = 60.0, chamfer: float = 2.0, edge_mm: float = 1.5) -> Cloud:
    """A round peg along z on z = 0 with its top end chamfered: any turn about its axis maps it onto
    itself, and end over end it nearly does (only the chamfer tells the ends apart)."""
    r, top = radius, length
    return _revolve([[(0.0, top), (r - chamfer, top)], [(r - chamfer, top), (r, top - chamfer)],
                     [(r, top - chamfer), (r, 0.0)], [(r, 0.0), (0.0, 0.0)]], edge_mm, "peg")


def d_shaft(radius: float = 12.0, length: float = 100.0, flat: float = 3.0, edge_mm: float = 2.0) -> Cloud:
    """A shaft along z (0 to ``length``) with a flat ``flat`` mm deep ground along its length on the +y
    side (a D profile): the flat stops it turning about its axis, and only a half turn about the
    flat's normal (end over end) maps it onto itself."""
    half = np.arccos((radius - flat) / radius)
    t = np.linspace(np.pi / 2 + half, 2.5 * np.pi - half, max(8, int(np.ceil(2 * np.pi * radius / edge_mm))))
    return _prism(radius * np.column_stack([np.cos(t), np.sin(t)]), length, edge_mm, "D shaft")


def shell(length: float = 140.0, width: float = 90.0, thickness: float = 4.0, bend_radius: float = 110.0,
          notch=(22.0, 9.0), notch_offset: float = 16.0, edge_mm: float = 2.0) -> Cloud:
    """A curved tile: a notched plate (see ``plate``) bent about the y axis with its inner face
    ``bend_radius`` mm from the axis, its outer face convex.  Front and back differ in curvature,
    and turned about its normal only the notch tells it apart."""
    flat = plate(length, width, thickness, notch, notch_offset, edge_mm=edge_mm)
    return _bent(flat, bend_radius, "shell")
