"""OpenBLAS's thread count is one setting for the whole process: matches that overlap in several threads
must leave it as they found it, and a caller that asks for no change gets none."""
import threading

import numpy as np
import pytest

from workcal_wb.core import pointops
from workcal_wb.core.geometry import Cloud
from workcal_wb.core.match import match


class FakeOpenBLAS:
    """Stands for the OpenBLAS library: one process-wide thread count, every call recorded."""

    def __init__(self, threads=2):
        self.threads, self.calls = threads, []

    def openblas_get_num_threads(self):
        return self.threads

    def openblas_set_num_threads(self, n):
        self.calls.append(n)
        self.threads = n


@pytest.fixture
def blas(monkeypatch):
    fake = FakeOpenBLAS()
    monkeypatch.setattr(pointops, "_openblas", lambda: fake)
    return fake


def test_overlapping_blocks_in_two_threads_restore_the_setting(blas):
    """A enters, B enters, A leaves, B leaves: the order two GUI calibrations can take.  Pinned by the
    first, the count must come back to 2 only when the last one leaves."""
    a_in, b_in, a_out = threading.Event(), threading.Event(), threading.Event()
    seen = {}

    def first():
        with pointops.blas_threads(1):
            a_in.set()
            b_in.wait(5)
            seen["a"] = blas.threads
        a_out.set()

    def second():
        a_in.wait(5)
        with pointops.blas_threads(1):
            b_in.set()
            a_out.wait(5)
            seen["b"] = blas.threads

    threads = [threading.Thread(target=first), threading.Thread(target=second)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(10)
    assert seen == {"a": 1, "b": 1}  # one thread while any match runs
    assert blas.threads == 2, "the process was left on one BLAS thread"


def test_none_leaves_the_setting_alone(blas):
    with pointops.blas_threads(None):
        assert blas.threads == 2
    assert blas.calls == []


def test_match_passes_its_thread_setting(blas):
    rng = np.random.default_rng(0)
    u, v = rng.uniform(-1, 1, (2, 3000))
    model = Cloud(np.column_stack([40 * u, 30 * v, 8 * np.sin(2 * u) * np.cos(3 * v)]), name="model")
    match(model, model, init=np.eye(4), blas_threads=None)
    assert blas.calls == []  # a worker thread inside FreeCAD leaves the process's BLAS alone
    match(model, model, init=np.eye(4))
    assert blas.calls == [1, 2] and blas.threads == 2  # headless default: one thread while matching
