"""Transforming a path by W (point by point against numpy), arcs kept or linearised, the rotary-table chain."""
import numpy as np
import pytest

from workcal_wb.core import frames
from workcal_wb.core.toolpath import LINEAR, RotaryTable, linearised, parse_gcode, placement, transformed
from workcal_wb.core.toolpath import arcs

PATH = """G0 X0 Y0 Z20
G0 X30 Y0
G1 Z-2 F200
G3 X0 Y30 I-30 J0 F800
G2 X-30 Y0 Z-4 I0 J-30
G1 X-30 Y-20
G18 G2 X-10 Z-4 I10 K0
G17 G0 Z20
"""
TILTED = frames.from_euler_zyz(25.0, 35.0, -70.0, (812.5, -143.2, 95.0))
TURNED = frames.rigid(frames.rot_z(37.0), (400.0, 250.0, -30.0))  # keeps the XY plane, not ZX or YZ


@pytest.fixture
def path():
    return parse_gcode(PATH, "path.nc")


def points_at(start, arc, fractions):
    fractions = np.asarray(fractions, dtype=float)
    return arcs.points_at(start, arc.end, arc.centre, arc.normal, arc.kind == "arc_ccw",
                          np.zeros(len(fractions), dtype=int), fractions)


def chords(start, arc, tol):
    return arcs.linearise(start, arc.end, arc.centre, arc.normal, arc.kind == "arc_ccw", tol)[0]


def test_points_and_tool_axes_match_numpy(path):
    moved = transformed(path, TILTED)
    reference = linearised(path)
    np.testing.assert_allclose(linearised(moved).points(), reference.points() @ TILTED[:3, :3].T + TILTED[:3, 3],
                               atol=1e-9)
    for m in moved.moves:
        np.testing.assert_allclose(m.tool_axis, TILTED[:3, 2], atol=1e-12)


def test_a_tilted_plane_turns_arcs_into_lines(path):
    moved = transformed(path, TILTED)
    assert not any(m.is_arc for m in moved.moves)
    assert {m.line for m in moved.moves} == {m.line for m in path.moves}


def test_a_turn_about_z_keeps_xy_arcs_and_matches_their_linearised_form(path):
    xy_only = parse_gcode(PATH.split("G18")[0], "xy.nc")
    moved = transformed(xy_only, TURNED)
    assert [m.kind for m in moved.moves] == [m.kind for m in xy_only.moves]
    for (s0, m0), (s1, m1) in zip(zip(xy_only.starts(), xy_only.moves), zip(moved.starts(), moved.moves)):
        np.testing.assert_allclose(m1.end, frames.apply(TURNED, m0.end[None])[0], atol=1e-9)
        if m0.is_arc:
            np.testing.assert_allclose(m1.centre, frames.apply(TURNED, m0.centre[None])[0], atol=1e-9)
            np.testing.assert_allclose(chords(s1, m1, 0.01),
                                       frames.apply(TURNED, chords(s0, m0, 0.01)), atol=1e-9)
    # the ZX arc of the full path is not in a machine plane any more: chords
    kinds = [m.kind for m in transformed(path, TURNED).moves]
    assert kinds.count("arc_ccw") + kinds.count("arc_cw") == 2 and len(kinds) > len(path)


def test_turning_upside_down_keeps_arcs_with_their_sense():
    """Rx(180) maps the XY plane onto itself with its normal flipped: the arc stays, seen from below."""
    path = parse_gcode("G0 X10 Y0 Z0\nG3 X0 Y10 I-10 J0 F100\n")
    flip = frames.rigid(frames.rot_x(180.0))
    arc = transformed(path, flip).moves[1]
    assert arc.is_arc
    np.testing.assert_allclose(arc.normal, [0, 0, -1])
    mid = points_at(np.array([10.0, 0, 0]), arc, [0.5])[0]
    np.testing.assert_allclose(mid, flip[:3, :3] @ [10 * np.cos(np.pi / 4), 10 * np.sin(np.pi / 4), 0], atol=1e-9)


def _max_chord_deviation(start, arc, chords):
    """Largest distance from a dense sampling of the true arc to the polyline of ``chords``."""
    dense = points_at(start, arc, np.linspace(0, 1, 4001))
    poly = np.vstack([start, chords])
    a, b = poly[:-1], poly[1:]
    d = b - a
    t = np.clip(np.einsum("ijk,jk->ij", dense[:, None] - a[None], d) / np.einsum("ij,ij->i", d, d), 0, 1)
    closest = a[None] + t[..., None] * d[None]
    return np.linalg.norm(dense[:, None] - closest, axis=2).min(axis=1).max()


@pytest.mark.parametrize("tol", [0.1, 0.01, 0.001])
def test_linearised_arcs_stay_within_the_chordal_tolerance(tol):
    path = parse_gcode("G0 X25 Y0 Z0\nG3 X25 Y0 Z-3 I-25 J0 F100\n")  # full helical circle, r = 25
    start, arc = path.moves[0].end, path.moves[1]
    chords = linearised(path, tol).points()[1:]
    deviation = _max_chord_deviation(start, arc, chords)
    assert deviation <= tol * (1 + 1e-6)
    assert deviation > tol / 2, "no more segments than needed"
    np.testing.assert_array_equal(chords[-1], arc.end)
    assert all(m.kind == LINEAR for m in linearised(path, tol).moves[1:])


def test_linearised_arc_keeps_feed_line_and_comment_once():
    path = parse_gcode("G0 X10 Y0 Z0\nG3 X0 Y10 I-10 J0 F250 (arc)\n")
    pieces = linearised(path, 0.01).moves[1:]
    assert len(pieces) > 5
    assert {m.feed for m in pieces} == {250} and {m.line for m in pieces} == {2}
    assert [m.comment for m in pieces[:2]] == ["arc", ""]


def test_rotary_table_at_zero_is_w():
    W = TILTED
    BQ = frames.from_euler_zyz(10, 2, -5, (1200, 300, 50))
    np.testing.assert_allclose(placement(W, RotaryTable(BQ, 0.0)), W, atol=1e-12)
    assert placement(W) is not None and np.array_equal(placement(W), W)


@pytest.mark.parametrize("angle", [30.0, -90.0, 180.0])
def test_rotary_table_chain(angle):
    W = TILTED
    BQ = frames.from_euler_zyz(10, 2, -5, (1200, 300, 50))
    expected = BQ @ frames.rigid(frames.rot_z(angle)) @ np.linalg.inv(BQ) @ W
    T = placement(W, RotaryTable(BQ, angle))
    np.testing.assert_allclose(T, expected, atol=1e-9)
    # The part turns with the table: its origin stays at the same height above the table and distance from its axis.
    origin_in_Q = np.linalg.inv(BQ) @ np.append(W[:3, 3], 1)
    moved_in_Q = np.linalg.inv(BQ) @ np.append(T[:3, 3], 1)
    assert moved_in_Q[2] == pytest.approx(origin_in_Q[2])
    assert np.hypot(*moved_in_Q[:2]) == pytest.approx(np.hypot(*origin_in_Q[:2]))
