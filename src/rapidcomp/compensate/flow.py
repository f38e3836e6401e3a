"""The order in which the controller runs a task's moves, and the motion
state each move runs in.

Three things decide what the controller does with a move besides its own
arguments, and all of them depend on what ran before it:

* configuration supervision (ConfJ for joint moves, ConfL for linear and
  circular ones): on at program start, changed by ConfJ/ConfL \\On|\\Off,
  kept across routine calls. Off, the controller takes the solution closest
  to where the robot is;
* program displacement (PDispOn/PDispSet ... PDispOff; with a track,
  EOffsOn/EOffsSet too): robtarget moves are displaced, MoveAbsJ is not;
* where the robot is: the previous move's target.

This walks the task from main through routine calls (each call site with
its own state), IF/TEST branches (joined), FOR loops with constant bounds
(unrolled, so an array walked by a loop is a chain of moves) and other
loops (to a fixed point). It is sound where it must guess: main is walked
again from the state its cycle ends in (continuous run restarts main
without resetting), a routine that calls itself has its moves recorded in
the unknown state, an error handler starts where any statement of its
routine may have left off and what it leaves behind flows on, a TRAP that
switches supervision or displacement makes them unknown everywhere, and a
call whose target is not known statically (%...%, CallByVar, a procedure
no given module declares) makes everything unknown after it.

Per target use it records the state before it: each component is the set
of values it may have, and the previous move as the set of uses that may
have run last (None: unknown).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from ..rapid import ast as A
from ..rapid.model import Module, ParsedFile
from ..rapid.motions import (BUILTIN_INSTRUCTIONS, DISPLACEMENT_OFF, DISPLACEMENT_ON,
                             MOVES_OTHERWISE, SUPERVISION, TRACK_OFFSET_ON, UNKNOWN_TARGET_CALLS,
                             motion_spec)
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

    def flags(self) -> tuple:
        return (self.confj, self.confl, self.pdisp)


START = State(frozenset((ON,)), frozenset((ON,)), frozenset((OFF,)), None)
UNKNOWN = State(BOTH, BOTH, frozenset((OFF, ON)), None)


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


@dataclass
class _Frame:
    """One walk of a routine: the call stack, the states its RETURNs and
    RETRYs leave, and the join of every state inside it (where an error
    handler may start)."""

    rt: _Routine
    stack: tuple
    returns: list = field(default_factory=list)
    retries: list = field(default_factory=list)
    inside: State | None = None
    exit_cycle: bool = False


class _Walker:
    def __init__(self, files, n_written: int, resolver, track: bool):
        self.files = files
        self.n_written = n_written
        self.resolver = resolver
        self.track = track
        self.flow = Flow()
        self.visits = 0
        self.memo: dict = {}
        self.recursed: set = set()
        self.cycle_ends: list = []
        self.local: dict[tuple[int, str], _Routine] = {}
        self.glob: dict[str, _Routine] = {}
        self.motion_index: dict[tuple[int, int], int] = {}
        self.target_names: dict[tuple[int, int], list] = {}
        self.routines: list[_Routine] = []
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
        self.displacing = DISPLACEMENT_ON | (TRACK_OFFSET_ON if track else frozenset())

    def callee(self, module: Module, name: str) -> _Routine | None:
        return self.local.get((id(module), name.lower())) or self.glob.get(name.lower())

    # ------------------------------------------------------------ entry
    def run(self) -> Flow:
        called = set()
        has_pdisp = False
        for rt in self.routines:
            for name in _called_names(rt.node):
                if name in self.displacing:
                    has_pdisp = True
                c = self.callee(rt.module, name)
                if c is not None and c is not rt:
                    called.add(id(c.node))
        pdisp_entry = frozenset((OFF, ON)) if has_pdisp else frozenset((OFF,))
        entry = State(BOTH, BOTH, pdisp_entry, None)
        main = next((rt for rt in self.routines if rt.fi < self.n_written
                     and rt.node.kind == "PROC" and rt.node.name.lower() == "main"), None)
        others = [rt for rt in self.routines if rt is not main and id(rt.node) not in called]
        try:
            if main is not None:
                self.main(main)
            for rt in others:
                self.routine(rt, entry, ())
        except _TooLarge:
            self.flow = Flow(notes=[f"the task's control flow is too large to follow (more than "
                                    f"{MAX_VISITS} statement visits): configuration supervision, "
                                    "program displacement and the previous position of every "
                                    "move are treated as unknown"])
            return self.flow
        self.interrupts(others)
        self.notes(others, has_pdisp)
        return self.flow

    def main(self, main: _Routine) -> None:
        """main from program start; then again from the state a cycle ends
        in (continuous run restarts main without resetting supervision or
        displacement), until nothing new is reached."""
        state = START
        for _ in range(4):
            self.cycle_ends = []
            out = self.routine(main, state, ())
            ends = join(out, *self.cycle_ends)
            if ends is None:
                return
            nxt = state.join(replace(ends, last=None))
            if nxt == state:
                return
            state = nxt

    def interrupts(self, others: list[_Routine]) -> None:
        """A TRAP may run between any two statements: what it switches
        (supervision, displacement) is unknown everywhere."""
        switched: set[str] = set()
        for rt in others:
            if rt.node.kind != "TRAP":
                continue
            for name in self._reachable_calls(rt):
                if name in SUPERVISION:
                    switched.add(name)
                elif name in self.displacing or name in DISPLACEMENT_OFF:
                    switched.add("pdisp")
        if not switched:
            return
        widen = {k: (BOTH if k != "pdisp" else frozenset((OFF, ON))) for k in switched}
        for key, st in self.flow.before.items():
            self.flow.before[key] = replace(st, **widen)
        self.flow.notes.append("an interrupt routine (TRAP) switches "
                               + ", ".join(sorted(k if k != "pdisp" else "program displacement"
                                                  for k in switched))
                               + ": it may run anywhere, so that state is unknown everywhere")

    def _reachable_calls(self, rt: _Routine) -> set[str]:
        seen, names, todo = set(), set(), [rt]
        while todo:
            r = todo.pop()
            if id(r.node) in seen:
                continue
            seen.add(id(r.node))
            for name in _called_names(r.node):
                names.add(name)
                c = self.callee(r.module, name)
                if c is not None:
                    todo.append(c)
        return names

    def notes(self, others: list[_Routine], has_pdisp: bool) -> None:
        moving = [rt for rt in others if rt.fi < self.n_written and _has_motion(rt.node)]
        if moving:
            names = ", ".join(rt.node.name for rt in moving)
            disp = "" if not has_pdisp else ", program displacement"
            self.flow.notes.append(
                f"not called by any given routine, so entered from outside what was given "
                f"(PP to routine, another module, an interrupt or a late-bound call): {names}; "
                f"followed with configuration supervision{disp} and the robot position unknown"
                + ("" if has_pdisp else "; no given module switches program displacement "
                   "on, so none is assumed"))
        if self.recursed:
            names = ", ".join(sorted(rt.node.name for rt in self.routines
                                     if id(rt.node) in self.recursed))
            self.flow.notes.append(f"routines that call themselves: {names}; their moves are "
                                   "followed with supervision, displacement and position unknown")
        if self.flow.unknown_calls:
            calls = ", ".join(f"{n} ({w})" for n, w in sorted(self.flow.unknown_calls.items()))
            self.flow.notes.append(
                "calls whose routine is not known statically (late-bound, CallByVar, or not "
                f"declared in the given modules): {calls}; after them supervision, displacement "
                "and the robot position are treated as unknown")

    # ------------------------------------------------------------ routines
    def routine(self, rt: _Routine, state: State, stack: tuple) -> State | None:
        key = (id(rt.node), state)
        if key in self.memo:
            return self.memo[key]
        if id(rt.node) in stack:
            # Recursion: this entry's state is not followed into the body;
            # its moves are recorded once more with everything unknown.
            if id(rt.node) not in self.recursed:
                self.recursed.add(id(rt.node))
                self.routine(rt, UNKNOWN, ())
            return state.join(UNKNOWN)
        frame = _Frame(rt, stack + (id(rt.node),))
        out = self.walk(rt.node.body, state, {}, frame)
        exit_state = join(out, *frame.returns)
        for h in rt.node.handlers:
            if h.kind != "ERROR":
                # BACKWARD and UNDO run only when stepping backwards or
                # leaving the routine: their moves in the unknown state.
                self.walk(h.body, UNKNOWN, {}, _Frame(rt, frame.stack))
                continue
            # An error may stop the routine at any statement: the handler
            # starts from there, the robot wherever it stopped.
            hframe = _Frame(rt, frame.stack)
            start = replace(frame.inside or state, last=None)
            h_out = self.walk(h.body, start, {}, hframe)
            exit_state = join(exit_state, h_out, *hframe.returns)
            retry = join(*hframe.retries)
            if retry is not None and not _within(retry, frame.inside or state):
                # RETRY/TRYNEXT resume the body with what the handler switched.
                again = self.walk(rt.node.body, state.join(replace(retry, last=state.last)), {},
                                  frame)
                exit_state = join(exit_state, again, *frame.returns)
        self.memo[key] = exit_state
        return exit_state

    def walk(self, stmts, st: State | None, env: dict, frame: _Frame) -> State | None:
        for s in stmts:
            if st is None:
                return None
            # Only the flags: where an error handler starts, the position is
            # unknown anyway (and a union of positions would grow with the body).
            if frame.inside is None:
                frame.inside = replace(st, last=None)
            elif not _within(st, frame.inside):
                frame.inside = frame.inside.join(st)
            self.visits += 1
            if self.visits > MAX_VISITS:
                raise _TooLarge
            t = type(s)
            if t is A.ProcCall:
                st = self.call(s, st, env, frame)
            elif t is A.LateCall:
                st = self.unknown_call("%late-bound call%", s, frame)
            elif t is A.If:
                outs = [self.walk(body, st, env, frame) for _, body in s.branches]
                outs.append(self.walk(s.orelse, st, env, frame) if s.orelse else st)
                st = join(*outs)
            elif t is A.CompactIf:
                st = join(st, self.walk((s.stmt,), st, env, frame))
            elif t is A.For:
                st = self.for_loop(s, st, env, frame)
            elif t is A.While:
                st = self.loop(s.body, st, env, frame)
            elif t is A.Test:
                outs = [self.walk(body, st, env, frame) for _, body in s.cases]
                outs.append(self.walk(s.default, st, env, frame) if s.default is not None
                            else st)
                st = join(*outs)
            elif t is A.Simple:
                if s.kind == "RETURN":
                    frame.returns.append(st)
                    st = None
                elif s.kind in ("RETRY", "TRYNEXT"):
                    frame.retries.append(st)
                    st = None
                elif s.kind in ("EXIT", "RAISE", "GOTO"):
                    st = None
                elif s.kind == "LABEL":
                    # A GOTO may jump here from anywhere in the routine.
                    st = replace(st.join(UNKNOWN), last=None)
        return st

    def for_loop(self, s: A.For, st: State, env: dict, frame: _Frame) -> State | None:
        rt = frame.rt
        values = self.resolver.loop_range(s, rt.module, rt.node.name)
        if values is None:
            return self.loop(s.body, st, env, frame)
        var = s.var.lower()
        for v in values:
            st = self.walk(s.body, st, {**env, var: v}, frame)
            if st is None:
                return None
        return st

    def loop(self, body, st: State, env: dict, frame: _Frame) -> State:
        head = st
        for _ in range(8):
            out = self.walk(body, head, env, frame)
            nxt = head.join(out) if out is not None else head
            if nxt == head:
                return head
            head = nxt
        return replace(head.join(UNKNOWN), last=None)

    # ------------------------------------------------------------ calls
    def unknown_call(self, name: str, s, frame: _Frame) -> State:
        rt = frame.rt
        self.flow.unknown_calls.setdefault(name, f"{rt.pf.source.display_path}:"
                                                 f"{rt.pf.line(s.span)}")
        return UNKNOWN

    def call(self, s: A.ProcCall, st: State, env: dict, frame: _Frame) -> State | None:
        rt = frame.rt
        name = s.name.lower()
        spec = motion_spec(name)
        if spec is not None:
            return self.motion(s, spec, st, env, rt)
        if name in SUPERVISION:
            flags = {a.name.lower() for a in s.args if a.kind == "opt"}
            value = frozenset((OFF,)) if "off" in flags else frozenset((ON,)) if "on" in flags \
                else None
            if value is None:
                return st
            return replace(st, **{name: value})
        if name in self.displacing:
            return replace(st, pdisp=frozenset((ON,)))
        if name in DISPLACEMENT_OFF:
            return replace(st, pdisp=frozenset((OFF,)))
        if name == "exitcycle":
            # The cycle ends here and main starts again (see main()).
            self.cycle_ends.append(st)
            return None
        if name in MOVES_OTHERWISE:
            return replace(st, last=None)
        if name in UNKNOWN_TARGET_CALLS:
            return self.unknown_call(s.name, s, frame)
        callee = self.callee(rt.module, name)
        if callee is not None:
            out = self.routine(callee, st, frame.stack)
            return out
        if name in BUILTIN_INSTRUCTIONS:
            return st
        return self.unknown_call(s.name, s, frame)

    def motion(self, s: A.ProcCall, spec, st: State, env: dict, rt: _Routine) -> State:
        if spec.interpolation == "external":
            return st
        fi = rt.fi
        mi = self.motion_index[(fi, s.span.start)]
        written = fi < self.n_written
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
            st = replace(st, last=frozenset((key,)) if written else None)
        if "search" in spec.roles:
            # A search stops where the sensor triggers: position unknown.
            st = replace(st, last=None)
        return st


def _within(a: State, b: State) -> bool:
    """a's flags are among b's."""
    return a.confj <= b.confj and a.confl <= b.confl and a.pdisp <= b.pdisp


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


def analyse(files: list[ParsedFile], n_written: int, resolver, track: bool = False) -> Flow:
    """The flow of the task made of files[:n_written] (files after that are
    --with modules: their routines are followed, their moves are not
    recorded). track: a track axis carries the robot (EOffs displaces)."""
    return _Walker(files, n_written, resolver, track).run()
