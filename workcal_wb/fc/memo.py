"""The last result of a slow, deterministic computation, by key.

The GUI runs slow work (reading a scan, finding regions, calibrating) in a worker thread, then records
and runs the ``fc`` call that does the document change (``Gui.doCommand``), so that a recorded macro
replays headless.  That call computes the same thing again from the same inputs; with the worker's
result remembered here under the inputs' key it finds it instead.  One entry: memory stays bounded.
"""
from __future__ import annotations

import threading


class LastResult:
    def __init__(self):
        self._lock = threading.Lock()
        self._key = None
        self._value = None

    def get(self, key):
        """The value stored under ``key``, or None (also for a None key: nothing is remembered for it)."""
        with self._lock:
            return self._value if key is not None and key == self._key else None

    def put(self, key, value) -> None:
        if key is None:
            return
        with self._lock:
            self._key, self._value = key, value
