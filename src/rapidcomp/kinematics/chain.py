"""Batched forward kinematics and Jacobians in numpy.

Pinocchio builds the model; this kernel reads the serial chain out of it
(joint placements, joint axes, flange placement) and evaluates N
configurations at once. tests/test_kinematics.py checks it against
Pinocchio to 1e-12 mm.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .frames import rot_axis, rotation_log, stack_times
from .robot import RobotModel

_AXES = {"JointModelRX": (1.0, 0.0, 0.0), "JointModelRY": (0.0, 1.0, 0.0),
         "JointModelRZ": (0.0, 0.0, 1.0)}


def _rotate_columns(R: np.ndarray, axis_index: int, axis: np.ndarray, q: np.ndarray):
    """R @ Rot(axis, q) for a batch. For x/y/z axes only two columns mix,
    which is several times faster than a stacked 3x3 matrix product."""
    if axis_index < 0:
        return R @ rot_axis(axis, q)
    c = np.cos(q)[:, None]
    s = np.sin(q)[:, None]
    out = np.empty(R.shape)
    a, b = [(1, 2), (2, 0), (0, 1)][axis_index]
    ca, cb = R[:, :, a], R[:, :, b]
    out[:, :, axis_index] = R[:, :, axis_index]
    out[:, :, a] = ca * c + cb * s
    out[:, :, b] = cb * c - ca * s
    return out


@dataclass(frozen=True, eq=False)
class Chain:
    rot: np.ndarray      # (n, 3, 3) joint placement rotations (parent_M_joint)
    trans: np.ndarray    # (n, 3) joint placement translations, mm
    axes: np.ndarray     # (n, 3) joint axes in their own frames
    flange_rot: np.ndarray    # (3, 3) lastjoint_M_flange
    flange_trans: np.ndarray  # (3,)

    @classmethod
    def from_robot(cls, robot: RobotModel) -> "Chain":
        model = robot.model
        rots, trans, axes = [], [], []
        for jid in range(1, model.njoints):
            j = model.joints[jid]
            if model.parents[jid] != jid - 1:
                raise ValueError("the batch kernel handles serial chains only")
            name = j.shortname()
            if name in _AXES:
                axis = _AXES[name]
            elif "RevoluteUnaligned" in name:
                axis = tuple(np.asarray(j.extract().axis, float))
            else:
                raise ValueError(f"joint {model.names[jid]} is {name}, expected revolute")
            p = model.jointPlacements[jid]
            rots.append(np.array(p.rotation))
            trans.append(np.array(p.translation))
            axes.append(axis)
        frame = model.frames[robot.flange_frame]
        if frame.parentJoint != model.njoints - 1:
            raise ValueError("the flange frame must hang on the last joint")
        return cls(np.array(rots), np.array(trans), np.array(axes, float),
                   np.array(frame.placement.rotation), np.array(frame.placement.translation))

    def joint_frames(self, q: np.ndarray):
        """World rotation and origin of every joint frame (after its rotation).

        q: (N, n) radians. Returns R (N, n, 3, 3), p (N, n, 3).
        """
        q = np.atleast_2d(q)
        N, n = q.shape
        R = np.broadcast_to(np.eye(3), (N, 3, 3))
        p = np.zeros((N, 3))
        Rs = np.empty((N, n, 3, 3))
        ps = np.empty((N, n, 3))
        for i in range(n):
            p = p + stack_times(R, self.trans[i])
            if not self._identity[i]:
                R = stack_times(R, self.rot[i])
            R = _rotate_columns(R, self._axis_index[i], self.axes[i], q[:, i])
            Rs[:, i] = R
            ps[:, i] = p
        return Rs, ps

    @cached_property
    def _identity(self) -> tuple[bool, ...]:
        return tuple(bool(np.array_equal(r, np.eye(3))) for r in self.rot)

    @cached_property
    def _axis_index(self) -> tuple[int, ...]:
        """0/1/2 for joints about x/y/z, -1 for other axes."""
        out = []
        for a in self.axes:
            hits = [k for k in range(3) if np.array_equal(a, np.eye(3)[k])]
            out.append(hits[0] if hits else -1)
        return tuple(out)

    def fk(self, q: np.ndarray):
        """base_M_flange for q (N, n) radians: R (N, 3, 3), p (N, 3) mm."""
        return self.fk_and_frames(q)[0]

    def fk_and_frames(self, q: np.ndarray):
        """(fk(q), joint_frames(q)), the frames computed once."""
        Rs, ps = self.joint_frames(q)
        R = np.ascontiguousarray(Rs[:, -1])
        return ((stack_times(R, self.flange_rot), ps[:, -1] + stack_times(R, self.flange_trans)),
                (Rs, ps))

    def fk_jacobian(self, q: np.ndarray):
        """Flange pose and the geometric Jacobian (N, 6, n), rows (v; w), at
        the flange origin, expressed in base axes (LOCAL_WORLD_ALIGNED)."""
        (Rf, pe), (Rs, ps) = self.fk_and_frames(q)
        z = self._world_axes(Rs)                           # (N, n, 3)
        v = np.cross(z, pe[:, None, :] - ps)
        J = np.concatenate([v, z], axis=2).transpose(0, 2, 1)
        return Rf, pe, J

    def _world_axes(self, Rs: np.ndarray) -> np.ndarray:
        """Each joint's axis in base axes (N, n, 3): for joints about x, y
        or z the column of its frame's rotation (what Rs @ axis sums, with
        the other two terms 0), taken instead of summed."""
        if -1 in self._axis_index:
            return np.einsum("nkij,kj->nki", Rs, self.axes)
        n = Rs.shape[1]
        return Rs[:, np.arange(n), :, list(self._axis_index)].transpose(1, 0, 2)

    def pose_error(self, q: np.ndarray, R: np.ndarray, p: np.ndarray):
        """Distance (mm) and rotation angle (rad) from the flange at q
        (N, n radians) to the poses R (N, 3, 3), p (N, 3)."""
        Rf, pf = self.fk(q)
        return (np.linalg.norm(pf - p, axis=1),
                np.linalg.norm(rotation_log(R @ np.swapaxes(Rf, 1, 2)), axis=1))
