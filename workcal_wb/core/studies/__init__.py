"""The paper's experiments on simulated scenes with exact truth, one module per study.

repeatability (Fig. 7), placement (Table 1, Fig. 9, and the honesty of the predicted bound),
point_count (accuracy against cloud size) and object_size (figurine against car).  Each ``run``
returns a StudyResult (flat rows, summary, checked targets) and, given an out dir, writes
<name>.png, <name>.csv and <name>.json there.  ``quick`` settings keep a study to seconds for tests.
See docs/studies.md for the measured numbers.
"""
from __future__ import annotations

from . import object_size, placement, point_count, repeatability
from .common import StudyResult, StudySettings, summary_lines

STUDIES = {
    repeatability.NAME: repeatability,
    placement.NAME: placement,
    point_count.NAME: point_count,
    object_size.NAME: object_size,
}

__all__ = ["STUDIES", "StudyResult", "StudySettings", "summary_lines", "run_study"]


def run_study(name: str, out_dir=None, *, settings: StudySettings = StudySettings(), n=None, positions=None,
              arc_deg=None, progress=None, runner=None) -> StudyResult:
    """Run one study by name; ``n``, ``positions`` and ``arc_deg`` go to the studies that take them,
    ``runner`` (parallel.Runner) says where its calibrations run (default: here, one after the other)."""
    from ..errors import InputError

    if name not in STUDIES:
        raise InputError(f"unknown study {name!r}; choose one of {', '.join(STUDIES)}")
    kwargs = {}
    if name in (repeatability.NAME, point_count.NAME):
        kwargs["n"] = n
    if name in (placement.NAME, object_size.NAME):
        kwargs["positions"] = positions
    if name == placement.NAME and arc_deg is not None:
        kwargs["arc_deg"] = arc_deg
    return STUDIES[name].run(out_dir, settings=settings, progress=progress, runner=runner, **kwargs)
