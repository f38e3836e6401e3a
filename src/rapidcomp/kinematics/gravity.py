"""Gravity torques about the joint axes, batched.

tau_k(q) = z_k . sum over bodies b moved by joint k of (c_b - o_k) x (m_b g):
the torque gravity exerts about axis k, i.e. minus Pinocchio's generalized
gravity (tests/test_discover_model.py checks it against
pin.computeGeneralizedGravity).
Masses and centres of mass come from the Pinocchio model's inertias, plus an
optional payload on the flange. The model is in millimetres and kg, so its
torques are in kg mm^2/s^2 = 1e-6 N m; they are converted to N m here, in
one place, because N m is the unit users see (compliance in deg/(N m)).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .chain import Chain
from .robot import RobotModel

NM_PER_MODEL_TORQUE = 1e-6


@dataclass(frozen=True, slots=True)
class Payload:
    """Load on the flange: mass (kg) and centre of mass in the flange frame (mm)."""

    mass_kg: float
    com_mm: tuple[float, float, float]


NO_PAYLOAD = Payload(0.0, (0.0, 0.0, 0.0))


@dataclass(frozen=True, eq=False)
class GravityModel:
    chain: Chain
    masses: np.ndarray   # (n,) kg, the payload added to the last body
    levers: np.ndarray   # (n, 3) centre of mass in each joint's frame, mm
    gravity: np.ndarray  # (3,) mm/s^2 in base axes

    @classmethod
    def from_robot(cls, robot: RobotModel, payload: Payload = NO_PAYLOAD) -> "GravityModel":
        model = robot.model
        masses = np.array([model.inertias[j].mass for j in range(1, model.njoints)], float)
        levers = np.array([np.array(model.inertias[j].lever) for j in range(1, model.njoints)])
        if payload.mass_kg > 0:
            flange = model.frames[robot.flange_frame].placement
            com = np.array(flange.act(np.asarray(payload.com_mm, float)))
            m0 = masses[-1]
            total = m0 + payload.mass_kg
            levers[-1] = (levers[-1] * m0 + com * payload.mass_kg) / total
            masses[-1] = total
        return cls(Chain.from_robot(robot), masses, levers,
                   np.array(model.gravity.linear, float))

    def torques_nm(self, q_rad: np.ndarray) -> np.ndarray:
        """(N, n) torque of gravity about each axis, N m, for q (N, n) rad."""
        q = np.atleast_2d(np.asarray(q_rad, float))
        Rs, ps = self.chain.joint_frames(q)
        com = ps + np.einsum("nkij,kj->nki", Rs, self.levers)          # (N, n, 3)
        force = self.masses[None, :, None] * self.gravity               # (1, n, 3)
        # Moment of every body about the base origin, then accumulated from
        # the tip: the moment about o_k of bodies k.. is M_k - o_k x F_k.
        moment = np.cumsum(np.cross(com, force)[:, ::-1], axis=1)[:, ::-1]
        weight = np.cumsum(np.broadcast_to(force, com.shape)[:, ::-1], axis=1)[:, ::-1]
        about = moment - np.cross(ps, weight)
        axes = np.einsum("nkij,kj->nki", Rs, self.chain.axes)
        return np.einsum("nki,nki->nk", axes, about) * NM_PER_MODEL_TORQUE
