"""Units and rotations, in one place.

User-facing units are millimetres and degrees (RAPID's). The kinematic model
is built in millimetres, so lengths never need converting; angles are
converted here and nowhere else. Quaternions at the edges are RAPID order
(w, x, y, z); Pinocchio's own order is (x, y, z, w) and is only used via
SE3/rotation matrices, never as raw coefficient arrays.

All functions accept a single value or a batch (leading axes).
"""

from __future__ import annotations

import numpy as np

DEG = np.pi / 180.0
# URDF and controller configuration files are in metres.
MM_PER_M = 1000.0


def _quat_matrix_rows(w, x, y, z):
    """Rows of the rotation matrix of a unit quaternion (scalars or arrays)."""
    return ((1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
            (2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
            (2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)))


def unit_wxyz(w: float, x: float, y: float, z: float) -> tuple[float, float, float, float]:
    """One quaternion normalised in plain float arithmetic (the resolver's
    case, 1e5 times per program: ~10x faster than numpy on 4 numbers).
    Every one-quaternion path normalises here, so a batch built from these
    is bit for bit what one quaternion gets."""
    n = (w * w + x * x + y * y + z * z) ** 0.5
    return w / n, x / n, y / n, z / n


def row_dots(a) -> np.ndarray:
    """row.dot(row) of each row of a (n, k) made C-contiguous (as the rows
    of the arrays the callers built are), bit for bit: numpy computes one
    contiguous row's dot product by BLAS (with its own order and fused
    multiply-adds; a strided row may sum otherwise), and a stack of
    (1, k) @ (k, 1) products by the same call per row (tested against the
    rows one by one), without a Python step per row."""
    a = np.ascontiguousarray(a, dtype=float)
    return np.matmul(a[:, None, :], a[:, :, None])[:, 0, 0]


def stack_times(A: np.ndarray, M: np.ndarray) -> np.ndarray:
    """A @ M for a stack of 3x3 matrices A (..., 3, 3) and one matrix
    (3, k) or vector (3,) M, bit for bit: numpy multiplies a stack matrix
    by matrix, one BLAS call each (~30 ns; 8192 in a chunk of the IK); the
    rows of a C-contiguous stack are one (n, 3) matrix, and one call on it
    computes each row as the call per matrix does (tested against A @ M)."""
    A = np.asarray(A)
    if (A.ndim < 3 or A.shape[-2:] != (3, 3) or not A.flags.c_contiguous
            or A.dtype != np.float64):
        return A @ M
    return (A.reshape(-1, 3) @ M).reshape(A.shape[:-1] + np.shape(M)[1:])


def quat_wxyz_to_matrix(q) -> np.ndarray:
    """Rotation matrix of a (possibly unnormalised) RAPID quaternion w,x,y,z."""
    q = np.asarray(q, dtype=float)
    if q.shape == (4,):
        return np.array(_quat_matrix_rows(*unit_wxyz(*q.tolist())))
    return unit_quat_matrices(q / np.linalg.norm(q, axis=-1, keepdims=True))


def unit_quat_matrices(q) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of unit quaternions (..., 4) w, x, y,
    z, taken as given (the caller normalised them)."""
    q = np.asarray(q, dtype=float)
    rows = _quat_matrix_rows(*np.moveaxis(q, -1, 0))
    return np.stack([np.stack(row, axis=-1) for row in rows], axis=-2)


def matrix_to_quat_wxyz(R) -> np.ndarray:
    """Unit quaternion (w, x, y, z) with w >= 0 of a rotation matrix."""
    R = np.asarray(R, dtype=float)
    shape = R.shape[:-2]
    R = R.reshape(-1, 3, 3)
    q = np.empty((R.shape[0], 4))
    tr = R[:, 0, 0] + R[:, 1, 1] + R[:, 2, 2]
    # Shepperd's method: pick the largest of w, x, y, z for stability.
    cand = np.stack([tr, R[:, 0, 0], R[:, 1, 1], R[:, 2, 2]], axis=1)
    k = np.argmax(cand, axis=1)
    for idx in range(4):
        m = k == idx
        if not m.any():
            continue
        r = R[m]
        if idx == 0:
            s = np.sqrt(1.0 + tr[m]) * 2
            q[m] = np.stack([0.25 * s, (r[:, 2, 1] - r[:, 1, 2]) / s,
                             (r[:, 0, 2] - r[:, 2, 0]) / s, (r[:, 1, 0] - r[:, 0, 1]) / s], 1)
        elif idx == 1:
            s = np.sqrt(1.0 + r[:, 0, 0] - r[:, 1, 1] - r[:, 2, 2]) * 2
            q[m] = np.stack([(r[:, 2, 1] - r[:, 1, 2]) / s, 0.25 * s,
                             (r[:, 0, 1] + r[:, 1, 0]) / s, (r[:, 0, 2] + r[:, 2, 0]) / s], 1)
        elif idx == 2:
            s = np.sqrt(1.0 + r[:, 1, 1] - r[:, 0, 0] - r[:, 2, 2]) * 2
            q[m] = np.stack([(r[:, 0, 2] - r[:, 2, 0]) / s, (r[:, 0, 1] + r[:, 1, 0]) / s,
                             0.25 * s, (r[:, 1, 2] + r[:, 2, 1]) / s], 1)
        else:
            s = np.sqrt(1.0 + r[:, 2, 2] - r[:, 0, 0] - r[:, 1, 1]) * 2
            q[m] = np.stack([(r[:, 1, 0] - r[:, 0, 1]) / s, (r[:, 0, 2] + r[:, 2, 0]) / s,
                             (r[:, 1, 2] + r[:, 2, 1]) / s, 0.25 * s], 1)
    q[q[:, 0] < 0] *= -1
    return q.reshape(shape + (4,))


def _principal_rotation(a, axis: int) -> np.ndarray:
    """Rotation by angle(s) a about base axis 0 (x), 1 (y) or 2 (z)."""
    a = np.asarray(a, dtype=float)
    c, s = np.cos(a), np.sin(a)
    i, j = ((1, 2), (2, 0), (0, 1))[axis]
    out = np.zeros(a.shape + (3, 3))
    out[..., axis, axis] = 1
    out[..., i, i] = c
    out[..., i, j] = -s
    out[..., j, i] = s
    out[..., j, j] = c
    return out


def rot_x(a) -> np.ndarray:
    return _principal_rotation(a, 0)


def rot_y(a) -> np.ndarray:
    return _principal_rotation(a, 1)


def rot_z(a) -> np.ndarray:
    return _principal_rotation(a, 2)


def rot_axis(axis, a) -> np.ndarray:
    """Rotation by angle(s) a about a unit axis (Rodrigues)."""
    axis = np.asarray(axis, dtype=float)
    a = np.asarray(a, dtype=float)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    s = np.sin(a)[..., None, None]
    c = np.cos(a)[..., None, None]
    return np.eye(3) + s * K + (1 - c) * (K @ K)


def rotation_log(R) -> np.ndarray:
    """Rotation vector (axis * angle, rad) of rotation matrices; robust near 0 and pi."""
    R = np.asarray(R, dtype=float)
    tr = np.clip((R[..., 0, 0] + R[..., 1, 1] + R[..., 2, 2] - 1) / 2, -1.0, 1.0)
    angle = np.arccos(tr)
    v = np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0],
                  R[..., 1, 0] - R[..., 0, 1]], axis=-1)
    s = np.sin(angle)
    small = angle < 1e-6
    factor = np.where(small, 0.5 + angle ** 2 / 12, angle / (2 * np.where(small, 1, s)))
    out = v * factor[..., None]
    near_pi = angle > np.pi - 1e-6
    if np.any(near_pi):
        Rp = R[near_pi]
        B = (Rp + np.eye(3)) / 2
        axis = np.sqrt(np.clip(np.stack([B[:, 0, 0], B[:, 1, 1], B[:, 2, 2]], 1), 0, None))
        i = np.argmax(axis, axis=1)
        col = B[np.arange(len(i)), :, i]
        axis = col / np.linalg.norm(col, axis=1, keepdims=True)
        out[near_pi] = axis * angle[near_pi][:, None]
    return out


def rpy_matrix(rx, ry, rz) -> np.ndarray:
    """R = Rz(rz) . Ry(ry) . Rx(rx), angles in radians (profile semantics)."""
    return rot_z(rz) @ rot_y(ry) @ rot_x(rx)


def rpy_angles(R) -> tuple[float, float, float]:
    """rx, ry, rz (radians) with R = Rz(rz) . Ry(ry) . Rx(rx); the inverse of
    rpy_matrix for |ry| < 90 deg (all the small rotations a profile holds)."""
    R = np.asarray(R, dtype=float)
    ry = np.arctan2(-R[2, 0], np.hypot(R[0, 0], R[1, 0]))
    return float(np.arctan2(R[2, 1], R[2, 2])), float(ry), float(np.arctan2(R[1, 0], R[0, 0]))
