"""Fuzz every reader with mutated and truncated files: every outcome is a result or a WorkCalError, never
another exception (PLY ascii and binary in both byte orders, PCD ascii/binary/binary_compressed, XYZ,
CSV, PTS, STL ascii and binary, OBJ, OFF, result.json with its region side file, G-code).

hypothesis draws the mutations (tests/fuzz_inputs.py) and shrinks a failure to the smallest one.
``make test`` runs WORKCAL_FUZZ_EXAMPLES (default 200) per file kind, derandomized so that every run
tries the same cases; ``make fuzz`` runs many more with fresh randomness.
"""
import os
import re

import numpy as np
import pytest
from fuzz_inputs import GCODE, KINDS, SEEDS, SPECIAL, apply, regions_npz, result_json
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from workcal_wb.core.errors import WorkCalError
from workcal_wb.core.readers import read_cloud
from workcal_wb.core.result import CalibrationResult
from workcal_wb.core.toolpath import read_gcode

EXAMPLES = int(os.environ.get("WORKCAL_FUZZ_EXAMPLES", "200"))
FUZZ = settings(max_examples=EXAMPLES, deadline=None, database=None, derandomize="WORKCAL_FUZZ_EXAMPLES" not in os.environ,
                suppress_health_check=list(HealthCheck), print_blob=True)

where = st.floats(0, 1)
MUTATION = st.one_of(
    st.tuples(st.just("truncate"), where),
    st.tuples(st.just("flip"), where, st.integers(0, 255)),
    st.tuples(st.just("insert"), where, st.binary(min_size=1, max_size=64)),
    st.tuples(st.just("delete"), where, st.integers(1, 64)),
    st.tuples(st.just("repeat"), where, st.integers(1, 200), st.integers(2, 4)),
    st.tuples(st.just("number"), where, st.sampled_from(SPECIAL) | st.integers(-10, 10**7).map(lambda i: str(i).encode())),
)
MUTATIONS = st.lists(MUTATION, min_size=1, max_size=3)
assert set(KINDS) == {"truncate", "flip", "insert", "delete", "repeat", "number"}  # every kind drawn above


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("fuzz")


def check_cloud(cloud):
    """What every reader promises of what it returns."""
    assert cloud.points.ndim == 2 and cloud.points.shape[1] == 3 and len(cloud.points) > 0
    assert np.isfinite(cloud.points).all()
    if cloud.triangles is not None and len(cloud.triangles):
        assert cloud.triangles.min() >= 0 and cloud.triangles.max() < len(cloud.points)
    if cloud.normals is not None:
        assert cloud.normals.shape == cloud.points.shape


@pytest.mark.parametrize("name", SEEDS)
def test_every_seed_file_reads(folder, name):
    path = folder / name
    path.write_bytes(SEEDS[name])
    check_cloud(read_cloud(path))


@pytest.mark.parametrize("name", SEEDS)
def test_a_mutated_file_gives_a_cloud_or_a_workcal_error(folder, name):
    path = folder / f"mutated-{name}"

    @FUZZ
    @given(mutations=MUTATIONS)
    def read(mutations):
        path.write_bytes(apply(SEEDS[name], mutations))
        try:
            cloud = read_cloud(path)
        except WorkCalError:
            return
        check_cloud(cloud)

    read()


def test_a_mutated_result_json_gives_a_result_or_a_workcal_error(folder):
    seed = result_json()
    assert "calibration OK" in CalibrationResult.from_text(seed, "seed").summary()

    @FUZZ
    @given(mutations=MUTATIONS, side=st.one_of(st.none(), MUTATIONS))
    def read(mutations, side):
        path = folder / "result.json"
        path.write_bytes(apply(seed, mutations))
        (folder / "result.regions.npz").write_bytes(apply(regions_npz(), side or []))
        try:
            result = CalibrationResult.from_json(path)
            result.summary()  # what every consumer does with it first
        except WorkCalError:
            return

    read()


def test_a_mutated_gcode_file_gives_a_toolpath_or_a_workcal_error(folder):
    path = folder / "part.nc"

    @FUZZ
    @given(mutations=MUTATIONS)
    def read(mutations):
        path.write_bytes(apply(GCODE, mutations))
        try:
            read_gcode(path)
        except WorkCalError:
            return

    read()


# Text that would end a comment or a string, or be read as code, in one program language or another.
HOSTILE = ["\n", "\r", "\r\n", "\x00", "\x0b", "\x0c", "\x1c", "\x1e", "\x7f", "\x85", "\u2028", "\t", ";", "(", ")",
           "%", '"', "'", "\\", "[", "]", "{", "}", "&", "!", "#", "/END", "FOLD PTP HIDDEN", "ENDFOLD", ";FOLD",
           "G0 X0 Y0 Z-500", "LIN {X 0, Y 0, Z -500, A 0, B 0, C 0}", "1,linear,9999,9999,-500,1,0,0,0,0,0,0,1,1",
           "MoveL [[0,0,-500],[1,0,0,0]]", 'movel(p[0,0,-0.5,0,0,0])', "L P[1] 100mm/sec FINE ;", "M30", "é",
           "\uff1b", "\u037e", "\uff08", "\uff09", "\uff05", "\uff3b", "\uff3d", "\uff02", "\uff3c"]
TEXT = st.lists(st.one_of(st.sampled_from(HOSTILE), st.text(max_size=6)), min_size=1, max_size=6).map("".join)


@pytest.mark.slow
def test_no_text_from_outside_writes_into_a_program(folder):
    """Arbitrary text in every slot an export writes from outside (the toolpath file's name, its header
    and move comments, the reader's warnings, the calibration file's name, its reasons and gate names,
    the output file's name where the format lets it be any, the name in the robot file of a robot
    program's --robot): every program still holds exactly the moves of the toolpath, parsed back
    (G-code by WorkCal's own reader), every line printable ASCII, and no KRL line a fold marker."""
    import dataclasses
    import json

    from program_checkers import check_fanuc, check_gcode, check_krl, check_rapid, check_urscript
    from test_toolpath_exporters import PARSERS, SOURCE, assert_poses, calibration, expected

    from workcal_wb.core.result import Reason
    from workcal_wb.core.robots.model import LIBRARY, robot_from_dict
    from workcal_wb.core.toolpath import export, linearised, parse_gcode

    plain = parse_gcode(SOURCE, "part.nc")
    names = {"krl": "prog.src", "fanuc": "prog.ls"}
    checks = {"krl": lambda t: check_krl(t, "prog"), "fanuc": lambda t: check_fanuc(t, "PROG"), "rapid": check_rapid,
              "urscript": check_urscript, "gcode": check_gcode, "csv": lambda t: None}
    # A robot of each format's maker that follows the path (so its configuration is written too).
    robot_files = {"krl": "kuka_kr16_2", "rapid": "abb_irb6700_200_260", "fanuc": "fanuc_m20ia", "urscript": "ur10e",
                   "csv": "kuka_kr16_2"}

    @FUZZ
    @given(fmt=st.sampled_from(sorted(checks)), texts=st.lists(TEXT, min_size=9, max_size=9))
    def write(fmt, texts):
        path = dataclasses.replace(plain, source=texts[0], header=[texts[1]], warnings=[texts[2]],
                                   comments={0: texts[3], 2: texts[4] + "\n" + texts[5]})
        result = calibration()
        result.reasons = [Reason("rms", texts[6])]
        result.quality_gates[0]["name"] = texts[7]
        stem = "".join(c for c in texts[0] if c not in "/\0")[:40]
        name = names.get(fmt) or f"p{stem}.{ {'rapid': 'mod', 'urscript': 'script', 'gcode': 'nc', 'csv': 'csv'}[fmt] }"
        out = folder / fmt / name
        out.parent.mkdir(exist_ok=True)
        robot = None
        if fmt in robot_files:
            data = json.loads((LIBRARY / f"{robot_files[fmt]}.json").read_text())
            robot = robot_from_dict({**data, "name": "R" + texts[8]})
        job = export(path, result, fmt, out, calibration_source=texts[5], machine="5axis-tcp" if fmt == "gcode" else None,
                     robot=robot)
        assert robot is None or job.reach.reachable
        text = out.read_text(encoding="ascii")
        assert all(line.replace("\t", " ").isprintable() for line in text.split("\n")), text
        checks[fmt](text)
        if fmt == "gcode":
            again = linearised(parse_gcode(text, "again.nc"), 0.01)
            np.testing.assert_allclose(again.points(), expected(plain)[0], atol=1e-3)
        elif fmt == "urscript":
            assert_poses(PARSERS[fmt](text, robot), plain)
        else:
            assert_poses(PARSERS[fmt](text), plain)
        if fmt == "krl":
            assert not any(re.match(r"\s*;\s*(END)?FOLD", line, re.I) for line in text.split("\n")), text
        if fmt == "fanuc":  # a remark holds no ';' (it ends a TP line)
            assert all(line.count(";") == 1 for line in text.split("\n") if re.match(r"\s*\d+:\s*!", line)), text

    write()
