"""regions._clusters: a cloud searched in two halves on two threads (its linked pairs across the
cut found among the points near it) falls apart exactly as the same cloud searched whole."""
import numpy as np

from workcal_wb.core import regions


def test_a_cloud_split_in_two_falls_apart_as_one_searched_whole(monkeypatch):
    # Random points near the density where links start to span the box: thousands of clusters of
    # every size, dozens of them across the cut (the median of x, the longest extent).
    rng = np.random.default_rng(0)
    points = rng.uniform(0, 1, (30000, 3)) * [60.0, 35.0, 30.0]
    monkeypatch.setattr(regions, "SPLIT_POINTS", 10**9)
    whole = regions._clusters(points, 1.0)
    monkeypatch.setattr(regions, "SPLIT_POINTS", 1000)
    halves = regions._clusters(points, 1.0)
    assert np.array_equal(halves, whole)
    low = points[:, 0] < np.median(points[:, 0])
    across = np.intersect1d(whole[low], whole[~low])
    assert len(np.unique(whole)) > 1000 and len(across) > 50
