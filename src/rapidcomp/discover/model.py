"""The simulation of a measurement campaign: where the model (robot +
profile + effects at given values) puts the measuring point, with the exact
Jacobian with respect to every effect parameter.

This is a chain evaluator of its own, written from the effect definitions
in effects.py; `rapidcomp simulate` makes data with Pinocchio on the model
`effects.to_profile` builds, and tests/test_discover_model.py checks that
the two agree to 1e-9 mm and that the Jacobian matches central differences.
"""

from __future__ import annotations

import copy

from dataclasses import replace

import numpy as np

from ..kinematics.chain import Chain
from ..kinematics.frames import DEG, rot_axis, rot_x, rot_y, rot_z
from ..kinematics.gravity import GravityModel, Payload
from ..kinematics.profile import ThermalProfile, deform
from ..kinematics.robot import RobotModel
from .effects import Effect, tilt_rotation

# A Jacobian column below this (mm per internal unit: rad, mm, 1, rad/(N m))
# is round-off: the parameter does not move the measuring point (a J6
# offset with the point on the J6 axis, the compliance of a vertical axis).
ZERO_COLUMN = 1e-8


def approach_directions(q_deg: np.ndarray) -> np.ndarray:
    """(N, J): the sign of each joint's last motion before each pose, in the
    order the poses were measured (the robot moves from one to the next);
    0 where it is not known (the first pose, a joint that has not moved)."""
    q = np.asarray(q_deg, float)
    out = np.zeros_like(q)
    last = np.zeros(q.shape[1]) if q.ndim == 2 else np.zeros(0)
    for i in range(1, len(q)):
        step = np.sign(q[i] - q[i - 1])
        last = np.where(step != 0, step, last)
        out[i] = last
    return out


class ParamModel:
    """Measuring point positions (base frame, mm) for N commanded joint
    vectors; `evaluate` adds effects at internal values."""

    def __init__(self, robot: RobotModel, profile: ThermalProfile, q_deg: np.ndarray,
                 tool_mm=(0.0, 0.0, 0.0), payload: Payload | None = None,
                 approach: np.ndarray | None = None):
        if payload is not None:
            profile = replace(profile, payload=payload)
        self.robot = robot
        self.profile = profile
        deformed = deform(robot, profile)
        self.chain = Chain.from_robot(deformed)
        self.nominal = Chain.from_robot(robot)
        self.q_cmd = np.asarray(q_deg, float) * DEG
        jm = deformed.joint_map
        self.q0 = jm.apply(self.q_cmd) if jm is not None else self.q_cmd.copy()
        self.tau_nm = GravityModel.from_robot(robot, profile.payload).torques_nm(self.q_cmd)
        # The measuring point in the flange frame, per pose (several
        # reflectors: one row each).
        self.tool = np.array(np.broadcast_to(np.asarray(tool_mm, float), (len(self.q_cmd), 3)))
        self.n = len(self.chain.trans)
        # Each joint's last direction of motion before each pose (backlash).
        self.direction = (np.asarray(approach, float) if approach is not None
                          else approach_directions(q_deg))
        self.s: np.ndarray | None = None     # thermal state per pose (with_state)

    @property
    def size(self) -> int:
        return len(self.q_cmd)

    def subset(self, rows) -> "ParamModel":
        """The same model on some of its poses (rows: indices)."""
        out = copy.copy(self)
        out.q_cmd, out.q0, out.tau_nm = self.q_cmd[rows], self.q0[rows], self.tau_nm[rows]
        out.direction = self.direction[rows]
        out.tool = self.tool[rows]
        if self.s is not None:
            out.s = self.s[rows]
        return out

    def with_state(self, s: np.ndarray) -> "ParamModel":
        """The same model with each pose's thermal state (warm-up campaign):
        thermal effects act as s times their value."""
        out = copy.copy(self)
        out.s = np.asarray(s, float)
        return out

    def evaluate(self, effects: tuple[Effect, ...], values, jacobian: bool = True):
        """Positions (N, 3) and, if asked, the Jacobian (N, 3, P) with
        respect to the concatenated internal parameters of `effects`.

        A thermal effect acts as s_i times its value at pose i, to first
        order: its Jacobian columns at the static model, times s_i (thermal
        deformations are microns on a metre-sized arm: the second-order
        term is ~1e-5 mm)."""
        if not any(e.thermal for e in effects):
            return self._evaluate(effects, values, jacobian)
        if self.s is None:
            raise ValueError("thermal effects need the poses' thermal states (with_state)")
        vals = [np.asarray(v, float) for v in values]
        zeroed = [np.zeros(e.size) if e.thermal else v for e, v in zip(effects, vals)]
        X, J = self._evaluate(effects, zeroed, True)
        J = J.copy()
        col = 0
        for e, v in zip(effects, vals):
            if e.thermal:
                J[:, :, col:col + e.size] *= self.s[:, None, None]
                X = X + J[:, :, col:col + e.size] @ v
            col += e.size
        return X, (J if jacobian else None)

    def _evaluate(self, effects: tuple[Effect, ...], values, jacobian: bool = True):
        vals = [np.asarray(v, float) for v in values]
        n, N = self.n, self.size
        q = self.q0.copy()
        eps = np.zeros(n + 1)
        disp = np.zeros((n, 3))
        tilt = [np.eye(3) for _ in range(n)]
        tool = self.tool.copy()
        T_ang, T_d = np.zeros(3), np.zeros(3)
        for e, v in zip(effects, vals):
            k = e.joint
            if e.kind == "joint_offset":
                q[:, k] += v[0]
            elif e.kind == "joint_scale":
                q[:, k] += v[0] * self.q_cmd[:, k]
            elif e.kind == "gravity_compliance":
                q[:, k] += v[0] * self.tau_nm[:, k]
            elif e.kind == "backlash":
                q[:, k] += 0.5 * v[0] * self.direction[:, k]
            elif e.kind == "cyclic":
                h = e.harmonic * self.q_cmd[:, k]
                q[:, k] += v[0] * np.sin(h) + v[1] * np.cos(h)
            elif e.kind == "link_elongation":
                eps[k] += v[0]
            elif e.kind == "axis_tilt":
                tilt[k] = tilt[k] @ tilt_rotation(e, v)
            elif e.kind == "joint_displacement":
                disp[k] += e.axes @ v
            elif e.kind == "tool_offset":
                tool = tool + v
            elif e.kind == "base_frame":
                T_d, T_ang = T_d + v[:3], T_ang + v[3:]
        c = self.chain
        R = np.broadcast_to(np.eye(3), (N, 3, 3))
        p = np.zeros((N, 3))
        parent, W, origin, z = [], [], [], []
        for k in range(n):
            parent.append(R)
            p = p + R @ (c.trans[k] + eps[k] * self.nominal.trans[k] + c.rot[k] @ disp[k])
            Wk = R @ c.rot[k]
            W.append(Wk)
            Wt = Wk @ tilt[k]
            origin.append(p)
            z.append(Wt @ c.axes[k])
            R = Wt @ rot_axis(c.axes[k], q[:, k])
        last = R
        Rf = R @ c.flange_rot
        P = (p + R @ (c.flange_trans + eps[n] * self.nominal.flange_trans)
             + (Rf @ tool[..., None])[..., 0])
        Rx, Ry, Rz = rot_x(T_ang[0]), rot_y(T_ang[1]), rot_z(T_ang[2])
        TR = Rz @ Ry @ Rx
        X = P @ TR.T + T_d
        if not jacobian:
            return X, None
        # Columns in the model's base frame (rotated by T below), except
        # base_frame's own, which are the derivatives of T . P itself.
        cols = []
        for e, v in zip(effects, vals):
            k = e.joint
            if e.kind in ("joint_offset", "joint_scale", "gravity_compliance", "backlash"):
                d = np.cross(z[k], P - origin[k])
                w = {"joint_offset": 1.0, "joint_scale": self.q_cmd[:, k],
                     "gravity_compliance": self.tau_nm[:, k],
                     "backlash": 0.5 * self.direction[:, k]}[e.kind]
                block = [d * np.reshape(w, (-1, 1))]
            elif e.kind == "cyclic":
                d = np.cross(z[k], P - origin[k])
                h = e.harmonic * self.q_cmd[:, k]
                block = [d * np.sin(h)[:, None], d * np.cos(h)[:, None]]
            elif e.kind == "link_elongation":
                seg = self.nominal.trans[k] if k < n else self.nominal.flange_trans
                block = [(parent[k] if k < n else last) @ seg]
            elif e.kind == "axis_tilt":
                u1, u2 = e.axes
                w1 = W[k] @ u1
                w2 = W[k] @ (rot_axis(u1, v[0]) @ u2)
                block = [np.cross(w1, P - origin[k]), np.cross(w2, P - origin[k])]
            elif e.kind == "joint_displacement":
                block = [W[k] @ e.axes[:, j] for j in range(3)]
            elif e.kind == "tool_offset":
                block = [Rf[:, :, j] for j in range(3)]
            else:   # base_frame
                ex, ey, ez = np.eye(3)
                cols += [np.broadcast_to(ex, (N, 3)), np.broadcast_to(ey, (N, 3)),
                         np.broadcast_to(ez, (N, 3)),
                         np.cross(ex, P @ Rx.T) @ (Rz @ Ry).T,
                         np.cross(ey, P @ (Ry @ Rx).T) @ Rz.T,
                         np.cross(ez, X - T_d)]
                continue
            cols += [np.broadcast_to(d, (N, 3)) @ TR.T for d in block]
        J = np.stack(cols, axis=-1) if cols else np.empty((N, 3, 0))
        return X, J
