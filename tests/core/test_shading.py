"""The brightness a scan is drawn with: surfaces square to the light bright, oblique ones darker, the same
with or without open3d; and the unit a cloud's size says it was written in."""
import sys

import numpy as np
import pytest

from workcal_wb.core.pointops import OPEN3D_NORMALS_FROM, SHADING_AMBIENT, shading
from workcal_wb.core.units import likely_unit, unit_warning


def two_planes(count=OPEN3D_NORMALS_FROM + 5000, seed=0):
    """A plane square to a light at the origin (z = 1000) beside one tilted 60 degrees, interleaved."""
    rng = np.random.default_rng(seed)
    square = np.column_stack([rng.uniform(-100, 0, count // 2), rng.uniform(-50, 50, count // 2),
                              np.full(count // 2, 1000.0)])
    x = rng.uniform(0, 100, count // 2)
    tilted = np.column_stack([x + 200, rng.uniform(-50, 50, count // 2), 1000.0 + np.tan(np.radians(60)) * x])
    return square, tilted


def test_a_surface_square_to_the_light_is_brighter_than_a_tilted_one():
    square, tilted = two_planes()
    values = shading(np.vstack([square, tilted]), (0.0, 0.0, 0.0))
    lit, oblique = values[:len(square)], values[len(square):]
    assert np.median(lit) > 0.95 and np.median(oblique) < 0.75
    assert values.min() >= SHADING_AMBIENT - 1e-9 and values.max() <= 1.0 + 1e-9


def test_shading_without_open3d_is_the_same(monkeypatch):
    square, tilted = two_planes()
    points = np.vstack([square, tilted])
    with_open3d = shading(points, (0.0, 0.0, 0.0))
    monkeypatch.setitem(sys.modules, "open3d", None)  # as if it were not installed
    np.testing.assert_allclose(shading(points, (0.0, 0.0, 0.0)), with_open3d, atol=1e-3)


@pytest.mark.parametrize("size_mm, read_as, expected", [(0.55, "mm", "m"), (5.5, "cm", None), (550.0, "mm", None),
                                                        (5.4e5, "mm", "um"), (0.2, "in", "m")])
def test_the_unit_a_size_says_a_file_is_in(size_mm, read_as, expected):
    assert likely_unit(size_mm, read_as) == expected


def test_the_unit_warning_names_the_file_and_the_unit_to_read_it_in():
    points = np.random.default_rng(1).uniform(0.0, 0.32, size=(1000, 3))
    text, suggestion = unit_warning(points, "box.xyz", "mm")
    assert text.startswith("box.xyz: only 0.5") and "read it with unit m" in text and suggestion == "m"
    assert unit_warning(points * 1000.0, "box.xyz", "mm") == ("", None)
