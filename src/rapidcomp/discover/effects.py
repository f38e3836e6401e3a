"""The effect catalogue: named, parameterized additions to a robot model.

Each effect has an id (`joint_offset:J2`), user-facing parameters in
millimetres / degrees / plain numbers, and the scale to the internal unit
(radians for angles). Where an effect acts on the chain:

- base_frame (6)          measured = T . model, T = (Rz.Ry.Rx, d), base axes
- tool_offset (3)         measuring point moved by d in the flange frame
- joint_offset:Jk (1)     q_k <- q_k + delta
- joint_scale:Jk (1)      q_k <- q_k (1 + s)
- gravity_compliance:Jk   q_k <- q_k + c tau_k(q), c >= 0 (gravity.py)
- link_elongation:A-B     segment A->B (nominal joint placement of B) x (1 + eps)
- axis_tilt:Jk (2)        joint k's frame rotated about the two base axes
                          perpendicular to its axis at the zero pose
- joint_displacement:Jk   joint k's origin translated (base axes, zero pose)

`to_profile` turns fitted values into an (extended) thermal profile, which
is how `rapidcomp fix` and `rapidcomp simulate` see them; model.py
evaluates the same definitions with its own chain code and exact Jacobians.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin

from ..errors import RapidcompError
from ..kinematics.chain import Chain
from ..kinematics.frames import DEG, rot_axis, rpy_matrix
from ..kinematics.profile import Displacement, JointTerms, ThermalProfile
from ..kinematics.robot import RobotModel

KINDS = ("base_frame", "tool_offset", "joint_offset", "joint_scale", "gravity_compliance",
         "link_elongation", "axis_tilt", "joint_displacement")
_AXIS_NAMES = "xyz"


@dataclass(frozen=True, eq=False)
class Effect:
    id: str
    kind: str
    joint: int | None            # 0-based joint index; link_elongation: B (n = flange)
    params: tuple[str, ...]      # user-facing names, unit in the suffix
    to_internal: tuple[float, ...]  # internal value = user value * this
    axes: np.ndarray | None = None  # axis_tilt (2, 3) / joint_displacement (3, 3), local
    harmonic: int = 0               # cyclic: cycles per turn of the joint
    # Thermal: grows with the thermal state s(t) of a warm-up campaign (its
    # values are the steady state's); id "thermal:<base id>".
    thermal: bool = False

    @property
    def base_id(self) -> str:
        return self.id[len(THERMAL_PREFIX):] if self.thermal else self.id

    @property
    def size(self) -> int:
        return len(self.params)

    def internal(self, user_values) -> np.ndarray:
        return np.asarray(user_values, float) * np.asarray(self.to_internal)

    def user(self, internal_values) -> dict[str, float]:
        return {n: float(v) / s for n, v, s in zip(self.params, internal_values, self.to_internal)}


def zero_pose_rotations(chain: Chain) -> np.ndarray:
    """World rotation of every joint frame at q = 0 (n, 3, 3)."""
    Rs, _ = chain.joint_frames(np.zeros((1, len(chain.trans))))
    return Rs[0]


def _perpendicular_base_axes(z0: np.ndarray) -> list[tuple[str, np.ndarray]]:
    """The two base axes perpendicular to z0 (named), or, for an axis not
    parallel to a base axis, the two least aligned made orthonormal to it."""
    eye = np.eye(3)
    dots = np.abs(eye @ z0)
    if np.isclose(dots.max(), 1.0, atol=1e-9):
        return [(_AXIS_NAMES[m], eye[m]) for m in range(3) if m != int(np.argmax(dots))]
    out = []
    for m in np.argsort(dots)[:2]:
        v = eye[m] - z0 * (z0 @ eye[m]) - sum(u * (u @ eye[m]) for _, u in out)
        out.append((f"t{len(out) + 1}", v / np.linalg.norm(v)))
    return out


# A cyclic gear error of joint k: q_k <- q_k + a sin(h q_k) + b cos(h q_k)
# for h cycles per turn (a gear stage, a bearing); h = 1 is an offset and an
# eccentricity the other effects already express.
CYCLIC_HARMONICS = (2, 3, 4)


THERMAL_PREFIX = "thermal:"
# What heat changes: joint zeros (encoder mounts), link lengths, axis
# directions and joint origins (the paper's Table 1), and the base
# (the stand). Gear ratios, compliances, backlash and gear errors do not.
THERMAL_KINDS = ("base_frame", "joint_offset", "link_elongation", "axis_tilt",
                 "joint_displacement")


def thermal_variants(effects) -> tuple[Effect, ...]:
    """The thermal twin of every effect heat can change, for a warm-up
    campaign (data with a t_min column)."""
    return tuple(replace(e, id=THERMAL_PREFIX + e.id, thermal=True) for e in effects
                 if e.kind in THERMAL_KINDS and not e.thermal)


def catalogue(robot: RobotModel) -> tuple[Effect, ...]:
    """Every candidate effect for `robot`, in a fixed order (ties are broken
    by it, and the report says so)."""
    chain = Chain.from_robot(robot)
    names = robot.joint_names
    n = len(names)
    A = zero_pose_rotations(chain)
    mm, deg = 1.0, DEG
    out = [Effect("base_frame", "base_frame", None,
                  ("dx_mm", "dy_mm", "dz_mm", "rx_deg", "ry_deg", "rz_deg"),
                  (mm, mm, mm, deg, deg, deg)),
           Effect("tool_offset", "tool_offset", None, ("x_mm", "y_mm", "z_mm"), (mm, mm, mm))]
    for k in range(n):
        out.append(Effect(f"joint_offset:{names[k]}", "joint_offset", k, ("offset_deg",), (deg,)))
    for k in range(n):
        out.append(Effect(f"joint_scale:{names[k]}", "joint_scale", k, ("scale",), (1.0,)))
    for k in range(n):
        out.append(Effect(f"gravity_compliance:{names[k]}", "gravity_compliance", k,
                          ("c_deg_per_nm",), (deg,)))
    for b in range(1, n + 1):
        seg = chain.trans[b] if b < n else chain.flange_trans
        if np.linalg.norm(seg) > 1e-9:
            to = names[b] if b < n else "flange"
            out.append(Effect(f"link_elongation:{names[b - 1]}-{to}", "link_elongation", b,
                              ("epsilon",), (1.0,)))
    for k in range(n):
        z0 = A[k] @ chain.axes[k]
        pair = _perpendicular_base_axes(z0 / np.linalg.norm(z0))
        out.append(Effect(f"axis_tilt:{names[k]}", "axis_tilt", k,
                          tuple(f"r{a}_deg" if len(a) == 1 else f"{a}_deg" for a, _ in pair),
                          (deg, deg), np.array([A[k].T @ u for _, u in pair])))
    for k in range(n):
        out.append(Effect(f"joint_displacement:{names[k]}", "joint_displacement", k,
                          ("dx_mm", "dy_mm", "dz_mm"), (mm, mm, mm), A[k].T.copy()))
    for k in range(n):
        out.append(Effect(f"backlash:{names[k]}", "backlash", k, ("b_deg",), (deg,)))
    for k in range(n):
        for h in CYCLIC_HARMONICS:
            out.append(Effect(f"cyclic:{names[k]}:{h}", "cyclic", k, ("a_deg", "b_deg"),
                              (deg, deg), harmonic=h))
    return tuple(out)


def find(effects, effect_id: str) -> Effect:
    for e in effects:
        if e.id.lower() == effect_id.lower():
            return e
    kinds = sorted({e.kind for e in effects})
    raise RapidcompError(f"unknown effect {effect_id!r}; the catalogue has "
                         + ", ".join(e.id for e in effects) + f" (kinds: {', '.join(kinds)})")


def tilt_rotation(effect: Effect, theta) -> np.ndarray:
    """Rot(u1, t1) . Rot(u2, t2) in the joint's own frame."""
    return rot_axis(effect.axes[0], theta[0]) @ rot_axis(effect.axes[1], theta[1])


def to_profile(robot: RobotModel, profile: ThermalProfile, values) -> ThermalProfile:
    """`profile` plus effects at internal values ({Effect: array}), as the
    extended profile format expresses them (see model.py for the same
    definitions evaluated directly):

    joint k:  Delta' = (I, eps R_Pk^T s_k) . Delta_k . (R_tilt, d_disp)
    flange:   Delta' = (I, eps R_F^T s_F) . Delta_F . (I, d_tool)
    base:     T . base;  joint terms add.

    Backlash depends on the direction each move approaches its target from,
    and a cyclic gear error is a function of the angle, neither of which a
    profile holds: they are left out (job.py says so).
    """
    chain = Chain.from_robot(robot)
    names = robot.joint_names
    n = len(names)
    pre = {k: pin.SE3.Identity() for k in range(n + 1)}
    # Tilt and displacement of one joint compose as (I, d) . (R, 0) = (R, d)
    # whatever order they were listed in; the tool offset is the flange's d.
    tilt = [np.eye(3) for _ in range(n + 1)]
    disp = np.zeros((n + 1, 3))
    terms = {k: np.zeros(3) for k in range(n)}   # offset_deg, scale, compliance_deg_per_nm
    base = profile.base.se3()
    for e, v in values.items():
        v = np.asarray(v, float)
        if e.kind in ("backlash", "cyclic"):
            continue
        if e.kind == "base_frame":
            base = pin.SE3(rpy_matrix(*v[3:]), v[:3]) * base
        elif e.kind == "tool_offset":
            disp[n] += v
        elif e.kind == "axis_tilt":
            tilt[e.joint] = tilt[e.joint] @ tilt_rotation(e, v)
        elif e.kind == "joint_displacement":
            disp[e.joint] += e.axes @ v
        elif e.kind in ("joint_offset", "joint_scale", "gravity_compliance"):
            col = ("joint_offset", "joint_scale", "gravity_compliance").index(e.kind)
            terms[e.joint][col] += v[0] / e.to_internal[0]
        elif e.kind == "link_elongation":
            b = e.joint
            rot = chain.rot[b] if b < n else chain.flange_rot
            seg = chain.trans[b] if b < n else chain.flange_trans
            pre[b] = pin.SE3(np.eye(3), rot.T @ seg * v[0]) * pre[b]
    disps = []
    for k, name in enumerate([*names, "flange"]):
        M = pre[k] * profile.get(name).se3() * pin.SE3(tilt[k], disp[k])
        disps.append((name, Displacement.from_se3(M)))
    jt = []
    for k, name in enumerate(names):
        old = profile.terms(name)
        new = JointTerms(old.offset_deg + terms[k][0], old.scale + terms[k][1],
                         old.compliance_deg_per_nm + terms[k][2])
        if not new.is_zero:
            jt.append((name, new))
    return replace(profile, displacements=tuple(disps),
                   base=Displacement.from_se3(base), joint_terms=tuple(jt))
