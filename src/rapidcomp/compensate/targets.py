"""Resolve each motion instruction's target to a flange pose, or say why not.

base_M_flange = base_M_world . world_M_uframe . uframe_M_oframe . oframe_M_tcp
                . tframe^-1

world_M_base is the robot's base frame in the world (--base, or a backup's
SYSPAR/MOC.cfg; the identity by default), moved along a world axis by a
track axis value when a track carries the robot (--track). tool0 and wobj0 are
built in; tooldata/wobjdata come from the task's modules or from --with
modules. Names are looked up as the controller does: the routine's own data
and parameters, then the module's data (LOCAL included), then the global
data of every module of the task.

Only values known statically are resolved: literal targets, declared
targets with literal values, array elements with literal indices or
indexed by the enclosing FOR loop's variable with constant bounds,
Offs/RelTool with literal numbers or CONST nums, and jointtargets of
MoveAbsJ. What is not resolved says why, and whether that is by design
(untouched: a value known only at run time, a stationary tool) or a gap in
the input (blocked: a name no given module declares), which fails the
compensation.
"""

from __future__ import annotations

import math
import operator
from bisect import bisect_left, bisect_right
from contextlib import contextmanager
from dataclasses import dataclass, replace
from itertools import repeat
from typing import NamedTuple

import numpy as np

from ..construct import maker
from ..errors import RapidcompError
from ..kinematics.frames import (DEG, quat_wxyz_to_matrix, rot_x, rot_y, rot_z,
                                 unit_quat_matrices, unit_wxyz)
from ..rapid import ast as A
from ..rapid.model import Declaration, Module, Motion, ParsedFile, RoutineTable
from ..rapid.refs import literal_leaves, loop_names, usage
from ..rapid.writes import Writes, task_writes
from ..rapid.values import DecodeIssue, JointTarget, Pose, RobTarget, ToolData, WobjData, decode
from .flow import LATE, calls_of, statements
from .transient import FUNC_J, FUNC_R, state_values

IDENTITY_POSE = (np.eye(3), np.zeros(3))
# A quaternion further than this from unit length is reported when normalised.
QUAT_TOLERANCE = 1e-3
MAX_POSITION_MM = 1e5
MAX_JOINT_DEG = 1e5
# confdata: cf1, cf4, cf6 count quarter turns (|cf| <= 8 is +-720 deg); cfx 0..7.
MAX_QUADRANT = 8
# External axis values at or above this are "not used" (RAPID writes 9E9).
EXTAX_UNUSED = 8.9e9
# A FOR loop walking more iterations than this is not expanded.
MAX_LOOP_ITERATIONS = 1_000_000
MISSING_HINT = ("give the whole task: its folder, program file or backup, or the declaring "
                "module with --with")
# A MoveAbsJ whose tool is not known (its note: this, why, and what
# follows): its joints reach the flange's whole pose all the same, except at
# the wrist singularity, where only one point's position is held exact
# (solve.py fails those).
UNKNOWN_TOOL = "its tool is not known"
UNKNOWN_TOOL_MEANS = (": its errors are measured at the flange (its joints reach the flange's "
                      "whole pose, so the tool's too)")
AXES = "abcdef"
# A transient output's targets (transient.py), evaluated at a thermal state.
_STATE_FUNCS = frozenset((FUNC_J.lower(), FUNC_R.lower()))


@dataclass(frozen=True, eq=False, slots=True)
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
    rel_d: tuple | None            # Offs/RelTool displacement (x, y, z), mm
    home_module: Module | None = None  # the module holding decl

    def with_record(self, record) -> "Source":
        """The same source holding `record` (as an output writes it);
        dataclasses.replace costs ~10 times more, once per target."""
        return _source(record, self.decl, self.home, self.element, self.by_loop, self.ref,
                       self.expr, self.call, self.rel_R, self.rel_d, self.home_module)


@dataclass(frozen=True, eq=False, slots=True)
class TargetUse:
    """One target of one motion instruction, resolved or not."""

    motion: Motion
    role: str
    label: str                 # e.g. "pPath{3}" or "inline"
    line: int
    kind: str                  # "robtarget" or "jointtarget"
    # base_M_flange: row `row` of its batch's (R (n, 3, 3), p (n, 3) mm),
    # read as R and p (a CAM program's 1e5 uses: no two array views each).
    flange: tuple | None
    row: int | None
    conf: tuple[int, int, int, int] | None
    joints_deg: tuple[float, ...] | None  # jointtarget robax
    reason: str | None         # why it was not resolved
    source: Source | None = None
    tool: tuple | None = None  # (key, (R, p) tframe)
    wobj: tuple | None = None  # (key, (R, p) uframe . oframe)
    env: tuple = ()            # FOR-loop variable values, sorted (name, value)
    blocked: bool = False      # the reason is a gap in the input: not compensated
    file: ParsedFile | None = None
    module: Module | None = None
    ext: tuple[float, ...] = ()  # external axes of the target as written
    key: tuple = ()            # (file index, motion index in the file, role, env)
    notes: tuple[str, ...] = ()  # what was assumed of its values (a quaternion normalised)

    @property
    def R(self) -> np.ndarray | None:
        """base_M_flange rotation."""
        return None if self.flange is None else self.flange[0][self.row]

    @property
    def p(self) -> np.ndarray | None:
        """base_M_flange translation, mm."""
        return None if self.flange is None else self.flange[1][self.row]


# (A CAM program's 1e5 uses: made as their classes make them, construct.py.)
_source, _use = maker(Source), maker(TargetUse)


class _Homes(dict):
    """id(declaration) -> its file (Resolver.home) or module (home_module).
    Where the files hold one module, no entry is made: every declaration's
    is that one (`only`; a CAM program's 1e5 declared targets, ~16 MB of
    entries otherwise)."""

    only = None

    def __missing__(self, key):
        if self.only is None:
            raise KeyError(key)
        return self.only


class _Reentry:
    """Which calls of a routine may run it again before they return
    (recursion, directly or through others; a late-bound call or a routine
    no given module declares, which may call anything), and whether an
    interrupt may run it: where a routine's assignments are not in the
    order its text has them."""

    def __init__(self, files):
        self.calls_by: dict = {}          # (module id, name) -> [(offset, callee name)]
        self.named: dict = {}             # name -> [(module id, name)]
        self.traps: list = []
        for pf in files:
            for m in pf.modules:
                for r in m.routines:
                    key = (id(m), r.name.lower())
                    self.calls_by[key] = list(calls_of(r.node))
                    self.named.setdefault(key[1], []).append(key)
                    if r.node.kind == "TRAP":
                        self.traps.append(key)
        self._reach: dict = {}

    def _reached(self, name: str) -> tuple[frozenset, bool]:
        """The routines a call of `name` may run, and whether it may run
        anything (a late-bound call, a routine not given, on the way)."""
        hit = self._reach.get(name)
        if hit is not None:
            return hit
        seen: set = set()
        anything = False
        todo = [name]
        while todo:
            n = todo.pop()
            if n == LATE or n not in self.named:
                anything = True
                continue
            for key in self.named[n]:
                if key not in seen:
                    seen.add(key)
                    todo.extend(c for _, c in self.calls_by[key])
        hit = self._reach[name] = (frozenset(seen), anything)
        return hit

    def calls(self, key: tuple, others=frozenset()) -> list | None:
        """The offsets of the calls of routine `key` that may run it again,
        or any of the routines `others`; None when an interrupt may run one
        of them (anywhere)."""
        them = others | {key}
        for trap in self.traps:
            reached, anything = self._reached(trap[1])
            if anything or not them.isdisjoint(reached):
                return None
        out = []
        for at, name in self.calls_by[key]:
            reached, anything = self._reached(name)
            if anything or not them.isdisjoint(reached):
                out.append(at)
        return sorted(out)


class Sites(NamedTuple):
    """Where one routine assigns a tool or work object (Resolver.site_map):
    its whole value, or one component of it (rdkTool.tframe := [...]).
    reentries: its calls that may run it again, or another routine that
    assigns the same data (RoboDK: a main program and each program it
    calls assign rdkTool before their own moves)."""

    routine: tuple          # (module id, lower-case routine name)
    starts: list            # the assignments' offsets, in order
    assigns: list           # (ParsedFile, Assign) of each, in that order
    body_end: int           # where the routine's body ends (its handlers follow)
    reentries: list         # offsets of its calls that may run it, or another assigning it
    parts: frozenset = frozenset()   # the components assigned (lower case)
    whole: bool = True      # some assignment is of the whole value
    # Other routines' assignments of the same data, in order: a component
    # they assign that this routine's value does not, or a whole value,
    # may be what the rest of its value is.
    elsewhere: tuple = ()
    # Why this routine's moves are not followed (a GOTO), or None.
    why: str | None = None


# In what a routine runs (Resolver._root_reach): any routine may run.
ANY = ("any routine",)

# The components of PARTS that are no frame (which target a move reaches
# does not depend on them).
_LOADS = frozenset(("tload",))

# The components of a tool or work object a routine may assign a literal to
# (their types): the frames; the rest of the value is the declared one.
PARTS = {"tooldata": {"tframe": "pose", "tload": "loaddata"},
         "wobjdata": {"uframe": "pose", "oframe": "pose"}}


def _part(assign) -> str | None:
    """The component an assignment assigns (lower case), None: the whole."""
    selectors = assign.target.selectors
    return selectors[0].name.lower() if selectors else None


def assigned_name(assign) -> str:
    """The data an assignment assigns, as written: rdkTool, rdkTool.tframe."""
    part = assign.target.selectors
    return assign.target.name + (f".{part[0].name}" if part else "")


def _loop_indexed(motion, *refs) -> Unresolved | None:
    """Why a tool or work object indexed with the variable of an enclosing
    FOR loop is not followed (each iteration may take another element), or
    None."""
    if not motion.loops:
        return None
    names = {lp.var.lower() for lp in motion.loops if lp.var}
    for ref in refs:
        if type(ref) is A.Ref and ref.selectors and names & loop_names(ref, motion.loops):
            return Unresolved(f"{ref.name} is indexed with the variable of an enclosing FOR "
                              "loop (each iteration may take another element): not followed")
    return None


def _data_key(expr, site) -> str:
    """A tool's or work object's key (grouping: one value, one key): its
    name, and where a routine assigns it, the place of the assignment last
    before the move (which decides the assignments its value is made of):
    its file (routines of several modules may assign it) and offset."""
    name = expr.name.lower()
    if site is None:
        return name
    pf, assign = site[-1]
    return f"{name}@{id(pf)}:{assign.span.start}"


def _at_run_time(ref, at: tuple, why: str) -> str:
    """Why a move's tool or work object (ref) is not known: it is assigned
    at run time, at (ParsedFile, Assign), and why that value is not this
    move's."""
    pf, a = at
    return f"{ref.name} is assigned at run time ({_where(pf, a.span.start)}): {why}"


def _place(hit: Sites, at: int) -> tuple:
    """Where offset `at` lies for a routine's assignments (hit): in a
    handler or not, after how many of them, after how many of the calls
    that may run it again; all a move's chain depends on but for its loop
    (Resolver._site_chain)."""
    return at > hit.body_end, bisect_left(hit.starts, at), bisect_right(hit.reentries, at)


def _chain(hit: Sites, k: int) -> tuple | str:
    """The assignments of hit whose values make the one a move after the
    first k of them uses (Resolver._sites), or why that is not known."""
    done = hit.assigns[:k]
    if hit.whole:
        w = next((i for i in range(k - 1, -1, -1) if _part(done[i][1]) is None), None)
        # (No whole value before the move: the one it has where the routine
        # begins is that of an earlier run, or not known.)
        if w is None:
            pf, a = next(x for x in hit.assigns if _part(x[1]) is None)
            return (f"its routine assigns the whole value only after this move "
                    f"({_where(pf, a.span.start)}): the rest is the one it had where the routine "
                    "began")
        return tuple(done[w:])
    assigned = {_part(a) for _, a in done}
    if assigned != hit.parts:
        pf, a = next(x for x in hit.assigns[k:] if _part(x[1]) not in assigned)
        return (f"its routine assigns {assigned_name(a)} only after this move "
                f"({_where(pf, a.span.start)}): that part is the one it had where the routine "
                "began")
    # (Only components: the rest as declared, unless another routine
    # assigns the whole value, or a frame this one does not: a tool's
    # load moves nothing.)
    other = next((x for x in hit.elsewhere if _part(x[1]) not in assigned
                  and _part(x[1]) not in _LOADS), None)
    if other is not None:
        pf, a = other
        if _part(a) is None:
            return (f"another routine assigns the whole {a.target.name} "
                    f"({_where(pf, a.span.start)}), this one only "
                    + ", ".join(sorted(assigned)) + ": the rest of the value is not known here")
        return (f"another routine assigns {assigned_name(a)} ({_where(pf, a.span.start)}), "
                "which this one does not before the move: that frame is not known here")
    return tuple(done)


def _one_value(by_routine: dict) -> bool:
    """Whether every assignment of by_routine's data ({routine: [(pf,
    Assign)]}) gives the part it assigns one and the same literal value (the
    whole value, or each component; not both)."""
    values: dict = {}
    for assigns in by_routine.values():
        for _, a in assigns:
            leaves = literal_leaves(a.value)
            if leaves is None or values.setdefault(_part(a), leaves) != leaves:
                return False
    return None not in values or len(values) == 1


def _components(keys, callees: dict) -> dict:
    """Each routine's strongly connected component of the call graph (an
    id; Tarjan's, without recursion: a chain of 1e4 calls is no limit).
    callees: each routine's distinct callees (no ANY)."""
    index: dict = {}
    low: dict = {}
    comp: dict = {}
    stack: list = []
    on: set = set()
    counter = 0
    for start in keys:
        if start in index:
            continue
        work = [(start, 0)]
        index[start] = low[start] = counter
        counter += 1
        stack.append(start)
        on.add(start)
        while work:
            v, i = work[-1]
            nexts = callees.get(v, ())
            if i < len(nexts):
                work[-1] = (v, i + 1)
                w = nexts[i]
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, 0))
                elif w in on:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                u = work[-1][0]
                low[u] = min(low[u], low[v])
            if low[v] == index[v]:
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp[w] = index[v]
                    if w == v:
                        break
    return comp


def _where(pf, offset: int) -> str:
    """"file:line" of an offset of pf."""
    return f"{pf.source.display_path}:{pf.source.position(offset)[0]}"


# Where an inline target may name data for a part of its value (the
# Grasshopper plugin Robots: [[x,y,z],[q],conf,extj]): item -> (the data's
# type, what the part is called).
# item -> (the data's type, what the part is called, its fields' name).
_NAMED = {"robtarget": {2: ("confdata", "confdata", "robconf"),
                        3: ("extjoint", "external axes", "extax")},
          "jointtarget": {1: ("extjoint", "external axes", "extax")}}


def named_part(expr, item: int) -> str | None:
    """The name of the data an inline target names for its part `item`
    (Resolver._named_axes: 2 a robtarget's confdata, -1 the external axes),
    or None: the part is a literal (or expr is no literal target)."""
    if type(expr) is A.Agg and len(expr.items) in (2, 4) and item < len(expr.items):
        ref = expr.items[item]
        if type(ref) is A.Ref:
            return ref.name
    return None


def _are(what: str) -> str:
    return "are" if what.endswith("s") else "is"


def _a(type_: str) -> str:
    return f"an {type_}" if type_[0] in "aeiou" else f"a {type_}"


class Unresolved(NamedTuple):
    """Why a target, tool or work object has no static value; blocked: the
    input lacks something (a gap to fill), else it is so by design."""

    reason: str
    blocked: bool = False


def compose_pose(a, b):
    return a[0] @ b[0], a[0] @ b[1] + a[1]


def invert_pose(a):
    return a[0].T, -a[0].T @ a[1]


def _compose_many(a, b):
    return a[0] @ b[0], (a[0] @ b[1][..., None])[..., 0] + a[1]


def _invert_many(a):
    Rt = np.swapaxes(a[0], -1, -2)
    return Rt, -(Rt @ a[1][..., None])[..., 0]


def stacked_poses(poses: list) -> tuple[np.ndarray, np.ndarray]:
    """(R (n, 3, 3), p (n, 3)) of poses (R, p), most of them one object (a
    CAM program's tool, work object and base): each distinct pose converted
    once, then copied into place (C order, as the products expect)."""
    if poses and all(map(operator.is_, poses, repeat(poses[0]))):
        # (One pose, as a CAM program's tool, work object and base are: its
        # rows copied, no index per pose.)
        r, v = poses[0]
        R = np.asarray(r, float).reshape(3, 3)
        p = np.asarray(v, float).reshape(3)
        return (np.broadcast_to(R, (len(poses), 3, 3)).copy(),
                np.broadcast_to(p, (len(poses), 3)).copy())
    index: dict[int, int] = {}
    distinct = []
    at = []
    for pose in poses:
        k = index.get(id(pose))
        if k is None:
            k = index[id(pose)] = len(distinct)
            distinct.append(pose)
        at.append(k)
    R = np.array([np.asarray(r, float).reshape(3, 3) for r, _ in distinct]).reshape(-1, 3, 3)
    p = np.array([np.asarray(v, float).reshape(3) for _, v in distinct]).reshape(-1, 3)
    return R[at], p[at]


def flange_stack(uses: list) -> tuple[np.ndarray, np.ndarray]:
    """(R (n, 3, 3), p (n, 3)): the flange poses of resolved robtarget uses,
    as np.array of their R and p makes them (a CAM program's 1e5 rows of
    one batch taken at once)."""
    if not uses:
        return np.zeros((0, 3, 3)), np.zeros((0, 3))
    batch = uses[0].flange
    if all(u.flange is batch for u in uses):
        rows = [u.row for u in uses]
        return batch[0][rows], batch[1][rows]
    return (np.array([u.R for u in uses]).reshape(-1, 3, 3),
            np.array([u.p for u in uses]).reshape(-1, 3))


def flange_poses(base, wobj, target, tool):
    """flange_pose of stacks: each argument (R (n, 3, 3), p (n, 3)). The
    products in the one-pose order and layout (inverses as transposed
    views): each pose bit for bit flange_pose's (tested)."""
    return _compose_many(_compose_many(_invert_many(base), _compose_many(wobj, target)),
                         _invert_many(tool))


def wobj_targets(base, wobj, flange, tool):
    """wobj_M_target of stacks that put the flange at base_M_flange
    (flange_poses inverted): wobj^-1 . (world_M_base . base_M_flange) . tframe."""
    return _compose_many(_compose_many(_invert_many(wobj), _compose_many(base, flange)), tool)


def flange_pose(base, wobj, target, tool):
    """base_M_flange = base_M_world . world_M_wobj . wobj_M_target . tcp_M_flange
    (base: world_M_base; wobj: uframe . oframe; tool: tframe)."""
    return compose_pose(compose_pose(invert_pose(base), compose_pose(wobj, target)),
                        invert_pose(tool))


def unit_parts(v: np.ndarray, float32: bool):
    """(unit quaternions (n, 4), positions (n, 3), confdata (n, 4), ok
    (n,)) of robtargets' values v (n, >= 11) as a resolver reads them
    (float32: one that verifies), with the arithmetic of one target: the
    sums of squares in its order, math.sqrt's correctly rounded root as
    np.sqrt, then unit_wxyz's ** 0.5 on Python floats. ok: no check of
    _confdata, _quaternion or _position stops or notes it."""
    conf = v[:, 7:11]
    qp = v[:, :7].astype(np.float32).astype(float) if float32 else v[:, :7]
    # Contiguous, as poses() of one stack them: a product's bits may
    # depend on the layout of its operands.
    p, q = np.ascontiguousarray(qp[:, :3]), np.ascontiguousarray(qp[:, 3:7])
    w, x, y, z = q.T
    norm = np.sqrt(w * w + x * x + y * y + z * z)
    ok = ((norm > 1e-6) & np.all(np.floor(conf) == conf, axis=1)
          & np.all(np.abs(conf[:, :3]) <= MAX_QUADRANT, axis=1)
          & (conf[:, 3] >= 0) & (conf[:, 3] <= 7))
    if not float32:
        ok &= (np.abs(norm - 1.0) <= QUAT_TOLERANCE) & np.all(np.abs(p) <= MAX_POSITION_MM,
                                                             axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):   # (a zero one is not ok)
        q = np.where((np.abs(norm - 1.0) > 1e-12)[:, None], q / norm[:, None], q)
        w, x, y, z = q.T
        q = q / np.array([s ** 0.5 for s in (w * w + x * x + y * y + z * z).tolist()])[:, None]
    return q, p, conf, ok


def robtarget_flanges(v: np.ndarray, base, wobj, tool, float32: bool, offs=None):
    """(R, p, conf, ok) of robtargets' values v (n, 17) through stacks of
    their bases, work objects and tools (each (R (n, 3, 3), p (n, 3))), as
    poses() composes them: base_M_flange of each, its confdata, and
    whether no check would stop or note it (unit_parts). offs: (rows,
    displacements) of Offs uses, added to their positions as poses() adds
    them (_relative)."""
    q, p, conf, ok = unit_parts(v, float32)
    R = unit_quat_matrices(q)
    if offs is not None:
        rows, d = offs
        p[rows] = p[rows] + d
    Rf, pf = flange_poses(base, wobj, (R, p), tool)
    return Rf, pf, conf, ok


def parse_base(values) -> tuple | None:
    """`--base X,Y,Z,Q1,Q2,Q3,Q4`: world_M_base, mm and a quaternion in
    RAPID order (w, x, y, z)."""
    if values is None:
        return None
    q = np.asarray(values[3:], float)
    n = float(np.linalg.norm(q))
    if not n > 1e-6:
        raise RapidcompError("--base: the orientation Q1..Q4 is not a rotation (norm 0)")
    if abs(n - 1.0) > QUAT_TOLERANCE:
        raise RapidcompError(f"--base: the orientation Q1..Q4 has norm {n:.6f}; expected a unit "
                             "quaternion (w, x, y, z)")
    return quat_wxyz_to_matrix(q / n), np.asarray(values[:3], float)


def parse_track(specs) -> tuple[tuple[int, np.ndarray], ...]:
    """`--track AXIS:x|y|z` options: eax_<AXIS> carries the robot base along
    that world axis (mm; -x etc. for the opposite sense). Returns
    ((axis index, unit vector), ...)."""
    out = []
    for spec in specs or ():
        axis, _, direction = spec.strip().lower().partition(":")
        axis = axis[4:] if axis.startswith("eax_") else axis
        sign, along = (-1.0, direction[1:]) if direction.startswith("-") else (
            1.0, direction.lstrip("+"))
        if len(axis) != 1 or axis not in AXES or along not in ("x", "y", "z"):
            raise RapidcompError(f"--track {spec}: expected AXIS:DIRECTION with AXIS one of "
                                 "a..f (eax_a..eax_f) and DIRECTION x, y or z, e.g. a:x")
        k = AXES.index(axis)
        if any(k == j for j, _ in out):
            raise RapidcompError(f"--track {spec}: axis {axis} given twice")
        vec = np.zeros(3)
        vec["xyz".index(along)] = sign
        out.append((k, vec))
    return tuple(out)


def _name_or_node(expr):
    """A plain name's text (the same data wherever it is written), else
    where the expression is (a move's tool is made when asked, A.TailArgs:
    no identity to key by); None for none."""
    if expr is None:
        return None
    return expr.name if type(expr) is A.Ref and not expr.selectors else expr.span


# An Offs's rotation (a RelTool's before its angles), one array for all
# (read only: an Offs-relative program has one per move).
NO_ROTATION = np.eye(3)
NO_ROTATION.flags.writeable = False
# RelTool's \Rx, \Ry, \Rz.
_TURN = {"rx": rot_x, "ry": rot_y, "rz": rot_z}


def _written_key(src: Source, pf) -> tuple[int, int]:
    """Where src's literal is written: (id(its file), its offset in the
    input), the key of Written (verify.relex makes them so)."""
    return (id(src.home if src.home is not None else pf), src.record.span.start)


class Written:
    """Records as an output writes them, by (id(file), offset of the literal
    in the input): the written program's values on the input's structure
    (verify.relex). A robtarget read by its frame is a row of one array
    (a CAM program writes 1e5: no record, tuple and 17 floats each); its
    record is made only when asked for (again(): Offs/RelTool, a message).
    Others are records."""

    def __init__(self, records: dict, keys: list, values: np.ndarray, where: tuple):
        self.records = records
        self.rows = {k: n for n, k in enumerate(keys)}
        self.values = values              # (n, 17), rows in the order of keys
        # Columns, a row each: the input record, the output's text, the
        # literal's start and end there.
        self.where = where
        # Use key -> what it reads where the output gives that use a copy
        # of its target (verify.relex_copies), not the literal its name
        # reads in the input: a record, or a robtarget read plainly as
        # (its numbers' array, its row, the output's text, the literal's
        # start and end there): no record and tuple of 17 floats each for
        # 1e5 copies (a program whose every move is an Offs of one target).
        self.uses: dict = {}

    def __bool__(self) -> bool:
        return bool(self.records) or bool(self.rows) or bool(self.uses)

    def copy(self, key, span):
        """The record use `key` reads as its copy (span: its input record's,
        as the record's), or None."""
        got = self.uses.get(key)
        if type(got) is not tuple:
            return got
        values, k, text, start, end = got
        return RobTarget(tuple(values[k].tolist()), text[start:end], span)

    def copy_values(self, key):
        """The 17 numbers of the robtarget use `key` reads as its copy, a
        row of an array or a record's tuple; None where it reads none or a
        jointtarget."""
        got = self.uses.get(key)
        if got is None:
            return None
        if type(got) is tuple:
            return got[0][got[1]]
        return got.values if isinstance(got, RobTarget) else False

    def row(self, key) -> int | None:
        return self.rows.get(key)

    def get(self, key, default=None):
        record = self.records.get(key)
        if record is not None:
            return record
        n = self.rows.get(key)
        if n is None:
            return default
        recs, texts, starts, ends = self.where
        rec = recs[n]
        return type(rec)(tuple(self.values[n].tolist()), texts[n][starts[n]:ends[n]], rec.span)

    def __getitem__(self, key):
        record = self.get(key)
        if record is None:
            raise KeyError(key)
        return record


class Resolver:
    """Resolves motion targets of `files` (the task's modules, then --with
    modules). With float32=True every number is first rounded to a 32-bit
    float, as the controller stores it (used to verify written output)."""

    def __init__(self, files: list[ParsedFile], float32: bool = False,
                 usages: dict | None = None, writes: bool = True, track=(), base=None,
                 observers=(), moved_by: str | None = None, written: Written | None = None,
                 like: "Resolver | None" = None, states: tuple[float, ...] = (),
                 events: tuple[str, ...] = (), entry: str = "main", unreadable=(),
                 unlisted=()):
        """like: a resolver of these very files (the plan's, for verify.py):
        its tables of the files' declarations are taken, not made again.
        states: the thermal states a transient output is read at, each in
        turn (self.state, one of them): its rcTcJ/rcTcR(cold, dq) are
        evaluated there as the controller does (_at_state). events: the
        routines the controller runs at events (a backup's SYS.cfg), lower
        case; entry: the routine the program starts at (main unless a
        backup's SYS.cfg names another); unreadable: the task's modules
        that cannot be read (encrypted), where a name no given module
        declares may be; unlisted: a backup's module files its backinfo.txt
        does not list (not read: a restore does not load them), where such
        a name may be too."""
        self.float32 = float32
        self.unreadable = tuple(unreadable)
        self.unlisted = tuple(unlisted)
        self.events = frozenset(events)
        self.entry = entry
        self.states = tuple(states)
        self.state: float | None = None
        # (call, its FOR loops' values) -> (the Source of its cold value, its
        # values at each of self.states), or why not: read once, not per state.
        self._at_states: dict = {}
        self.files = list(files)
        # Records as an output writes them (verify.py, when every edit is of
        # numeric fields).
        self.written = (written if written is not None
                        else Written({}, [], np.empty((0, 17)), ([], [], [], [])))
        self._memos: dict = {}
        self._pairs: dict = {}                  # _tool_wobj's
        # _site_chain's, by what decides it (a RoboDK program's 1e5 moves
        # come after the same few assignments), and _data_id's.
        self._chains: dict = {}
        self._tail_sites: dict = {}             # _tool_wobj's
        self._data_ids: dict = {}
        # _tool_wobj's of a move lexed as one token, by its shared tail.
        self._tails: dict = {}
        self._confs: dict = {}                  # _conf's: confdata numbers -> ints
        self._records: dict | None = None       # _component_type's: RECORD name -> components
        # Tools and work objects a routine assigns literals to (site_map).
        self._site_map: dict | None = None
        # What each routine nothing calls runs (_root_reach: made where needed).
        self._roots: tuple | None = None
        # id -> (the declaration given an assigned value, the file of the
        # assignment): kept, so the id stays its own (self.home, which a
        # resolver of the same files shares, is not written).
        self._assigned: dict = {}
        # id -> the key of a tool or work object array's element (_element):
        # its name and indices, one key per value.
        self._elements: dict = {}
        # The names the plan found so (verify.py: a resolver of the output,
        # which knows no writes, finds their assignments there).
        self.site_names: frozenset = frozenset()
        # Robtarget uses whose flange pose is composed in one batch (poses()).
        self._pending: list = []
        self.track = tuple(track)
        self.moved_by = moved_by
        self.base = base if base is not None else IDENTITY_POSE   # world_M_base at track 0
        # Global data by lower-case name: its declaration, a list where two
        # or more modules declare it (1e5 targets: no list each).
        self.globals: dict[str, Declaration | list[Declaration]] = {}
        self.module_decls: dict[tuple[int, str], Declaration] = {}
        self.routine_decls: dict[tuple[int, str, str], Declaration] = {}
        self.params: dict[tuple[int, str], set[str]] = {}
        self.home: dict[int, ParsedFile] = _Homes()
        self.home_module: dict[int, Module] = _Homes()
        self.writes = Writes({}, None)         # what the task changes at run time
        self.pers_anything: str | None = None  # another task may change any PERS
        self.shared: frozenset = frozenset()   # PERS names other tasks refer to
        self.usages: dict[int, object] = {}   # id(Module) -> refs.Usage
        self._notes: list[str] = []             # of the use being resolved
        self._guarded: set = set()              # FOR variables of the use behind a condition
        self._loop_vars: frozenset = frozenset()  # FOR variables around the use (_in_loops)
        self._hidden: dict | None = None        # LOCAL module data by name (_not_declared)
        self._turns: dict = {}                  # RelTool's rotations -> matrix (_offset)
        self._consts: list = []                 # CONST nums being evaluated (integer())
        # A use's confdata and external axes as one tuple per distinct value
        # (a CAM program's 1e5 uses have a few: ~15 MB).
        self._same: dict = {}
        self._same_floats: dict = {}
        if like is not None and len(like.files) == len(self.files) and all(
                a is b for a, b in zip(like.files, self.files)):
            # (5e4 declarations of a CAM program: the same tables.)
            self.params, self.home, self.home_module = like.params, like.home, like.home_module
            self.module_decls, self.globals = like.module_decls, like.globals
            self.routine_decls = like.routine_decls
        else:
            self._tables()
        for pf in files:
            for m in pf.modules:
                mid = id(m)
                us = usages.get(mid) if usages is not None else None
                if us is None:
                    if not writes:
                        continue
                    us = usage(m.node)
                self.usages[mid] = us
        if writes or usages is None:
            self._task_writes(files, observers)
        # (The other tasks' modules: flow.py asks whether any reads where
        # this task's robot is, CRobT(\\TaskName:=...).)
        self.observers = tuple(observers)

    def _tables(self) -> None:
        """The files' declarations by where their names are seen, and the
        routines' parameters."""
        one = sum(len(pf.modules) for pf in self.files) == 1
        if one:
            (self.home.only,) = self.files
            (self.home_module.only,) = self.files[0].modules
        for pf in self.files:
            for m in pf.modules:
                mid = id(m)
                for r in m.routines:
                    self.params[(mid, r.name.lower())] = {p.name.lower() for p in r.node.params}
                for d in m.declarations:
                    if not one:
                        self.home[id(d)] = pf
                        self.home_module[id(d)] = m
                    name = d.name.lower()
                    if d.routine is None:
                        self.module_decls.setdefault((mid, name), d)
                        if d.scope != "LOCAL":
                            got = self.globals.get(name)
                            if got is None:
                                self.globals[name] = d
                            elif type(got) is Declaration:
                                self.globals[name] = [got, d]
                            else:
                                got.append(d)
                    else:
                        self.routine_decls[(mid, d.routine.lower(), name)] = d

    def _num(self, values) -> np.ndarray:
        a = np.asarray(values, float)
        return a.astype(np.float32).astype(float) if self.float32 else a

    def _floats(self, values) -> list[float]:
        """_num as Python floats (a few of them: no array needed)."""
        if self.float32:
            return np.asarray(values, np.float32).tolist()
        return [float(v) for v in values]

    def _pose(self, pose: Pose, pf: ParsedFile, what: str):
        q = self._quaternion(pose.quat_wxyz, pose.rot[0].span.start, pf, what)
        return quat_wxyz_to_matrix(q), np.array(self._position(
            pose.xyz, pose.trans[0].span.start, pf, what))

    def _position(self, xyz, offset, pf: ParsedFile, what: str) -> np.ndarray:
        """A position a move uses: within 100 m (nothing in a robot cell is
        further; a larger number is a unit or data error). offset: where it
        is written (or a function giving it: a compact literal's fields are
        lexed again only for a message)."""
        p = self._floats(xyz)
        # The bound is a plausibility check of input. Verification reads
        # rapidcomp's own output, where compensation may move a position
        # that was within it a fraction of a millimetre past it.
        if not self.float32 and not all(abs(v) <= MAX_POSITION_MM for v in p):
            raise pf.source.error(_at(offset), f"{what}: the position [{', '.join(f'{v:g}' for v in p)}] "
                                          f"mm is beyond {MAX_POSITION_MM:g} mm of the robot")
        return p

    def _quaternion(self, q, offset: int, pf: ParsedFile, what: str) -> np.ndarray:
        """A quaternion of a value a move uses: none with no rotation (bad
        input); one far from unit length normalised, with a note (the
        controller would complain about it)."""
        q = self._floats(q)
        norm = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
        if not norm > 1e-6:
            raise pf.source.error(_at(offset), f"{what}: the orientation [{', '.join(f'{v:g}' for v in q)}] "
                                          "is not a rotation (norm 0); expected a unit quaternion")
        if abs(norm - 1.0) > QUAT_TOLERANCE and not self.float32:
            line = pf.line(A.Span(_at(offset), _at(offset)))
            self._notes.append(f"{what} ({pf.source.display_path}:{line}): quaternion norm "
                               f"{norm:.7g}, not 1 (the controller expects a unit quaternion); "
                               "normalised")
        return [v / norm for v in q] if abs(norm - 1.0) > 1e-12 else q

    def lookup(self, name: str, module: Module, routine: str | None):
        """The declaration a name means in a routine of a module, None when
        no given module declares it, or Unresolved (a routine parameter, an
        ambiguous global)."""
        key = name.lower()
        mid = id(module)
        if routine is not None:
            d = self.routine_decls.get((mid, routine.lower(), key))
            if d is not None:
                return d
            if key in self.params.get((mid, routine.lower()), ()):
                return Unresolved(f"{name} is a parameter of routine {routine} (its value "
                                  "comes from the caller)")
        d = self.module_decls.get((mid, key))
        if d is not None and d.scope == "LOCAL":
            return d
        found = self.globals.get(key)
        if found is None:
            return d
        if type(found) is Declaration:
            # (One module declares it: this one's, which it is, or another's.)
            return found
        # Global data of one name in two modules: the controller refuses to
        # load the task. PERS of one type are one shared object: allowed, but
        # which initial value it holds depends on the load order unless they
        # are all the same. A PERS declared without one (`PERS tooldata t;`)
        # takes the value the others give it.
        valued = [x for x in found if x.node.init is not None] or found
        if len(found) > 1 and not (all(x.storage == "PERS" and x.type == found[0].type
                                       for x in found) and _same_values(valued, self.home)):
            where = ", ".join(f"{self.home[id(x)].source.display_path}:"
                              f"{self.home[id(x)].line(x.span)}" for x in found)
            what = ("PERS with different values" if all(x.storage == "PERS" for x in found)
                    else "globally more than once")
            return Unresolved(f"{name} is declared {what} ({where})", True)
        if d is not None and (d.node.init is not None or valued is found):
            return d
        return valued[0]

    def _not_declared(self, name: str, what: str = "") -> Unresolved:
        """Why no declaration a move sees gives `name` a meaning: another
        module's LOCAL one, which its own module alone sees (the controller
        does not load such a task: a reference error); else no given module
        declares it (the rest of the task is missing)."""
        if self._hidden is None:
            # (Once: the LOCAL module data of every module, by name.)
            self._hidden = {}
            for (_, key), d in self.module_decls.items():
                if d.scope == "LOCAL":
                    self._hidden.setdefault(key, []).append(d)
        hidden = self._hidden.get(name.lower())
        if hidden:
            where = ", ".join(f"{self.home[id(d)].source.display_path}:"
                              f"{self.home[id(d)].line(d.span)}" for d in hidden)
            return Unresolved(f"{what}{name} is declared LOCAL in another module ({where}), "
                              "which alone sees it: the controller does not load this task (a "
                              "reference error)", True)
        if self.unreadable:
            # (Not a gap the user can fill: the module is there, unread.)
            return Unresolved(f"{what}{name} is not declared in the modules rapidcomp can read "
                              f"(it may be in {', '.join(self.unreadable)}, which is encrypted); "
                              "left as written")
        if self.unlisted:
            # (The controller, restoring the backup, does not declare it
            # either: the program as the backup lists it does not load.)
            return Unresolved(f"{what}{name} is not declared in the modules the backup's "
                              "BACKINFO/backinfo.txt lists (it may be in "
                              f"{', '.join(self.unlisted)}, which it does not list, so a "
                              "restore does not load it either: list it there, or give the "
                              "declaring module with --with)", True)
        return Unresolved(f"{what}{name} is not declared in the given modules ({MISSING_HINT})",
                          True)

    # ------------------------------------------------------------ tool / wobj
    def _builtin(self, d, expr, cls, what: str):
        """None: the controller's own tool0 or wobj0 (the identity, which its
        BASE module declares) where no given module declares one of that
        name; Unresolved where a module declares one globally with another
        literal value: which of the two the controller takes is not known
        here, and the move is left as written rather than compensated at a
        place that may be wrong; else the declaration, read as any data of
        the program (a LOCAL or routine's own hides the controller's; one
        declared as the identity is that data, and what assigns it is
        followed). d: what the name means where the move is (lookup())."""
        if type(d) is not Declaration:
            return None
        v = d.value
        if (d.routine is not None or d.scope == "LOCAL" or not isinstance(v, cls)
                or ((v.robhold.value is True and _identity(v.tframe)) if cls is ToolData else
                    (v.robhold.value is False and v.ufprog.value is True
                     and _identity(v.uframe) and _identity(v.oframe)))):
            return d
        pf = self.home[id(d)]
        return Unresolved(f"{what} {expr.name} is declared at {pf.source.display_path}:"
                          f"{pf.line(d.node.span)} with another value than the controller's own "
                          f"{expr.name.lower()} (the identity, which its BASE module declares): "
                          "which of the two the controller takes is not known here")

    def _data(self, expr, module, routine: str, builtin: str, cls, what: str, site=None):
        """The literal value of a tool/work object argument, None for the
        built-in one, or Unresolved. site: the assignments ((ParsedFile,
        Assign), in order) whose values make the one the move uses
        (_sites), for data the program assigns: a whole value, then
        components of it; or components of the declared value."""
        if type(expr) is not A.Ref:
            return Unresolved(f"the {what} is not a plain data name")
        d = self.lookup(expr.name, module, routine)
        if expr.name.lower() == builtin and not expr.selectors:
            own = self._builtin(d, expr, cls, what)
            if type(own) is not Declaration:
                return own
        if isinstance(d, Unresolved):
            return d
        if d is None:
            return self._not_declared(expr.name, f"{what} ")
        if expr.selectors:
            return self._element(expr, d, module, routine, cls, what, site)
        if not isinstance(d.value, cls):
            if d.type != cls.__name__.lower():
                return Unresolved(f"{expr.name} is a {d.type}, not {what} data", True)
            return Unresolved(f"{what} {expr.name} has no literal value "
                              f"({d.issue or 'run-time data'})")
        if site is not None:
            value = d.value
            # The file each part of the value is read from (messages say
            # where): a component the routine assigns, its assignment's;
            # the rest, the whole value's assignment's, or the declaration's.
            homes = {None: site[0][0] if _part(site[0][1]) is None else self.home[id(d)]}
            for pf, assign in site:
                part = _part(assign)
                homes[part] = pf
                try:
                    if part is None:
                        value = decode(d.type, assign.value, d.name)
                    elif part not in PARTS.get(d.type, ()):
                        raise DecodeIssue(f"a {d.type} has no component {part} whose "
                                          "frame rapidcomp reads", assign.target.span)
                    else:
                        value = replace(value, **{part: decode(
                            PARTS[d.type][part], assign.value, f"{d.name}.{part}")})
                except DecodeIssue as exc:
                    return Unresolved(f"{assigned_name(assign)} is assigned a value rapidcomp "
                                      f"cannot read ({pf.source.display_path}:"
                                      f"{pf.line(assign.span)}: {exc})")
            d = replace(d, value=value)
            self._assigned[id(d)] = (d, homes)
            return d
        written = self._written(d)
        return Unresolved(written) if written else d

    def _element(self, expr, d: Declaration, module, routine, cls, what: str, site):
        """_data of an element of a tool or work object array named with
        fixed indices (`tGrip{2}`: literals or CONST nums), or Unresolved:
        its declared value, where nothing writes the array."""
        sel = expr.selectors
        index = (None if len(sel) != 1 or type(sel[0]) is not A.Index else
                 [self.integer(i, module, routine) for i in sel[0].indices])
        if index is None or None in index:
            return Unresolved(f"the {what} is not a plain data name, nor an element of an array "
                              "with fixed indices")
        if site is not None:
            return Unresolved(f"{what} {expr.name} is an array the program assigns: its "
                              "elements are not followed")
        dims = d.dims
        if None in dims:
            return Unresolved(f"{what} {expr.name} is an array whose size is not a literal")
        if not dims or type(d.value) is not tuple or not all(
                isinstance(v, cls) for v in d.value):
            if d.type != cls.__name__.lower():
                return Unresolved(f"{expr.name} is a {d.type}, not {what} data", True)
            if not dims:
                return Unresolved(f"{what} {expr.name} is not an array", True)
            return Unresolved(f"{what} {expr.name} has no literal value "
                              f"({d.issue or 'run-time data'})")
        if len(index) != len(dims):
            raise self._file_of(module).source.error(
                sel[0].span.start, f"{expr.name} has {len(dims)} dimensions, indexed with "
                f"{len(index)}")
        if not all(1 <= i <= n for i, n in zip(index, dims)):
            # (As a target's index beyond its array: the controller stops
            # there with ERR_INDEX.)
            pf = self._file_of(module)
            shown = ",".join(map(str, index))
            at = next((e.span.start for e, i, n in zip(sel[0].indices, index, dims)
                       if not 1 <= i <= n), sel[0].span.start)
            raise pf.source.error(at, f"{what} {expr.name}{{{shown}}} is beyond "
                                  f"the array's bounds {{{','.join(map(str, dims))}}}: the "
                                  "controller stops here with ERR_INDEX")
        written = self._written(d)
        if written:
            return Unresolved(written)
        flat = 0
        for i, n in zip(index, dims):
            flat = flat * n + (i - 1)
        # (The element as data of its own: its file is the array's.)
        e = replace(d, value=d.value[flat])
        self._assigned[id(e)] = (e, {None: self.home[id(d)]})
        self._elements[id(e)] = f"{d.name.lower()}{{{','.join(map(str, index))}}}"
        return e

    def _file_of(self, module) -> ParsedFile:
        """The file holding a module (for a message's place)."""
        return next(f for f in self.files if any(m is module for m in f.modules))

    def site_map(self) -> dict:
        """Tool and work object names whose every assignment is a literal
        (of the whole value or of one component) and a statement of a
        routine's body itself -> {each data of that name (_data_id): the
        Sites of each routine that assigns it ({routine key: Sites}), or
        why none of its moves is followed (an interrupt or a service or
        event routine may change it: _sites_of)}. Names only ever assigned
        their own declared value are left out (that value, everywhere).
        Made once."""
        sites = self._site_map
        if sites is not None:
            return sites
        sites = self._site_map = {}
        # (Not where a name computed at run time may be written: any data
        # may change then.)
        literal = (self.writes.literal if self.writes.anything is None
                   and self.pers_anything is None else {})
        if not literal and not self.site_names:
            return sites
        body, ends, jumps, names, modules = {}, {}, set(), {}, {}
        found: dict = {}        # (the output: the plan's names, assigned where they were)
        for pf in self.files:
            for m in pf.modules:
                for r in m.routines:
                    key = (id(m), r.name.lower())
                    names[key] = r.name
                    modules[key] = m
                    # Where the body ends: a move in a handler runs after an
                    # error anywhere, before an assignment too.
                    ends[key] = r.node.body[-1].span.end if r.node.body else -1
                    if any(type(n) is A.Simple and n.kind == "GOTO" for n in statements(r.node)):
                        jumps.add(key)
                    for st in r.node.body:
                        body[id(st)] = key
                        if (not literal and type(st) is A.Assign
                                and st.target.name.lower() in self.site_names
                                and (not st.target.selectors
                                     or (len(st.target.selectors) == 1
                                         and type(st.target.selectors[0]) is A.Component))):
                            found.setdefault(st.target.name.lower(), []).append((pf, st))
        reentry = _Reentry(self.files)
        # (The output's resolver, which knows no writes, follows the names
        # the plan followed: a move the plan left as written is not verified,
        # and a service routine is the plan's to find.)
        moves_with = self._moves_with() if literal else None
        for name, assigns in (literal or found).items():
            # (By the data each assigns: a LOCAL declaration of a module or
            # routine is data of its own, as RoboDK's LOCAL PERS rdkTool in
            # each program's module; global data of one name is one.)
            by_data: dict = {}
            for pf, a in assigns:
                routine = body.get(id(a))
                data = (None if routine is None else
                        self._data_id(a.target.name, modules[routine], names[routine]))
                by_data.setdefault(data, {}).setdefault(routine, []).append((pf, a))
            if None in by_data or (literal and self._only_itself(name)):
                continue
            sites[name] = {data: self._sites_of(data, by_routine, reentry, moves_with, jumps,
                                                ends, names)
                           for data, by_routine in by_data.items()}
        return sites

    def _data_id(self, name: str, module: Module, routine: str | None):
        """Which data a name means in a routine: its LOCAL declaration
        (module's or routine's), else the name (global data of one name is
        one, PERS shared)."""
        key = (name, id(module), routine)
        got = self._data_ids.get(key)
        if got is None:
            d = self.lookup(name, module, routine)
            got = self._data_ids[key] = (
                id(d) if type(d) is Declaration and (d.routine is not None or d.scope == "LOCAL")
                else name.lower())
        return got

    def _sites_of(self, data, by_routine: dict, reentry: _Reentry, moves_with: dict | None,
                  jumps: set, ends: dict, names: dict) -> dict | str:
        """site_map's entry of one data the routines by_routine assign:
        {routine key: Sites}, or why no move of it is followed."""
        # (Each routine's moves take the value it assigns itself: a call
        # between that may run any routine assigning it, this one
        # again included, changes the value.)
        here: dict | str = {}
        them = frozenset(by_routine)
        for routine, mine in by_routine.items():
            risky = reentry.calls(routine, them)
            if risky is None:
                pf, a = mine[0]
                here = (f"{a.target.name} is assigned at run time ({_where(pf, a.span.start)})"
                        " by a routine an interrupt may run: at any moment")
                break
            ordered = sorted(mine, key=lambda x: x[1].span.start)
            parts = [_part(a) for _, a in ordered]
            elsewhere = tuple(x for r, xs in by_routine.items() if r != routine for x in xs)
            here[routine] = Sites(
                routine, [a.span.start for _, a in ordered], ordered, ends[routine], risky,
                frozenset(parts) - {None}, None in parts, elsewhere,
                "its routine has a GOTO (its body may run out of order)"
                if routine in jumps else None)
        # A routine nothing calls, other than the program's entry, that
        # runs a routine assigning the data (itself, or through others; or
        # anything, late-bound), is a service or event routine: it may run
        # while the program is stopped, between any two statements, and
        # take back or change the value the moves after take.
        if type(here) is dict and moves_with is not None:
            roots = self._roots
            if roots is None:
                roots = self._roots = self._root_reach(reentry)
            mains, reach, where = roots
            movers = {key for key, used in moves_with.items() if data in used}
            # (Without a main, each routine nothing calls that runs a move
            # with the data is a program: RoboDK's, entered by PP to routine;
            # of several LOCAL mains, those that do.)
            if len(mains) > 1:
                programs = [r for r in mains if not reach[r].isdisjoint(movers)] or mains
            else:
                programs = mains or [r for r in reach if not reach[r].isdisjoint(movers)]
            # (Where every assignment gives each part it assigns one and the
            # same value, a routine run at a stop assigns that value again:
            # nothing changes.)
            same = _one_value(by_routine)
            for root, runs in reach.items():
                if root in programs:
                    continue
                hit = None if same else next((r for r in by_routine if r in runs), None)
                if hit is None and ANY not in runs:
                    continue
                if hit is None:
                    pf, a = next(iter(by_routine.values()))[0]
                    return (f"{a.target.name} is assigned at run time "
                            f"({_where(pf, a.span.start)}), and {names[root]} "
                            f"({where[root]}), which no given routine calls and that is not "
                            f"the program's entry ({self.entry}, or where no module has one, a routine "
                            "that moves with it), may run any routine (a late-bound call, or "
                            "one no given module declares): a service or event routine, it "
                            "may run while the program is stopped")
                pf, a = by_routine[hit][0]
                if root[1] in self.events:
                    who = ("which is an event routine" if hit == root else
                           f"which {names[root]} ({where[root]}), an event routine, runs")
                    return (f"{a.target.name} is assigned at run time by {names[hit]} "
                            f"({_where(pf, a.span.start)}), {who} (SYSPAR/SYS.cfg "
                            "CAB_EXEC_HOOKS, Event Routine): it may run at a stop or a restart, "
                            "between any two statements")
                who = ("which" if hit == root else
                       f"which {names[root]} ({where[root]}) runs, a routine that")
                return (f"{a.target.name} is assigned at run time by {names[hit]} "
                        f"({_where(pf, a.span.start)}), {who} no given routine calls and "
                        f"that is not the program's entry ({self.entry}, or where no module has "
                        "one, a routine that moves with it): a service or event routine, "
                        "it may run while the program is stopped")
        return here

    def _root_reach(self, reentry: _Reentry) -> tuple[list, dict, dict]:
        """(the program's entries, {each routine no other routine calls, but
        an interrupt's: the routines it runs, itself among them, or ANY
        where it may run any (a late-bound call, a routine no given module
        declares)}, {each routine: "file:line" of it}). The entries: main (a
        LOCAL main only where no other is), called or not. An event routine
        (self.events) is a root, called or not. A routine is
        called where another calls it that it does not run itself (a
        routine calling itself, or routines calling each other, are
        entered from outside all the same). Calls resolved as the
        controller resolves them (the calling module's own routine first)."""
        table = RoutineTable()
        keys: dict = {}                 # routine key -> (its module, its node)
        where: dict = {}
        for pf in self.files:
            for m in pf.modules:
                for r in m.routines:
                    key = (id(m), r.name.lower())
                    keys.setdefault(key, (m, r.node))
                    where.setdefault(key, _where(pf, r.node.span.start))
                    table.add(m, r, (m, key))
        callees: dict = {}              # routine key -> the routines it calls, or ANY among them
        for key, (m, _) in keys.items():
            out = {}                    # (distinct, in the order called: a CAM-like routine
            for _, name in reentry.calls_by.get(key, ()):   # calls one 1e4 times)
                hit = table.find(m, name) if name != LATE else None
                out[hit[1] if hit is not None else ANY] = None
            callees[key] = list(out)
        # Called from outside: by a routine of another strongly connected
        # component (a routine calling itself, or routines calling each
        # other, are entered from outside all the same).
        comp = _components(keys, {k: [c for c in cs if c is not ANY]
                                  for k, cs in callees.items()})
        inside = {comp[c] for k in keys for c in callees[k]
                  if c is not ANY and comp[c] != comp[k]}
        entry = self.entry.lower()
        mains = [k for k, (_, n) in keys.items() if k[1] == entry and n.scope != "LOCAL"]
        mains = mains or [k for k in keys if k[1] == entry]
        # (In text order, as keys are: a reason names the first it finds.
        # An event routine is entered from outside, called or not.)
        roots = [k for k, (_, n) in keys.items() if n.kind != "TRAP"
                 and (k in mains or comp[k] not in inside or k[1] in self.events)]
        reach: dict = {}
        for root in roots:
            seen = {root}
            todo = [root]
            while todo:
                for callee in callees.get(todo.pop(), ()):
                    if callee not in seen:
                        seen.add(callee)
                        if callee is not ANY:
                            todo.append(callee)
            reach[root] = seen
        return mains, reach, where

    def _moves_with(self) -> dict:
        """(module id, lower-case routine name) -> the data (_data_id) of
        the tools and work objects its moves name."""
        out: dict = {}
        seen: dict = {}                 # (a CAM program's 1e5 moves name a few)
        for pf in self.files:
            for m in pf.modules:
                for mo in m.motions:
                    routine = mo.routine or ""
                    datas = out.setdefault((id(m), routine.lower()), set())
                    for ref in (mo.tool, mo.wobj):
                        if type(ref) is A.Ref:
                            k = (id(m), routine, ref.name)
                            data = seen.get(k)
                            if data is None:
                                data = seen[k] = self._data_id(ref.name, m, mo.routine)
                            datas.add(data)
        return out

    def _home_of(self, d: Declaration, part: str | None = None) -> ParsedFile:
        """The file of d's value (of its component `part`): its
        declaration's, or the assignment's."""
        hit = self._assigned.get(id(d))
        if hit is None:
            return self.home[id(d)]
        return hit[1].get(part, hit[1][None])

    def _assigned_anywhere(self) -> bool:
        """Whether a routine may assign a tool or work object a literal
        (this task's writes, or the names the plan found so): else no
        move's tool or work object depends on where the move is."""
        return bool(self.writes.literal or self.site_names)

    def _sites(self, motion, module) -> tuple | None:
        """For a move's tool and work object, each the assignments whose
        values make the one it uses ((ParsedFile, Assign), in order), why
        its value is not known (a string: the move is left as written), or
        None: not such data. Followed where all assignments of that data
        are literals, of the whole value or of one component, each a
        statement of a routine's body
        itself (not in a block or a handler: RoboDK's `rdkTool := [...]` or
        `rdkTool.tframe := [...]` before its moves, in each program), the
        move lies in the body of a routine that assigns it, after those
        assignments, and no call after the first of them may run that
        routine again, or another that assigns it, before the move (the
        routine runs its body in order: whatever ran before it, the move
        uses that value). Its
        value is the whole value assigned last before it, with the
        components assigned after that; where the routine assigns no whole
        value, the declared one with the components assigned before it,
        each component the routine assigns among them (else the value it
        has where the routine begins is not known), and where another
        routine assigns the data, the components it assigns among them.
        None when neither is such data (the common case: memoised
        lookups)."""
        # (No literal assignment, and none the plan found: no site map made.)
        if not self._assigned_anywhere():
            return None
        sites = self.site_map()
        if not sites:
            return None
        out = []
        routine = (id(module), (motion.routine or "").lower())
        for ref in (motion.tool, motion.wobj):
            entry = self._site_entry(sites, ref, module, motion.routine)
            if type(entry) is dict:
                entry = self._site_chain(ref, entry, routine, motion)
                # (The output's resolver takes the plan's word: a move the
                # plan left as written is not verified.)
                if type(entry) is str and not self.writes.literal:
                    entry = None
            out.append(entry)
        return tuple(out) if out[0] is not None or out[1] is not None else None

    def _site_entry(self, sites: dict, ref, module, routine: str | None):
        """site_map()'s entry for the data a tool or work object argument
        names in a routine: {routine key: Sites}, why its moves are not
        followed, or None."""
        entry = sites.get(ref.name.lower()) if type(ref) is A.Ref and not ref.selectors else None
        # (The data the name means here; one no routine assigns a literal to
        # goes the common way: _written says why.)
        return None if entry is None else entry.get(self._data_id(ref.name, module, routine))

    def _site_chain(self, ref, by_routine: dict, routine: tuple, motion) -> tuple | str:
        """_sites of one tool or work object the routines by_routine
        assign: the chain, or why the value is not known (a reason the move
        is left untouched with)."""
        hit = by_routine.get(routine)
        if hit is not None:
            # (The chain depends on the move only through where it lies among
            # its routine's assignments and the calls that may run it again,
            # whether in a handler, and whether in a loop.)
            key = (id(hit), ref.name, *_place(hit, motion.span.start), bool(motion.loops))
            got = self._chains.get(key)
            if got is None:
                got = self._chains[key] = self._site_chain_of(ref, hit, motion)
            return got
        return _at_run_time(ref, next(iter(by_routine.values())).assigns[0],
                            "by other routines, not by this move's own: its value here is the "
                            "one some routine left")

    def _site_chain_of(self, ref, hit: Sites, motion) -> tuple | str:
        """_site_chain of a move in a routine that assigns the data (hit)."""
        def unknown(why: str, at=None) -> str:
            return _at_run_time(ref, at or first, why)

        first = hit.assigns[0]
        if hit.why is not None:
            return unknown(hit.why)
        if motion.span.start > hit.body_end:
            return unknown("this move is in a handler of its routine (ERROR, UNDO or "
                           "BACKWARD), which may run before any of its assignments")
        k = bisect_left(hit.starts, motion.span.start)
        if not k:
            return unknown("this move comes before its routine assigns it: the value is the "
                           "one it had where the routine began")
        chain = _chain(hit, k)
        if type(chain) is str:
            return unknown(chain, hit.assigns[k - 1])
        # A call that may run the routine again, or another that assigns
        # the data, after the first assignment the value is made of: the
        # value is not known where the call lies before the move (in the
        # move's own statement too: its arguments are evaluated before it
        # moves), or runs before the move again (later in the move's
        # loop: before its next round; in an error handler: RETRY runs
        # the statement again).
        if hit.reentries:
            later = hit.reentries[bisect_right(hit.reentries, chain[0][1].span.start):]
            if later:
                pf = first[0]
                if later[0] <= motion.span.start:
                    return unknown(f"the call at line {pf.source.position(later[0])[0]} may "
                                   "assign it again before this move", chain[-1])
                if motion.loops:
                    return unknown(f"the call at line {pf.source.position(later[0])[0]} may "
                                   "assign it again before this move's loop runs it again",
                                   chain[-1])
                if later[-1] > hit.body_end:
                    return unknown(f"the call at line {pf.source.position(later[-1])[0]}, in "
                                   "a handler of its routine, may assign it again before a "
                                   "RETRY runs this move again", chain[-1])
        return chain

    def _task_writes(self, files, observers) -> None:
        """What the task may change at run time, and what the controller's
        other tasks may change of its PERS data (shared between tasks);
        which PERS the other tasks refer to (editing their value in place
        would change it for them too)."""
        self.writes = task_writes(files, self.usages)
        if not observers:
            return
        pers = {name for name, ds in self.globals.items()
                if any(d.storage == "PERS" for d in ((ds,) if type(ds) is Declaration else ds))}
        theirs = {id(m): usage(m.node) for pf in observers for m in pf.modules}
        other = task_writes(list(observers), theirs)
        by_name = dict(self.writes.by_name)
        for name, (pf, span, how) in other.by_name.items():
            if name in pers:
                # (Said by the other task's write: this task's own may be
                # one rapidcomp follows.)
                by_name[name] = (pf, span, f"{how} in another task")
        # (Data only this task assigns literals to stays followed: a backup's
        # other tasks that never write it change nothing.)
        literal = {name: assigns for name, assigns in self.writes.literal.items()
                   if not (name in pers and name in other.by_name)}
        self.writes = Writes(by_name, self.writes.anything, literal, self.writes.assigned)
        if other.anything is not None and pers:
            pf, span, what = other.anything
            self.pers_anything = (f"may be changed at run time by {what} with a name computed at "
                                  f"run time in another task ({pf.source.display_path}:"
                                  f"{pf.line(span)}; PERS data are shared between tasks)")
        self.shared = frozenset(name for name in pers
                                if any(name in us.refs for us in theirs.values()))

    def _component_type(self, type_: str, selectors) -> str | None:
        """The type of data of type_ reached by these selectors: components
        of a record some given module defines, and indices (an element of an
        array of records, `Welds{1}.position`, has the record's type); None
        otherwise, or with no component."""
        if not selectors or not all(isinstance(x, (A.Component, A.Index)) for x in selectors) \
                or not any(isinstance(x, A.Component) for x in selectors):
            return None
        records = self._records
        if records is None:
            records = self._records = {
                r.name.lower(): {name.lower(): t.lower() for t, name in r.components}
                for pf in self.files for m in pf.modules for r in m.records}
        for x in selectors:
            if isinstance(x, A.Index):
                continue
            type_ = records.get(type_, {}).get(x.name.lower())
            if type_ is None:
                return None
        return type_

    def fixed(self, expr, module: Module, routine: str | None, type_: str) -> bool:
        """Whether expr is a value the program fixes: a literal of literals,
        or data of type_ (an element of an array of it, by a constant
        index) with a literal value nothing changes at run time (as for a
        move's target: _written) — not a search's result, CRobT(), a
        variable."""
        if isinstance(expr, (A.Agg, A.NumAgg)):
            return literal_leaves(expr) is not None
        if not isinstance(expr, A.Ref):
            return False
        d = self.lookup(expr.name, module, routine)
        if not isinstance(d, Declaration) or d.type != type_ or d.value is None:
            return False
        if expr.selectors or d.dims:
            # (An element by constant indices: the array's value is fixed.)
            if (len(expr.selectors) != 1 or not isinstance(expr.selectors[0], A.Index)
                    or len(expr.selectors[0].indices) != len(d.dims)
                    or any(self.integer(e, module, routine) is None
                           for e in expr.selectors[0].indices)):
                return False
        return self._written(d, noted=False) is None

    def _written(self, d: Declaration, noted: bool = True) -> str | None:
        """Why d may change at run time, or None (noted: the note that it is
        assigned only its own value, once its value is taken)."""
        if d.storage == "CONST":
            return None
        why = self.writes.why(d.name)
        same = self._assigned_itself(d) if why is not None else None
        if same is not None:
            if noted:
                self._notes.append(same)
            why = self.writes.why(d.name, literal_ok=True)
        if why is None and d.storage == "PERS" and self.pers_anything is not None:
            why = f"{d.name} {self.pers_anything}"
        return why

    def _only_itself(self, name: str) -> bool:
        """Whether every declaration of this name (lower case) is only ever
        assigned its own declared value (_assigned_itself): that value,
        wherever a move uses it."""
        decls = [d for (_, n), d in self.module_decls.items() if n == name]
        decls += [d for (_, _, n), d in self.routine_decls.items() if n == name]
        return bool(decls) and all(self._assigned_itself(d) is not None for d in decls)

    def _assigned_itself(self, d: Declaration) -> str | None:
        """A note when every write of d assigns it its own declared value
        (which changes nothing), else None."""
        assigns = self.writes.literal.get(d.name.lower())
        if not assigns or d.node.init is None or d.routine is not None:
            return None
        mine = literal_leaves(d.node.init)
        if mine is None or any(literal_leaves(a.value) != mine for _, a in assigns):
            return None
        where = ", ".join(f"{pf.source.display_path}:{pf.line(a.span)}" for pf, a in assigns[:3])
        return (f"{d.name} is assigned at run time ({where}), but only its own declared "
                "value: compensated with that value")

    def _memo(self, kind: str, expr, module, routine: str | None, how):
        """tool()/wobj() once per name and scope (a CAM program names the
        same tool 1e5 times), the notes of the first resolution repeated."""
        if type(expr) is not A.Ref or expr.selectors:
            return how(expr, module, routine)
        # First as written (a CAM program's moves share the name strings:
        # one lookup), then in RAPID's case-insensitive terms.
        written = (kind, id(module), routine, expr.name)
        hit = self._memos.get(written)
        if hit is None:
            key = (kind, id(module), routine.lower() if routine else None, expr.name.lower())
            hit = self._memos.get(key)
            if hit is None:
                before = len(self._notes)
                result = how(expr, module, routine)
                hit = self._memos[key] = (result, tuple(self._notes[before:]))
                self._memos[written] = hit
                return result
            self._memos[written] = hit
        self._notes.extend(hit[1])
        return hit[0]

    def _tool_wobj(self, motion, module) -> tuple:
        """(tool(), wobj()) of a move, the work object not resolved (None)
        where the tool is not; by one lookup where the move names both by
        a plain name (a CAM program's 1e5 moves name the same two), with
        the notes their resolution gave."""
        args = motion.args
        if type(args) is A.TailArgs and not motion.loops:
            # (A CAM program's 1e5 moves share a few tails, ",v100,z1,tool1
            # \WObj:=wobj1;": the same tool and work object in one routine,
            # looked up without making their nodes from the text of each.
            # Keyed by the tail itself, which the entry keeps alive, and the
            # roles, which say which of its arguments is which.)
            key = (id(module), motion.routine, motion.roles, args.tail)
            if self._assigned_anywhere():
                # (Where the routine assigns them, RoboDK's rdkTool.tframe
                # := [...]: and by where the move lies among those
                # assignments, all _site_chain reads of it.)
                hits = self._tail_sites.get(key)
                if hits is None:
                    hits = self._tail_sites[key] = self._routine_sites(motion, module)
                at = motion.span.start
                key += tuple(None if h is None else _place(h, at) for h in hits)
            return self._noted(self._tails, key, lambda: self._tool_wobj_of(motion, module))
        return self._tool_wobj_of(motion, module)

    def _routine_sites(self, motion, module) -> tuple:
        """The Sites of its own routine's assignments of a move's tool and
        of its work object (_sites), each None where there is none."""
        sites = self.site_map()
        routine = (id(module), (motion.routine or "").lower())
        entries = (self._site_entry(sites, ref, module, motion.routine)
                   for ref in (motion.tool, motion.wobj))
        return tuple(e.get(routine) if type(e) is dict else None for e in entries)

    def _tool_wobj_of(self, motion, module) -> tuple:
        t, w, routine = motion.tool, motion.wobj, motion.routine
        looped = _loop_indexed(motion, t, w)
        if looped is not None:
            return looped, None
        sites = self._sites(motion, module)
        if sites is not None:
            # (Data the routine assigns: once per assignment it takes, and
            # per name where the move names it plainly, as _memo: a RoboDK
            # program's 1e5 moves name the same two; keyed by the assignment
            # nodes, which live as long as the parse.)
            key = (id(module), routine, _name_or_node(t), _name_or_node(w),
                   *(id(site[-1][1]) if type(site) is tuple else site for site in sites))

            def pair():
                tool = self._tool_at(t, module, routine, sites[0])
                return tool, None if type(tool) is Unresolved else (
                    Unresolved(sites[1]) if type(sites[1]) is str else
                    self._wobj(w, module, routine, sites[1]) if sites[1] is not None
                    else self.wobj(w, module, routine))
            return self._noted(self._pairs, key, pair)
        if type(t) is not A.Ref or type(w) is not A.Ref or t.selectors or w.selectors:
            tool = self.tool(t, module, routine)
            return tool, (None if type(tool) is Unresolved else self.wobj(w, module, routine))

        def pair():
            tool = self.tool(t, module, routine)
            return tool, None if type(tool) is Unresolved else self.wobj(w, module, routine)
        return self._noted(self._pairs, (id(module), routine, t.name, w.name), pair)

    def _noted(self, table: dict, key, make):
        """make()'s result, made once per key of `table`; the notes its
        making gave (a quaternion normalised) said again at each later
        call, for every move that takes it."""
        hit = table.get(key)
        if hit is None:
            before = len(self._notes)
            result = make()
            table[key] = (result, tuple(self._notes[before:]))
            return result
        if hit[1]:
            self._notes.extend(hit[1])
        return hit[0]

    def _tool_of(self, motion, module):
        """tool() of a move as _tool_wobj resolves it, without its work
        object (a MoveAbsJ's joints do not depend on one)."""
        t, routine = motion.tool, motion.routine
        looped = _loop_indexed(motion, t)
        if looped is not None:
            return looped
        sites = self._sites(motion, module)
        return self._tool_at(t, module, routine, None if sites is None else sites[0])

    def _tool_at(self, t, module, routine: str, site):
        """tool() of a move whose tool the site (_sites: the assignments,
        why not known, or None) describes."""
        if type(site) is str:
            return Unresolved(site)
        if site is not None:
            return self._tool(t, module, routine, site)
        return self.tool(t, module, routine)

    def tool(self, expr, module, routine: str):
        """(key, tframe as (R, p)), or Unresolved."""
        return self._memo("tool", expr, module, routine, self._tool)

    def wobj(self, expr, module, routine: str):
        """(key, uframe . oframe as (R, p)), or Unresolved."""
        return self._memo("wobj", expr, module, routine, self._wobj)

    def _tool(self, expr, module, routine: str, site=None):
        if expr is None:
            return Unresolved("no tool argument", True)
        d = self._data(expr, module, routine, "tool0", ToolData, "tool", site)
        if isinstance(d, Unresolved):
            return d
        if d is None:
            return "tool0", IDENTITY_POSE
        t = d.value
        if t.robhold.value is not True:
            return Unresolved(f"tool {expr.name} is a stationary tool (robhold FALSE)")
        return self._elements.get(id(d)) or _data_key(expr, site), self._pose(
            t.tframe, self._home_of(d, "tframe"), f"tool {d.name}")

    def _wobj(self, expr, module, routine: str, site=None):
        if expr is None:
            return "wobj0", IDENTITY_POSE
        d = self._data(expr, module, routine, "wobj0", WobjData, "work object", site)
        if isinstance(d, Unresolved):
            return d
        if d is None:
            return "wobj0", IDENTITY_POSE
        w = d.value
        if w.robhold.value is not False:
            return Unresolved(f"work object {expr.name} is held by the robot (stationary tool "
                              "set-up)")
        # (ufprog TRUE: a fixed user frame; ufmec names the unit a movable
        # one moves with, and is not used then.)
        if w.ufprog.value is not True:
            return Unresolved(f"work object {expr.name} is coordinated with a mechanical unit")
        return self._elements.get(id(d)) or _data_key(expr, site), compose_pose(
            self._pose(w.uframe, self._home_of(d, "uframe"), f"work object {d.name}"),
            self._pose(w.oframe, self._home_of(d, "oframe"), f"work object {d.name}"))

    def world_M_base(self, record) -> tuple | Unresolved:
        """The robot base in the world frame for a target's external axes:
        the base frame, moved along the track axes (--track)."""
        if not self.track:
            return self.base
        ext = self._num(record.ext)
        d = np.zeros(3)
        for k, u in self.track:
            if abs(ext[k]) >= EXTAX_UNUSED:
                return Unresolved(f"the target has no value for track axis eax_{AXES[k]} "
                                  "(9E9) but --track says it carries the robot", True)
            d = d + ext[k] * u
        return self.base[0], self.base[1] + d

    # ------------------------------------------------------------ targets
    def _source(self, pf, expr, module, routine: str, env: dict[str, int], outer=None,
                types: tuple[str, ...] = ("robtarget", "jointtarget")):
        """The Source of a target expression (types: of declared data, the
        types it may have), or Unresolved."""
        whole = outer if outer is not None else expr
        if isinstance(expr, A.Ref):
            d = self.lookup(expr.name, module, routine)
            if isinstance(d, Unresolved):
                return d
            if d is None:
                return self._not_declared(expr.name)
            if d.type not in types:
                inner = self._component_type(d.type, expr.selectors)
                if inner in types:
                    # (A target inside a record the program defines: the
                    # controller moves there; only not one rapidcomp edits.)
                    return Unresolved(f"the target is a component of {expr.name}, a {d.type}: "
                                      "rapidcomp compensates robtarget and jointtarget data, "
                                      "not components of other data; left as written")
                if inner is not None:
                    return Unresolved(f"{pf.text(expr)} is a {inner}, not a target", True)
                return Unresolved(f"{expr.name} is a {d.type}, not a target", True)
            if d.value is None:
                # (Module data declared without a value that the program
                # assigns: that is why. Not a routine's own variable: the
                # writes are known by name, and one of its name may be
                # another routine's.)
                why = (self.writes.why(d.name) if d.node.init is None and d.routine is None
                       else None)
                return Unresolved(why or f"{expr.name} has no literal value "
                                  f"({d.issue or 'run-time data'})")
            written = self._written(d)
            if written:
                return Unresolved(written)
            home, home_m = self.home[id(d)], self.home_module[id(d)]
            if not expr.selectors:
                if isinstance(d.value, tuple):
                    return Unresolved(f"{expr.name} is an array", True)
                return _source(d.value, d, home, None, False, expr, whole, None, None, None,
                               home_m)
            if len(expr.selectors) == 1 and isinstance(expr.selectors[0], A.Index):
                if not isinstance(d.value, tuple):
                    return Unresolved(f"{expr.name} is not an array", True)
                idx = []
                by_loop = False
                guarded = False
                for e in expr.selectors[0].indices:
                    # A FOR loop's variable hides data of the same name.
                    if isinstance(e, A.Ref) and not e.selectors and e.name.lower() in env:
                        idx.append(env[e.name.lower()])
                        by_loop = True
                        guarded = guarded or e.name.lower() in self._guarded
                    elif (k := self.integer(e, module, routine)) is not None:
                        idx.append(k)
                    else:
                        return Unresolved(f"index of {expr.name} is not a literal or the "
                                          "variable of an enclosing FOR loop with constant bounds")
                if len(idx) != len(d.dims):
                    raise pf.source.error(expr.span.start, f"{expr.name} has {len(d.dims)} "
                                          f"dimensions, indexed with {len(idx)}")
                flat = 0
                for k, dim, e in zip(idx, d.dims, expr.selectors[0].indices):
                    if not 1 <= k <= dim:
                        loop = "" if not by_loop else (
                            f" (a FOR loop walks it to {k}; the array has {dim} elements)")
                        if guarded:
                            # A condition in the loop may keep the move from
                            # running there: the program may well be right.
                            return Unresolved(
                                f"index {k} of {expr.name} is outside 1..{dim}{loop}; a "
                                "condition in the loop holds the move, so it may never run "
                                "there (if it did, the controller would stop with ERR_INDEX)")
                        raise pf.source.error(e.span.start, f"index {k} of {expr.name} is outside "
                                              f"1..{dim}{loop}: the controller stops here with "
                                              "ERR_INDEX")
                    flat = flat * dim + (k - 1)
                return _source(d.value[flat], d, home, flat, by_loop, expr, whole, None, None,
                               None, home_m)
            return Unresolved(f"{expr.name} with components is not a target")
        if isinstance(expr, A.Call) and expr.name.lower() in ("offs", "reltool") and outer is None:
            return self._offset(pf, expr, module, routine, env)
        if (self.states and isinstance(expr, A.Call)
                and expr.name.lower() in _STATE_FUNCS):
            return self._at_state(pf, expr, module, routine, env, whole)
        if isinstance(expr, (A.Agg, A.NumAgg)):
            return Unresolved("inline aggregate is not a literal value")
        return Unresolved("the target is computed at run time")

    def _offset(self, pf, call: A.Call, module, routine: str, env):
        pos = [a.value for a in call.args if a.kind == "pos"]
        if len(pos) != 4:
            return Unresolved(f"{call.name} takes a target and three numbers")
        # (Literal numbers, or CONST nums: fixed before the program runs.)
        xyz = [self.number(v, module, routine) for v in pos[1:]]
        if None in xyz:
            return self._not_fixed(pf, call, pos[1 + xyz.index(None)], module, routine)
        if isinstance(pos[0], (A.Agg, A.NumAgg)):
            try:
                record = decode("robtarget", pos[0], f"{call.name} robtarget")
            except DecodeIssue as exc:
                if exc.illegal:
                    raise pf.source.error(exc.span.start, exc.reason) from None
                return Unresolved(exc.reason)
            base = Source(record, None, None, None, False, pos[0], call, None, None, None)
        else:
            base = self._source(pf, pos[0], module, routine, env, outer=call)
        if isinstance(base, Unresolved):
            return base
        if not isinstance(base.record, RobTarget):
            return Unresolved(f"{call.name} of a non-robtarget", True)
        # (A tuple: poses() makes the array of every use's at once.)
        d = tuple(self._position(xyz, pos[1].span.start, pf, f"the {call.name} displacement"))
        rot = NO_ROTATION
        if call.name.lower() == "reltool":
            turns = []
            for a in call.args:
                if a.kind == "optval" and a.name.lower() in ("rx", "ry", "rz"):
                    angle = self.number(a.value, module, routine)
                    if angle is None:
                        return self._not_fixed(pf, call, a.value, module, routine)
                    angle, = self._floats((angle,))
                    if not abs(angle) <= 1e5:
                        written = (a.value.text if isinstance(a.value, A.Num)
                                   else f"{pf.text(a.value)} = {angle:g}")
                        raise pf.source.error(a.value.span.start, f"RelTool \\{a.name} is "
                                              f"{written} deg: not an angle")
                    turns.append((a.name.lower(), angle))
                elif a.kind != "pos":
                    return Unresolved(f"RelTool argument \\{a.name} is not supported")
            if turns:
                # (One matrix per distinct rotation, read only: a CAM
                # program's 1e5 RelTool turn by a few angles.)
                key = tuple(turns)
                rot = self._turns.get(key)
                if rot is None:
                    rot = NO_ROTATION
                    for name, angle in turns:
                        rot = rot @ _TURN[name](angle * DEG)
                    rot.flags.writeable = False
                    self._turns[key] = rot
        elif any(a.kind != "pos" for a in call.args):
            return Unresolved("Offs takes no optional arguments")
        return _source(base.record, base.decl, base.home, base.element, base.by_loop, base.ref,
                       call, call, rot, d, base.home_module)

    def _not_fixed(self, pf, call: A.Call, expr, module, routine: str) -> Unresolved:
        """Why number `expr` of Offs/RelTool `call` is not one fixed before
        the program runs (number() gave None), naming it: a name no given
        module declares, or that the controller does not see here (blocked,
        as a target's name is); else known at run time only (untouched)."""
        while isinstance(expr, (A.Unary, A.Paren)):
            expr = expr.operand if isinstance(expr, A.Unary) else expr.expr
        what = f"{call.name} number {pf.text(expr)}"
        if not (isinstance(expr, A.Ref) and not expr.selectors):
            return Unresolved(f"{what} is an expression: rapidcomp reads literal numbers and "
                              "CONST nums of them; known at run time")
        if expr.name.lower() in self._loop_vars:
            return Unresolved(f"{what} is the variable of an enclosing FOR loop: known at run "
                              "time")
        d = self.lookup(expr.name, module, routine)
        if isinstance(d, Unresolved):
            return d
        if d is None:
            return self._not_declared(expr.name, f"{call.name} number ")
        if d.storage != "CONST" or d.type != "num":
            return Unresolved(f"{what} is a {d.storage} {d.type}: known at run time only")
        return Unresolved(f"{what} is a CONST whose value is not a literal number (rapidcomp "
                          "reads literal numbers and CONST nums of them)")

    def _at_state(self, pf, call: A.Call, module, routine: str, env, whole):
        """rcTcJ/rcTcR(cold, dq) of a transient output at thermal state
        self.state, as the controller computes it (transient.state_values):
        the Source of the cold value holding that value."""
        key = (id(call), tuple(sorted(env.items())))
        got = self._at_states.get(key)
        if got is None:
            got = self._at_states[key] = self._state_parts(pf, call, module, routine, env,
                                                           whole)
        if type(got) is Unresolved:
            return got
        cold, values = got
        c = cold.record
        new = values[self.states.index(self.state)]
        return Source(type(c)(new + c.values[len(new):], c.lexed, c.span), cold.decl,
                      cold.home, cold.element, cold.by_loop, cold.ref, whole, None, None, None,
                      cold.home_module)

    def _state_parts(self, pf, call: A.Call, module, routine: str, env, whole):
        """(the Source of rcTcJ/rcTcR's cold value, the numbers the call
        gives at each of self.states: rcTcJ's joints, rcTcR's position and
        quaternion), or Unresolved."""
        joint = call.name.lower() == FUNC_J.lower()
        if len(call.args) != 2 or any(a.kind != "pos" for a in call.args):
            return Unresolved(f"{call.name} takes two arguments")
        parts = []
        for a, type_ in zip(call.args, ("jointtarget", "jointtarget") if joint
                            else ("robtarget", "pose")):
            v = a.value
            if isinstance(v, (A.Agg, A.NumAgg)):
                try:
                    record = decode(type_, v, f"{call.name} {type_}")
                except DecodeIssue as exc:
                    # (The cold value's external axes named data, as its
                    # move's target names them: _named_axes.)
                    record = (self._named_record(v, type_, module, routine, exc.reason)
                              if not parts and not exc.illegal else Unresolved(exc.reason))
                    if type(record) is Unresolved:
                        return record
                parts.append(Source(record, None, None, None, False, v, whole, None, None, None))
            else:
                src = self._source(pf, v, module, routine, env, outer=whole, types=(type_,))
                if isinstance(src, Unresolved):
                    return src
                parts.append(src)
        cold, dq = parts
        c, d = cold.record, dq.record
        if joint:
            values = state_values(c.joints, d.joints, self.states, True)
        else:
            values = state_values(c.xyz + c.quat_wxyz, d.xyz + d.quat_wxyz, self.states, False)
        return cold, list(map(tuple, values.tolist()))

    def target_pose(self, src: Source, pf: ParsedFile | None = None):
        """wobj_M_target of a robtarget source, with Offs/RelTool applied
        (pf: the file of an inline target)."""
        q, p = self._target_parts(src, pf)
        return _relative(src, unit_quat_matrices([q])[0], np.array(p))

    def _target_parts(self, src: Source, pf: ParsedFile | None):
        """The checked unit quaternion (w, x, y, z) and position of a
        robtarget source, as written (before Offs/RelTool)."""
        home = src.home if src.home is not None else pf
        where = f"{src.decl.name}" if src.decl is not None else "the inline robtarget"
        rec = src.record
        q = unit_wxyz(*self._quaternion(rec.quat_wxyz, lambda: rec.span.start + rec.regs[3][0],
                                        home, where))
        p = self._position(rec.xyz, lambda: rec.span.start + rec.regs[0][0], home, where)
        return q, p

    def poses(self) -> None:
        """Every flange pose the resolved uses wait for, in one batch: the
        uses are complete from here on (a CAM program has 1e5, and their
        3x3 products one by one cost more than resolving them)."""
        pending, self._pending = self._pending, []
        if not pending:
            return
        q, p = self._checked_parts(pending)
        R = unit_quat_matrices(q)
        _relative_many(R, p, [item[1] for item in pending])

        flange = flange_poses(*(stacked_poses([item[k] for item in pending]) for k in (3, 4)),
                              (R, p), stacked_poses([item[5] for item in pending]))
        for i, (u, *_) in enumerate(pending):
            # Two-phase construction: the use has not left the resolver's
            # client yet (Plan, verify call poses() before reading it).
            object.__setattr__(u, "flange", flange)
            object.__setattr__(u, "row", i)

    def _unit_parts(self, v: np.ndarray):
        """unit_parts of v as this resolver reads values (float32 when it
        verifies)."""
        return unit_parts(v, self.float32)

    def _checked_parts(self, pending: list) -> tuple[np.ndarray, np.ndarray]:
        """_confdata and _target_parts of every pending use, as arrays (q
        (n, 4), p (n, 3)) by _unit_parts; a use that any check would stop
        or note goes through them one by one, in order (so the first
        error, its message and the notes are theirs)."""
        n = len(pending)
        if not n:
            return np.zeros((0, 4)), np.zeros((0, 3))
        v = np.array([item[1].record.values[:11] for item in pending], float).reshape(n, 11)
        q, p, _, ok = self._unit_parts(v)
        for i in np.flatnonzero(~ok).tolist():
            u, src, pf = pending[i][:3]
            notes, self._notes = self._notes, []
            try:
                self._confdata(src, pf)
                q[i], p[i] = self._target_parts(src, pf)
            finally:
                extra, self._notes = self._notes, notes
            if extra:
                object.__setattr__(u, "notes", u.notes + tuple(extra))
        return q, p

    def integer(self, expr, module, routine: str | None) -> int | None:
        """A literal integer, a CONST num with a literal integer value, or
        Dim() of a declared array."""
        return self._fixed(expr, module, routine, self._integer)

    def number(self, expr, module, routine: str | None) -> float | None:
        """The value of a num argument where it is fixed before the program
        runs: a literal number, or a CONST num whose value is one (or such
        a CONST), negated or in parentheses (the controller evaluates a
        CONST when it loads the module); None for anything else (a VAR or
        PERS num, an expression: known at run time only)."""
        if type(expr) is A.Num:       # (most: a CAM program's 3e5 Offs numbers)
            return expr.value
        return self._fixed(expr, module, routine, _num_value)

    def _fixed(self, expr, module, routine: str | None, leaf):
        """What expr comes to before the program runs, through '-',
        parentheses and CONST nums (their values, read with the names of the
        module and routine that declare them) down to leaf(expr, module,
        routine): None where leaf gives None, or a name is not a CONST num."""
        if isinstance(expr, A.Unary) and expr.op == "-":
            v = self._fixed(expr.operand, module, routine, leaf)
            return -v if v is not None else None
        if isinstance(expr, A.Paren):
            return self._fixed(expr.expr, module, routine, leaf)
        if isinstance(expr, A.Ref) and not expr.selectors:
            if expr.name.lower() in self._loop_vars and not self._consts:
                # (An enclosing FOR loop's variable, not data of its name.
                # In a CONST's value the names are the module's.)
                return None
            d = self.lookup(expr.name, module, routine)
            if not (isinstance(d, Declaration) and d.storage == "CONST" and d.type == "num"):
                return None
            if any(c is d for c in self._consts):
                # CONST a:=b; CONST b:=a; has no value: the controller
                # does not load it (and the evaluation would not end).
                chain = self._consts[next(i for i, c in enumerate(self._consts) if c is d):]
                raise self.home[id(d)].source.error(
                    d.node.name_span.start,
                    f"CONST {d.name} is defined through itself ("
                    + " -> ".join(c.name for c in chain + [d]) + "): it has no value")
            if d.node.init is None:
                return None
            self._consts.append(d)
            try:
                return self._fixed(d.node.init, self.home_module[id(d)], d.routine, leaf)
            finally:
                self._consts.pop()
        return leaf(expr, module, routine)

    def _integer(self, expr, module, routine: str | None) -> int | None:
        """integer()'s own cases: a literal integer, Dim() of a declared
        array."""
        if isinstance(expr, A.Num) and float(expr.value).is_integer() and abs(expr.value) < 2**53:
            return int(expr.value)
        if (isinstance(expr, A.Call) and expr.name.lower() == "dim" and len(expr.args) == 2
                and all(a.kind == "pos" for a in expr.args)):
            # Dim(array, k): an array's sizes are fixed where it is declared
            # (a parameter's, array{*}, is the caller's: lookup says so).
            arr, k = expr.args[0].value, self.integer(expr.args[1].value, module, routine)
            if isinstance(arr, A.Ref) and not arr.selectors and k is not None:
                d = self.lookup(arr.name, module, routine)
                if isinstance(d, Declaration) and 1 <= k <= len(d.dims):
                    return d.dims[k - 1]
        return None

    def loop_range(self, loop, module, routine: str, bounded: bool = True,
                   around=()) -> range | None:
        """The values a FOR loop walks when its bounds are constant (None
        when they are not, or, when bounded, when it walks more than the
        limit). around: the variables of the FOR loops around it, which its
        bounds may name (FOR j FROM 1 TO i inside FOR i: not fixed, whatever
        data named i there is)."""
        with self._hiding(around):
            start = self.integer(loop.start, module, routine)
            stop = self.integer(loop.stop, module, routine)
            step = 1 if loop.step is None else self.integer(loop.step, module, routine)
        if start is None or stop is None or not step:
            return None
        r = range(start, stop + (1 if step > 0 else -1), step)
        return r if len(r) <= MAX_LOOP_ITERATIONS or not bounded else None

    def resolve(self, pf: ParsedFile, module: Module, motion: Motion,
                index: tuple[int, int] = (0, 0)) -> list[TargetUse]:
        """Every target use of a motion; index = (file index, motion index in
        the file), the first part of each use's key."""
        try:
            return self._resolve(pf, module, motion, index)
        except Exception:
            # An earlier use's error comes first, before any other (an
            # input error, or the nesting limit's RecursionError).
            self._checked_parts(self._pending)
            raise

    def resolve_all(self, pf: ParsedFile, module: Module, motions, index: tuple[int, int]
                    ) -> list[TargetUse]:
        """resolve() of each motion of a module in turn, motion k's index
        (file index, index[1] + k): the same uses. A plain move to a
        robtarget (its one target a decoded literal or a declared name, no
        enclosing loop, tool and work object resolved; a CAM program's 1e5
        moves) is resolved without resolve()'s machinery for everything
        else, its line among all the moves' lines found at once."""
        fi, first = index
        out: list[TargetUse] = []
        plain = self._plain_moves()
        lines = pf.source.lines([m.span.start for m in motions]) if plain else ()
        try:
            for k, motion in enumerate(motions):
                u = self._plain_use(pf, module, motion, lines[k], (fi, first + k)) if plain \
                    else None
                if u is None:
                    # (resolve()'s own way, its errors checked below once.)
                    out.extend(self._resolve(pf, module, motion, (fi, first + k)))
                else:
                    out.append(u)
        except Exception:
            self._checked_parts(self._pending)      # an earlier use's error comes first
            raise
        return out

    def _plain_moves(self) -> bool:
        """Plain moves are resolved by _plain_use: not for the output's
        values (verify.py: float32, records as written), not with a track
        or a moved base (their base depends on the target)."""
        return not (self.float32 or self.written or self.track or self.moved_by)

    def _plain_use(self, pf, module, motion, line: int, index) -> TargetUse | None:
        """resolve()'s one use of a plain move (see resolve_all; its target
        may be an Offs/RelTool), or None when the move is not one (resolve()
        then says what it is): the same source, checks, notes and use, made
        directly."""
        targets = motion.targets
        if len(targets) != 1 or motion.loops:
            return None
        t = targets[0]
        spec = motion.spec
        if t.role == "search" or spec.joint_space or not spec.moves_arm:
            return None
        value = t.value
        self._notes = notes = []
        if value is not None:
            if type(value) is not RobTarget:
                return None
            src = _source(value, None, None, None, False, t.expr, t.expr, None, None, None,
                          None)
            label = "inline"
        else:
            expr = t.expr
            if t.issue:
                return None
            if type(expr) is A.Call:
                # Offs/RelTool(<target>, <numbers>...) (a CAM program's
                # pattern path: 1e5 of them), as resolve() reads it
                # (_offset); anything else it is not is resolve()'s to say.
                if expr.name.lower() not in ("offs", "reltool"):
                    return None
                src = self._offset(pf, expr, module, motion.routine, {})
                if type(src) is Unresolved:
                    return None
                label = pf.text(expr)
            else:
                if type(expr) is not A.Ref or expr.selectors:
                    return None
                d = self.lookup(expr.name, module, motion.routine)
                if type(d) is not Declaration or type(d.value) is not RobTarget \
                        or d.type != "robtarget" or self._written(d):
                    return None
                key = id(d)
                src = _source(d.value, d, self.home[key], None, False, expr, expr, None, None,
                              None, self.home_module[key])
                # (A plain name is its text: the Ref's own string, not a copy per use.)
                label = expr.name
        tool, wobj = self._tool_wobj(motion, module)
        if type(tool) is Unresolved or type(wobj) is Unresolved:
            return None
        record = src.record
        u = _use(motion, t.role, label, line, "robtarget", None, None, self._conf(record),
                 None, None, src, tool, wobj, (), False, pf, module,
                 self._one(record.ext, True), index + (t.role, ()), tuple(notes))
        self._pending.append((u, src, pf, self.base, wobj[1], tool[1]))
        return u

    def _resolve(self, pf, module, motion, index) -> list[TargetUse]:
        out = []
        for t in motion.targets:
            if t.role == "search":
                continue
            kind = "jointtarget" if motion.spec.joint_space else "robtarget"
            inline = isinstance(t.expr, (A.Agg, A.NumAgg))
            for env in self._loop_envs(pf, module, motion, t.expr):
                label = pf.text(t.expr) if not inline else "inline"
                if env:
                    label += " [" + ", ".join(f"{k}={v}" for k, v in env.items()) + "]"
                out.append(self._use(pf, module, motion, t, kind, label, env,
                                     index + (t.role, tuple(sorted(env.items())))))
        return out

    def _loop_envs(self, pf, module, motion: Motion, expr) -> list[dict[str, int]]:
        """One environment per iteration of the enclosing FOR loops whose
        variable the target expression uses."""
        envs: list[dict[str, int]] = [{}]
        names = loop_names(expr, motion.loops)
        for at, lp in enumerate(motion.loops):
            if lp.var is None or lp.var.lower() not in names:
                continue
            # (motion.loops: the outermost first.)
            values = self.loop_range(lp, module, motion.routine, bounded=False,
                                     around=[x.var for x in motion.loops[:at] if x.var])
            if values is None:
                continue  # the target stays unresolved and says why
            if len(envs) * len(values) > MAX_LOOP_ITERATIONS:
                raise pf.source.error(lp.span.start, f"FOR {lp.var} walks {len(values)} "
                                      f"iterations here; rapidcomp follows at most "
                                      f"{MAX_LOOP_ITERATIONS} target uses of one move (no "
                                      "array holds more targets)")
            envs = [{**e, lp.var.lower(): v} for e in envs for v in values]
        return envs

    def _all_missing(self, first: Unresolved, module, motion,
                     tool: bool = True) -> Unresolved:
        """A target no given module declares (tool=False: the move's tool):
        name the tool (tool) and work object of the move too when they are
        missing as well, so that the declaring modules are given at once."""
        if not first.reason.endswith(f"({MISSING_HINT})"):
            return first
        names = [_missing_name(first.reason)]
        if _loop_indexed(motion, motion.tool, motion.wobj) is not None:
            return first
        for what in ((self.tool(motion.tool, module, motion.routine),) if tool else ()) + (
                self.wobj(motion.wobj, module, motion.routine),):
            if isinstance(what, Unresolved) and what.reason.endswith(f"({MISSING_HINT})"):
                names.append(_missing_name(what.reason))
        if len(names) == 1:
            return first
        listed = ", ".join(names[:-1]) + " and " + names[-1]
        return Unresolved(f"{listed} are not declared in the given modules ({MISSING_HINT})",
                          True)

    def _use(self, pf, module, motion, t, kind, label, env, key) -> TargetUse:
        if not motion.loops:          # (a CAM program's 1e5 moves: no loop hides a name)
            return self._use_in(pf, module, motion, t, kind, label, env, key)
        with self._in_loops(motion):
            return self._use_in(pf, module, motion, t, kind, label, env, key)

    def _in_loops(self, motion):
        """While a move's target is resolved: the variables of its enclosing
        FOR loops, which hide data of the same name (_fixed: `FOR k ...`
        with a CONST num k in the module: the k of Offs(p, 0, 0, k) is the
        loop's); none outside (where _loop_vars is empty already)."""
        return self._hiding(lp.var for lp in motion.loops if lp.var)

    @contextmanager
    def _hiding(self, names):
        """FOR loop variables `names` hide data of their names meanwhile
        (_fixed); as before after."""
        before, self._loop_vars = self._loop_vars, frozenset(n.lower() for n in names)
        try:
            yield
        finally:
            self._loop_vars = before

    def _use_in(self, pf, module, motion, t, kind, label, env, key) -> TargetUse:
        line = pf.line(motion.span)
        envt = key[3]
        self._notes = []
        self._guarded = {lp.var.lower() for lp in motion.loops if lp.guarded and lp.var}

        def fail(why: Unresolved):
            return TargetUse(motion, t.role, label, line, kind, None, None, None, None,
                             why.reason, env=envt, blocked=why.blocked, file=pf, module=module,
                             key=key)

        if not motion.spec.moves_arm:
            return fail(Unresolved(f"{motion.spec.name} moves only external axes; the arm "
                                   "stays where it is"))
        if kind == "robtarget" and self.moved_by and not self.track:
            return fail(Unresolved(
                f"SYSPAR/MOC.cfg says {self.moved_by} moves the robot's base: where the "
                "base is depends on its axis; say which "
                "external axis it is and along which base axis it moves with --track "
                "AXIS:x|y|z", True))
        if t.value is not None:
            src = _source(t.value, None, None, None, False, t.expr, t.expr, None, None, None,
                          None)
        elif t.issue:
            src = self._named_axes(t, kind, module, motion.routine)
        else:
            src = self._source(pf, t.expr, module, motion.routine, env)
        src = self._as_written(src, pf)
        if (isinstance(src, Unresolved) and src.blocked and kind == "robtarget"
                and src.reason.endswith(f"({MISSING_HINT})")):
            return fail(self._all_missing(src, module, motion))
        return self._complete(pf, module, motion, t.role, kind, label, line, envt, key, src)

    def _named_axes(self, t, kind: str, module, routine: str | None):
        """The Source of an inline target whose external axes, or a
        robtarget's confdata, are named data (the Grasshopper plugin Robots
        writes [[x,y,z],[q],conf,extj], [[x,y,z],[q],[cf],extj] and
        [[j1,..,j6],extj], extj a VAR extjoint of 9E9s, conf a VAR
        confdata), the rest literal: its record with that data's values,
        where each is data of its type with a literal value nothing changes
        at run time (never written: only the literal parts are); else why
        not."""
        record = self._named_record(t.expr, kind, module, routine, t.issue)
        if type(record) is Unresolved:
            return record
        return Source(record, None, None, None, False, t.expr, t.expr, None, None, None)

    def _named_record(self, expr, kind: str, module, routine: str | None, issue: str):
        """The record of a literal target whose external axes (or a
        robtarget's confdata) are named data (_named_axes), or Unresolved
        (issue: why the literal alone is not one)."""
        named = _NAMED[kind]
        if (type(expr) is not A.Agg or len(expr.items) != (4 if kind == "robtarget" else 2)
                or any(type(x) not in (A.Agg, A.NumAgg) and not (i in named and type(x) is A.Ref)
                       for i, x in enumerate(expr.items))):
            return Unresolved(issue)
        items = list(expr.items)
        decls = []
        for i, (type_, what, field) in named.items():
            ref = items[i]
            if type(ref) is not A.Ref:
                continue
            d = None if ref.selectors else self.lookup(ref.name, module, routine)
            if type(d) is Unresolved:
                return Unresolved(f"its {what} {_are(what)} {ref.name}: {d.reason}")
            if (not isinstance(d, Declaration) or d.type != type_ or d.dims
                    or type(d.node.init) not in (A.Agg, A.NumAgg)):
                if d is None and not ref.selectors:
                    return Unresolved(f"its {what} {_are(what)} {ref.name}, which is not declared "
                                      f"in the given modules ({MISSING_HINT})", True)
                why = ("not a plain name" if ref.selectors else
                       f"a {d.type}, not {_a(type_)}" if d.type != type_ else
                       "an array" if d.dims else "declared without a literal value")
                return Unresolved(f"its {what} {_are(what)} {ref.name}, {why}")
            why = self._written(d, noted=False)
            if why is not None:
                return Unresolved(f"its {what} {_are(what)} {d.name}, which "
                                  f"{why.split(' ', 1)[1]}" if why.startswith(d.name + " ")
                                  else why)
            # (The record reads the declared value in place of the name: the
            # spans of those fields are the declaration's, never edited: the
            # compensation writes the pose's values, and a confdata only
            # where it changes, which a named one may not: edit.py.)
            items[i] = d.node.init
            decls.append((d, field))
        try:
            return decode(kind, A.Agg(tuple(items), expr.span), f"inline {kind}")
        except DecodeIssue as exc:
            if not exc.illegal:
                return Unresolved(issue)
            # (A value no controller loads, in a declaration's numbers: the
            # literal's own were read by the parse.)
            for d, field in decls:
                init = d.node.init.span
                if init.start <= exc.span.start < init.end:
                    raise self.home[id(d)].source.error(
                        exc.span.start, exc.reason.replace(f"inline {kind}.{field}", d.name)
                    ) from None
            return Unresolved(str(exc))

    def _as_written(self, src, pf):
        """src holding its record as the output writes it (self.written),
        where the output rewrote it."""
        if isinstance(src, Unresolved) or not self.written:
            return src
        record = self._written_record(src, pf)
        return src if record is src.record else src.with_record(record)

    def _written_record(self, src: Source, pf):
        """src's record as the output writes it (itself where not rewritten)."""
        return self.written.get(_written_key(src, pf), src.record)

    def again(self, u: TargetUse) -> TargetUse:
        """A use resolve() gave for the input, resolved again by this
        resolver (float32, the records as written) on the same structure:
        what resolve() of its motion gives, without looking up again what
        the structure decides (which literal, the move's checks; an
        Offs/RelTool is evaluated again, its numbers being values too). For
        an output whose every edit is numbers of existing literals
        (verify.py)."""
        try:
            if not u.motion.loops:
                return self._again(u)
            with self._in_loops(u.motion):
                return self._again(u)
        except Exception:
            self._checked_parts(self._pending)      # an earlier use's error comes first
            raise

    def _again(self, u: TargetUse) -> TargetUse:
        src = u.source
        self._notes = []
        if src.call is not None:
            # Offs/RelTool: their own numbers (displacement, angles) are
            # evaluated by this resolver too (float32), not taken from the
            # plan's source.
            self._guarded = {lp.var.lower() for lp in u.motion.loops if lp.guarded and lp.var}
            src = self._source(u.file, src.expr, u.module, u.motion.routine, dict(u.env))
        copy = self.written.copy(u.key, u.source.record.span) if self.written.uses else None
        src = self._as_written(src, u.file) if copy is None else src.with_record(copy)
        return self._complete(u.file, u.module, u.motion, u.role, u.kind, u.label, u.line,
                              u.env, u.key, src)

    def again_many(self, uses: list[TargetUse]):
        """again() of many robtarget uses at once, as arrays: (indices of
        `uses` done here, R (m, 3, 3), p (m, 3), conf (m, 4)); the others
        (MoveAbsJ, Offs/RelTool, --track, a value outside what a checked
        use holds) are again()'s. Bit for bit again()'s arithmetic: the
        same float32 rounding, the products and sums in its order (a sum of
        squares elementwise, the ** 0.5 of Python floats), the poses
        composed by flange_poses, as poses() does."""
        if self.track or not self.float32:
            return [], None, None, None
        done, recs, tools, wobjs = [], [], [], []
        # Rows of the written array (at: their place in done), records' values.
        at, rows = [], []
        # An Offs of literal numbers: its place in done, its displacement
        # as this resolver reads it (poses() adds it to the target's
        # position, as here; again() evaluates it again, float32).
        offs_at, offs = [], []
        written = self.written
        written_row = written.row
        copies = written.uses
        for n, u in enumerate(uses):
            src = u.source
            if u.kind != "robtarget":
                continue
            d = None
            if src.call is not None:
                d = self._offs(src.call)
                if d is None:
                    continue
            # (A use whose tool is not resolved goes to again(), which says
            # why: its work object is not needed here.)
            tool, wobj = self._tool_wobj(u.motion, u.module)
            if type(tool) is Unresolved or type(wobj) is Unresolved:
                continue
            if not isinstance(src.record, RobTarget):
                continue
            copy = written.copy_values(u.key) if copies else None
            row = written_row(_written_key(src, u.file)) if copy is None else None
            if copy is False:
                continue          # (a jointtarget copy: again() says why)
            if copy is not None:
                recs.append(copy)
            elif row is not None:
                at.append(len(done))
                rows.append(row)
            else:
                record = self._written_record(src, u.file)
                if not isinstance(record, RobTarget):
                    continue
                recs.append(record.values)
            if d is not None:
                offs_at.append(len(done))
                offs.append(d)
            done.append(n)
            tools.append(tool[1])
            wobjs.append(wobj[1])
        if not done:
            return [], None, None, None
        m = len(done)
        v = np.empty((m, 17))
        v[at] = written.values[rows]
        if recs:
            # (Not where every value is a written row, as a CAM program's
            # 1e5 are: the set difference of 1e5 indices costs ~70 ms.)
            v[np.setdiff1d(np.arange(m), at)] = np.array(recs, float).reshape(-1, 17)
        # What again() would refuse or note (not ok) goes to again(): it
        # says why.
        return self._flanges(done, v, tools, wobjs,
                             (offs_at, np.array(offs, float).reshape(-1, 3)) if offs else None)

    def _offs(self, call: A.Call) -> list[float] | None:
        """The displacement of Offs(target, x, y, z) of literal numbers, as
        _offset reads it (this resolver's floats); None for anything else
        (RelTool, an expression: again() evaluates it)."""
        if call.name.lower() != "offs" or len(call.args) != 4:
            return None
        xyz = []
        for a in call.args[1:]:
            if a.kind != "pos" or type(a.value) is not A.Num:
                return None
            xyz.append(a.value.value)
        if call.args[0].kind != "pos":
            return None
        return self._floats(xyz)

    def _flanges(self, done: list, v: np.ndarray, tools: list, wobjs: list, offs=None):
        """(the entries of `done` kept, R, p, conf) of robtargets' values v
        (one row per entry) through their tools and work objects, as poses()
        composes them; a row a check would stop or note (not ok) is left
        out. offs: (rows, displacements) of Offs uses, added to their
        positions as poses() adds them (_relative)."""
        Rf, pf, conf, ok = robtarget_flanges(v, stacked_poses([self.base] * len(done)),
                                             stacked_poses(wobjs), stacked_poses(tools),
                                             self.float32, offs)
        keep = np.flatnonzero(ok)
        return ([done[k] for k in keep.tolist()], Rf[keep], pf[keep],
                conf[keep].astype(int))

    def state_many(self, uses: list[TargetUse]):
        """A transient output's uses, resolved at one of self.states before,
        at self.state, as arrays: (indices of `uses` done as robtargets, R
        (m, 3, 3), p (m, 3), conf (m, 4); index -> joints of those done as
        jointtargets). A use whose target is rcTcJ/rcTcR(cold, dq) takes its
        values at self.state from what _at_state read of the call; the
        others (Offs/RelTool, --track, a value a check would stop or note)
        are left for the caller to resolve() again. Bit for bit
        _complete's and poses()' arithmetic, as again_many's."""
        if self.track or not self.float32 or not self.states:
            return [], None, None, None, {}
        at = self.states.index(self.state)
        done, values, tools, wobjs = [], [], [], []
        joints: dict = {}
        for n, u in enumerate(uses):
            src = u.source
            if src is None or src.call is not None or type(src.expr) is not A.Call:
                continue
            got = self._at_states.get((id(src.expr), u.env))
            if got is None or type(got) is Unresolved:
                continue
            cold, by_state = got
            new = by_state[at]
            if u.kind == "jointtarget":
                # (Float32 values already: _num keeps them.)
                if all(abs(v) <= MAX_JOINT_DEG for v in new):
                    joints[n] = new
                continue
            tool, wobj = self._tool_wobj(u.motion, u.module)
            if type(tool) is Unresolved or type(wobj) is Unresolved:
                continue
            done.append(n)
            values.append(new + cold.record.values[len(new):])
            tools.append(tool[1])
            wobjs.append(wobj[1])
        if not done:
            return [], None, None, None, joints
        return (*self._flanges(done, np.array(values, float).reshape(len(done), 17), tools,
                               wobjs), joints)

    def _complete(self, pf, module, motion, role, kind, label, line, envt, key,
                  src: Source | Unresolved) -> TargetUse:
        """The use of a source: its values checked, its tool, work object and
        base resolved (or why it has none)."""
        def fail(why: Unresolved):
            return TargetUse(motion, role, label, line, kind, None, None, None, None,
                             why.reason, env=envt, blocked=why.blocked, file=pf, module=module,
                             key=key)

        if isinstance(src, Unresolved):
            return fail(src)
        if kind == "jointtarget":
            if not isinstance(src.record, JointTarget):
                return fail(Unresolved("not a jointtarget", True))
            joints = tuple(float(v) for v in self._num(src.record.joints))
            for i, v in enumerate(joints):
                if not abs(v) <= MAX_JOINT_DEG:
                    home = src.home if src.home is not None else pf
                    raise home.source.error(src.record.span.start + src.record.regs[i][0],
                                            f"J{i + 1} is {src.record.texts[i]} deg: not a "
                                            f"joint angle (|J| <= {MAX_JOINT_DEG:g})")
            # Its tool: where its errors are measured and what the wrist
            # singularity's fallback holds exact (the joints reach the
            # flange's whole pose elsewhere, whatever the tool).
            tool = self._tool_of(motion, module)
            if type(tool) is Unresolved:
                self._notes.append(f"{UNKNOWN_TOOL} ({tool.reason}){UNKNOWN_TOOL_MEANS}")
                tool = None
            # (Made as the class makes it, construct.py: a FOR loop's 1e5
            # elements.)
            return _use(motion, role, label, line, kind, None, None, None, joints, None,
                        src, tool, None, envt, False, pf, module,
                        self._one(src.record.ext, True), key, tuple(self._notes))
        if not isinstance(src.record, RobTarget):
            return fail(Unresolved("not a robtarget", True))
        tool, wobj = self._tool_wobj(motion, module)
        if isinstance(tool, Unresolved):
            return fail(self._all_missing(tool, module, motion, tool=False))
        if isinstance(wobj, Unresolved):
            return fail(wobj)
        base = self.world_M_base(src.record)
        if isinstance(base, Unresolved):
            return fail(base)
        # Its confdata, quaternion and position are checked with every
        # other pending use's, in poses() (an error raised before that
        # raises the first pending one's first, as one by one would).
        record = src.record
        u = _use(motion, role, label, line, kind, None, None, self._conf(record), None, None,
                 src, tool, wobj,
                 envt, False, pf, module, self._one(record.ext, True), key,
                 tuple(self._notes))
        self._pending.append((u, src, pf, base, wobj[1], tool[1]))
        return u

    def _conf(self, record: RobTarget) -> tuple:
        """record.conf, as the one tuple this resolver holds for it (a CAM
        program's 1e5 confdata are a few values: each made once, keyed by
        its numbers as written; equal numbers, equal ints)."""
        written = record.values[7:11]
        conf = self._confs.get(written)
        if conf is None:
            conf = self._confs[written] = self._one(record.conf)
        return conf

    def _one(self, value: tuple, floats: bool = False) -> tuple:
        """`value`, as the one tuple this resolver holds equal to it; of
        numbers that may be floats (floats), of the same signs too (0.0 ==
        -0.0, and the two print differently)."""
        if not floats:
            return self._same.setdefault(value, value)
        key = value
        if 0.0 in value:
            key = (value, tuple(math.copysign(1.0, v) for v in value))
        return self._same_floats.setdefault(key, value)

    def _confdata(self, src: Source, pf: ParsedFile) -> None:
        """confdata of a robtarget a move uses: whole numbers, cfx one of
        the 8 configurations, quadrant counts within two turns."""
        record = src.record
        home = src.home if src.home is not None else pf
        for i, name in enumerate(("cf1", "cf4", "cf6", "cfx")):
            v = record.values[7 + i]
            if float(v).is_integer() and (0 <= v <= 7 if name == "cfx" else
                                          abs(v) <= MAX_QUADRANT):
                continue      # (the field's place is lexed again only for a message)
            s, _ = record.regs[7 + i]
            where = record.span.start + s
            what = src.decl.name if src.decl is not None else "the inline robtarget"
            if not float(v).is_integer():
                raise home.source.error(where, f"{what}: confdata {name} is {record.texts[7 + i]}, "
                                        "expected a whole number")
            if name == "cfx" and not 0 <= v <= 7:
                raise home.source.error(where, f"{what}: confdata cfx is {record.texts[7 + i]}, "
                                        "expected 0..7 (the configuration: 4 x shoulder, 2 x "
                                        "elbow, 1 x wrist)")
            if name != "cfx" and abs(v) > MAX_QUADRANT:
                raise home.source.error(where, f"{what}: confdata {name} is {record.texts[7 + i]}, "
                                        f"expected a quadrant count of a joint angle (within "
                                        f"+-{MAX_QUADRANT}, i.e. +-{90 * MAX_QUADRANT} deg)")


def _num_value(expr, module, routine) -> float | None:
    """Resolver.number()'s leaf: a literal number's value."""
    return expr.value if isinstance(expr, A.Num) else None


def _identity(pose) -> bool:
    """A pose of no translation and no rotation (the unit quaternion, of
    either sign), as written."""
    return pose.xyz == (0.0, 0.0, 0.0) and pose.quat_wxyz in ((1.0, 0.0, 0.0, 0.0),
                                                             (-1.0, 0.0, 0.0, 0.0))


def _relative(src: Source, R, p):
    """wobj_M_target: the literal's pose (R, p) through src's Offs/RelTool."""
    if src.call is None:
        return R, p
    if src.call.name.lower() == "offs":
        return R, p + src.rel_d
    return R @ src.rel_R, p + R @ src.rel_d


def _relative_many(R: np.ndarray, p: np.ndarray, srcs: list) -> None:
    """_relative of every row, in place (R (n, 3, 3), p (n, 3) mm: the
    literals' poses of srcs): the Offs rows' displacements added at once,
    the RelTool rows' 3x3 products in one batch (an Offs- or RelTool-relative
    CAM program's 1e5, each alone: 0.35 s). The same products as one by one."""
    offs, rel = [], []
    for i, s in enumerate(srcs):
        if s.call is not None:
            (offs if s.call.name.lower() == "offs" else rel).append(i)
    if offs:
        p[offs] += np.array([srcs[i].rel_d for i in offs])
    if rel:
        R_rel = R[rel]
        d = np.array([srcs[i].rel_d for i in rel])
        p[rel] += np.matmul(R_rel, d[:, :, None])[:, :, 0]
        R[rel] = np.matmul(R_rel, np.array([srcs[i].rel_R for i in rel]))


def _at(offset) -> int:
    return offset() if callable(offset) else offset


def _same_values(decls, home) -> bool:
    texts = {"".join(home[id(d)].text(d.node.init).split()) if d.node.init is not None else ""
             for d in decls}
    return len(texts) == 1


def _missing_name(reason: str) -> str:
    return reason.split(" is not declared")[0]


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
