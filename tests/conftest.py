"""Shared test set-up: the checkout first on sys.path, an output folder per test, the shared data."""
import os
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))  # helpers shared by tests/core and tests/fc (fuzz_inputs)

# Real scanner data lives beside the checkout (../shared); tests that use it skip cleanly without it.
SHARED = Path(os.environ.get("WORKCAL_SHARED", ROOT.parent / "shared"))
BUNNY = SHARED / "data" / "stanford-bunny"
OUTPUT = Path(os.environ.get("WORKCAL_TEST_OUTPUT", ROOT / "build" / "test-output"))


def pytest_configure(config):
    """The ``slow`` mark: tests that take seconds (a whole calibration, a global search, a benchmark run, a
    real-scan study, a large batch).  `make test-fast` leaves them out (``-m "not slow"``); `make test` runs
    every test."""
    config.addinivalue_line("markers", "slow: takes seconds (a whole calibration, a global search, a benchmark "
                                       "run, a real-scan study, a large batch); left out by `make test-fast`")


@pytest.fixture(scope="session", autouse=True)
def _own_cache_folder(tmp_path_factory):
    """The model cache of every run in the tests (in process and in subprocesses) in a folder of the
    session's own: the tests never read or fill the user's cache."""
    before = os.environ.get("XDG_CACHE_HOME")
    os.environ["XDG_CACHE_HOME"] = str(tmp_path_factory.mktemp("xdg-cache"))
    yield
    if before is None:
        os.environ.pop("XDG_CACHE_HOME", None)
    else:
        os.environ["XDG_CACHE_HOME"] = before


@pytest.fixture
def output_dir(request) -> Path:
    """A folder for this test's artefacts (screenshots, reports) that survives the run."""
    folder = OUTPUT / re.sub(r"[^\w.-]+", "_", request.node.nodeid)
    folder.mkdir(parents=True, exist_ok=True)
    return folder


@pytest.fixture
def bunny() -> Path:
    if not (BUNNY / "bun_zipper.ply").exists():
        pytest.skip(f"Stanford bunny data not found at {BUNNY}")
    return BUNNY
