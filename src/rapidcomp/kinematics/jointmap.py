"""Joint-space terms of a deformed model: what the arm does with a commanded
angle. A joint offset, a gear-ratio (scale) error and gravity compliance
cannot be expressed as a displaced frame; they act on the angle itself:

    q_actual_k = q_cmd_k * (1 + scale_k) + offset_k + compliance_k * tau_k(q_cmd)

with tau_k the torque gravity exerts about axis k at the commanded pose
(gravity.py). The IK finds the actual angles that reach a target; the
controller must be sent the commanded ones, hence `invert`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .gravity import GravityModel


@dataclass(frozen=True, eq=False)
class JointMap:
    offset_rad: np.ndarray          # (n,)
    scale: np.ndarray               # (n,)
    compliance_rad_per_nm: np.ndarray  # (n,)
    gravity: GravityModel | None    # needed only when a compliance is non-zero

    def apply(self, q_cmd: np.ndarray) -> np.ndarray:
        """Actual angles (rad) for commanded ones (N, n) rad."""
        q_cmd = np.asarray(q_cmd, float)
        q = q_cmd * (1.0 + self.scale) + self.offset_rad
        if self.gravity is not None and np.any(self.compliance_rad_per_nm):
            q = q + self.compliance_rad_per_nm * self.gravity.torques_nm(q_cmd).reshape(q.shape)
        return q

    def invert(self, q_act: np.ndarray) -> np.ndarray:
        """Commanded angles (rad) that give the actual ones (N, n) rad.

        Fixed-point iteration on the compliance term: it changes by
        c * dtau/dq ~ 1e-6 per step, so two or three steps reach round-off.
        """
        q_act = np.asarray(q_act, float)
        q = (q_act - self.offset_rad) / (1.0 + self.scale)
        if self.gravity is None or not np.any(self.compliance_rad_per_nm):
            return q
        for _ in range(20):
            tau = self.gravity.torques_nm(q).reshape(q.shape)
            nxt = (q_act - self.offset_rad - self.compliance_rad_per_nm * tau) / (1.0 + self.scale)
            step = np.max(np.abs(nxt - q)) if nxt.size else 0.0
            q = nxt
            if step < 1e-15:
                break
        return q
