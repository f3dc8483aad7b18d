"""RANSAC's stop rules, counted in rounds (one batch of hypotheses solved per round), not timed."""
import inspect

import numpy as np
import pytest

from workcal_wb.core import frames, global_search


def _correspondences(inliers: int, total: int, seed: int):
    """``total`` putative pairs of oriented points, ``inliers`` of them true under a known pose, the rest
    drawn at random in the same box, and the pose."""
    rng = np.random.default_rng(seed)
    T = frames.rigid(frames.from_rotvec([0.3, -0.5, 0.8])[:3, :3], [40.0, -25.0, 10.0])
    src = rng.uniform(0, 200, (total, 3))
    normals = rng.normal(size=(total, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    dst, dst_normals = frames.apply(T, src), normals @ T[:3, :3].T
    wrong = rng.permutation(total)[inliers:]
    dst[wrong] = rng.uniform(0, 200, (len(wrong), 3))
    dst_normals[wrong] = normals[rng.permutation(wrong)]
    return src, dst, normals, dst_normals, T


def _search(inliers: int, total: int, monkeypatch, seed: int = 0):
    """(best pose's error in mm at the points' centre, rounds run)."""
    src, dst, normals, dst_normals, T = _correspondences(inliers, total, seed)
    solved = []
    batch = global_search.kabsch_batch
    monkeypatch.setattr(global_search, "kabsch_batch", lambda *a: solved.append(1) or batch(*a))
    poses, _ = global_search.ransac_poses(src, dst, normals, dst_normals, 2.0, np.random.default_rng(seed),
                                          min_edge=6.0)
    centre = src.mean(axis=0)
    return float(np.linalg.norm(frames.apply(poses[0], centre[None]) - frames.apply(T, centre[None]))), len(solved)


def test_a_pose_drawn_often_enough_stops_the_search_early(monkeypatch):
    """5 % of the votes (under the 10 % of a clean view) but drawn many times in the first round:
    the rounds after it would only add copies."""
    error, rounds = _search(100, 2000, monkeypatch)
    assert error < 0.5 and rounds == 1


@pytest.mark.parametrize("seed", [0, 1])
def test_a_pose_drawn_rarely_is_searched_for_with_the_whole_budget(monkeypatch, seed):
    """1.5 % of the votes: drawn a few times a round, never enough to stop; the whole budget finds it."""
    error, rounds = _search(30, 2000, monkeypatch, seed)
    assert error < 0.5 and rounds == inspect.signature(global_search.ransac_poses).parameters["rounds"].default
