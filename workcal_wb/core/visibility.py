"""What a sensor at a viewpoint sees of a surface, and how a scan taken from there agrees with a
placed model: the evidence a match verdict weighs.

A scan point says more than "here is surface": the ray from the sensor to it crossed free space, and
the surface it hit faces the sensor.  A pose of the model is judged by what the sensor should have
seen from it (its expected visible surface) against what it saw, pixel by pixel on one view image:
scan points on the visible model surface count for the pose, scan points the model would hide
(behind its front surface) and model surface facing the sensor inside the scan's footprint where the
scan shows nothing count against it.  A near-symmetric flip that puts the scan onto the wrong side,
or leaves part of the scan or of the model unexplained, loses there even when most scan points land
somewhere on the model.

open3d 0.16's ray casting returns no hits (Debian 12), so views are z-buffers of surface samples:
each sample is dropped into the pixel its ray from the viewpoint crosses and the nearest one wins.
Pixels are a few sample spacings wide, so the samples cover every pixel the surface does.

Nothing here depends on a match: ``expected_surface`` (which samples of a surface a viewpoint sees)
is the function to reuse for other visibility questions.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# A surface sample faces a viewpoint when its normal is turned towards it by more than this cosine
# (slightly negative: the matched normals of a scan's silhouette are nearly edge-on).
FACING_COS = -0.1
# Model surface seen more obliquely than this (cosine of the incidence) may be missing from a real
# scan (scanners drop grazing returns), so it is not counted as missing.
MISSING_COS = 0.5
# Holes in a scan's footprint up to about twice this many pixels across are closed: the sensor saw
# all around them, so the model surface it should have seen there is missing.
CLOSE_PIXELS = 3
# A scan pixel inside the model's outline is off the model when its points' mean weight is at most this.
OFF_WEIGHT = 0.25
# The model surface is flat around a pixel when the normals there agree within this angle.
FLAT_DEG = 3.0
# A pixel's evidence: +weight for scan points on the visible model surface, HIDDEN for a scan point
# the placed model would hide, MISSING for an empty footprint pixel where the model faces the sensor.
HIDDEN, MISSING = -1.0, -1.0
# A view sees this far off its axis (the tangent of 60 deg, wider than any scanner's field): a point beyond
# lies outside it, as one behind the viewpoint does (its pixel coordinates grow without bound near the sensor).
MAX_OFF_AXIS = np.tan(np.radians(60.0))


@dataclass
class View:
    """A pinhole view from ``viewpoint`` towards ``target`` (mm, one frame) with pixels ``pixel_mm``
    wide at the target's distance, over the pixel window ``lo``..``hi`` (column, row) inclusive."""

    viewpoint: np.ndarray
    target: np.ndarray
    pixel_mm: float
    lo: np.ndarray = None
    hi: np.ndarray = None

    def __post_init__(self):
        self.viewpoint = np.asarray(self.viewpoint, dtype=float)
        self.target = np.asarray(self.target, dtype=float)
        z = self.target - self.viewpoint
        self.distance = float(np.linalg.norm(z))
        z /= self.distance
        x = np.cross(z, [0.0, 0.0, 1.0] if abs(z[2]) < 0.9 else [1.0, 0.0, 0.0])
        x /= np.linalg.norm(x)
        self.axes = np.vstack([x, np.cross(z, x), z])  # rows: image x, image y, depth

    def coordinates(self, points: np.ndarray):
        """(pixel coordinates (n, 2) as floats, depth along the view axis) of points."""
        local = (points - self.viewpoint) @ self.axes.T
        depth = local[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            off_axis = local[:, :2] / depth[:, None]
            seen = (depth > 0) & (np.abs(off_axis) <= MAX_OFF_AXIS).all(axis=1)
        return np.where(seen[:, None], off_axis * (self.distance / self.pixel_mm), np.nan), depth

    def framed(self, points: np.ndarray, margin: int = CLOSE_PIXELS + 1) -> "View":
        """This view with its window around the pixels of ``points`` (plus a margin)."""
        uv, _ = self.coordinates(points)
        return self._around(uv, margin)

    def _around(self, uv: np.ndarray, margin: int) -> "View":
        uv = np.floor(uv[np.isfinite(uv).all(axis=1)]).astype(np.int64)
        return View(self.viewpoint, self.target, self.pixel_mm, uv.min(axis=0) - margin, uv.max(axis=0) + margin)

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, columns) of the window."""
        return int(self.hi[1] - self.lo[1] + 1), int(self.hi[0] - self.lo[0] + 1)

    def pixels(self, points: np.ndarray, projected=None):
        """(flat pixel index in the window, -1 outside it or behind the viewpoint; depth); pass
        ``projected`` (``coordinates`` of the points) when it is known."""
        uv, depth = self.coordinates(points) if projected is None else projected
        ok = np.isfinite(uv).all(axis=1)
        cell = np.floor(np.where(ok[:, None], uv, 0)).astype(np.int64) - self.lo
        rows, cols = self.shape
        ok &= (cell[:, 0] >= 0) & (cell[:, 0] < cols) & (cell[:, 1] >= 0) & (cell[:, 1] < rows)
        return np.where(ok, cell[:, 1] * cols + cell[:, 0], -1), depth


def facing(points: np.ndarray, normals: np.ndarray, viewpoint) -> np.ndarray:
    """Cosine between each normal and the direction from its point to the viewpoint."""
    towards = np.asarray(viewpoint) - points
    return np.einsum("ij,ij->i", normals, towards) / np.maximum(np.linalg.norm(towards, axis=1), 1e-12)


def front(view: View, points: np.ndarray, normals: np.ndarray):
    """The z-buffer of surface samples: per pixel of the window the depth of the nearest sample
    facing the viewpoint (inf where none) and that sample's index (-1 where none)."""
    pixel, depth = view.pixels(points)
    keep = np.flatnonzero((pixel >= 0) & (facing(points, normals, view.viewpoint) > FACING_COS))
    size = view.shape[0] * view.shape[1]
    nearest, index = np.full(size, np.inf), np.full(size, -1, dtype=np.int64)
    np.minimum.at(nearest, pixel[keep], depth[keep])
    won = keep[depth[keep] == nearest[pixel[keep]]]
    index[pixel[won]] = won
    return nearest, index


def wall_thickness(view: View, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Per pixel of the window, the thickness of the wall the sensor looks at: how far behind the
    surface seen there the nearest surface facing away lies, across the wall (along its normal, not
    the slanted ray); inf where there is none."""
    near, index = front(view, points, normals)
    back, _ = front(view, points, -normals)
    cos = np.ones(len(near))
    seen = index >= 0
    cos[seen] = facing(points[index[seen]], normals[index[seen]], view.viewpoint)
    with np.errstate(invalid="ignore"):
        return np.where(back > near, (back - near) * cos, np.inf)


def median_wall_thickness(view: View, points: np.ndarray, normals: np.ndarray, pixels=None,
                          least: int = 30) -> float:
    """Median of wall_thickness over ``pixels`` (default: every pixel of the window) where there is a
    wall; inf where fewer than ``least`` pixels show one."""
    thickness = wall_thickness(view, points, normals)
    thickness = thickness if pixels is None else thickness[pixels]
    thickness = thickness[np.isfinite(thickness)]
    return float(np.median(thickness)) if len(thickness) >= least else float("inf")


def expected_surface(points: np.ndarray, normals: np.ndarray, viewpoint, pixel_mm: float,
                     depth_margin: float | None = None) -> np.ndarray:
    """Which samples of a surface (points with unit outward normals, one frame) a sensor at
    ``viewpoint`` sees: those facing it that lie within ``depth_margin`` (default two pixels) of the
    nearest sample on their pixel, with pixels ``pixel_mm`` wide at the samples' middle (at least a
    couple of sample spacings, so that a surface leaves no holes for the one behind to show through).
    """
    centre = points.mean(axis=0)
    view = View(viewpoint, centre, pixel_mm).framed(points, margin=0)
    nearest, _ = front(view, points, normals)
    pixel, depth = view.pixels(points)
    margin = 2 * pixel_mm if depth_margin is None else depth_margin
    ok = pixel >= 0
    seen = np.zeros(len(points), dtype=bool)
    seen[ok] = depth[ok] <= nearest[pixel[ok]] + margin
    return seen & (facing(points, normals, viewpoint) > FACING_COS)


def footprint(view: View, pixel: np.ndarray) -> np.ndarray:
    """Flat indices of the window's pixels the scan covers, small holes closed (see CLOSE_PIXELS)."""
    from scipy.ndimage import binary_closing

    mask = np.zeros(view.shape[0] * view.shape[1], dtype=bool)
    mask[pixel[pixel >= 0]] = True
    closed = binary_closing(mask.reshape(view.shape), structure=np.ones((3, 3), bool), iterations=CLOSE_PIXELS)
    return np.flatnonzero(closed.ravel() | mask)


@dataclass
class ScanView:
    """A scan seen in a view: each point's pixel and depth, the nearest scan depth per pixel, and
    the footprint pixels the evidence of every pose is counted on (so the evidence of two poses
    compares pixel by pixel)."""

    view: View
    pixel: np.ndarray
    depth: np.ndarray
    nearest: np.ndarray  # per pixel of the window, inf where no scan point
    cells: np.ndarray  # footprint pixels, flat indices into the window

    def at_depth_edge(self, margin: float) -> np.ndarray:
        """Which points lie more than ``margin`` behind a scan point on their pixel or one next to it:
        past a depth edge of the scan, where mixed pixels lie."""
        rows, cols = self.view.shape
        nearest_around = _around(self.nearest.reshape(rows, cols), "min").ravel()
        inside = self.pixel >= 0
        edge = np.zeros(len(self.pixel), bool)
        edge[inside] = self.depth[inside] > nearest_around[self.pixel[inside]] + margin
        return edge

    @classmethod
    def of(cls, points: np.ndarray, view: View) -> "ScanView":
        projected = view.coordinates(points)
        view = view._around(projected[0], CLOSE_PIXELS + 1)
        pixel, depth = view.pixels(points, projected)
        nearest = np.full(view.shape[0] * view.shape[1], np.inf)
        inside = pixel >= 0
        np.minimum.at(nearest, pixel[inside], depth[inside])
        return cls(view, pixel, depth, nearest, footprint(view, pixel))


@dataclass
class Evidence:
    """Per footprint pixel, in [-1, 1]: how well a placed model explains what the sensor saw there."""

    cells: np.ndarray  # one value per footprint pixel (ScanView.cells order)
    hidden: int  # scan points the placed model would hide from the sensor
    missing: int  # empty footprint pixels where the model faces the sensor
    explained: int  # scan points on the model's visible surface
    continued: int = 0  # scan pixels just past the model's outline that continue its surface
    outline: int = 0  # pixels on the model's outline in the view
    inside: int = 0  # scan pixels inside the model's outline
    off: int = 0  # of those, pixels whose scan points lie behind the model's surface (inside the part)

    @property
    def score(self) -> float:
        return float(self.cells.sum())


def _around(image: np.ndarray, kind: str) -> np.ndarray:
    """Over each pixel's 3 x 3 neighbourhood: the "max" or "min" (inf off the window), "any" or "all"
    (true off the window)."""
    from scipy import ndimage

    square = np.ones((3, 3), bool)
    if kind == "max":
        return ndimage.maximum_filter(image, footprint=square, mode="constant", cval=np.inf)
    if kind == "min":
        return ndimage.minimum_filter(image, footprint=square, mode="constant", cval=np.inf)
    if kind == "any":
        return ndimage.binary_dilation(image, structure=square)
    return ndimage.binary_erosion(image, structure=square, border_value=1)


def evidence(scan: ScanView, weights: np.ndarray, model_points: np.ndarray, model_normals: np.ndarray,
             gate: float, depth_margin: float, off_band: float, on_model: np.ndarray | None = None,
             support: np.ndarray | None = None) -> Evidence:
    """The evidence of one pose: ``weights`` (per scan point, in [0, 1]) say how well each scan point
    lies on a model sample facing the viewpoint; ``on_model`` (per scan point, default weights > 0)
    whether it lies on the model's surface at all, facing or not; ``model_points``/``model_normals`` are the model's
    view samples placed in the scan's frame by the pose.  A scan pixel inside the model's outline
    whose points lie more than ``gate`` behind its surface, but less than ``off_band``, is off the
    model (see Evidence.off); in front of it they may be an occluder.

    Against the pose count: a scan point more than ``depth_margin`` behind the model's front surface
    (over its whole 3 x 3 neighbourhood: the model would hide it) unless it lies at a depth edge of the
    scan (more than ``depth_margin`` behind a scan point in that neighbourhood: a mixed pixel strung
    between a near edge and what lies behind it is no evidence of what hides what), an empty footprint pixel with no
    scan point next to it where the model faces the sensor (missing), and a scan pixel just past the
    model's outline whose points lie on the plane of a flat model face ending there (the scanned
    face goes on where the model's ends: a misplaced outline), unless they lie on the model itself (a
    face seen grazing from the real sensor may turn away from an estimated viewpoint, and the
    z-buffer of samples leaves such a face's pixels empty) or on the plane the part stands on
    (``support``, per scan point: it meets every side face along the line the part rests on).
    """
    view = scan.view
    rows, cols = view.shape
    nearest, index = front(view, model_points, model_normals)
    # The farthest front surface around each pixel: a point behind it is hidden whichever pixel its
    # ray really crosses; a neighbourhood with no model surface hides nothing.
    around = _around(nearest.reshape(rows, cols), "max").ravel()
    inside = scan.pixel >= 0
    hidden = np.zeros(len(weights), dtype=bool)
    hidden[inside] = scan.depth[inside] > around[scan.pixel[inside]] + depth_margin
    hidden[inside] &= ~scan.at_depth_edge(depth_margin)[inside]
    per_point = np.where(hidden, HIDDEN, weights)
    total = np.bincount(scan.pixel[inside], per_point[inside], minlength=rows * cols)
    count = np.bincount(scan.pixel[inside], minlength=rows * cols)
    cells = np.zeros(rows * cols)
    seen = count > 0
    cells[seen] = total[seen] / count[seen]
    model_there = index >= 0
    cos = np.zeros(rows * cols)
    cos[model_there] = facing(model_points[index[model_there]], model_normals[index[model_there]], view.viewpoint)
    # Missing: no scan point on the pixel nor next to it (pixels are about a scan spacing wide, so a
    # lone empty pixel is sampling, not a hole), where the model faces the sensor squarely enough.
    near = _around(seen.reshape(rows, cols), "any").ravel()
    missing = (~near) & model_there & (cos > MISSING_COS)
    cells[missing] = MISSING
    flat = _flat(index, model_normals, rows, cols)
    on = (weights > 0) if on_model is None else on_model
    on_there = np.bincount(scan.pixel[inside], on[inside], minlength=rows * cols) > 0.5 * count
    continued = _continued(scan, cells, index, (cos > MISSING_COS) & flat, model_points, model_normals, depth_margin)
    continued &= ~on_there
    if support is not None:
        continued &= ~(np.bincount(scan.pixel[inside], support[inside], minlength=rows * cols) > 0.5 * count)
    cells[continued] = MISSING
    outline = model_there & ~_around(model_there.reshape(rows, cols), "all").ravel()
    # Off the model: scan pixels inside its outline whose points lie behind its surface, within the
    # band (further behind they would be hidden anyway; in front they may be something in the way).
    inside = seen & model_there
    with np.errstate(invalid="ignore"):
        behind = scan.nearest - nearest
    off = inside & (cells <= OFF_WEIGHT) & (behind > gate) & (behind <= off_band)
    return Evidence(cells[scan.cells], int(hidden.sum()), int(missing[scan.cells].sum()),
                    int(((weights > 0) & ~hidden).sum()), int(continued.sum()), int(outline.sum()),
                    int(inside.sum()), int(off.sum()))


def _flat(index: np.ndarray, normals: np.ndarray, rows: int, cols: int) -> np.ndarray:
    """Mask of pixels on a flat face of the model: the normal seen there agrees within FLAT_DEG with
    those of at least three neighbouring pixels (a curved surface turns by more from pixel to pixel;
    a pixel at a face's edge still has its face on one side)."""
    image = np.full((rows + 2, cols + 2, 3), np.nan)
    there = index >= 0
    image[1:-1, 1:-1][there.reshape(rows, cols)] = normals[index[there]]
    centre = image[1:-1, 1:-1]
    agreeing = np.zeros((rows, cols), int)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            if dr or dc:
                cos = np.einsum("ijk,ijk->ij", centre, image[1 + dr:1 + dr + rows, 1 + dc:1 + dc + cols])
                agreeing += np.nan_to_num(cos, nan=-1.0) >= np.cos(np.radians(FLAT_DEG))
    return (there.reshape(rows, cols) & (agreeing >= 3)).ravel()


def _continued(scan: ScanView, cells, index, usable, model_points, model_normals, margin: float) -> np.ndarray:
    """Mask of scan pixels with no model surface and unexplained points that lie, within
    ``margin``, on the plane of the model surface in a neighbouring explained pixel where the model
    is ``usable``: flat and facing the sensor (a grazing plane would predict any depth, and a curved
    surface meets a table it rests on tangentially)."""
    view = scan.view
    rows, cols = view.shape
    candidate = np.isfinite(scan.nearest) & (index < 0) & (cells <= 0)
    explained = (index >= 0) & usable & (cells > 0.5)
    out = np.zeros(rows * cols, dtype=bool)
    p = np.flatnonzero(candidate)
    if len(p) == 0 or not explained.any():
        return out
    r, c = p // cols, p % cols
    # The ray through each candidate pixel's centre, scaled to unit depth along the view axis.
    uv = (np.column_stack([c, r]) + view.lo + 0.5) * (view.pixel_mm / view.distance)
    rays = np.column_stack([uv, np.ones(len(p))]) @ view.axes
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            rq, cq = r + dr, c + dc
            ok = (rq >= 0) & (rq < rows) & (cq >= 0) & (cq < cols)
            q = np.where(ok, rq * cols + cq, 0)
            ok &= explained[q]
            j = index[q[ok]]
            normal, point = model_normals[j], model_points[j]
            with np.errstate(divide="ignore", invalid="ignore"):
                depth = np.einsum("ij,ij->i", normal, point - view.viewpoint) / np.einsum("ij,ij->i", normal, rays[ok])
            out[p[ok]] |= np.abs(scan.nearest[p[ok]] - depth) <= margin
    return out


def viewing_direction(normals: np.ndarray, rng: np.random.Generator | None = None) -> np.ndarray:
    """The direction a single view was most likely taken from, given the outward normals of the
    surface it saw: the centre of the smallest cone around which (all but 2 % of) the normals lie.
    A scanner sees surfaces turned towards it up to a grazing angle on every side, so the centre of
    what it saw points at it, also when part of the view was cut away (the mean normal then tilts
    towards what is left)."""
    rng = rng or np.random.default_rng(0)
    sample = normals[rng.permutation(len(normals))[:500]]
    low = int(0.02 * len(sample))  # the 2 % quantile
    best = sample.sum(axis=0)
    best /= max(np.linalg.norm(best), 1e-12)
    for step in (12.0, 3.0):
        directions = cone(best, step, rings=4)
        best = directions[np.argmax(np.partition(sample @ directions.T, low, axis=0)[low])]
    return best


def cone(axis: np.ndarray, step_deg: float, rings: int) -> np.ndarray:
    """``axis`` and directions on ``rings`` cones around it, ``step_deg`` apart, 12 per cone."""
    u = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(axis, u)
    out = [axis]
    for ring in range(1, rings + 1):
        tilt = np.radians(ring * step_deg)
        turn = np.linspace(0, 2 * np.pi, 12, endpoint=False)[:, None]
        out.append(np.cos(tilt) * axis + np.sin(tilt) * (np.cos(turn) * u + np.sin(turn) * v))
    return np.vstack(out)


def compare(best: np.ndarray, rival: np.ndarray, floor: float) -> float:
    """How many standard errors the total evidence of ``best`` lies above that of ``rival`` (per
    view cell, both from one view, so paired cell by cell); ``floor`` is the least variance of one
    cell's difference (sampling of model and scan), counted over the cells either pose covers."""
    d = best - rival
    involved = int(np.count_nonzero((best != 0) | (rival != 0)))
    spread = float(np.sum((d - d.mean()) ** 2)) + involved * floor
    return float(d.sum() / np.sqrt(max(spread, 1e-12)))
