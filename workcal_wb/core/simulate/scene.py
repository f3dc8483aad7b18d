"""The scene of the paper's Fig. 3: platform, L-shaped reference P and workpiece A, placed in B.

Layout in the robot base frame B (mm): the 600 x 600 x 20 mm platform is centred at (700, 0) with
its top face at z = 300; the L-block stands on it near one corner at a fixed pose (its mesh moved
into B is the model B-P a user has); the workpiece rests on the platform beside it, with a random
yaw and a small random tilt from the seed, as close as it fits without touching anything else.
Optional clutter: a loose box and a cylinder on the platform.  Layouts as in a real cell: the
workpiece apart from the reference (default), touching it, or joined to it by a bridge of clay;
and a scene without the platform (the objects held in the air).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from .. import frames
from ..errors import InputError
from ..geometry import Cloud
from . import clay, shapes

ROLES = ("platform", "reference", "workpiece", "clutter", "bridge")
LAYOUTS = ("apart", "touching", "bridge")

PLATFORM_TOP_Z = 300.0
PLATFORM_POSE = frames.rigid(translation=(700.0, 0.0, PLATFORM_TOP_Z))  # ^B Q, top face at z = 0 in Q
PLATFORM_HALF_SIZE = 300.0
# ^Q P: the L-block's outer corner near the platform's (-x, +y) corner, its arms opening towards the middle.
REFERENCE_ON_PLATFORM = frames.rigid(frames.rot_z(-20.0), (-250.0, 160.0, 0.0))
# The workpiece is put as close as it fits to this point in the L's open corner (in P), moving out
# towards the platform's middle: beside the reference, as in the paper's Fig. 3.
WORKPIECE_ANCHOR_IN_P = (75.0, 55.0, 0.0)
WORKPIECE_SEARCH_STEP_MM = 3.0
WORKPIECE_SPREAD_DEG = 45.0  # directions tried around the one towards the platform's middle
MAX_TILT_DEG = 5.0
CLEARANCE_MM = 15.0  # minimum gap between outlines of objects on the platform, seen from above
CLUTTER_SPOTS = {"clutter box": (170.0, 190.0), "clutter cylinder": (-190.0, -170.0)}
# The L-block's arms (P frame, mm: the default shapes.l_block): two boxes (lower corner, upper corner).
REFERENCE_BOXES = (((0.0, 0.0, 0.0), (120.0, 30.0, 60.0)), ((0.0, 0.0, 0.0), (30.0, 80.0, 60.0)))
# A touching workpiece is left this far (mm) from the reference where they are closest; a bridged one
# BRIDGE_GAP_MM, joined by an ellipsoid of clay BRIDGE_RADIUS_MM thick pressed BRIDGE_OVERLAP_MM into both.
TOUCH_GAP_MM = 0.3
BRIDGE_GAP_MM, BRIDGE_RADIUS_MM, BRIDGE_OVERLAP_MM = 10.0, 10.0, 6.0

_WORKPIECES = {"car": (shapes.car, shapes.CAR_BODY_IN_X), "figurine": (shapes.figurine, shapes.FIGURINE_BODY_IN_X)}


@dataclass
class SceneObject:
    """A mesh in its own frame O and its pose ^B O; the workpiece's mesh is the shape as scanned."""

    name: str
    mesh: Cloud
    pose: np.ndarray
    role: str

    def __post_init__(self):
        if self.role not in ROLES:
            raise InputError(f"scene object {self.name}: role must be one of {ROLES}, not {self.role!r}")

    def in_base(self) -> Cloud:
        placed = self.mesh.transformed(self.pose)
        placed.name = self.name
        return placed


@dataclass
class Scene:
    """The objects in B (exactly one workpiece) and what the truth needs besides their poses."""

    objects: list
    workpiece_original: Cloud  # X-A before any clay change: the model the matcher is given
    workpiece_upright: np.ndarray  # ^X N, the workpiece's upright body frame (z up) in X
    reshaped: clay.Reshaped | None = None  # the clay change, if any: which vertices moved and how far
    seed: int = 0

    def _one(self, role: str) -> SceneObject:
        found = [o for o in self.objects if o.role == role]
        if len(found) != 1:
            raise InputError(f"scene: expected one {role}, found {len(found)}")
        return found[0]

    @property
    def workpiece(self) -> SceneObject:
        return self._one("workpiece")

    @property
    def reference(self) -> SceneObject:
        return self._one("reference")

    @property
    def W(self) -> np.ndarray:
        """Ground truth ^B X: the workpiece's model frame in the robot base frame."""
        return self.workpiece.pose

    def reference_model(self) -> Cloud:
        """B-P: the reference block's mesh in B, as the user has it."""
        model = self.reference.in_base()
        model.name = "B-P"
        return model

    def workpiece_model(self) -> Cloud:
        """X-A: the unchanged workpiece model in its frame X."""
        return Cloud(self.workpiece_original.points, triangles=self.workpiece_original.triangles,
                     name=self.workpiece_original.name)


def _resting_pose(points_in_n: np.ndarray, yaw: float, tilt_axis_deg: float, tilt: float, spot,
                  rotation=None) -> np.ndarray:
    """^Q N: the upright body turned by yaw, tilted a little (or turned by ``rotation``), its lowest
    point on the top face at spot."""
    R = frames.rot_z(tilt_axis_deg) @ frames.rot_x(tilt) @ frames.rot_z(yaw - tilt_axis_deg) if rotation is None \
        else np.asarray(rotation, dtype=float)
    turned = points_in_n @ R.T
    centre = 0.5 * (turned[:, :2].min(axis=0) + turned[:, :2].max(axis=0))
    return frames.rigid(R, (spot[0] - centre[0], spot[1] - centre[1], -turned[:, 2].min()))


def _place_workpiece(points_in_n: np.ndarray, obstacles: np.ndarray, rng, rotation=None) -> np.ndarray:
    """A resting pose ^Q N with a random yaw and tilt (or turned by ``rotation``), as close to the anchor
    as it fits on the platform CLEARANCE_MM from the obstacles' vertices (x, y in Q: dense meshes, so
    vertices stand for outlines)."""
    tree = cKDTree(obstacles)
    anchor = frames.apply(REFERENCE_ON_PLATFORM, np.array([WORKPIECE_ANCHOR_IN_P]))[0, :2]
    inwards = np.degrees(np.arctan2(-anchor[1], -anchor[0]))
    outline = points_in_n[:: max(1, len(points_in_n) // 4000)]
    for attempt in range(int(2 * PLATFORM_HALF_SIZE / WORKPIECE_SEARCH_STEP_MM)):
        direction = np.radians(inwards + rng.uniform(-WORKPIECE_SPREAD_DEG, WORKPIECE_SPREAD_DEG))
        spot = anchor + attempt * WORKPIECE_SEARCH_STEP_MM * np.array([np.cos(direction), np.sin(direction)])
        pose = _resting_pose(points_in_n, rng.uniform(0.0, 360.0), rng.uniform(0.0, 360.0),
                             rng.uniform(0.0, MAX_TILT_DEG), spot, rotation)
        seen_from_above = frames.apply(pose, outline)[:, :2]
        on_platform = np.abs(seen_from_above).max() <= PLATFORM_HALF_SIZE - CLEARANCE_MM
        if on_platform and np.isinf(tree.query(seen_from_above, distance_upper_bound=CLEARANCE_MM)[0]).all():
            return pose
    raise InputError("workpiece: too large to rest on the 600 x 600 mm platform clear of the other objects")


def _reference_gap(points_in_q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per point (Q frame): the signed distance to the L-block (negative inside) and the nearest
    point of the block's surface (Q frame)."""
    Q_P = REFERENCE_ON_PLATFORM
    local = frames.apply(frames.invert(Q_P), points_in_q)
    best_d, best_p = np.full(len(local), np.inf), np.zeros_like(local)
    inside = np.zeros(len(local), dtype=bool)
    for lo, hi in REFERENCE_BOXES:
        lo, hi = np.asarray(lo), np.asarray(hi)
        nearest = np.clip(local, lo, hi)
        d = np.linalg.norm(local - nearest, axis=1)
        inside |= np.all((local > lo) & (local < hi), axis=1)
        closer = d < best_d
        best_d[closer], best_p[closer] = d[closer], nearest[closer]
    return np.where(inside, -1.0, best_d), frames.apply(Q_P, best_p)


def _moved_to_reference(resting: np.ndarray, points_in_n: np.ndarray, gap: float) -> np.ndarray:
    """The resting pose ^Q N slid across the platform towards the L-block until its surface is ``gap``
    mm from the block where they are closest (vertices stand for the surface: dense meshes)."""
    placed = frames.apply(resting, points_in_n)
    d, nearest = _reference_gap(placed)
    towards = nearest[np.argmin(d)] - placed[np.argmin(d)]
    towards[2] = 0.0
    towards /= np.linalg.norm(towards)

    def clearance(t):
        return _reference_gap(placed + t * towards)[0].min()

    lo, hi = 0.0, float(d.min()) + 1.0
    while clearance(hi) > gap:  # a slanted face: slide further until the part would come closer
        hi *= 2
    for _ in range(40):  # the largest slide that keeps the part ``gap`` away (the clearance falls as it slides)
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if clearance(mid) > gap else (lo, mid)
    t = lo
    return frames.rigid(translation=t * towards) @ resting


def contact(scene: "Scene") -> tuple[np.ndarray, np.ndarray]:
    """Where the workpiece comes closest to the reference (B, mm) and the horizontal direction from the
    reference towards it there."""
    in_q = frames.apply(frames.invert(PLATFORM_POSE) @ scene.W, scene.workpiece_original.points)
    d, nearest = _reference_gap(in_q)
    i = int(np.argmin(d))
    away = in_q[i] - nearest[i]
    away[2] = 0.0
    return frames.apply(PLATFORM_POSE, nearest[i][None])[0], away / max(np.linalg.norm(away), 1e-12)


def _clay_bridge(workpiece_in_b: np.ndarray) -> SceneObject:
    """A lump of clay from the workpiece to the L-block, at the block's top edge where they are closest."""
    in_q = frames.apply(frames.invert(PLATFORM_POSE), workpiece_in_b)
    top = REFERENCE_BOXES[0][1][2]  # over the block's top edge, where a scanner from above sees both ends
    low = in_q[np.abs(in_q[:, 2] - (top - 0.5 * BRIDGE_RADIUS_MM)) < BRIDGE_RADIUS_MM]
    if len(low) == 0:
        low = in_q
    d, nearest = _reference_gap(low)
    i = int(np.argmin(d))
    start, end = low[i], nearest[i]
    end = np.array([end[0], end[1], start[2]])
    axis = end - start
    length = float(np.linalg.norm(axis))
    axis /= length
    across = np.cross([0.0, 0.0, 1.0], axis)
    rotation = np.column_stack([axis, across, np.cross(axis, across)])
    mesh = shapes.ellipsoid((length / 2 + BRIDGE_OVERLAP_MM, BRIDGE_RADIUS_MM, BRIDGE_RADIUS_MM), edge_mm=1.5)
    mesh.name = "clay bridge"
    return SceneObject("clay bridge", mesh, PLATFORM_POSE @ frames.rigid(rotation, 0.5 * (start + end)), "bridge")


def _clutter(rng) -> list:
    """A 60 x 40 x 30 mm box and a 40 mm wide, 50 mm tall cylinder standing on the platform, randomly turned."""
    out = []
    for mesh, lift in ((shapes.box((60.0, 40.0, 30.0), edge_mm=3.0, name="clutter box"), 30.0),  # top at z = 0
                       (shapes.cylinder(20.0, 50.0, edge_mm=3.0, name="clutter cylinder"), 0.0)):
        x, y = CLUTTER_SPOTS[mesh.name]
        pose = PLATFORM_POSE @ frames.rigid(frames.rot_z(rng.uniform(0.0, 360.0)), (x, y, lift))
        out.append(SceneObject(mesh.name, mesh, pose, "clutter"))
    return out


def build_scene(workpiece="car", workpiece_pose=None, seed: int = 0, clutter: bool = False,
                clay_change=None, layout: str = "apart", platform: bool = True, upright=None,
                rotation=None) -> Scene:
    """Platform, L-block and workpiece (and clutter) in B, with the ground truth W = ^B X.

    workpiece: "car", "figurine" or a closed mesh (Cloud with triangles) whose z axis is up, or whose
    upright body frame ^X N (z up) is ``upright``.
    workpiece_pose: ^B X to use as is; by default the workpiece rests on the platform at a pose drawn
    from ``seed``.  clay_change: edits applied to what the scanner sees (``clay.ClayEdit`` with a centre
    in X, or "lump" / "carve" for ``clay.suggested``); the model stays unchanged.  layout: "apart",
    "touching" (the workpiece moved up to the reference until they touch) or "bridge" (a lump of
    clay joins them).  platform=False leaves the platform out (the objects stay where they were).
    rotation: the workpiece's upright body frame turned by this 3 x 3 rotation in B to rest, instead
    of a random yaw and tilt.
    """
    if isinstance(workpiece, str):
        if workpiece not in _WORKPIECES:
            raise InputError(f"workpiece must be one of {sorted(_WORKPIECES)} or a mesh, not {workpiece!r}")
        make, upright = _WORKPIECES[workpiece]
        model = make()
    else:
        if not workpiece.is_mesh:
            raise InputError(f"{workpiece.name}: the workpiece must be a closed mesh (it has no triangles)")
        model, upright = workpiece, np.eye(4) if upright is None else frames.as_transform(upright, "upright")
    # Separate streams, so that adding clutter does not change the draws for the workpiece.
    workpiece_rng, clutter_rng = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(2))

    if layout not in LAYOUTS:
        raise InputError(f"layout must be one of {LAYOUTS}, not {layout!r}")
    objects = [SceneObject("platform", shapes.platform(), PLATFORM_POSE, "platform")]
    block = shapes.l_block()
    objects.append(SceneObject("L-block", block, PLATFORM_POSE @ REFERENCE_ON_PLATFORM, "reference"))
    if clutter:
        objects += _clutter(clutter_rng)
    if workpiece_pose is None:
        obstacles = np.vstack([frames.apply(frames.invert(PLATFORM_POSE) @ o.pose, o.mesh.points)[:, :2]
                               for o in objects if o.role != "platform"])
        body_points = frames.apply(frames.invert(upright), model.points)
        resting = _place_workpiece(body_points, obstacles, workpiece_rng, rotation)
        if layout != "apart":
            resting = _moved_to_reference(resting, body_points, TOUCH_GAP_MM if layout == "touching" else BRIDGE_GAP_MM)
        workpiece_pose = PLATFORM_POSE @ resting @ frames.invert(upright)
    workpiece_pose = frames.as_transform(workpiece_pose, "workpiece pose")
    if layout == "bridge":
        objects.append(_clay_bridge(frames.apply(workpiece_pose, model.points)))
    if not platform:
        objects = objects[1:]

    edits = [clay.suggested(e, model, upright) if isinstance(e, str) else e for e in (clay_change or [])]
    reshaped = clay.reshape(model, edits) if edits else None
    scanned = reshaped.mesh if reshaped else model
    objects.append(SceneObject(model.name, scanned, workpiece_pose, "workpiece"))
    return Scene(objects, model, upright, reshaped, seed)


def object_scene(mesh: Cloud, pose=None) -> Scene:
    """The mesh alone, as the workpiece, at ``pose`` (^B X, default identity): for scanning one part
    from any side, without platform or reference in the way."""
    pose = np.eye(4) if pose is None else frames.as_transform(pose, "object pose")
    return Scene([SceneObject(mesh.name, mesh, pose, "workpiece")], mesh, np.eye(4))
