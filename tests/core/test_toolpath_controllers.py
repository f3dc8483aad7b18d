"""Programs a controller loads as written: each language's rules checked by a strict checker,
a corpus of CAM files in the shapes real posts write, the G-code reader's findings and the safety bounds."""
import hashlib
import math
import re
from pathlib import Path

import numpy as np
import pytest

from program_checkers import (check_fanuc, check_gcode, check_krl, check_rapid, check_urscript, comment_text,
                              rapid_declarations)
from test_toolpath_exporters import parse_csv, parse_fanuc, parse_krl, parse_rapid, parse_urscript
from workcal_wb.core import frames
from workcal_wb.core.errors import InputError
from workcal_wb.core.result import CalibrationResult, result_fingerprint
from workcal_wb.core.toolpath import ExportRefused, export, linearised, parse_gcode, read_gcode

CORPUS = Path(__file__).resolve().parent.parent / "data" / "cam"
# a part turned on the table and moved: the tool axis stays vertical, so 3-axis G-code is possible
TURNED = frames.rigid(frames.rot_z(-33.0), (612.5, -143.2, 95.0))
TILTED = frames.from_euler_zyz(25.0, 3.0, -70.0, (812.5, -143.2, 95.0))
FILES = {"freecad_linuxcnc.ngc": "ab", "fusion360_fanuc.nc": "ab", "mastercam_fanuc.nc": "ab",
         "powermill_5axis.tap": "ac"}
EXT = {"krl": ".src", "rapid": ".mod", "urscript": ".script", "fanuc": ".ls", "csv": ".csv", "gcode": ".nc"}
PARSERS = {"krl": parse_krl, "rapid": parse_rapid, "urscript": parse_urscript, "fanuc": parse_fanuc, "csv": parse_csv}


def calibration(W=TURNED, status="ok"):
    return CalibrationResult(status, W, uncertainty={"toolpath_bound_mm": 0.0275, "toolpath_median_mm": 0.011},
                             quality_gates=[{"name": "rms", "value": 0.05, "limit": 0.3, "passed": True, "unit": "mm"}])


def check(fmt, text, name):
    {"krl": lambda: check_krl(text, name), "rapid": lambda: check_rapid(text),
     "urscript": lambda: check_urscript(text), "fanuc": lambda: check_fanuc(text, name.upper()),
     "gcode": lambda: check_gcode(text), "csv": lambda: None}[fmt]()


@pytest.mark.parametrize("fmt", sorted(EXT))
@pytest.mark.parametrize("name", sorted(FILES))
def test_corpus_exports_pass_the_checkers_and_parse_back(name, fmt, tmp_path):
    rotary = FILES[name]
    path = read_gcode(CORPUS / name, rotary=rotary)
    five_axis = path.tool_axis is not None
    W = TILTED if five_axis or fmt != "gcode" else TURNED
    out = tmp_path / f"prog{EXT[fmt]}"
    export(path, calibration(W), fmt, out, rotary=rotary, machine="5axis-tcp" if fmt == "gcode" and five_axis else None)
    text = out.read_text()
    check(fmt, text, "prog")
    assert f"result sha256 {result_fingerprint(calibration(W))}" in comment_text(text)
    if fmt == "gcode":
        again = read_gcode(out, rotary=rotary)
        np.testing.assert_allclose(linearised(again).points(), frames.apply(W, linearised(path).points()), atol=1e-3)
        if five_axis:
            np.testing.assert_allclose(again.axes(), path.axes() @ W[:3, :3].T, atol=1e-6)
        # G43 H moves into the block of the next Z move, so it may come after that move's other events
        offsets = [e.number for e in path.events if e.kind == "length_offset"]
        again_offsets = [e.number for e in again.events if e.kind == "length_offset"]
        if again_offsets[-1:] == [None] and offsets[-1] is not None:
            again_offsets.pop()  # the export cancels tool-length compensation at the end when the CAM file did not
        assert again_offsets == offsets
        assert [e.kind for e in again.events if e.kind != "length_offset"] == \
            [e.kind for e in path.events if e.kind != "length_offset"]
        return
    poses = PARSERS[fmt](text)
    expected = frames.apply(W, linearised(path).points())
    found = np.array([p[:3, 3] for p, _ in poses])
    # every CAM point is a robot target, in order (robots add a retract at each G28 and use the top Z before it)
    distance = np.linalg.norm(found[:, None] - expected[None], axis=2)
    assert distance.min(axis=0).max() < 1e-3


def test_krl_starts_with_def_has_ext_bas_a_ptp_first_and_limits_speed(tmp_path):
    path = parse_gcode("(fast)\nG0 X0 Y0 Z10\nG1 Z0 F300000\nG1 X10\n", "fast.nc")
    out = tmp_path / "fast.src"
    export(path, calibration(), "krl", out)
    text = out.read_text()
    lines = text.splitlines()
    assert lines[2] == "DEF fast( )" and lines[3].startswith("EXT BAS (BAS_COMMAND :IN, REAL :IN)")
    motions = [line for line in lines if line.startswith(("PTP", "LIN"))]
    assert motions[0] == "PTP XHOME" and motions[1].startswith("PTP {")
    assert "$VEL.CP = 2.000000" in text and "$VEL.CP = 5.0" not in text
    assert "speed limited: 2 moves" in comment_text(text)


def test_rapid_declares_its_tool_avoids_main_and_moves_joint_first(tmp_path):
    path = parse_gcode("G0 X0 Y0 Z10\nG1 Z0 F300\nT2 M6\nG1 X10\n", "part.nc")
    out = tmp_path / "part.mod"
    export(path, calibration(), "rapid", out)
    text = out.read_text()
    check_rapid(text)
    assert "PERS tooldata tWorkCal1" in text and "PERS tooldata tWorkCal2" in text
    moves = [line.strip() for line in text.splitlines() if line.strip().startswith("Move")]
    assert moves[0].startswith("MoveJ") and "tWorkCal2" in moves[-1] and "ConfJ\\Off;" in text
    assert "PROC main()" not in text and "Stop;" in text


def test_urscript_has_def_first_everything_indented_and_blends(tmp_path):
    path = parse_gcode("(a)\nG0 X0 Y0 Z10\nG1 Z0 F300\nG1 X10\nG1 X20 Y5\nG1 X30\n", "part.nc")
    out = tmp_path / "part.script"
    export(path, calibration(), "urscript", out)
    text = out.read_text()
    check_urscript(text)
    radii = [float(r) for r in re.findall(r"r=([\d.]+)\)", text)]
    assert radii[-1] == 0 and max(radii) > 0


def test_fanuc_lines_remarks_attr_joint_first_and_parts(tmp_path):
    moves = "\n".join(f"G1 X{i % 50} Y{i // 50} F600" for i in range(300))
    path = parse_gcode(f"(a very long comment that a teach pendant cannot show on one line at all)\n"
                       f"G0 X0 Y0 Z10\n{moves}\n", "long.nc")
    out = tmp_path / "long.ls"
    export(path, calibration(), "fanuc", out, max_lines=120)
    files = sorted(p.name for p in tmp_path.iterdir())
    assert files[0] == "long.ls" and files[1:] == [f"long_{i:03d}.ls" for i in range(1, len(files))]
    assert len(files) >= 4
    main = out.read_text()
    check_fanuc(main, "LONG")
    assert [line.split(":")[1].strip() for line in main.splitlines() if "CALL" in line] == \
        [f"CALL LONG_{i:03d} ;" for i in range(1, len(files))]
    targets = []
    for name in files[1:]:
        text = (tmp_path / name).read_text()
        check_fanuc(text, Path(name).stem.upper())
        targets += parse_fanuc(text)
    assert re.search(r"^\s*\d+:J P\[1\] ", (tmp_path / files[1]).read_text(), flags=re.M)
    expected = frames.apply(TURNED, path.points())
    np.testing.assert_allclose([p[:3, 3] for p, _ in targets], expected, atol=1e-3)
    # a shorter export into the same folder removes the parts it no longer has
    export(parse_gcode("G0 X0 Y0 Z10\nG1 X1 F100\n", "long.nc"), calibration(), "fanuc", out, max_lines=120)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["long.ls"]


def test_krl_and_rapid_parts_are_called_in_order(tmp_path):
    moves = "\n".join(f"G1 X{i % 50} Y{i // 50} F600" for i in range(200))
    path = parse_gcode(f"G0 X0 Y0 Z10\n{moves}\n", "big.nc")
    for fmt in ("krl", "rapid"):
        out = tmp_path / f"big{EXT[fmt]}"
        export(path, calibration(), fmt, out, max_lines=60)
        parts = sorted(tmp_path.glob(f"big_*{EXT[fmt]}"))
        assert len(parts) >= 4
        main = out.read_text()
        calls = [f"big_{i:03d}" for i in range(1, len(parts) + 1)]
        assert all(c in main for c in calls) and main.index(calls[0]) < main.index(calls[-1])
        poses = []
        for part in parts:
            text = part.read_text()
            if fmt == "krl":
                check_krl(text, part.stem)
                poses += parse_krl(main.split("PTP XHOME")[0] + text)
            else:
                check_rapid(text, known=rapid_declarations(main))
                poses += parse_rapid(main.split("  PROC")[0] + text)
        np.testing.assert_allclose([p[:3, 3] for p, _ in poses], frames.apply(TURNED, path.points()), atol=1e-3)


def test_gcode_3axis_refuses_a_tilted_w_with_the_tilt_and_keeps_arcs_when_level(tmp_path):
    path = parse_gcode("G0 X10 Y0 Z5\nG1 Z0 F300\nG3 X0 Y10 I-10 J0\nG0 Z5\n", "part.nc")
    tilted = frames.rigid(frames.rot_x(0.2), (500.0, 0, 0))
    with pytest.raises(ExportRefused, match=r"W tilts the tool axis 0\.2000 deg .* --vertical-tol 0\.2 .*"
                                            r"--machine 5axis-tcp"):
        export(path, calibration(tilted), "gcode", tmp_path / "p.nc")
    assert not (tmp_path / "p.nc").exists()
    export(path, calibration(tilted), "gcode", tmp_path / "p.nc", vertical_tol_deg=0.25)
    text = (tmp_path / "p.nc").read_text()
    check_gcode(text)
    assert " A" not in text.split("G21 G90")[1] and re.search(r"\nG0 G43 X\S+ Y\S+ Z\S+ H1\n", text)
    export(path, calibration(TURNED), "gcode", tmp_path / "q.nc")
    assert "\nG3 " in (tmp_path / "q.nc").read_text()


def test_gcode_5axis_states_its_kinematics_and_tcp(tmp_path):
    path = read_gcode(CORPUS / "powermill_5axis.tap", rotary="ac")
    out = tmp_path / "p.nc"
    export(path, calibration(TILTED), "gcode", out, machine="5axis-tcp", rotary="ac")
    text = comment_text(out.read_text()) + out.read_text()
    assert "tool-centre-point control G43.4" in text and "Rz[C] Rx[A]" in text
    assert re.search(r"\nG\d G43\.4 X\S+ Y\S+ Z\S+ H3 A", text)
    with pytest.raises(InputError, match="not --machine robot"):
        export(path, calibration(TILTED), "gcode", out, machine="robot")


def test_gcode_comments_hold_no_semicolon_or_percent(tmp_path):
    path = parse_gcode("(50% stepover; climb)\nG0 X0 Y0 Z5\nG1 X1 F100 (50%; again)\n", "p.nc")
    out = tmp_path / "p.nc"
    export(path, calibration(), "gcode", out)
    check_gcode(out.read_text())


@pytest.mark.parametrize("text, kinds", [
    ("G0 X0 Y0 Z5\nM0\nG1 X1 F100\nM1\nG1 X2\n", ["stop", "stop"]),
    ("G0 X0 Y0 Z5\nT2 M6\nG43 H2 Z5\nS9000 M4\nM8\nG4 P250\nG1 X1 F100\nM5 M9\n",
     ["tool_change", "length_offset", "spindle", "coolant", "dwell", "spindle", "coolant"]),
])
def test_reader_keeps_stops_tools_spindle_coolant_and_dwell(text, kinds):
    path = parse_gcode(text, "p.nc")
    assert [e.kind for e in path.events] == kinds
    dwell = [e for e in path.events if e.kind == "dwell"]
    assert not dwell or dwell[0].number == pytest.approx(0.25)  # G4 P250: milliseconds (Fanuc)


def test_reader_stops_at_m30_and_warns_about_what_follows():
    path = parse_gcode("G0 X0 Y0 Z5\nG1 X1 F100\nM30\nG1 X99\n", "p.nc")
    assert len(path) == 2 and "M30 (line 3)" in path.warnings[0]


@pytest.mark.parametrize("text, message", [
    ("G0 X10 Y0 Z0\nG2 X0 Y10 I-10 J0 R10 F100\n", "line 2: R and I/J in one arc"),
    ("G0 X0 Y0 Z0\nG1 G0 X10 F100\n", "line 2: G1 and G0 are both in the motion group"),
    ("G0 X10 Y0 Z0\nG17 G2 X0 Y10 I-10 J0 K5 F100\n", "line 2: K in a G17 arc"),
    ("G0 X0 Y0 Z0\n/G1 X5 F100\n", "line 2: block delete"),
    ("N10 G0 X0 Y0 Z0*99\n", "line 1: checksum *99"),
    ("G0 X0 Y0 Z0\nM98 P100\n", "line 2: M98 is not supported"),
    ("G0 X0 Y0 Z0\nG1 X1 I0 J0 K0 F10\n", "line 2: tool vector I J K of zero length"),
    ("G0 X0 Y0 Z0\nG28 G1 X0\n", "line 2: G28 and G1 in one block"),
])
def test_reader_refuses_what_it_cannot_honour_with_line_and_word(text, message):
    with pytest.raises(InputError, match=message.replace("*", r"\*")):
        parse_gcode(text, "p.nc")


def test_reader_honours_g28_g53_tool_vectors_ac_axes_block_delete_and_checksums():
    checksum = 0
    for byte in b"N3 G1 X5 F100":
        checksum ^= byte
    path = parse_gcode("G0 X0 Y0 Z5\nG28 G91 Z0\nG90\nG0 X10 Y10\nG0 Z5\n/G1 X7 F10\n"
                       f"N3 G1 X5 F100*{checksum}\nG1 X6 I0 J1 K1\nG53 G0 Z0\n", "p.nc", block_delete="on")
    assert [e.code for e in path.events] == ["G28 Z", "G53 G0 Z0.0000"]
    assert path.partial == {1: "XY"} and path.points()[1].tolist() == [10, 10, 5]
    np.testing.assert_allclose(path.axes()[-1], [0, 1 / math.sqrt(2), 1 / math.sqrt(2)])
    assert len(parse_gcode("G0 X0 Y0 Z5\n/G1 X7 F10\n", "p.nc", block_delete="off")) == 2
    ac = parse_gcode("G0 X0 Y0 Z5 A90 C90\n", "p.nc", rotary="ac")
    np.testing.assert_allclose(ac.axes()[0], [1, 0, 0], atol=1e-12)


def test_robot_programs_keep_events_as_stops_and_waits(tmp_path):
    path = read_gcode(CORPUS / "fusion360_fanuc.nc")
    expectations = {"krl": ("HALT", "WAIT SEC 0.500", "BAS(#TOOL, 1)"),
                    "rapid": ("Stop;", "WaitTime 0.500;", "TPWrite"),
                    "urscript": ("blocking=True", "sleep(0.500)", "set_tcp(workcal_tcp_1)"),
                    "fanuc": ("PAUSE ;", "WAIT 0.50(sec) ;", "UTOOL_NUM=1 ;")}
    for fmt, needles in expectations.items():
        out = tmp_path / f"prog{EXT[fmt]}"
        export(path, calibration(TILTED), fmt, out)
        text = out.read_text()
        for needle in needles:
            assert needle in text, (fmt, needle)
        assert "spindle on clockwise (M3) at 8000 rpm" in comment_text(text)


@pytest.mark.parametrize("translation", [1e308, 6e4])
def test_an_absurd_w_is_refused_even_without_an_envelope(translation, tmp_path):
    path = parse_gcode("G0 X0 Y0 Z5\nG1 X1 F100\n", "p.nc")
    with pytest.raises(ExportRefused, match="farther than any machine reaches"):
        export(path, calibration(frames.rigid(np.eye(3), (translation, 0, 0))), "krl", tmp_path / "p.src")
    assert list(tmp_path.iterdir()) == []


def test_every_program_names_its_result_and_shows_the_bound(tmp_path):
    result = calibration()
    result.to_json(tmp_path / "result.json")
    digest = hashlib.sha256((tmp_path / "result.json").read_bytes()).hexdigest()[:16]
    path = parse_gcode("G0 X0 Y0 Z5\nG1 X1 F100\n", "p.nc")
    for fmt, ext in EXT.items():
        export(path, CalibrationResult.from_json(tmp_path / "result.json"), fmt, tmp_path / f"p{ext}")
        text = comment_text((tmp_path / f"p{ext}").read_text())
        assert f"result sha256 {digest}" in text and "bound 0.0275 mm, median 0.011 mm" in text, fmt


@pytest.mark.parametrize("fmt", sorted(EXT))
def test_every_program_is_plain_ascii(fmt, tmp_path):
    """UR's script interface takes only (extended) ASCII, Fanuc TP and CNC posts write ASCII: the CAM file's
    own words (tool descriptions with Ø and °, names with umlauts) reach the program as ASCII."""
    path = parse_gcode("(Ø6 end mill, 90° chamfer, Müller)\nG0 X0 Y0 Z5\nG1 X1 F100 (naïve pass)\n", "p.nc")
    out = tmp_path / f"p{EXT[fmt]}"
    export(path, calibration(), fmt, out)
    data = out.read_bytes()
    assert max(data) < 128, fmt
    check(fmt, data.decode("ascii"), "p")
    assert "Muller" in comment_text(data.decode("ascii")), fmt


def test_urscript_stops_with_the_halt_keyword(tmp_path):
    """The Script Manual lists halt as a keyword (like return), not a function: no halt()."""
    out = tmp_path / "p.script"
    export(parse_gcode("G0 X0 Y0 Z5\nG1 X1 F100\n", "p.nc"), calibration(), "urscript", out)
    text = out.read_text()
    check_urscript(text)
    assert "    halt" in text.splitlines()


@pytest.mark.parametrize("text, machine, rotary", [
    ("G0 X0 Y0 Z5\nG1 X1 F100\n", "3axis", "ab"),  # no G43 in the file: WorkCal adds one
    ("G43 H2\nG0 X0 Y0\nG0 Z5\nG1 X1 F100\n", "3axis", "ab"),  # LinuxCNC style: G43 alone, Z later
    ("G0 X0 Y0 Z5 A0 C0\nG1 X1 A10 C30 F100\n", "5axis-tcp", "ac"),
])
def test_gcode_length_offset_comes_with_a_z_move(text, machine, rotary, tmp_path):
    """G43 H / G43.4 H moves Z on Fanuc-family controls: posts write it with the first Z move (G43 Z15. H1),
    never alone, where it would lift the spindle by the tool length from wherever it is."""
    out = tmp_path / "p.nc"
    export(parse_gcode(text, "p.nc", rotary=rotary), calibration(), "gcode", out, machine=machine, rotary=rotary)
    program = out.read_text()
    check_gcode(program)
    blocks = [re.sub(r"\([^()]*\)", "", line) for line in program.splitlines()]
    offsets = [block for block in blocks if re.search(r"G43(\.4)? ", block)]
    assert len(offsets) == 1 and re.search(r" Z-?\d", offsets[0]) and re.search(r" H\d", offsets[0]), offsets


@pytest.mark.parametrize("name", ["while.src", "trap.mod", "sleep.script", "halt.script"])
def test_a_program_name_that_is_a_word_of_the_language_is_refused(name, tmp_path):
    """KRL keywords (krl.g4), RAPID reserved words (ABB's table), URScript keywords and the functions the
    program calls: a program named after one cannot be loaded (or calls itself instead of sleep)."""
    fmt = {".src": "krl", ".mod": "rapid", ".script": "urscript"}[Path(name).suffix]
    with pytest.raises(InputError, match="reserved word"):
        export(parse_gcode("G0 X0 Y0 Z5\nG1 X1 F100\n", "p.nc"), calibration(), fmt, tmp_path / name)
    assert list(tmp_path.iterdir()) == []
