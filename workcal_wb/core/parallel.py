"""Many independent calibrations at once: one after the other, on every core, or on a Dask cluster.

A study or a batch is a list of tasks, each a module-level function and plain (picklable) arguments
that seeds its own randomness, so where it runs cannot change its result: ``Runner(workers=1)`` runs
them here, ``Runner()`` in a process pool with one worker per core, ``Runner(scheduler=ADDRESS)`` on
the Dask cluster whose scheduler listens there (Debian's python3-distributed; its workers must be
able to import workcal_wb).  ``map`` gives the results in the tasks' order, each as soon as it and
those before it are done, so progress can be reported while the rest run.
"""
from __future__ import annotations

import multiprocessing
import os
import sys

from .errors import InputError

CONNECT_TIMEOUT_S = 10  # how long a scheduler that does not answer is waited for


def cores() -> int:
    """The cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


class Runner:
    """Where tasks run: ``workers`` processes here (None: every core, 1: this process), or the Dask
    cluster at ``scheduler`` (then ``workers`` is the cluster's business)."""

    def __init__(self, workers: int | None = None, scheduler: str | None = None):
        if workers is not None and workers < 1:
            raise InputError(f"workers must be at least 1, got {workers}")
        self.workers = cores() if workers is None else int(workers)
        self.scheduler = scheduler

    def describe(self) -> str:
        if self.scheduler:
            return f"on the Dask cluster at {self.scheduler}"
        return "in this process" if self.workers == 1 else f"in {self.workers} worker processes"

    def map(self, fn, tasks):
        """``fn(*task)`` for every task (a tuple of arguments), results in the tasks' order."""
        tasks = [tuple(task) for task in tasks]
        if self.scheduler:
            yield from _on_dask(self.scheduler, fn, tasks)
        elif self.workers == 1 or len(tasks) <= 1:
            for task in tasks:
                yield fn(*task)
        else:
            yield from _in_pool(min(self.workers, len(tasks)), fn, tasks)


def _in_pool(workers: int, fn, tasks):
    from concurrent.futures import ProcessPoolExecutor

    # fork where there is one: the workers start at once with what this process imported and built
    # (and need no Python executable: inside FreeCAD sys.executable is FreeCAD itself).
    method = "fork" if sys.platform.startswith("linux") else "spawn"
    with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context(method)) as pool:
        futures = [pool.submit(fn, *task) for task in tasks]
        try:
            for future in futures:
                yield future.result()
        finally:
            for future in futures:  # an error or an interrupt: nothing more is started
                future.cancel()


def _on_dask(address: str, fn, tasks):
    try:
        from distributed import Client
    except ImportError:
        raise InputError("--scheduler needs Dask's distributed package (Debian: apt-get install "
                         "python3-distributed)") from None
    try:
        client = Client(address, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
    except (OSError, ValueError, TimeoutError) as exc:
        raise InputError(f"cannot reach the Dask scheduler at {address} ({exc})") from None
    with client:
        futures = client.map(fn, *zip(*tasks), pure=False) if tasks else []
        try:
            for future in futures:
                yield future.result()
        finally:
            client.cancel(futures)
