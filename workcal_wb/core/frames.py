"""Rigid frames as 4x4 homogeneous matrices, with the paper's Z-Y-Z Euler angles and Omega.

Conventions (the paper's, section 2): a frame ^B A is a 4x4 matrix whose columns hold A's axes and origin
in B, so ^B p = ^B A @ ^A p.  Points are rows of an (N, 3) array here, hence ``apply(T, p)``.
Angles are degrees at every public boundary; lengths are millimetres.
"""
from __future__ import annotations

import numpy as np

# Below this sin(theta) the Z-Y-Z decomposition is gimbal-locked: only phi + psi (theta = 0)
# or phi - psi (theta = 180) is defined, and we put all of it into psi.
_GIMBAL_EPS = 1e-9


def rigid(rotation=None, translation=None) -> np.ndarray:
    """4x4 transform from a 3x3 rotation and a translation (either may be omitted)."""
    T = np.eye(4)
    if rotation is not None:
        T[:3, :3] = rotation
    if translation is not None:
        T[:3, 3] = translation
    return T


def as_transform(matrix, name: str = "transform") -> np.ndarray:
    """Validate a 4x4 rigid transform (finite, orthonormal, det +1); return it as float64."""
    T = np.asarray(matrix, dtype=float)
    if T.shape != (4, 4):
        raise ValueError(f"{name}: expected a 4x4 matrix, got shape {T.shape}")
    if not np.all(np.isfinite(T)):
        raise ValueError(f"{name}: matrix contains NaN or inf")
    if not np.allclose(T[3], [0, 0, 0, 1], atol=1e-9):
        raise ValueError(f"{name}: last row must be 0 0 0 1, got {T[3].tolist()}")
    R = T[:3, :3]
    # Entries of a rotation lie in [-1, 1]; checked first so that a huge one cannot overflow the product.
    if np.abs(R).max() > 1 + 1e-6 or not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
        raise ValueError(f"{name}: upper-left 3x3 is not a rotation (orthonormal, det +1)")
    return T


def invert(T: np.ndarray) -> np.ndarray:
    """Inverse of a rigid transform, exact (transpose of the rotation)."""
    R = T[:3, :3]
    return rigid(R.T, -R.T @ T[:3, 3])


def compose(*transforms: np.ndarray) -> np.ndarray:
    """Product left to right: compose(A, B, C) = A @ B @ C (C acts first)."""
    out = np.eye(4)
    for T in transforms:
        out = out @ T
    return out


def apply(T: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Transform (N, 3) points."""
    return points @ T[:3, :3].T + T[:3, 3]


def apply_vectors(T: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """Rotate (N, 3) direction vectors (no translation)."""
    return vectors @ T[:3, :3].T


def rot_x(angle_deg: float) -> np.ndarray:
    c, s = np.cos(np.radians(angle_deg)), np.sin(np.radians(angle_deg))
    return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(angle_deg: float) -> np.ndarray:
    c, s = np.cos(np.radians(angle_deg)), np.sin(np.radians(angle_deg))
    return np.array([[c, 0, s], [0, 1.0, 0], [-s, 0, c]])


def rot_z(angle_deg: float) -> np.ndarray:
    c, s = np.cos(np.radians(angle_deg)), np.sin(np.radians(angle_deg))
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


def from_euler_zyz(phi: float, theta: float, psi: float, translation=(0.0, 0.0, 0.0)) -> np.ndarray:
    """T(x, y, z) Rz(phi) Ry(theta) Rz(psi), the paper's parameterisation (degrees, mm)."""
    return rigid(rot_z(phi) @ rot_y(theta) @ rot_z(psi), translation)


def euler_zyz(T: np.ndarray) -> tuple[float, float, float]:
    """(phi, theta, psi) in degrees, by the paper's formulas; theta in [0, 180].

    At theta = 0 or 180 the formulas give atan2(0, 0): there phi is set to 0 and the whole
    rotation about z goes into psi, so the angles still rebuild the matrix exactly.
    """
    R = np.asarray(T)[:3, :3]
    sin_theta = np.hypot(R[2, 0], R[2, 1])
    theta = np.arctan2(sin_theta, R[2, 2])
    if sin_theta > _GIMBAL_EPS:
        phi = np.arctan2(R[1, 2], R[0, 2])
        psi = np.arctan2(R[2, 1], -R[2, 0])
    elif R[2, 2] > 0:  # theta = 0: R = Rz(phi + psi)
        phi, psi = 0.0, np.arctan2(R[1, 0], R[0, 0])
    else:  # theta = 180: R = Rz(phi) Ry(180) Rz(psi) = [[-c, s, 0], [s, c, 0], [0, 0, -1]] for phi = 0
        phi, psi = 0.0, np.arctan2(R[1, 0], R[1, 1])
    return tuple(float(np.degrees(a)) for a in (phi, theta, psi))


def omega(T: np.ndarray) -> float:
    """Principal-axis rotation angle in degrees: acos((trace(R) - 1) / 2), in [0, 180]."""
    R = np.asarray(T)[:3, :3]
    return float(np.degrees(np.arccos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0))))


def rotation_axis(T: np.ndarray) -> np.ndarray:
    """Unit principal axis of the rotation (any unit vector when Omega = 0)."""
    from scipy.spatial.transform import Rotation

    rotvec = Rotation.from_matrix(np.asarray(T)[:3, :3]).as_rotvec()
    n = np.linalg.norm(rotvec)
    return rotvec / n if n > 0 else np.array([0.0, 0.0, 1.0])


def rotation_between_deg(A: np.ndarray, B: np.ndarray) -> float:
    """Angle of the rotation that takes A's orientation to B's (Omega of A^-1 B), degrees."""
    return omega(invert(A) @ B)


def quaternion_wxyz(T: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of the rotation, with w >= 0."""
    from scipy.spatial.transform import Rotation

    x, y, z, w = Rotation.from_matrix(np.asarray(T)[:3, :3]).as_quat()
    q = np.array([w, x, y, z])
    return -q if w < 0 else q


def from_quaternion_wxyz(q, translation=(0.0, 0.0, 0.0)) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    w, x, y, z = q
    return rigid(Rotation.from_quat([x, y, z, w]).as_matrix(), translation)


def from_rotvec(rotvec_rad, translation=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Transform from an axis-angle vector (radians) and a translation."""
    from scipy.spatial.transform import Rotation

    return rigid(Rotation.from_rotvec(rotvec_rad).as_matrix(), translation)


def random_motion(rng: np.random.Generator, shift_mm: float = 200.0) -> np.ndarray:
    """A random rigid motion drawn from ``rng``: a uniformly random rotation and a shift of up to
    ``shift_mm`` along each axis (the start a benchmark case or a simulated scan is moved by)."""
    from scipy.spatial.transform import Rotation

    return rigid(Rotation.random(random_state=int(rng.integers(2**31))).as_matrix(),
                 rng.uniform(-shift_mm, shift_mm, 3))


def nearest_rotation(M: np.ndarray) -> np.ndarray:
    """Closest proper rotation to a 3x3 matrix (SVD projection)."""
    U, _, Vt = np.linalg.svd(M)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
    return U @ D @ Vt


def describe(T: np.ndarray) -> dict:
    """JSON-ready description: matrix (row-major), Z-Y-Z Euler, Omega, translation, quaternion."""
    phi, theta, psi = euler_zyz(T)
    return {
        "matrix": np.asarray(T).tolist(),
        "euler_zyz_deg": [phi, theta, psi],
        "omega_deg": omega(T),
        "translation_mm": np.asarray(T)[:3, 3].tolist(),
        "quaternion_wxyz": quaternion_wxyz(T).tolist(),
    }
