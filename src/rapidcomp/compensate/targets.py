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
from ..rapid.refs import names_in, usage
from ..rapid.values import (DecodeIssue, JointTarget, Pose, RobTarget, ToolData, WobjData,
                             decode)

IDENTITY_POSE = (np.eye(3), np.zeros(3))


@dataclass(frozen=True, eq=False)
class Source:
    """Where a target's literal value comes from, and how it is transformed.

    The rewriter needs this to write the compensated value back: into the
    declaration (element) or the inline aggregate, or as a new declaration
    referenced in place of `expr`.
    """

    record: RobTarget | JointTarget
    decl: Declaration | None       # None: an inline aggregate
    home: ParsedFile | None        # the file holding decl
    element: int | None            # flat row-major index into an array declaration
    by_loop: bool                  # the index uses the variable of an enclosing FOR loop
    ref: A.Expr                    # the expression naming the literal (Ref or aggregate)
    expr: A.Expr                   # the whole target argument (Offs/RelTool call or ref)
    call: A.Call | None            # the Offs/RelTool around ref
    rel_R: np.ndarray | None       # RelTool rotation (identity for Offs)
    rel_d: np.ndarray | None       # Offs/RelTool displacement, mm


@dataclass(frozen=True, eq=False)
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
    source: Source | None = None
    tool: tuple | None = None  # (key, (R, p) tframe)
    wobj: tuple | None = None  # (key, (R, p) uframe . oframe)
    env: tuple = ()            # FOR-loop variable values, sorted (name, value)


def compose_pose(a, b):
    return a[0] @ b[0], a[0] @ b[1] + a[1]


def invert_pose(a):
    return a[0].T, -a[0].T @ a[1]


class Resolver:
    """Resolves motion targets of `files` (the program first, then --with
    modules). With float32=True every number is first rounded to a 32-bit
    float, as the controller stores it (used to verify written output)."""

    def __init__(self, files: list[ParsedFile], float32: bool = False,
                 usages: dict | None = None, writes: bool = True):
        self.float32 = float32
        self.decls: dict[str, Declaration] = {}
        self.routine_decls: dict[tuple[str, str], Declaration] = {}
        self.home: dict[int, ParsedFile] = {}
        self.writes: dict[str, tuple[ParsedFile, A.Span]] = {}
        self.usages: dict[int, object] = {}   # id(Module) -> refs.Usage
        for pf in files:
            for m in pf.modules:
                for d in m.declarations:
                    self.home[id(d)] = pf
                    if d.routine is None:
                        self.decls.setdefault(d.name.lower(), d)
                    else:
                        self.routine_decls[(d.routine.lower(), d.name.lower())] = d
                us = usages.get(id(m)) if usages is not None else None
                if us is None:
                    if not writes:
                        continue
                    us = usage(m.node)
                self.usages[id(m)] = us
                for name, spans in us.writes.items():
                    self.writes.setdefault(name, (pf, spans[0]))

    def _num(self, values) -> np.ndarray:
        a = np.asarray(values, float)
        return a.astype(np.float32).astype(float) if self.float32 else a

    def _pose(self, pose: Pose):
        return quat_wxyz_to_matrix(self._num(pose.quat_wxyz)), self._num(pose.xyz)

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
        written = self._written(d)
        return written or d.value

    def _written(self, d: Declaration) -> str | None:
        if d.storage == "CONST" or d.name.lower() not in self.writes:
            return None
        pf, span = self.writes[d.name.lower()]
        return f"{d.name} is assigned at run time ({pf.source.display_path}:{pf.line(span)})"

    def tool(self, expr, routine: str):
        """(key, tframe as (R, p)), or a reason string."""
        if expr is None:
            return "no tool argument"
        t = self._data(expr, routine, "tool0", ToolData, "tool")
        if isinstance(t, str):
            return t
        if t is None:
            return "tool0", IDENTITY_POSE
        if t.robhold.value is not True:
            return f"tool {expr.name} is a stationary tool (robhold FALSE)"
        return expr.name.lower(), self._pose(t.tframe)

    def wobj(self, expr, routine: str):
        """(key, uframe . oframe as (R, p)), or a reason string."""
        if expr is None:
            return "wobj0", IDENTITY_POSE
        w = self._data(expr, routine, "wobj0", WobjData, "work object")
        if isinstance(w, str):
            return w
        if w is None:
            return "wobj0", IDENTITY_POSE
        if w.robhold.value is not False:
            return f"work object {expr.name} is held by the robot (stationary tool set-up)"
        if w.ufprog.value is not True or w.ufmec.value != "":
            return f"work object {expr.name} is coordinated with a mechanical unit"
        return expr.name.lower(), compose_pose(self._pose(w.uframe), self._pose(w.oframe))

    # ------------------------------------------------------------ targets
    def _source(self, expr, routine: str, env: dict[str, int], outer=None):
        """The Source of a target expression, or a reason string."""
        whole = outer if outer is not None else expr
        if isinstance(expr, A.Ref):
            d = self._lookup(expr.name, routine)
            if d is None:
                return f"{expr.name} is not declared in the given modules"
            if d.value is None:
                return f"{expr.name} has no literal value ({d.issue or 'runtime data'})"
            written = self._written(d)
            if written:
                return written
            home = self.home[id(d)]
            if not expr.selectors:
                if isinstance(d.value, tuple):
                    return f"{expr.name} is an array"
                return Source(d.value, d, home, None, False, expr, whole, None, None, None)
            if len(expr.selectors) == 1 and isinstance(expr.selectors[0], A.Index):
                idx = []
                by_loop = False
                for e in expr.selectors[0].indices:
                    if isinstance(e, A.Num):
                        idx.append(int(e.value))
                    elif isinstance(e, A.Ref) and not e.selectors and e.name.lower() in env:
                        idx.append(env[e.name.lower()])
                        by_loop = True
                    else:
                        return (f"index of {expr.name} is not a literal or the variable of an "
                                "enclosing FOR loop with constant bounds")
                if len(idx) != len(d.dims):
                    return f"{expr.name} has {len(d.dims)} dimensions, indexed with {len(idx)}"
                flat = 0
                for k, dim in zip(idx, d.dims):
                    if not 1 <= k <= dim:
                        return f"index {k} of {expr.name} is outside 1..{dim}"
                    flat = flat * dim + (k - 1)
                return Source(d.value[flat], d, home, flat, by_loop, expr, whole, None, None, None)
            return f"{expr.name} with components is not a target"
        if isinstance(expr, A.Call) and expr.name.lower() in ("offs", "reltool") and outer is None:
            return self._offset(expr, routine, env)
        if isinstance(expr, (A.Agg, A.NumAgg)):
            return "inline aggregate is not a literal value"
        return "the target is computed at run time"

    def _offset(self, call: A.Call, routine: str, env):
        pos = [a.value for a in call.args if a.kind == "pos"]
        if len(pos) != 4 or not all(isinstance(v, A.Num) for v in pos[1:]):
            return f"{call.name} arguments are not literal numbers"
        if isinstance(pos[0], (A.Agg, A.NumAgg)):
            try:
                record = decode("robtarget", pos[0], f"{call.name} robtarget")
            except DecodeIssue as exc:
                return exc.reason
            base = Source(record, None, None, None, False, pos[0], call, None, None, None)
        else:
            base = self._source(pos[0], routine, env, outer=call)
        if isinstance(base, str):
            return base
        if not isinstance(base.record, RobTarget):
            return f"{call.name} of a non-robtarget"
        d = self._num([v.value for v in pos[1:]])
        rot = np.eye(3)
        if call.name.lower() == "reltool":
            for a in call.args:
                if a.kind == "optval" and a.name.lower() in ("rx", "ry", "rz"):
                    if not isinstance(a.value, A.Num):
                        return "RelTool rotation is not a literal number"
                    f = {"rx": rot_x, "ry": rot_y, "rz": rot_z}[a.name.lower()]
                    rot = rot @ f(float(self._num(a.value.value)) * DEG)
                elif a.kind != "pos":
                    return f"RelTool argument \\{a.name} is not supported"
        elif any(a.kind != "pos" for a in call.args):
            return "Offs takes no optional arguments"
        return Source(base.record, base.decl, base.home, base.element, base.by_loop, base.ref,
                      call, call, rot, d)

    def target_pose(self, src: Source):
        """wobj_M_target of a robtarget source, with Offs/RelTool applied."""
        R = quat_wxyz_to_matrix(self._num(src.record.quat_wxyz))
        p = self._num(src.record.xyz)
        if src.call is None:
            return R, p
        if src.call.name.lower() == "offs":
            return R, p + src.rel_d
        return R @ src.rel_R, p + R @ src.rel_d

    def resolve(self, pf: ParsedFile, motion: Motion) -> list[TargetUse]:
        out = []
        for t in motion.targets:
            if t.role == "search":
                continue
            kind = "jointtarget" if motion.spec.joint_space else "robtarget"
            inline = isinstance(t.expr, (A.Agg, A.NumAgg))
            for env in self._loop_envs(motion, names_in(t.expr)):
                label = pf.text(t.expr) if not inline else "inline"
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

    def _loop_envs(self, motion: Motion, names: set[str]) -> list[dict[str, int]]:
        """One environment per iteration of the enclosing FOR loops whose
        variable the target expression uses."""
        envs: list[dict[str, int]] = [{}]
        for lp in motion.loops:
            if lp.var is None or lp.var.lower() not in names:
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
        if t.value is not None:
            src = Source(t.value, None, None, None, False, t.expr, t.expr, None, None, None)
        else:
            src = t.issue if t.issue else self._source(t.expr, motion.routine, env)
        envt = tuple(sorted(env.items()))

        def fail(reason):
            return TargetUse(motion, t.role, label, line, kind, None, None, None, None, reason,
                             env=envt)

        if isinstance(src, str):
            return fail(src)
        if kind == "jointtarget":
            if not isinstance(src.record, JointTarget):
                return fail("not a jointtarget")
            joints = tuple(float(v) for v in self._num(src.record.joints))
            return TargetUse(motion, t.role, label, line, kind, None, None, None, joints, None,
                             src, env=envt)
        if not isinstance(src.record, RobTarget):
            return fail("not a robtarget")
        tool = self.tool(motion.tool, motion.routine)
        if isinstance(tool, str):
            return fail(tool)
        wobj = self.wobj(motion.wobj, motion.routine)
        if isinstance(wobj, str):
            return fail(wobj)
        Rf, pf_ = compose_pose(compose_pose(wobj[1], self.target_pose(src)), invert_pose(tool[1]))
        return TargetUse(motion, t.role, label, line, kind, Rf, pf_, src.record.conf, None, None,
                         src, tool, wobj, envt)


def base_pose(src: Source, target):
    """The literal's pose that gives wobj_M_target `target` through src's
    Offs/RelTool (the inverse of Resolver.target_pose)."""
    R, p = target
    if src.call is None:
        return R, p
    if src.call.name.lower() == "offs":
        return R, p - src.rel_d
    R = R @ src.rel_R.T
    return R, p - R @ src.rel_d


def target_uses(files: list[ParsedFile], float32: bool = False) -> list[TargetUse]:
    """Every target use of the first file's motions, resolved against all files."""
    resolver = Resolver(files, float32)
    main = files[0]
    out: list[TargetUse] = []
    for m in main.modules:
        for motion in m.motions:
            out.extend(resolver.resolve(main, motion))
    return out
