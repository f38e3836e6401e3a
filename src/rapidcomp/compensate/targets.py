"""Resolve each motion instruction's target to a flange pose, or say why not.

base_M_flange = world_M_uframe . uframe_M_oframe . oframe_M_tcp . tframe^-1
(the robot base is the world frame: no track, no base frame offset). tool0
and wobj0 are built in; tooldata/wobjdata come from the program or from the
modules given with --with. Only values known statically are resolved:
literal targets, declared targets with literal values, array elements with
literal indices or indexed by the enclosing FOR loop's variable with literal
bounds, Offs/RelTool with literal numbers, and jointtargets of MoveAbsJ.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..kinematics.frames import DEG, quat_wxyz_to_matrix, rot_x, rot_y, rot_z
from ..rapid import ast as A
from ..rapid.model import Declaration, Motion, ParsedFile
from ..rapid.values import JointTarget, Pose, RobTarget, ToolData, WobjData

IDENTITY_POSE = (np.eye(3), np.zeros(3))


@dataclass(frozen=True)
class TargetUse:
    """One target of one motion instruction, resolved or not."""

    motion: Motion
    role: str
    label: str                 # e.g. "pPath{3}" or "inline"
    line: int
    kind: str                  # "robtarget" or "jointtarget"
    R: np.ndarray | None       # base_M_flange rotation
    p: np.ndarray | None       # base_M_flange translation, mm
    conf: tuple[int, int, int, int] | None
    joints_deg: tuple[float, ...] | None  # jointtarget robax
    reason: str | None         # why it was not resolved


def _pose(pose: Pose):
    return quat_wxyz_to_matrix(pose.quat_wxyz), np.asarray(pose.xyz, float)


def _compose(a, b):
    return a[0] @ b[0], a[0] @ b[1] + a[1]


def _inverse(a):
    return a[0].T, -a[0].T @ a[1]


class Resolver:
    def __init__(self, files: list[ParsedFile]):
        self.decls: dict[str, Declaration] = {}
        self.routine_decls: dict[tuple[str, str], Declaration] = {}
        for pf in files:
            for m in pf.modules:
                for d in m.declarations:
                    if d.routine is None:
                        self.decls.setdefault(d.name.lower(), d)
                    else:
                        self.routine_decls[(d.routine.lower(), d.name.lower())] = d

    def _lookup(self, name: str, routine: str) -> Declaration | None:
        return self.routine_decls.get((routine.lower(), name.lower())) or self.decls.get(name.lower())

    # ------------------------------------------------------------ tool / wobj
    def _data(self, expr, routine: str, builtin: str, cls, what: str):
        """The literal value of a tool/work object argument, None for the
        built-in one, or a reason string."""
        if not (isinstance(expr, A.Ref) and not expr.selectors):
            return f"the {what} is not a plain data name"
        if expr.name.lower() == builtin:
            return None
        d = self._lookup(expr.name, routine)
        if d is None:
            return f"{what} {expr.name} is not declared in the given modules"
        if not isinstance(d.value, cls):
            return f"{what} {expr.name} has no literal value"
        return d.value

    def tool(self, expr, routine: str):
        """tframe as (R, p), or a reason string."""
        if expr is None:
            return "no tool argument"
        t = self._data(expr, routine, "tool0", ToolData, "tool")
        if t is None or isinstance(t, str):
            return IDENTITY_POSE if t is None else t
        if t.robhold.value is not True:
            return f"tool {expr.name} is a stationary tool (robhold FALSE)"
        return _pose(t.tframe)

    def wobj(self, expr, routine: str):
        """uframe . oframe as (R, p), or a reason string."""
        if expr is None:
            return IDENTITY_POSE
        w = self._data(expr, routine, "wobj0", WobjData, "work object")
        if w is None or isinstance(w, str):
            return IDENTITY_POSE if w is None else w
        if w.robhold.value is not False:
            return f"work object {expr.name} is held by the robot (stationary tool set-up)"
        if w.ufprog.value is not True or w.ufmec.value != "":
            return f"work object {expr.name} is coordinated with a mechanical unit"
        return _compose(_pose(w.uframe), _pose(w.oframe))

    # ------------------------------------------------------------ targets
    def _value(self, expr, routine: str, loop_env: dict[str, int]):
        """A RobTarget/JointTarget for an expression, or a reason string."""
        if isinstance(expr, (A.Agg, A.NumAgg)):
            return "inline aggregate is not a literal value"
        if isinstance(expr, A.Ref):
            d = self._lookup(expr.name, routine)
            if d is None:
                return f"{expr.name} is not declared in the given modules"
            if d.value is None:
                return f"{expr.name} has no literal value ({d.issue or 'runtime data'})"
            if not expr.selectors:
                return d.value if not isinstance(d.value, tuple) else f"{expr.name} is an array"
            if len(expr.selectors) == 1 and isinstance(expr.selectors[0], A.Index):
                idx = []
                for e in expr.selectors[0].indices:
                    if isinstance(e, A.Num):
                        idx.append(int(e.value))
                    elif isinstance(e, A.Ref) and not e.selectors and e.name.lower() in loop_env:
                        idx.append(loop_env[e.name.lower()])
                    else:
                        return (f"index of {expr.name} is not a literal or the variable of an "
                                "enclosing FOR loop with constant bounds")
                flat = 0
                for k, dim in zip(idx, d.dims):
                    if not 1 <= k <= dim:
                        return f"index {k} of {expr.name} is outside 1..{dim}"
                    flat = flat * dim + (k - 1)
                return d.value[flat]
            return f"{A.Ref.__name__} with components is not a target"
        if isinstance(expr, A.Call) and expr.name.lower() in ("offs", "reltool"):
            return self._offset(expr, routine, loop_env)
        return "the target is computed at run time"

    def _offset(self, call: A.Call, routine: str, loop_env):
        pos = [a.value for a in call.args if a.kind == "pos"]
        if len(pos) != 4 or not all(isinstance(v, A.Num) for v in pos[1:]):
            return f"{call.name} arguments are not literal numbers"
        base = self._value(pos[0], routine, loop_env)
        if not isinstance(base, RobTarget):
            return base if isinstance(base, str) else f"{call.name} of a non-robtarget"
        d = np.array([v.value for v in pos[1:]])
        R = quat_wxyz_to_matrix(base.quat_wxyz)
        p = np.asarray(base.xyz, float)
        if call.name.lower() == "offs":
            return ("pose", R, p + d, base.conf)
        rot = np.eye(3)
        for a in call.args:
            if a.kind == "optval" and a.name.lower() in ("rx", "ry", "rz"):
                if not isinstance(a.value, A.Num):
                    return "RelTool rotation is not a literal number"
                f = {"rx": rot_x, "ry": rot_y, "rz": rot_z}[a.name.lower()]
                rot = rot @ f(a.value.value * DEG)
        return ("pose", R @ rot, p + R @ d, base.conf)

    def resolve(self, pf: ParsedFile, motion: Motion) -> list[TargetUse]:
        envs = self._loop_envs(motion)
        out = []
        for t in motion.targets:
            if t.role == "search":
                continue
            kind = "jointtarget" if motion.spec.joint_space else "robtarget"
            for env in envs:
                label = pf.text(t.expr) if not isinstance(t.expr, (A.Agg, A.NumAgg)) else "inline"
                if env:
                    label += " [" + ", ".join(f"{k}={v}" for k, v in env.items()) + "]"
                out.append(self._use(pf, motion, t, kind, label, env))
        return out

    def _int(self, expr, routine: str) -> int | None:
        """A literal integer, or a CONST num with a literal integer value."""
        if isinstance(expr, A.Num) and float(expr.value).is_integer():
            return int(expr.value)
        if isinstance(expr, A.Unary) and expr.op == "-":
            v = self._int(expr.operand, routine)
            return -v if v is not None else None
        if isinstance(expr, A.Ref) and not expr.selectors:
            d = self._lookup(expr.name, routine)
            if d is not None and d.storage == "CONST" and d.type == "num":
                return self._int(d.node.init, routine)
        return None

    def _loop_envs(self, motion: Motion) -> list[dict[str, int]]:
        envs: list[dict[str, int]] = [{}]
        for lp in motion.loops:
            if lp.var is None:
                continue
            start = self._int(lp.start, motion.routine)
            stop = self._int(lp.stop, motion.routine)
            step = 1 if lp.step is None else self._int(lp.step, motion.routine)
            if start is None or stop is None or not step:
                continue  # the target stays unresolved and says why
            values = list(range(start, stop + (1 if step > 0 else -1), step))
            envs = [{**e, lp.var.lower(): v} for e in envs for v in values]
        return envs

    def _use(self, pf, motion, t, kind, label, env) -> TargetUse:
        line = pf.line(motion.span)
        value = t.value if t.value is not None else (
            t.issue if t.issue else self._value(t.expr, motion.routine, env))

        def fail(reason):
            return TargetUse(motion, t.role, label, line, kind, None, None, None, None, reason)

        if isinstance(value, str):
            return fail(value)
        if kind == "jointtarget":
            if not isinstance(value, JointTarget):
                return fail("not a jointtarget")
            return TargetUse(motion, t.role, label, line, kind, None, None, None,
                             value.joints, None)
        if isinstance(value, RobTarget):
            R, p, conf = quat_wxyz_to_matrix(value.quat_wxyz), np.asarray(value.xyz, float), value.conf
        elif isinstance(value, tuple) and value and value[0] == "pose":
            _, R, p, conf = value
        else:
            return fail("not a robtarget")
        tool = self.tool(motion.tool, motion.routine)
        if isinstance(tool, str):
            return fail(tool)
        wobj = self.wobj(motion.wobj, motion.routine)
        if isinstance(wobj, str):
            return fail(wobj)
        Rf, pf_ = _compose(_compose(wobj, (R, p)), _inverse(tool))
        return TargetUse(motion, t.role, label, line, kind, Rf, pf_, tuple(conf), None, None)


def target_uses(files: list[ParsedFile]) -> list[TargetUse]:
    """Every target use of the first file's motions, resolved against all files."""
    resolver = Resolver(files)
    main = files[0]
    out: list[TargetUse] = []
    for m in main.modules:
        for motion in m.motions:
            out.extend(resolver.resolve(main, motion))
    return out
