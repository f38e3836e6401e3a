"""`rapidcomp fix`: compensate every statically known target of a program
and splice the new values into its text.

Pipeline: resolve target uses (targets.py) -> group them by where their new
value will be written -> solve all values in one batch (nominal closed form,
then Newton on the deformed robot) -> decide placement (edit the literal in
place, or declare a new one next to it) -> span edits -> output text ->
re-parse the output and verify every written value with the float32 numbers
the controller will store.

Modes. absj: MoveJ/MoveL become MoveAbsJ on a new jointtarget; other
instructions get compensated robtargets. robtarget: every instruction keeps
its kind; robtargets become the pose the ideal controller must be given so
that its own IK lands on the compensated joints.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..edits import SpanEdit, apply_edits
from ..errors import RapidcompError
from ..kinematics.conf import confdata
from ..kinematics.frames import DEG
from ..kinematics.ik import IKBatch, Solver
from ..rapid import ast as A
from ..rapid.model import Declaration, Module, ParsedFile
from ..rapid.parse import parse_text
from ..rewrite import records
from ..rewrite.diff import unified_diff
from ..rewrite.names import NameAllocator
from .targets import Resolver, Source, TargetUse, base_pose, compose_pose, invert_pose

MODES = ("absj", "robtarget")
# Optional arguments MoveJ/MoveL share with MoveAbsJ (RAPID Instructions
# manual); anything else (\Corr) keeps the instruction as it is.
ABSJ_OPTIONALS = frozenset({"conc", "id", "v", "t", "z", "inpos", "wobj", "tload"})
TO_ABSJ = frozenset({"movej", "movel"})
LINEAR_WARNING = "MoveL -> MoveAbsJ: the path to this point is no longer a straight line"
# Acceptance of a written value, after float32 rounding (the bound).
VERIFY_UM = 1.0
VERIFY_DEG = 1e-4


class InternalError(RapidcompError):
    """The output failed its own check; nothing is written."""


@dataclass(frozen=True)
class FixRow:
    line: int
    instruction: str
    target: str
    status: str                      # "compensated", "not compensated", "untouched"
    action: str | None
    nominal_deg: tuple[float, ...] | None
    compensated_deg: tuple[float, ...] | None
    delta_deg: tuple[float, ...] | None
    error_um: float | None           # uncompensated program on the warm robot
    error_deg: float | None
    residual_um: float | None        # written output on the warm robot (float32 values)
    residual_deg: float | None
    conf_before: tuple[int, ...] | None
    conf_after: tuple[int, ...] | None
    warnings: tuple[str, ...]
    reason: str | None


@dataclass(frozen=True)
class FixResult:
    mode: str
    program: str                     # display name of the input
    output: str                      # display name of the output
    text: str                        # output text (== input text when nothing changed)
    edits: tuple[SpanEdit, ...]
    rows: tuple[FixRow, ...]
    diff: tuple[str, ...]
    notes: tuple[str, ...]

    @property
    def failed(self) -> int:
        return sum(r.status == "not compensated" for r in self.rows)

    def summary(self) -> dict:
        comp = [r for r in self.rows if r.status == "compensated"]
        untouched: dict[str, int] = {}
        for r in self.rows:
            if r.status == "untouched":
                untouched[r.reason] = untouched.get(r.reason, 0) + 1
        errs = [r.error_um for r in comp]
        res = [r.residual_um for r in comp]
        return {
            "target_uses": len(self.rows),
            "compensated": len(comp),
            "not_compensated": self.failed,
            "untouched": dict(sorted(untouched.items())),
            "error_before_um": {"max": max(errs), "mean": float(np.mean(errs))} if errs else None,
            "residual_after_um": {"max": max(res), "mean": float(np.mean(res))} if res else None,
            "movel_to_moveabsj": sum(1 for r in comp if LINEAR_WARNING in r.warnings),
            "edits": len(self.edits),
        }


@dataclass(frozen=True, eq=False)
class _Batch:
    """One solved batch (robtargets or jointtargets), row i = items[i]."""

    items: list                      # (group, element)
    R: np.ndarray                    # intended base_M_flange
    p: np.ndarray
    nominal: IKBatch
    deformed: IKBatch
    err_p: np.ndarray                # uncompensated error on the warm robot, mm
    err_r: np.ndarray                # ... rad
    flange_R: np.ndarray             # nominal FK of the compensated joints
    flange_p: np.ndarray
    conf_after: np.ndarray           # confdata of the compensated joints (ideal robot)


# ---------------------------------------------------------------- groups

@dataclass(eq=False)
class _Group:
    """Target uses whose compensated value is written in one place."""

    mode: str                        # "absj", "rob" or "joint"
    src: Source
    tool: tuple | None
    wobj: tuple | None
    uses: list[TargetUse] = field(default_factory=list)
    array: bool = False              # all elements of the array (FOR-loop index)
    elements: list = field(default_factory=list)  # element indices, or [None]
    sol: dict = field(default_factory=dict)       # element -> row in the solved batch
    failure: str | None = None
    placement: str | None = None     # "inline", "in place", "new"
    names: dict = field(default_factory=dict)     # element (or "array") -> new name

    @property
    def decl(self) -> Declaration | None:
        return self.src.decl


def _mode_of(u: TargetUse, mode: str) -> str:
    if u.kind == "jointtarget":
        return "joint"
    m = u.motion
    if (mode == "absj" and m.spec.name.lower() in TO_ABSJ
            and all(a.name.lower() in ABSJ_OPTIONALS for a in m.optional)):
        return "absj"
    return "rob"


def _call_key(src: Source):
    if src.call is None:
        return None
    return (src.call.name.lower(), tuple(np.round(src.rel_d, 12)),
            tuple(np.round(src.rel_R, 12).ravel()))


def _group_key(u: TargetUse, mode: str):
    src = u.source
    where = ("decl", id(src.decl)) if src.decl is not None else ("inline", src.ref.span)
    context = (None, None) if mode == "joint" else (u.tool[0], u.wobj[0])
    return (mode, where, _call_key(src)) + context


def _multi_index(flat: int, dims: tuple[int, ...]) -> tuple[int, ...]:
    out = []
    for dim in reversed(dims):
        out.append(flat % dim + 1)
        flat //= dim
    return tuple(reversed(out))


def _element_label(g: _Group, k) -> str:
    if k is None:
        return g.decl.name if g.decl is not None else "inline target"
    return f"{g.decl.name}{{{','.join(map(str, _multi_index(k, g.decl.dims)))}}}"


# ---------------------------------------------------------------- planning

class _Plan:
    def __init__(self, files: list[ParsedFile], solver: Solver, mode: str):
        if mode not in MODES:
            raise ValueError(f"mode must be one of {MODES}")
        self.files = files
        self.program = files[0]
        self.solver = solver
        self.mode = mode
        self.resolver = Resolver(files)
        self.uses: list[tuple[int, TargetUse]] = []   # (motion index, use)
        n = 0
        for m in self.program.modules:
            for motion in m.motions:
                for u in self.resolver.resolve(self.program, motion):
                    self.uses.append((n, u))
                n += 1
        self.groups: list[_Group] = []
        self.group_of: dict[int, _Group] = {}       # id(use) -> group
        self._group()

    # -------------------------------------------------------- grouping
    def _group(self) -> None:
        by_key: dict = {}
        for _, u in self.uses:
            if u.reason is not None:
                continue
            mode = _mode_of(u, self.mode)
            key = _group_key(u, mode)
            g = by_key.get(key)
            if g is None:
                g = by_key[key] = _Group(mode, u.source, u.tool, u.wobj)
                self.groups.append(g)
            g.uses.append(u)
            self.group_of[id(u)] = g
        for g in self.groups:
            if any(u.source.by_loop for u in g.uses):
                g.array = True
                g.elements = list(range(len(g.decl.value)))
            else:
                seen = []
                for u in g.uses:
                    if u.source.element not in seen:
                        seen.append(u.source.element)
                g.elements = seen

    def _element_source(self, g: _Group, k) -> Source:
        if k is None or k == g.src.element:
            return g.src
        return replace(g.src, record=g.decl.value[k], element=k)

    # -------------------------------------------------------- solving
    def solve(self) -> None:
        rob, joint = [], []
        for g in self.groups:
            for k in g.elements:
                (joint if g.mode == "joint" else rob).append((g, k))
        s = self.solver
        solved = {}
        if rob:
            R = np.empty((len(rob), 3, 3))
            p = np.empty((len(rob), 3))
            conf = np.empty((len(rob), 4), dtype=int)
            for i, (g, k) in enumerate(rob):
                src = self._element_source(g, k)
                Rf, pf = compose_pose(compose_pose(g.wobj[1], self.resolver.target_pose(src)),
                                      invert_pose(g.tool[1]))
                R[i], p[i], conf[i] = Rf, pf, src.record.conf
            solved["rob"] = (rob, R, p) + s.compensate(R, p, conf)
        if joint:
            q = np.array([self._element_source(g, k).record.joints for g, k in joint], float)
            R, p, nominal = s.seed_from_joints(q)
            solved["joint"] = (joint, R, p, nominal, s.solve_deformed(R, p, nominal))
        self.batches: dict[str, _Batch] = {}
        for name, (items, R, p, nominal, deformed) in solved.items():
            err_p, err_r = s.deformed_pose_error(np.nan_to_num(nominal.q_deg) * DEG, R, p)
            qc = np.nan_to_num(deformed.q_deg) * DEG
            Rn, pn = s.nominal_chain.fk(qc)
            _, frames = s.nominal_chain.joint_frames(qc)
            conf_after = confdata(qc, frames[:, 4], s.geometry.phi)
            for i, (g, k) in enumerate(items):
                g.sol[k] = (name, i)
            for i in np.flatnonzero(~(nominal.success & deformed.success)):
                g, k = items[i]
                if g.failure is None:
                    why = (f"nominal: {nominal.reason(i)}" if not nominal.success[i]
                           else deformed.reason(i))
                    g.failure = (why, k)
            self.batches[name] = _Batch(items, R, p, nominal, deformed, err_p, err_r, Rn, pn,
                                        conf_after)

    # -------------------------------------------------------- placement
    def place(self) -> None:
        refs: dict[str, set] = {}
        decl_count: dict[str, int] = {}
        for pf in self.files:
            for m in pf.modules:
                for name, rs in self.resolver.usages[id(m)].refs.items():
                    refs.setdefault(name, set()).update((id(pf), r.span) for r in rs)
                for d in m.declarations:
                    decl_count[d.name.lower()] = decl_count.get(d.name.lower(), 0) + 1
        consumed = {(id(self.program), u.source.ref.span)
                    for g in self.groups if g.mode == "absj" and g.failure is None
                    for u in g.uses if g.decl is not None}
        for g in self.groups:
            if g.failure is not None:
                continue
            if g.decl is None:
                g.placement = "inline"
                continue
            if g.mode == "absj":
                g.placement = "new"
                continue
            name = g.decl.name.lower()
            mine = {(id(self.program), u.source.ref.span) for u in g.uses}
            exclusive = (g.src.home is self.program and decl_count.get(name) == 1
                         and refs.get(name, set()) - consumed == mine)
            g.placement = "in place" if exclusive else "new"

    # -------------------------------------------------------- values
    def joints(self, g: _Group, k) -> np.ndarray:
        name, i = g.sol[k]
        return self.batches[name].deformed.q_deg[i]

    def robtarget_value(self, g: _Group, k):
        """(R, p, conf) of the literal the ideal controller must be given:
        nominal FK of the compensated joints, back in the tool and work
        object, with Offs/RelTool undone."""
        name, i = g.sol[k]
        b = self.batches[name]
        flange = (b.flange_R[i], b.flange_p[i])
        target = compose_pose(compose_pose(invert_pose(g.wobj[1]), flange), g.tool[1])
        return (*base_pose(g.src, target), b.conf_after[i])

    def field_texts(self, g: _Group, k) -> list[str]:
        record = self._element_source(g, k).record
        if g.mode == "joint":
            return records.jointtarget_texts(record, self.joints(g, k))
        R, p, conf = self.robtarget_value(g, k)
        return records.robtarget_texts(record, R, p, conf)

    def literal(self, g: _Group, k, texts: list[str] | None = None) -> str:
        """The new literal of element k (`texts`: its field texts, when the
        caller has them already)."""
        record = self._element_source(g, k).record
        if g.mode == "absj":
            return records.jointtarget_literal(records.absj_texts(self.joints(g, k), record))
        texts = texts if texts is not None else self.field_texts(g, k)
        if g.mode == "joint":
            return records.jointtarget_literal(texts)
        return records.robtarget_literal(texts)


# ---------------------------------------------------------------- text edits

def _style(word: str, like: str) -> str:
    """An inserted keyword in the letter case of the word it replaces."""
    if like.islower():
        return word.lower()
    if like.isupper():
        return word.upper()
    return word


def _line_end(text: str, pos: int) -> tuple[int, str]:
    """Offset of the end of the line holding `pos`, and its line break."""
    n = len(text)
    i = pos
    while i < n and text[i] not in "\r\n":
        i += 1
    if i == n:
        return n, "\n"
    return i, "\r\n" if text.startswith("\r\n", i) else text[i]


def _indent(text: str, pos: int) -> str:
    start = max(text.rfind("\n", 0, pos), text.rfind("\r", 0, pos)) + 1
    i = start
    while i < len(text) and text[i] in " \t":
        i += 1
    return text[start:i]


def _module_of(pf: ParsedFile, span) -> Module:
    for m in pf.modules:
        if m.node.span.start <= span.start < m.node.span.end:
            return m
    return pf.modules[0]


class _Editor:
    def __init__(self, plan: _Plan):
        self.plan = plan
        self.text = plan.program.source.text
        self.names = NameAllocator([pf.source.text for pf in plan.files])
        self.edits: dict[tuple[int, int], SpanEdit] = {}
        self.inserts: dict[int, list[str]] = {}      # offset -> declarations to insert
        self.insert_nl: dict[int, str] = {}
        self.insert_indent: dict[int, str] = {}
        self.actions: dict[int, str] = {}            # id(use) -> what was done

    def edit(self, span, text: str, why: str) -> None:
        key = (span.start, span.end)
        old = self.edits.get(key)
        if old is not None and old.replacement != text:
            raise InternalError(f"conflicting edits at offset {span.start}: {why}")
        self.edits[key] = SpanEdit(span.start, span.end, text, why)

    # -------------------------------------------------------- declarations
    def _anchor(self, g: _Group, motion_span) -> tuple[int, str, str, bool]:
        """Where a new declaration goes: after the source declaration when
        it is in the program, else after the module's last data
        declaration (or its MODULE line). Returns (line end offset, line
        break, indentation, in a routine)."""
        if g.decl is not None and g.src.home is self.plan.program:
            span, in_routine = g.decl.span, g.decl.routine is not None
            indent = _indent(self.text, span.start)
        else:
            module = _module_of(self.plan.program, motion_span)
            last = None
            for item in module.node.items:
                if isinstance(item, A.DataDecl):
                    last = item
                elif isinstance(item, A.Routine):
                    break
            span = last.span if last is not None else module.node.name_span
            indent = _indent(self.text, span.start) if last is not None else (
                _indent(self.text, span.start) + "    ")
            in_routine = False
        end, nl = _line_end(self.text, span.end)
        return end, nl, indent, in_routine

    def declare(self, g: _Group, motion_span, type_name: str, name: str, dims: str,
                value: str) -> None:
        end, nl, indent, in_routine = self._anchor(g, motion_span)
        scope = "" if in_routine else "LOCAL "
        decl = f"{scope}CONST {type_name} {name}{dims} := {value};"
        self.inserts.setdefault(end, []).append(decl)
        self.insert_nl[end] = nl
        self.insert_indent[end] = indent

    def array_value(self, g: _Group, nl: str, indent: str, texts: dict) -> str:
        dims = g.decl.dims
        lits = [self.plan.literal(g, k, texts.get(k)) for k in g.elements]
        rows = len(lits) // dims[0]

        def nest(items, ds):
            if len(ds) == 1:
                return "[" + ",".join(items) + "]"
            step = len(items) // ds[0]
            return "[" + ",".join(nest(items[i * step:(i + 1) * step], ds[1:])
                                  for i in range(ds[0])) + "]"
        parts = [nest(lits[i * rows:(i + 1) * rows], dims[1:]) if len(dims) > 1 else lits[i]
                 for i in range(dims[0])]
        inner = indent + "    "
        return "[" + nl + inner + ("," + nl + inner).join(parts) + "]"

    # -------------------------------------------------------- per group
    def apply(self, g: _Group) -> None:
        plan = self.plan
        first = g.uses[0]
        type_name = "jointtarget" if g.mode in ("absj", "joint") else "robtarget"
        texts = {} if g.mode == "absj" else {k: plan.field_texts(g, k) for k in g.elements}
        if g.mode != "absj" and all(
                texts[k] == list(plan._element_source(g, k).record.texts) for k in g.elements):
            # Nothing moves beyond the precision a new text would carry: the
            # value stays as written (a zero profile changes no byte).
            for u in g.uses:
                self.actions[id(u)] = "unchanged (the change is below the written precision)"
            return
        if g.placement == "in place" or (g.placement == "inline" and g.mode != "absj"):
            for k in g.elements:
                record = plan._element_source(g, k).record
                for e in records.field_edits(record, texts[k],
                                             f"{_element_label(g, k)} compensated"):
                    self.edit(e, e.replacement, e.why)
            what = (f"inline {type_name} rewritten" if g.decl is None
                    else f"{type_name} {g.decl.name} rewritten in place")
            for u in g.uses:
                self.actions[id(u)] = what
            return
        if g.placement == "inline":  # absj of an inline robtarget: inline jointtarget
            for u in g.uses:
                self._to_absj(u, plan.literal(g, None))
                self.actions[id(u)] = f"{u.motion.instruction} -> MoveAbsJ, inline jointtarget"
            return
        # A new declaration next to the source one.
        stem = g.decl.name
        if g.src.call is not None:
            stem += "_" + g.src.call.name.lower()
        if g.array:
            name = self.names.new(("jt_" + stem) if g.mode == "absj" else stem + "_c")
            _, nl, indent, _ = self._anchor(g, first.motion.span)
            dims = "{" + ",".join(map(str, g.decl.dims)) + "}"
            self.declare(g, first.motion.span, type_name, name, dims,
                         self.array_value(g, nl, indent, texts))
            g.names["array"] = name
        else:
            for k in g.elements:
                s = stem if k is None else stem + "_" + "_".join(
                    map(str, _multi_index(k, g.decl.dims)))
                name = self.names.new(("jt_" + s) if g.mode == "absj" else s + "_c")
                self.declare(g, first.motion.span, type_name, name, "",
                             plan.literal(g, k, texts.get(k)))
                g.names[k] = name
        for u in g.uses:
            src = u.source
            if g.array:
                ref_text = plan.program.text(src.ref)
                new_ref = g.names["array"] + ref_text[len(src.ref.name):]
            else:
                new_ref = g.names[src.element]
            if g.mode == "absj":
                self._to_absj(u, new_ref)
                self.actions[id(u)] = f"{u.motion.instruction} -> MoveAbsJ {new_ref}"
            else:
                self.edit(src.ref.span, new_ref, f"{u.label} -> {new_ref}")
                self.actions[id(u)] = f"new {type_name} {new_ref.split('{')[0]}"

    def _to_absj(self, u: TargetUse, target_text: str) -> None:
        m = u.motion
        self.edit(m.name_span, _style("MoveAbsJ", m.instruction), f"{m.instruction} -> MoveAbsJ")
        self.edit(u.source.expr.span, target_text, f"{u.label} -> {target_text[:40]}")

    def all_edits(self) -> list[SpanEdit]:
        out = list(self.edits.values())
        for pos, decls in self.inserts.items():
            nl, indent = self.insert_nl[pos], self.insert_indent[pos]
            out.append(SpanEdit(pos, pos, "".join(nl + indent + d for d in decls),
                                "new declarations"))
        return sorted(out, key=lambda e: (e.start, e.end))


# ---------------------------------------------------------------- verification

def _verify(plan: _Plan, out_pf: ParsedFile) -> dict[int, tuple[float, float]]:
    """Residual (um, deg) of every compensated use, evaluated on the written
    output: its values rounded to float32, robtargets through the ideal
    controller's IK, joints through the deformed robot's FK."""
    s = plan.solver
    # Run-time writes were ruled out on the input; the output adds none.
    out_res = Resolver([out_pf] + plan.files[1:], float32=True,
                       usages=plan.resolver.usages, writes=False)
    out_uses: dict = {}
    n = 0
    for m in out_pf.modules:
        for motion in m.motions:
            for u in out_res.resolve(out_pf, motion):
                out_uses[(n, u.role, u.env)] = u
            n += 1
    want = [(n, u) for n, u in plan.uses if u.reason is None
            and plan.group_of[id(u)].failure is None]
    outs = []
    for n, u in want:
        o = out_uses.get((n, u.role, u.env))
        if o is None or o.reason is not None:
            raise InternalError(f"line {u.line}: the written target of {u.label} does not "
                                f"resolve ({o.reason if o else 'missing'})")
        outs.append(o)
    q = np.full((len(want), 6), np.nan)
    rob = [i for i, o in enumerate(outs) if o.kind == "robtarget"]
    if rob:
        sol = s.solve_nominal(np.array([outs[i].R for i in rob]), np.array([outs[i].p for i in rob]),
                              np.array([outs[i].conf for i in rob]))
        q[rob] = sol.q_deg
    for i, o in enumerate(outs):
        if o.kind == "jointtarget":
            q[i] = o.joints_deg
    # The intended flange pose of each use, as solved (robtargets: through
    # tool and work object; jointtargets: nominal FK of the joints).
    R = np.empty((len(want), 3, 3))
    p = np.empty((len(want), 3))
    for i, (_, u) in enumerate(want):
        name, j = plan.group_of[id(u)].sol[u.source.element]
        R[i], p[i] = plan.batches[name].R[j], plan.batches[name].p[j]
    err_p, err_r = s.deformed_pose_error(np.nan_to_num(q) * DEG, R, p)
    out = {}
    for i, (_, u) in enumerate(want):
        if np.isnan(q[i]).any():
            raise InternalError(f"line {u.line}: the ideal controller finds no solution for "
                                f"the written target of {u.label}")
        out[id(u)] = (float(err_p[i]) * 1000, float(err_r[i]) / DEG)
    return out


# ---------------------------------------------------------------- entry point

def fix(files: list[ParsedFile], solver: Solver, mode: str = "absj",
        output_name: str = "<output>", timings: dict | None = None) -> FixResult:
    """Compensate files[0] (files[1:] supply tool/work object/target data).

    Targets that cannot be compensated keep their text and are listed with
    the reason; whether to write such an output is the caller's decision
    (FixResult.failed). `timings`, when given, receives seconds per stage."""
    import gc
    # Like the parser: 1e5 targets make millions of small objects and no
    # cycles; the cyclic collector would rescan them all, again and again.
    enabled = gc.isenabled()
    gc.disable()
    try:
        return _fix(files, solver, mode, output_name, timings)
    finally:
        if enabled:
            gc.enable()


def _fix(files, solver, mode, output_name, timings) -> FixResult:
    clock = _Clock(timings)
    plan = _Plan(files, solver, mode)
    clock("resolve")
    plan.solve()
    clock("solve")
    plan.place()
    editor = _Editor(plan)
    for g in plan.groups:
        if g.failure is None:
            editor.apply(g)
    edits = editor.all_edits()
    text = apply_edits(plan.program.source.text, edits)
    clock("print")
    try:
        out_pf = parse_text(text, output_name)
    except RapidcompError as exc:
        raise InternalError(f"the compensated module does not parse: {exc}") from exc
    clock("re-parse")
    verified = _verify(plan, out_pf) if edits or plan.groups else {}
    clock("verify")
    rows = tuple(_row(plan, editor, u, verified) for _, u in plan.uses)
    notes = []
    absj_lines = sorted({r.line for r in rows if LINEAR_WARNING in r.warnings})
    if absj_lines:
        notes.append("MoveL -> MoveAbsJ gives up the straight-line path between points "
                     f"(lines {_ranges(absj_lines)}); use --emit robtarget to keep MoveL linear.")
    for r in rows:
        if r.status == "compensated" and (r.residual_um > VERIFY_UM or r.residual_deg > VERIFY_DEG):
            raise InternalError(f"line {r.line}: written value of {r.target} misses by "
                                f"{r.residual_um:.3f} um / {r.residual_deg:.2e} deg")
    diff = unified_diff(plan.program.source.text, edits, plan.program.source.display_path,
                        output_name)
    clock("report")
    return FixResult(mode, plan.program.source.display_path, output_name, text, tuple(edits),
                     rows, tuple(diff), tuple(notes))


class _Clock:
    def __init__(self, timings: dict | None):
        import time
        self.now = time.perf_counter
        self.timings = timings
        self.last = self.now()

    def __call__(self, stage: str) -> None:
        if self.timings is not None:
            t = self.now()
            self.timings[stage] = self.timings.get(stage, 0.0) + t - self.last
            self.last = t


def _ranges(lines: list[int]) -> str:
    out = []
    start = prev = lines[0]
    for x in lines[1:] + [None]:
        if x is not None and x == prev + 1:
            prev = x
            continue
        out.append(str(start) if start == prev else f"{start}-{prev}")
        if x is not None:
            start = prev = x
    return ", ".join(out)


def _t(a) -> tuple[float, ...] | None:
    return None if a is None or np.isnan(a).any() else tuple(round(float(x), 6) for x in a)


def _row(plan: _Plan, editor: _Editor, u: TargetUse, verified) -> FixRow:
    base = dict(line=u.line, instruction=u.motion.instruction, target=u.label)
    if u.reason is not None:
        return FixRow(**base, status="untouched", action=None, nominal_deg=None,
                      compensated_deg=None, delta_deg=None, error_um=None, error_deg=None,
                      residual_um=None, residual_deg=None, conf_before=None, conf_after=None,
                      warnings=(), reason=u.reason)
    g = plan.group_of[id(u)]
    k = u.source.element
    name, i = g.sol[k]
    b = plan.batches[name]
    nominal, deformed = b.nominal, b.deformed
    n_ok = bool(nominal.success[i])
    d_warnings = deformed.warning_texts(i)
    qn = nominal.q_deg[i]
    error = (float(b.err_p[i]) * 1000, float(b.err_r[i]) / DEG) if n_ok else (None, None)
    conf_before = tuple(int(c) for c in (u.conf if u.conf is not None else nominal.conf[i]))
    if g.failure is not None:
        why, fk = g.failure
        reason = why if fk == k else f"{_element_label(g, fk)} of the same array: {why}"
        return FixRow(**base, status="not compensated", action=None, nominal_deg=_t(qn),
                      compensated_deg=None, delta_deg=None, error_um=error[0],
                      error_deg=error[1], residual_um=None, residual_deg=None,
                      conf_before=conf_before, conf_after=None,
                      warnings=d_warnings if n_ok else (), reason=reason)
    qc = deformed.q_deg[i]
    warnings = d_warnings
    if g.mode == "absj" and u.motion.spec.name == "MoveL":
        warnings = warnings + (LINEAR_WARNING,)
    elif plan.mode == "absj" and g.mode == "rob" and u.motion.spec.name.lower() in TO_ABSJ:
        extra = ", ".join("\\" + a.name for a in u.motion.optional
                          if a.name.lower() not in ABSJ_OPTIONALS)
        warnings = warnings + (f"kept as {u.motion.instruction}: {extra} has no MoveAbsJ "
                               "equivalent",)
    res = verified[id(u)]
    return FixRow(**base, status="compensated", action=editor.actions.get(id(u)),
                  nominal_deg=_t(qn), compensated_deg=_t(qc), delta_deg=_t(qc - qn),
                  error_um=error[0], error_deg=error[1], residual_um=res[0], residual_deg=res[1],
                  conf_before=conf_before, conf_after=tuple(int(c) for c in b.conf_after[i]),
                  warnings=warnings, reason=None)
