"""ABB configuration data (confdata) of joint vectors.

cf1, cf4, cf6 = floor(angle / 90 deg) of axes 1, 4, 6.
cfx = 4 * (wrist centre behind axis 1: on the negative side of the plane
           through axis 1 that turns with J1)
    + 2 * (wrist centre behind the lower arm; on the IRB 140, J3 < -90 deg)
    + 1 * (J5 < 0).
"""

from __future__ import annotations

import numpy as np

from .frames import DEG


def quadrant(angle_deg) -> np.ndarray:
    return np.floor(np.asarray(angle_deg, float) / 90.0).astype(int)


def quadrant_miss(angle_deg, cf) -> np.ndarray:
    """How far (deg) an angle lies outside quadrant cf, [90 cf, 90 cf + 90]
    (0 inside)."""
    lo = 90.0 * np.asarray(cf, float)
    a = np.asarray(angle_deg, float)
    return np.maximum(0.0, np.maximum(lo - a, a - (lo + 90.0)))


def wrap_pi(a) -> np.ndarray:
    """Angles wrapped into (-pi, pi]."""
    a = np.asarray(a, float)
    return np.pi - np.mod(np.pi - a, 2 * np.pi)


def cfx_bits(q_rad: np.ndarray, wrist: np.ndarray, elbow_phi: float) -> np.ndarray:
    """cfx of joint vectors (N, 6) rad with wrist centres (N, 3) mm.

    elbow_phi: the J3 angle (rad) at which the forearm is stretched along the
    lower arm (-90 deg on the IRB 140), from the arm geometry (analytic.py).
    """
    q = np.atleast_2d(q_rad)
    x1 = np.stack([np.cos(q[:, 0]), np.sin(q[:, 0])], axis=1)
    behind_axis1 = np.einsum("ij,ij->i", x1, wrist[:, :2]) < 0
    behind_lower_arm = wrap_pi(q[:, 2] - elbow_phi) < 0
    wrist_flip = q[:, 4] < 0
    return 4 * behind_axis1 + 2 * behind_lower_arm + 1 * wrist_flip


def confdata(q_rad: np.ndarray, wrist: np.ndarray, elbow_phi: float) -> np.ndarray:
    """(N, 4) int: cf1, cf4, cf6, cfx."""
    q = np.atleast_2d(q_rad)
    qd = q / DEG
    return np.stack([quadrant(qd[:, 0]), quadrant(qd[:, 3]), quadrant(qd[:, 5]),
                     cfx_bits(q, wrist, elbow_phi)], axis=1)
