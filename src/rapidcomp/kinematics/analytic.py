"""Closed-form inverse kinematics of ABB-convention arms with a spherical wrist.

Applies to arms whose zero pose has every joint frame parallel to the base,
axes +z, +y, +y, +x, +y, +x (the ABB convention, IRB 140 included), no
lateral shoulder offset, and axes 4 and 6 through the wrist centre (J5's
origin). The geometry is read from the Pinocchio model, not hard-coded.

Derivation (arm plane, J2 at (a1, c1); A = J3 - J2 and B = W - J3 at q = 0):
  |W - J2|^2 = |A|^2 + |B|^2 + 2|A||B| cos(q3 - phi),  phi = atan2(A x B, A . B)
  q3 = phi +- acos(k),   q2 = atan2(s, h) - atan2(V_x, V_z),  V = A + Ry(q3) B
  wrist: Rz(q1) Ry(q2+q3)^T R6 = Rx(q4) Ry(q5) Rx(q6)  (XYX Euler angles)
All 8 branches (shoulder front/back x elbow x wrist flip) are returned, in
(-180, 180] degrees; turns are chosen later from confdata (ik.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .chain import Chain
from .conf import cfx_bits, wrap_pi
from .frames import rot_y, rot_z, stack_times

_EXPECTED_AXES = np.array([[0, 0, 1], [0, 1, 0], [0, 1, 0], [1, 0, 0], [0, 1, 0], [1, 0, 0]], float)


class UnsupportedGeometry(ValueError):
    pass


@dataclass(frozen=True)
class ArmGeometry:
    a1: float
    c1: float
    A: np.ndarray            # J2 -> J3 at the zero pose, (x, z)
    B: np.ndarray            # J3 -> wrist centre at the zero pose, (x, z)
    flange_rot: np.ndarray   # J6 frame -> flange
    flange_trans: np.ndarray
    phi: float               # J3 angle with the forearm stretched along the lower arm

    @property
    def reach(self) -> float:
        return float(np.hypot(*self.A) + np.hypot(*self.B))

    @classmethod
    def from_chain(cls, chain: Chain) -> "ArmGeometry":
        if len(chain.axes) != 6 or not np.allclose(chain.axes, _EXPECTED_AXES):
            raise UnsupportedGeometry("closed-form IK needs joint axes +z,+y,+y,+x,+y,+x "
                                      "at the zero pose (ABB convention)")
        if not np.allclose(chain.rot, np.eye(3), atol=1e-12):
            raise UnsupportedGeometry("closed-form IK needs every joint frame parallel to "
                                      "the base at the zero pose")
        origins = np.cumsum(chain.trans, axis=0)
        if np.any(np.abs(origins[:, 1]) > 1e-9):
            raise UnsupportedGeometry("closed-form IK needs no lateral (y) offsets")
        if abs(origins[1, 0]) < 0 or np.hypot(*origins[0, :2]) > 1e-9:
            raise UnsupportedGeometry("axis 1 must pass through the base origin")
        w = origins[4]
        for k in (3, 5):  # axes 4 and 6 (along x) must pass through the wrist centre
            if abs(origins[k, 2] - w[2]) > 1e-9:
                raise UnsupportedGeometry("not a spherical wrist: axes 4 and 6 must pass "
                                          "through J5's origin")
        A = np.array([origins[2, 0] - origins[1, 0], origins[2, 2] - origins[1, 2]])
        B = np.array([w[0] - origins[2, 0], w[2] - origins[2, 2]])
        # (Lengths in mm: an arm whose lower arm or forearm is shorter than a
        # millimetre is not one; its elbow's IK would divide by zero.)
        if np.hypot(*A) < 1.0:
            raise UnsupportedGeometry("axis 3 lies on axis 2 (J2 to J3 has no length): not an "
                                      "arm")
        if np.hypot(*B) < 1.0:
            raise UnsupportedGeometry("the wrist centre lies on axis 3 (J3 to J5 has no "
                                      "length): not an arm")
        # Offset of J6's origin from the wrist centre along axis 6 is part of
        # the flange offset seen from the wrist centre.
        t6 = np.array([origins[5, 0] - w[0], 0.0, 0.0])
        phi = float(np.arctan2(A[0] * B[1] - A[1] * B[0], A @ B))
        return cls(float(origins[1, 0]), float(origins[1, 2]), A, B, chain.flange_rot,
                   chain.flange_trans + t6, phi)


@dataclass(frozen=True)
class Branches:
    """Candidate solutions of N targets on 8 branches."""

    q: np.ndarray          # (N, 8, 6) rad, NaN where unreachable
    cfx: np.ndarray        # (N, 8) int
    reach_excess: np.ndarray  # (N, 8) mm beyond the arm's annulus (0 when reachable)
    wrist: np.ndarray      # (N, 3) wrist centres


def wrist_centre(geom: ArmGeometry, R: np.ndarray, p: np.ndarray) -> np.ndarray:
    R6 = stack_times(R, geom.flange_rot.T)
    return p - stack_times(R6, geom.flange_trans)


def solve_branches(geom: ArmGeometry, R: np.ndarray, p: np.ndarray,
                   singular_eps: float = 1e-10) -> Branches:
    """All 8 closed-form solutions for flange poses R (N,3,3), p (N,3) mm."""
    R = np.asarray(R, float).reshape(-1, 3, 3)
    p = np.asarray(p, float).reshape(-1, 3)
    N = len(p)
    R6 = stack_times(R, geom.flange_rot.T)
    W = p - stack_times(R6, geom.flange_trans)
    la, lb = np.hypot(*geom.A), np.hypot(*geom.B)
    rho = np.hypot(W[:, 0], W[:, 1])
    base_q1 = np.arctan2(W[:, 1], W[:, 0])
    q = np.full((N, 8, 6), np.nan)
    excess = np.zeros((N, 8))
    b = 0
    for back in (False, True):
        q1 = wrap_pi(base_q1 + np.pi) if back else base_q1
        s = (-rho if back else rho) - geom.a1
        h = W[:, 2] - geom.c1
        D = np.hypot(s, h)
        k = (D * D - la * la - lb * lb) / (2 * la * lb)
        over = np.maximum(D - (la + lb), abs(la - lb) - D)
        reachable = np.abs(k) <= 1 + 1e-12
        acos = np.arccos(np.clip(k, -1.0, 1.0))
        for elbow in (1.0, -1.0):
            q3 = wrap_pi(geom.phi + elbow * acos)
            Vx = geom.A[0] + geom.B[0] * np.cos(q3) + geom.B[1] * np.sin(q3)
            Vz = geom.A[1] - geom.B[0] * np.sin(q3) + geom.B[1] * np.cos(q3)
            q2 = wrap_pi(np.arctan2(s, h) - np.arctan2(Vx, Vz))
            R03 = rot_z(q1) @ rot_y(q2 + q3)
            M = np.swapaxes(R03, 1, 2) @ R6
            sb = np.hypot(M[:, 1, 0], M[:, 2, 0])
            q5 = np.arctan2(sb, M[:, 0, 0])
            singular = sb < singular_eps
            # Regular case: XYX Euler angles. At q5 = 0 only q4 + q6 is
            # defined; q4 = 0 is taken and the wrist flagged singular (ik.py).
            q4 = np.where(singular, 0.0, np.arctan2(M[:, 1, 0], -M[:, 2, 0]))
            q6 = np.where(singular, np.arctan2(M[:, 2, 1], M[:, 1, 1]),
                          np.arctan2(M[:, 0, 1], M[:, 0, 2]))
            for flip in (False, True):
                if flip:
                    sol = np.stack([q1, q2, q3, wrap_pi(q4 + np.pi), -q5,
                                    wrap_pi(q6 + np.pi)], axis=1)
                else:
                    sol = np.stack([q1, q2, q3, q4, q5, q6], axis=1)
                sol[~reachable] = np.nan
                q[:, b] = sol
                excess[:, b] = np.where(reachable, 0.0, np.maximum(over, 0.0))
                b += 1
    cfx = np.zeros((N, 8), dtype=int)
    for i in range(8):
        cfx[:, i] = cfx_bits(np.nan_to_num(q[:, i]), W, geom.phi)
    return Branches(q, cfx, excess, W)
