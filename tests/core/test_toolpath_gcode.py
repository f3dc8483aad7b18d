"""G-code reading (modal state, units, planes, arcs, comments), its errors, and the identity round trip."""
import numpy as np
import pytest

from workcal_wb.core.errors import InputError
from workcal_wb.core.result import CalibrationResult
from workcal_wb.core.toolpath import ARC_CW, LINEAR, RAPID, export, parse_gcode, read_gcode
from workcal_wb.core.toolpath import arcs

# One program with every construct the reader supports; the round trip must preserve all of it.
PROGRAM = """%
(part: bracket)
(tool: 6 mm end mill)
N10 G21 G90 G17 M3 S12000
G0 Z16 (safe height)
G0 X10 Y0
G1 Z-1 F300
(a quarter circle, counter-clockwise)
G3 X0 Y10 I-10 J0 F600
G2 X10 Y0 R10
G3 X10 Y0 Z-3 I-5 J0 (helical full circle)
G91 G1 X5 Y5
G90 G18 G2 X25 Z-3 I5 K0
G19 G3 Y15 Z2 R6
G17
G0 Z16
(end of program)
M5 M2
%
"""


def read(text, **kw):
    return parse_gcode(text, source="test.nc", **kw)


def test_modal_axes_and_feed_are_carried():
    tp = read("G0 X1 Y2 Z3\nX4\nG1 Y5 F100\nZ6\n")
    np.testing.assert_allclose(tp.points(), [[1, 2, 3], [4, 2, 3], [4, 5, 3], [4, 5, 6]])
    assert [m.kind for m in tp.moves] == [RAPID, RAPID, LINEAR, LINEAR]
    assert [m.feed for m in tp.moves] == [None, None, 100, 100]


def test_leading_axes_take_their_first_later_value():
    tp = read("G0 Z16\nG0 X10 Y20\n")
    np.testing.assert_allclose(tp.points(), [[10, 20, 16], [10, 20, 16]])


def test_incremental_g91():
    tp = read("G0 X1 Y1 Z1\nG91 G1 X2 Y-1 F50\nZ-3\nG90 X0\n")
    np.testing.assert_allclose(tp.points(), [[1, 1, 1], [3, 0, 1], [3, 0, -2], [0, 0, -2]])


def test_g20_inches_convert_positions_centres_and_feed():
    tp = read("G20 G0 X1 Y0 Z0.5\nG3 X0 Y1 I-1 J0 F10\n")
    np.testing.assert_allclose(tp.moves[0].end, [25.4, 0, 12.7])
    np.testing.assert_allclose(tp.moves[1].centre, [0, 0, 12.7], atol=1e-12)
    assert tp.moves[1].feed == pytest.approx(254.0)


def test_units_in_applies_until_the_file_says_otherwise():
    assert read("G0 X1 Y0 Z0\n", units="in").moves[0].end[0] == pytest.approx(25.4)
    assert read("G21 G0 X1 Y0 Z0\n", units="in").moves[0].end[0] == pytest.approx(1.0)


@pytest.mark.parametrize("plane, words, normal, centre, end", [
    ("G17", "G2 X10 Y0 I5 J0", [0, 0, 1], [5, 0, 0], [10, 0, 0]),
    ("G18", "G2 X10 Z0 I5 K0", [0, 1, 0], [5, 0, 0], [10, 0, 0]),
    ("G19", "G2 Y10 Z0 J5 K0", [1, 0, 0], [0, 5, 0], [0, 10, 0]),
])
def test_arcs_in_each_plane_turn_clockwise_about_the_plane_axis(plane, words, normal, centre, end):
    """G2 is clockwise seen from the positive end of the plane's normal axis (Z, Y, X)."""
    tp = read(f"G0 X0 Y0 Z0\n{plane} {words} F100\n")
    arc = tp.moves[1]
    assert arc.kind == ARC_CW
    np.testing.assert_allclose(arc.normal, normal)
    np.testing.assert_allclose(arc.centre, centre)
    np.testing.assert_allclose(arc.end, end)
    # half circle clockwise about the normal: the midpoint is on the -(normal x start) side
    mid = arcs.points_at(np.zeros(3), arc.end, arc.centre, arc.normal, False, [0], [0.5])[0]
    u = np.zeros(3) - arc.centre
    np.testing.assert_allclose(mid, arc.centre - np.cross(arc.normal, u), atol=1e-12)


def test_full_circle_and_helix():
    tp = read("G0 X10 Y0 Z0\nG3 X10 Y0 Z-4 I-10 J0 F100\n")
    start, arc = tp.moves[0].end, tp.moves[1]
    assert arcs.signed_sweep(start, arc.end, arc.centre, arc.normal, True)[0] == pytest.approx(2 * np.pi)
    quarter, half = arcs.points_at(start, arc.end, arc.centre, arc.normal, True, [0, 0], [0.25, 0.5])
    np.testing.assert_allclose(quarter, [0, 10, -1], atol=1e-12)
    np.testing.assert_allclose(half, [-10, 0, -2], atol=1e-12)


def test_r_arcs_short_and_long_way():
    short = read("G0 X10 Y0 Z0\nG3 X0 Y10 R10 F100\n").moves[1]
    long = read("G0 X10 Y0 Z0\nG3 X0 Y10 R-10 F100\n").moves[1]
    np.testing.assert_allclose(short.centre, [0, 0, 0], atol=1e-12)
    np.testing.assert_allclose(long.centre, [10, 10, 0], atol=1e-12)
    assert arcs.signed_sweep([10.0, 0, 0], long.end, long.centre, long.normal, True)[0] == pytest.approx(1.5 * np.pi)


@pytest.mark.parametrize("plane, axis", [("G17", 2), ("G18", 1), ("G19", 0)])
@pytest.mark.parametrize("code", ["G2", "G3"])
@pytest.mark.parametrize("sign", [1, -1])
def test_r_arcs_in_every_plane_centre_at_r_from_both_ends_the_way_r_says(plane, axis, code, sign):
    """An R arc's centre (computed in plain floats, a plane at a time) lies |R| from its start and its
    end in the arc's plane, and the arc turns the short way for R > 0, the long way for R < 0, in the
    direction G2/G3 name about the plane's normal."""
    tp = read(f"G0 X1 Y2 Z3\n{plane} {code} X7 Y-2 Z8 R{sign * 6} F100\n")
    start, arc = tp.moves[0].end, tp.moves[1]
    in_plane = [k for k in range(3) if k != axis]
    for point in (start, arc.end):
        assert np.linalg.norm((point - arc.centre)[in_plane]) == pytest.approx(6.0, abs=1e-9)
    assert arc.normal[axis] == 1.0
    sweep = arcs.signed_sweep(start, arc.end, arc.centre, arc.normal, code == "G3")[0]
    assert np.sign(sweep) == (1 if code == "G3" else -1)
    assert (abs(sweep) <= np.pi) == (sign > 0)


def test_absolute_arc_centres_g90_1():
    tp = read("G0 X10 Y0 Z0\nG90.1 G3 X0 Y10 I0 J0 F100\n")
    np.testing.assert_allclose(tp.moves[1].centre, [0, 0, 0])


def test_comments_header_footer_and_inline():
    tp = read(PROGRAM)
    assert tp.header == ["part: bracket", "tool: 6 mm end mill"]
    assert tp.footer == ["end of program"]
    assert tp.moves[0].comment == "safe height"
    assert tp.moves[3].comment == "a quarter circle, counter-clockwise"
    assert tp.moves[5].comment == "helical full circle"
    assert read("G0 X1 Y1 Z1 ; semicolon comment\n").moves[0].comment == "semicolon comment"


def test_every_move_remembers_its_line():
    tp = read(PROGRAM)
    assert [m.line for m in tp.moves] == [5, 6, 7, 9, 10, 11, 12, 13, 14, 16]


def _assert_same_path(a, b, atol=1e-4):
    assert len(a) == len(b)
    for m, n in zip(a.moves, b.moves):
        assert (m.kind, m.feed, m.comment) == (n.kind, n.feed, n.comment)
        np.testing.assert_allclose(m.end, n.end, atol=atol)
        np.testing.assert_allclose(m.tool_axis, n.tool_axis, atol=1e-9)
        if m.is_arc:
            np.testing.assert_allclose(m.centre, n.centre, atol=atol)
            np.testing.assert_allclose(m.normal, n.normal)


def write_gcode(path, folder, machine="5axis-tcp"):
    """``path`` written by the G-code exporter through the identity."""
    out = folder / "again.nc"
    export(path, CalibrationResult("ok", np.eye(4)), "gcode", out, machine=machine)
    return out


def test_round_trip_through_identity_is_the_same_path(tmp_path):
    original = read(PROGRAM)
    again = read_gcode(write_gcode(original, tmp_path))
    _assert_same_path(original, again)
    assert again.footer == original.footer and set(original.header) <= set(h.removeprefix("source: ")
                                                                            for h in again.header)
    assert sum(m.is_arc for m in again.moves) == 5  # arcs stay arcs, in all three planes


def test_writer_states_units_and_repeats_full_positions(tmp_path):
    text = write_gcode(read("G20 G0 X1 Y2 Z3\nG1 X2 F10\n"), tmp_path, machine="3axis").read_text()
    assert "G21" in text
    assert "G1 X50.8000 Y50.8000 Z76.2000 F254.00" in text


@pytest.mark.parametrize("text, message", [
    ("G0 X1 Y1 Z1\nG1 X2 Q7\n", "line 2: unknown word Q"),
    ("G0 X1 Y1 Z1\nG1 X2 E5 F10\n", "line 2: unknown word E"),
    ("G0 X1 Y1 Z1\nG41 D1\n", "line 2: G41 is not supported (cutter radius compensation"),
    ("G0 X1 Y1 Z1\nG83 Z-5 R1 Q2 F100\n", "line 2: G83 is not supported"),
    ("G0 X1 Y1 Z1\nG4 P0.5\nG1 X2 C30 F10\n", "line 3: rotary axis C is not one of the AB"),
    ("G0 X1 Y1 Z1\nG1 X2\n", "line 2: missing feed (F) on the first cutting move (G1)"),
    ("G0 X0 Y0 Z0\nG2 X10 Y0 I4 J0 F100\n", "line 2: arc radius mismatch"),
    ("G0 X0 Y0 Z0\nG2 X30 Y0 R10 F100\n", "line 2: arc radius mismatch"),
    ("G91 G0 X1\n", "line 1: incremental (G91) X before the X position is known"),
    ("G0 Z5\nG2 X1 Y0 I1 J0 F100\n", "line 2: arc before the start position is known"),
    ("X1 Y2 Z3\n", "line 1: coordinates without a motion mode"),
    ("G0 X1 Y1 Z1\nG1 X2 X3 F10\n", "line 2: X given twice"),
    ("G0 X1 Y1 Z1\nG1 X2 #5 F10\n", "line 2: cannot read '#5"),
    ("G0 X1 Y1 Z1\nG0 X2 R1\n", "line 2: R given for a straight move"),
    ("G0 X1 Y1\n", "axis Z is never given"),
    ("G0 X1 Y1 Z1\nT9007199254740993 M6\n", "line 2: T9007199254740992 is more than 99,999,999"),
    ("G0 X1 Y1 Z1\nT0 M6\n", "line 2: tool change M6 to T0, which is no tool"),
    ("G0 X1 Y1 Z1\nT-3 M6\n", "line 2: T-3 is negative"),
    ("G0 X1 Y1 Z1\nT2.5 M6\n", "line 2: T2.5 is not a whole number"),
    ("G0 X1 Y1 Z1\nG4 P99999999999999\n", "line 2: a dwell of 1e+11 s, more than 3600 s"),
])
def test_errors_name_the_file_and_line(text, message):
    with pytest.raises(InputError) as err:
        read(text)
    assert str(err.value).startswith("test.nc")
    assert message in str(err.value)


def test_missing_file_is_an_input_error(tmp_path):
    with pytest.raises(InputError, match="cannot read G-code"):
        read_gcode(tmp_path / "nope.nc")
