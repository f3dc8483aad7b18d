"""Fuzz every reader with mutated and truncated files: every outcome is a result or a WorkCalError, never
another exception (PLY ascii and binary in both byte orders, PCD ascii/binary/binary_compressed, XYZ,
CSV, PTS, STL ascii and binary, OBJ, OFF, result.json with its region side file, G-code).

hypothesis draws the mutations (tests/fuzz_inputs.py) and shrinks a failure to the smallest one.
``make test`` runs WORKCAL_FUZZ_EXAMPLES (default 200) per file kind, derandomized so that every run
tries the same cases; ``make fuzz`` runs many more with fresh randomness.
"""
import os

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
