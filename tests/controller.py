"""A small model of an IRC5 running a RAPID task, written for the tests
independently of rapidcomp's compensation code (compensate/*).

It runs main() statement by statement: calls of routines without
arguments, FOR loops with literal bounds, ConfJ/ConfL \\On|\\Off,
PDispSet/PDispOff, assignments of a literal to a tool or work object, whole
or to its frame (rdkTool.tframe := [...], as RoboDK writes them; any other
assignment moves nothing), MoveAbsJ, MoveJ, MoveL, MoveC (circle point,
then end point) and MoveExtJ; inline targets whose external axes are named
data ([[x,y,z],[q],[cf],extj], as the Grasshopper plugin Robots writes
them). For every arm move it records the joints it commands, from the
numbers rounded to float32 as the controller stores them:

* MoveAbsJ: the joints as written;
* a robtarget: base_M_flange = base_M_world . uframe . oframe . D . target
  . tframe^-1 (D the active program displacement, in the object frame);
  with configuration supervision on, the solution in the confdata's
  quadrants (within 0.01 deg) on its cfx branch; with it off, and for a
  MoveC circle point, of all the solutions within the joint limits, the
  one nearest the current joints.

Only the syntax tree and literal decoding of rapidcomp are used (parse.py,
values.py: tested on their own) and the closed-form IK (checked against
the paper's Tables 5 and 6); the choice between solutions, frames, Offs,
displacement and the track are done here.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin

from rapidcomp.kinematics.ik import Solver
from rapidcomp.rapid import ast as A
from rapidcomp.rapid.motions import motion_spec
from rapidcomp.rapid.values import JointTarget, RobTarget, ToolData, WobjData, decode

# The frames of a tool and of a work object, by component name.
FRAMES = {ToolData: ("tframe",), WobjData: ("uframe", "oframe")}


def f32(x):
    return np.asarray(x, float).astype(np.float32).astype(float)


def se3(pos, quat_wxyz) -> pin.SE3:
    w, x, y, z = f32(quat_wxyz)
    q = pin.Quaternion(w, x, y, z)
    q.normalize()
    return pin.SE3(q.matrix(), f32(pos))


def fk(robot, q_deg) -> pin.SE3:
    data = robot.model.createData()
    q = np.radians(np.asarray(q_deg, float))
    if robot.joint_map is not None:
        q = robot.joint_map.apply(q[None])[0]
    pin.framesForwardKinematics(robot.model, data, q)
    return pin.SE3(data.oMf[robot.flange_frame])


@dataclass
class Executed:
    file: str
    line: int
    instruction: str
    kind: str                    # "joint" (MoveAbsJ), "rob" or "ext" (MoveExtJ)
    q_deg: np.ndarray | None
    pose: pin.SE3 | None         # the base_M_flange a robtarget asks for
    displaced: bool = False
    # The move's tool centre point in the flange frame (mm): where its
    # position is judged.
    tcp: np.ndarray | None = None


class Controller:
    def __init__(self, files, robot, track=None, start_deg=None, confj=True, base=None):
        self.files = files
        self.robot = robot
        self.ik = Solver(robot)
        self.track = track or {}          # external axis index -> unit vector (world)
        self.base = base if base is not None else pin.SE3.Identity()   # world_M_base
        self.decls = {}
        self.local = {}                   # (id(file), name) -> a module's LOCAL data
        self.procs = {}
        for pf in files:
            for m in pf.modules:
                for d in m.declarations:
                    if d.scope == "LOCAL" and d.routine is None:
                        self.local[(id(pf), d.name.lower())] = d
                    else:
                        self.decls[d.name.lower()] = d
                for r in m.routines:
                    self.procs[r.name.lower()] = (pf, r.node)
        self.motions = {}
        for pf in files:
            for m in pf.modules:
                for mo in m.motions:
                    self.motions[(id(pf), mo.span.start)] = mo
        self.q = None if start_deg is None else np.asarray(start_deg, float)
        self.confj = confj      # as at program start, unless the test says otherwise
        self.confl = True
        self.disp = None
        # Tools and work objects as assigned so far (name -> value).
        self.assigned = {}
        self.out: list[Executed] = []

    # ------------------------------------------------------------ data
    def value(self, expr, env):
        if isinstance(expr, A.Ref):
            d = self.named(expr.name)
            if not expr.selectors:
                return d.value
            idx = []
            for e in expr.selectors[0].indices:
                idx.append(int(e.value) if isinstance(e, A.Num) else env[e.name.lower()])
            flat = 0
            for k, dim in zip(idx, d.dims):
                flat = flat * dim + (k - 1)
            return d.value[flat]
        raise AssertionError(f"not a data reference: {expr}")

    def named(self, name: str):
        """Data by name where the file does not matter (targets, external
        axes): the global, else a module's LOCAL data of that name."""
        d = self.decls.get(name.lower())
        if d is None:
            d = next(x for (_, n), x in self.local.items() if n == name.lower())
        return d

    def data(self, pf, name: str):
        """(the declaration a name means in a file's module, where its
        assigned value is kept): its LOCAL data, else the global."""
        key = (id(pf), name.lower())
        if key in self.local:
            return self.local[key], key
        return self.decls.get(name.lower()), name.lower()

    def frame(self, pf, expr, kind) -> pin.SE3:
        if expr is None or expr.name.lower() in ("tool0", "wobj0"):
            return pin.SE3.Identity()
        d, slot = self.data(pf, expr.name)
        v = self.assigned.get(slot, d.value)
        if expr.selectors:
            # An array's element, its indices literal numbers or CONST nums.
            (sel,) = expr.selectors
            flat = 0
            for i, n in zip(sel.indices, d.dims):
                k = (int(i.value) if isinstance(i, A.Num)
                     else int(self.named(i.name).node.init.value))
                assert 1 <= k <= n
                flat = flat * n + k - 1
            v = v[flat]
        if kind == "tool":
            return se3(v.tframe.xyz, v.tframe.quat_wxyz)
        return se3(v.uframe.xyz, v.uframe.quat_wxyz) * se3(v.oframe.xyz, v.oframe.quat_wxyz)

    def world_M_base(self, ext) -> pin.SE3:
        d = np.zeros(3)
        for k, u in self.track.items():
            d += f32(ext[k]) * np.asarray(u, float)
        return pin.SE3(np.eye(3), d) * self.base

    def named_axes(self, expr, cls):
        """An inline target written with named data for its external axes
        or confdata ([[x,y,z],[q],conf,extj], [[j1,..,j6],extj]: the
        Grasshopper plugin Robots), read here: its literal numbers, the
        data's in place of each name."""
        assert isinstance(expr, A.Agg), expr
        parts = []
        for part in expr.items:
            if isinstance(part, A.Ref):
                d = self.named(part.name)
                assert d.type in ("extjoint", "confdata"), d.type
                part = d.node.init
            parts.append(part)
        numbers = [n.value for part in parts for n in part.items]
        return cls(tuple(float(v) for v in numbers), ((), ()), expr.span)

    def robtarget(self, expr, env, inline) -> tuple[pin.SE3, RobTarget]:
        if isinstance(expr, A.Call):        # Offs(p, dx, dy, dz)
            assert expr.name.lower() == "offs"
            base, *nums = [a.value for a in expr.args]
            M, rt = self.robtarget(base, env, None)
            return pin.SE3(M.rotation, M.translation + f32([n.value for n in nums])), rt
        rt = (inline if inline is not None else self.named_axes(expr, RobTarget)
              if isinstance(expr, A.Agg) else self.value(expr, env))
        assert isinstance(rt, RobTarget)
        return se3(rt.xyz, rt.quat_wxyz), rt

    # ------------------------------------------------------------ IK
    def solutions(self, pose: pin.SE3, around) -> np.ndarray:
        """Every solution within the limits whose J1/J4/J6 lie in the
        quadrants around `around` (rows of 6 joint angles, deg)."""
        around = np.asarray(around, float)
        quads = [range(int(np.floor(around[j] / 90)) - 2, int(np.floor(around[j] / 90)) + 3)
                 for j in (0, 3, 5)]
        confs = np.array([(a, b, c, x) for a, b, c in itertools.product(*quads)
                          for x in range(8)])
        n = len(confs)
        sol = self.ik.solve_nominal(np.repeat(pose.rotation[None], n, 0),
                                    np.repeat(pose.translation[None], n, 0), confs)
        return sol.q_deg[sol.success]

    def joints(self, pose: pin.SE3, rt: RobTarget, supervised: bool) -> np.ndarray:
        if supervised or self.q is None:
            sol = self.ik.solve_nominal(pose.rotation[None], pose.translation[None],
                                        np.array([rt.conf]))
            assert sol.success[0], sol.reason(0)
            return sol.q_deg[0]
        cands = self.solutions(pose, self.q)
        assert len(cands), "no solution"
        return cands[np.argmin(np.linalg.norm(cands - self.q, axis=1))]

    # ------------------------------------------------------------ running
    def run(self, entry: str = "main") -> list[Executed]:
        pf, node = self.procs[entry.lower()]
        self.block(pf, node.body, {})
        return self.out

    def block(self, pf, stmts, env) -> None:
        for s in stmts:
            if isinstance(s, A.ProcCall):
                self.call(pf, s, env)
            elif isinstance(s, A.Assign):
                self.assign(pf, s)
            elif isinstance(s, A.For):
                step = 1 if s.step is None else int(s.step.value)
                for v in range(int(s.start.value), int(s.stop.value) + 1, step):
                    self.block(pf, s.body, {**env, s.var.lower(): v})
            else:
                raise AssertionError(f"statement not modelled: {type(s).__name__}")

    def assign(self, pf, s: A.Assign) -> None:
        d, name = self.data(pf, s.target.name)
        if d is None or not isinstance(d.value, (ToolData, WobjData)):
            return                          # (a speed, a counter: no motion)
        if not s.target.selectors:
            self.assigned[name] = decode(d.type, s.value)
            return
        if s.target.selectors[0].name.lower() == "tload":
            return                          # (a tool's load, or a part of it, moves no target)
        (part,) = s.target.selectors
        assert part.name.lower() in FRAMES[type(d.value)], f"not modelled: {part.name}"
        old = self.assigned.get(name, d.value)
        self.assigned[name] = replace(old, **{part.name.lower(): decode("pose", s.value)})

    def call(self, pf, s: A.ProcCall, env) -> None:
        name = s.name.lower()
        opts = {a.name.lower() for a in s.args if a.kind == "opt"}
        if name in ("confj", "confl"):
            setattr(self, name, "on" in opts)
            return
        if name == "pdispset":
            p = self.value(s.args[0].value, env)
            self.disp = se3(p.xyz, p.quat_wxyz)
            return
        if name == "pdispoff":
            self.disp = None
            return
        if name in self.procs:
            callee_pf, node = self.procs[name]
            self.block(callee_pf, node.body, env)
            return
        spec = motion_spec(name)
        if spec is None:
            return                          # WaitTime, Set, ...: no motion
        mo = self.motions[(id(pf), s.span.start)]
        line = pf.line(mo.span)
        where = pf.source.display_path
        if spec.name == "MoveExtJ":
            self.out.append(Executed(where, line, mo.instruction, "ext", None, None))
            return
        for t in mo.targets:
            if spec.joint_space:
                jt = (t.value if t.value is not None else
                      self.named_axes(t.expr, JointTarget) if isinstance(t.expr, A.Agg)
                      else self.value(t.expr, env))
                assert isinstance(jt, JointTarget)
                self.q = f32(jt.joints)
                self.out.append(Executed(where, line, mo.instruction, "joint", self.q.copy(),
                                         None, tcp=self.frame(pf, mo.tool, "tool").translation))
                continue
            wobj_M_target, rt = self.robtarget(t.expr, env, t.value)
            if self.disp is not None:
                wobj_M_target = self.disp * wobj_M_target
            pose = (self.world_M_base(rt.ext).inverse() * self.frame(pf, mo.wobj, "wobj")
                    * wobj_M_target * self.frame(pf, mo.tool, "tool").inverse())
            # A circle point is passed on the way: the configuration follows
            # from where the robot is (its confdata is not read).
            supervised = (self.confj if spec.interpolation == "joint" else self.confl) \
                and t.role != "cir"
            self.q = self.joints(pose, rt, supervised)
            self.out.append(Executed(where, line, mo.instruction, "rob", self.q.copy(), pose,
                                     self.disp is not None,
                                     self.frame(pf, mo.tool, "tool").translation))
