"""Frames, Z-Y-Z Euler angles and Omega, checked against the paper's Table 1."""
import itertools

import numpy as np
import pytest

from workcal_wb.core import frames

# Table 1 of the paper: (phi, theta, psi, Omega) in degrees, calibrating object A2 from two scanner positions.
TABLE_1 = {
    "U1": (-144.48, 32.82, 134.41, 34.29),
    "U2": (-168.18, 44.28, 155.37, 46.00),
    "V1": (132.61, 43.36, 162.84, 76.44),
    "V2": (131.59, 57.89, 152.26, 92.92),
    "W1": (110.25, 48.93, -151.66, 63.29),
    "W2": (109.20, 47.61, -152.61, 63.55),
}


def table_matrix(name):
    return frames.from_euler_zyz(*TABLE_1[name][:3])


@pytest.mark.parametrize("name", ["U1", "U2", "V1", "V2", "W2"])
def test_table1_omega_from_euler_angles(name):
    assert frames.omega(table_matrix(name)) == pytest.approx(TABLE_1[name][3], abs=0.02)


def test_table1_w1_omega_is_inconsistent_in_the_paper():
    """W1's printed Omega (63.29) cannot come from its printed Euler angles: any angles that round to
    them give Omega in [63.256, 63.276].  We reproduce it to 0.025 deg and pin the inconsistency."""
    phi, theta, psi, printed = TABLE_1["W1"]
    omegas = [frames.omega(frames.from_euler_zyz(phi + a, theta + b, psi + c))
              for a, b, c in itertools.product((-0.005, 0.005), repeat=3)]
    assert max(omegas) < printed - 0.01
    assert frames.omega(table_matrix("W1")) == pytest.approx(printed, abs=0.025)


@pytest.mark.parametrize("i", ["1", "2"])
def test_table1_w_is_u_inverse_v_not_equation_1(i):
    """The table's W is U^-1 V = ^X B; equation (1) W = V^-1 U = ^B X is its inverse (what a robot needs)."""
    U, V, W_table = table_matrix("U" + i), table_matrix("V" + i), table_matrix("W" + i)
    # Inputs are rounded to 0.01 deg, which propagates to ~0.01 deg (measured 0.011 and 0.007).
    assert frames.rotation_between_deg(W_table, frames.invert(U) @ V) < 0.015
    assert frames.rotation_between_deg(frames.invert(W_table), frames.invert(V) @ U) < 0.015
    # Equation (1) taken literally is far from the printed W: the two are inverses of each other.
    assert frames.rotation_between_deg(W_table, frames.invert(V) @ U) > 100
    assert frames.omega(frames.invert(V) @ U) == pytest.approx(frames.omega(frames.invert(U) @ V), abs=1e-9)


def test_euler_round_trip_random():
    rng = np.random.default_rng(1)
    for _ in range(500):
        phi, psi = rng.uniform(-180, 180, 2)
        theta = rng.uniform(0, 180)
        T = frames.from_euler_zyz(phi, theta, psi, rng.normal(size=3) * 100)
        assert np.allclose(frames.from_euler_zyz(*frames.euler_zyz(T), T[:3, 3]), T, atol=1e-9)
        assert np.allclose(frames.euler_zyz(T), (phi, theta, psi), atol=1e-6)


def test_paper_formulas_for_euler_angles():
    T = frames.from_euler_zyz(30, 40, 50)
    w = T  # the paper's w_ij is T[i-1, j-1]
    assert frames.euler_zyz(T) == pytest.approx((
        np.degrees(np.arctan2(w[1, 2], w[0, 2])),
        np.degrees(np.arctan2(np.hypot(w[2, 0], w[2, 1]), w[2, 2])),
        np.degrees(np.arctan2(w[2, 1], -w[2, 0])),
    ))


@pytest.mark.parametrize("theta", [0.0, 180.0, 1e-12, 180 - 1e-12])
@pytest.mark.parametrize("phi,psi", [(0, 0), (30, 20), (-170, 100), (90, -45)])
def test_gimbal_lock_gives_no_nan_and_rebuilds_matrix(theta, phi, psi):
    T = frames.from_euler_zyz(phi, theta, psi)
    angles = frames.euler_zyz(T)
    assert np.all(np.isfinite(angles))
    assert np.allclose(frames.from_euler_zyz(*angles), T, atol=1e-9)
    assert angles[1] == pytest.approx(theta, abs=1e-6)


def test_omega_range_and_clipping():
    assert frames.omega(np.eye(4)) == 0.0
    assert frames.omega(frames.rigid(frames.rot_x(180))) == pytest.approx(180.0)
    # A rotation with rounding noise pushing the trace above 3 must not give NaN.
    assert frames.omega(np.eye(4) * (1 + 1e-15)) == 0.0
    assert frames.omega(frames.rigid(frames.rot_z(37.5))) == pytest.approx(37.5)


def test_inverse_compose_apply():
    rng = np.random.default_rng(2)
    A = frames.from_rotvec(rng.normal(size=3), rng.normal(size=3) * 50)
    B = frames.from_rotvec(rng.normal(size=3), rng.normal(size=3) * 50)
    assert np.allclose(frames.invert(A) @ A, np.eye(4), atol=1e-12)
    assert np.allclose(frames.compose(A, B), A @ B)
    p = rng.normal(size=(10, 3))
    assert np.allclose(frames.apply(frames.compose(A, B), p), frames.apply(A, frames.apply(B, p)))
    assert np.allclose(frames.apply_vectors(A, p), p @ A[:3, :3].T)


def test_quaternion_round_trip_and_sign():
    rng = np.random.default_rng(3)
    for _ in range(100):
        T = frames.from_rotvec(rng.normal(size=3) * 2, rng.normal(size=3))
        q = frames.quaternion_wxyz(T)
        assert q[0] >= 0 and np.linalg.norm(q) == pytest.approx(1.0)
        assert np.allclose(frames.from_quaternion_wxyz(q, T[:3, 3]), T, atol=1e-12)
    assert frames.quaternion_wxyz(frames.rigid(frames.rot_z(90))) == pytest.approx(
        [np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)])


def test_as_transform_rejects_bad_matrices():
    with pytest.raises(ValueError, match="4x4"):
        frames.as_transform(np.eye(3))
    with pytest.raises(ValueError, match="NaN"):
        frames.as_transform(np.full((4, 4), np.nan))
    with pytest.raises(ValueError, match="rotation"):
        frames.as_transform(np.diag([1, 1, -1, 1.0]))
    with pytest.raises(ValueError, match="last row"):
        frames.as_transform(np.ones((4, 4)))


def test_describe_is_json_ready():
    import json

    d = frames.describe(frames.from_euler_zyz(10, 20, 30, (1, 2, 3)))
    assert json.loads(json.dumps(d))["euler_zyz_deg"] == pytest.approx([10, 20, 30])
    assert d["translation_mm"] == [1, 2, 3]
