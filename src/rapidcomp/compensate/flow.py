"""The order in which the controller runs a task's moves, and the motion
state each move runs in.

Three things decide what the controller does with a move besides its own
arguments, and all of them depend on what ran before it:

* configuration supervision (ConfJ for joint moves, ConfL for linear and
  circular ones): on at program start and after PP to main, changed by
  ConfJ/ConfL \\On|\\Off, kept across routine calls. Off, the controller
  takes the solution closest to where the robot is;
* program displacement (PDispOn/PDispSet ... PDispOff): robtarget moves are
  displaced, MoveAbsJ is not;
* where the robot is: the previous move's target.

This walks the task from its entry points through routine calls (each call
site with its own state), IF/TEST branches (joined), FOR loops with
constant bounds (unrolled, so an array walked by a loop is a chain of
moves) and other loops (to a fixed point). Per target use it records the
state before it: each component is the set of values it may have (both,
when it cannot be known statically), and the previous move as the set of
uses that may have run last (None: unknown).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from ..rapid import ast as A
from ..rapid.model import Module, ParsedFile
from ..rapid.motions import (BUILTIN_INSTRUCTIONS, DISPLACEMENT_OFF, DISPLACEMENT_ON,
                             MOVES_OTHERWISE, motion_spec)
from ..rapid.refs import names_in

ON, OFF = "on", "off"
BOTH = frozenset((ON, OFF))
# Statement visits (loops unrolled, routines walked per call site) beyond
# which the flow is not followed: everything is then unknown.
MAX_VISITS = 3_000_000


@dataclass(frozen=True)
class State:
    confj: frozenset
    confl: frozenset
    pdisp: frozenset
    last: frozenset | None     # use keys that may have run last; None: unknown position

    def join(self, other: "State | None") -> "State":
        if other is None or other is self:
            return self
        last = None if self.last is None or other.last is None else self.last | other.last
        return State(self.confj | other.confj, self.confl | other.confl,
                     self.pdisp | other.pdisp, last)

    def supervision(self, interpolation: str) -> frozenset:
        return self.confj if interpolation == "joint" else self.confl


START = State(frozenset((ON,)), frozenset((ON,)), frozenset((OFF,)), None)


def join(*states):
    out = None
    for s in states:
        if s is not None:
            out = s if out is None else out.join(s)
    return out


@dataclass
class Flow:
    before: dict = field(default_factory=dict)   # use key -> State before it
    order: list = field(default_factory=list)    # use keys, first visit first
    notes: list = field(default_factory=list)
    unknown_calls: dict = field(default_factory=dict)  # name -> "file:line" of the first call


class _TooLarge(Exception):
    pass


@dataclass(frozen=True)
class _Routine:
    fi: int
    pf: ParsedFile
    module: Module
    node: A.Routine


class _Walker:
    def __init__(self, files, n_written: int, resolver):
        self.files = files
        self.n_written = n_written
        self.resolver = resolver
        self.flow = Flow()
        self.visits = 0
        self.memo: dict = {}
        self.handled: set = set()
        self.local: dict[tuple[int, str], _Routine] = {}
        self.glob: dict[str, _Routine] = {}
        self.motion_index: dict[tuple[int, int], int] = {}
        self.target_names: dict[tuple[int, int], list] = {}
        self.routines: list[_Routine] = []
        self.has_pdisp = False
        for fi, pf in enumerate(files):
            mi = 0
            for m in pf.modules:
                for r in m.routines:
                    rt = _Routine(fi, pf, m, r.node)
                    self.routines.append(rt)
                    self.local.setdefault((id(m), r.name.lower()), rt)
                    if r.node.scope != "LOCAL":
                        self.glob.setdefault(r.name.lower(), rt)
                for mo in m.motions:
                    self.motion_index[(fi, mo.span.start)] = mi
                    self.target_names[(fi, mi)] = [
                        (t.role, names_in(t.expr)) for t in mo.targets if t.role != "search"]
                    mi += 1

    def callee(self, module: Module, name: str) -> _Routine | None:
        return self.local.get((id(module), name.lower())) or self.glob.get(name.lower())

    # ------------------------------------------------------------ entry
    def run(self) -> Flow:
        called = set()
        for rt in self.routines:
            for name in _called_names(rt.node):
                if name in DISPLACEMENT_ON:
                    self.has_pdisp = True
                c = self.callee(rt.module, name)
                if c is not None and c is not rt:
                    called.add(id(c.node))
        pdisp_unknown = frozenset((OFF, ON)) if self.has_pdisp else frozenset((OFF,))
        entry = State(BOTH, BOTH, pdisp_unknown, None)
        self.unknown = State(BOTH, BOTH, frozenset((OFF, ON)), None)
        main = next((rt for rt in self.routines if rt.fi < self.n_written
                     and rt.node.kind == "PROC" and rt.node.name.lower() == "main"), None)
        others = [rt for rt in self.routines if rt is not main and id(rt.node) not in called]
        try:
            if main is not None:
                self.routine(main, START, ())
            for rt in others:
                self.routine(rt, entry, ())
        except _TooLarge:
            self.flow = Flow(notes=[f"the task's control flow is too large to follow (more than "
                                    f"{MAX_VISITS} statement visits): configuration supervision, "
                                    "program displacement and the previous position of every "
                                    "move are treated as unknown"])
            return self.flow
        moving = [rt for rt in others if rt.fi < self.n_written and _has_motion(rt.node)]
        if moving:
            names = ", ".join(rt.node.name for rt in moving)
            disp = "" if not self.has_pdisp else ", program displacement"
            self.flow.notes.append(
                f"not called by any given routine, so entered from outside what was given "
                f"(PP to routine, another module, an interrupt or a late-bound call): {names}; "
                f"followed with configuration supervision{disp} and the robot position unknown"
                + ("" if self.has_pdisp else "; no given module switches program displacement "
                   "on, so none is assumed"))
        if self.flow.unknown_calls:
            calls = ", ".join(f"{n} ({w})" for n, w in sorted(self.flow.unknown_calls.items()))
            self.flow.notes.append(
                "calls to procedures that are neither RAPID instructions nor routines of the "
                f"given modules: {calls}; after them supervision, displacement and the robot "
                "position are treated as unknown")
        return self.flow

    # ------------------------------------------------------------ routines
    def routine(self, rt: _Routine, state: State, stack: tuple) -> State | None:
        key = (id(rt.node), state)
        if key in self.memo:
            return self.memo[key]
        if id(rt.node) in stack:
            return state.join(self.unknown)  # recursion: the inner call's effect is unknown
        ctx = (rt, stack + (id(rt.node),), [])
        out = self.walk(rt.node.body, state, {}, ctx)
        exit_state = join(out, *ctx[2])
        if id(rt.node) not in self.handled:
            self.handled.add(id(rt.node))
            for h in rt.node.handlers:
                # An error handler runs after a failure anywhere in the routine.
                self.walk(h.body, self.unknown, {}, (rt, ctx[1], []))
        self.memo[key] = exit_state
        return exit_state

    def walk(self, stmts, st: State | None, env: dict, ctx) -> State | None:
        for s in stmts:
            if st is None:
                return None
            self.visits += 1
            if self.visits > MAX_VISITS:
                raise _TooLarge
            t = type(s)
            if t is A.ProcCall:
                st = self.call(s, st, env, ctx)
            elif t is A.LateCall:
                rt = ctx[0]
                self.flow.unknown_calls.setdefault(
                    "%late-bound call%", f"{rt.pf.source.display_path}:{rt.pf.line(s.span)}")
                st = st.join(self.unknown)
                st = replace(st, last=None)
            elif t is A.If:
                outs = [self.walk(body, st, env, ctx) for _, body in s.branches]
                outs.append(self.walk(s.orelse, st, env, ctx) if s.orelse else st)
                st = join(*outs)
            elif t is A.CompactIf:
                st = join(st, self.walk((s.stmt,), st, env, ctx))
            elif t is A.For:
                st = self.for_loop(s, st, env, ctx)
            elif t is A.While:
                st = self.loop(s.body, st, env, ctx)
            elif t is A.Test:
                outs = [self.walk(body, st, env, ctx) for _, body in s.cases]
                outs.append(self.walk(s.default, st, env, ctx) if s.default is not None else st)
                st = join(*outs)
            elif t is A.Simple:
                if s.kind == "RETURN":
                    ctx[2].append(st)
                    st = None
                elif s.kind in ("EXIT", "RAISE", "RETRY", "TRYNEXT", "GOTO"):
                    st = None
                elif s.kind == "LABEL":
                    # A GOTO may jump here from anywhere in the routine.
                    st = replace(st.join(self.unknown), last=None)
        return st

    def for_loop(self, s: A.For, st: State, env: dict, ctx) -> State | None:
        rt = ctx[0]
        values = self.resolver.loop_range(s, rt.module, rt.node.name)
        if values is None:
            return self.loop(s.body, st, env, ctx)
        var = s.var.lower()
        for v in values:
            st = self.walk(s.body, st, {**env, var: v}, ctx)
            if st is None:
                return None
        return st

    def loop(self, body, st: State, env: dict, ctx) -> State:
        head = st
        for _ in range(8):
            out = self.walk(body, head, env, ctx)
            nxt = head.join(out) if out is not None else head
            if nxt == head:
                return head
            head = nxt
        return replace(head.join(self.unknown), last=None)

    # ------------------------------------------------------------ calls
    def call(self, s: A.ProcCall, st: State, env: dict, ctx) -> State:
        rt = ctx[0]
        name = s.name.lower()
        spec = motion_spec(name)
        if spec is not None:
            return self.motion(s, spec, st, env, rt)
        if name in ("confj", "confl"):
            flags = {a.name.lower() for a in s.args if a.kind == "opt"}
            value = frozenset((OFF,)) if "off" in flags else frozenset((ON,)) if "on" in flags \
                else None
            if value is None:
                return st
            return replace(st, **{name: value})
        if name in DISPLACEMENT_ON:
            return replace(st, pdisp=frozenset((ON,)))
        if name in DISPLACEMENT_OFF:
            return replace(st, pdisp=frozenset((OFF,)))
        if name in MOVES_OTHERWISE:
            return replace(st, last=None)
        callee = self.callee(rt.module, name)
        if callee is not None:
            out = self.routine(callee, st, ctx[1])
            return out if out is not None else st
        if name in BUILTIN_INSTRUCTIONS:
            return st
        self.flow.unknown_calls.setdefault(s.name, f"{rt.pf.source.display_path}:"
                                                   f"{rt.pf.line(s.span)}")
        return replace(st.join(self.unknown), last=None)

    def motion(self, s: A.ProcCall, spec, st: State, env: dict, rt: _Routine) -> State:
        if spec.interpolation == "external":
            return st
        fi = rt.fi
        mi = self.motion_index[(fi, s.span.start)]
        written = fi < self.n_written
        last = None
        for role, names in self.target_names[(fi, mi)]:
            envr = tuple(sorted((k, v) for k, v in env.items() if k in names))
            key = (fi, mi, role, envr)
            if written:
                old = self.flow.before.get(key)
                if old is None:
                    self.flow.order.append(key)
                    self.flow.before[key] = st
                else:
                    self.flow.before[key] = old.join(st)
            last = frozenset((key,)) if written else None
            st = replace(st, last=last)
        if "search" in spec.roles:
            # A search stops where the sensor triggers: position unknown.
            st = replace(st, last=None)
        return st


def _called_names(node: A.Routine):
    """Lower-case names of the procedures a routine calls (statically)."""
    stack = [node.body] + [h.body for h in node.handlers]
    while stack:
        stmts = stack.pop()
        for s in stmts:
            t = type(s)
            if t is A.ProcCall:
                yield s.name.lower()
            elif t is A.If:
                stack.extend(body for _, body in s.branches)
                stack.append(s.orelse)
            elif t is A.CompactIf:
                stack.append((s.stmt,))
            elif t in (A.For, A.While):
                stack.append(s.body)
            elif t is A.Test:
                stack.extend(body for _, body in s.cases)
                if s.default:
                    stack.append(s.default)


def _has_motion(node: A.Routine) -> bool:
    return any(motion_spec(n) is not None for n in _called_names(node))


def analyse(files: list[ParsedFile], n_written: int, resolver) -> Flow:
    """The flow of the task made of files[:n_written] (files after that are
    --with modules: their routines are followed, their moves are not
    recorded)."""
    return _Walker(files, n_written, resolver).run()
