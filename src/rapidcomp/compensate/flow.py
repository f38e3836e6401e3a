"""The order in which the controller runs a task's moves, and the motion
state each move runs in.

Three things decide what the controller does with a move besides its own
arguments, and all of them depend on what ran before it:

* configuration supervision (ConfJ for joint moves, ConfL for linear and
  circular ones): on at program start, changed by ConfJ/ConfL \\On|\\Off,
  kept across routine calls. Off, the controller takes the solution closest
  to where the robot is;
* program displacement (PDispOn/PDispSet ... PDispOff) and, with a track
  carrying the robot, the external axis offset (EOffsOn/EOffsSet ...
  EOffsOff): robtarget moves are displaced, MoveAbsJ is not;
* where the robot is: the previous move's target.

This walks the task from main through routine calls (each call site with
its own state), IF/TEST branches (joined), FOR loops with constant bounds
(unrolled, so an array walked by a loop is a chain of moves) and other
loops (to a fixed point); functions of the given modules are walked where
an expression calls them. It is sound where it must guess: main is walked
again from the state its cycle ends in (continuous run restarts main
without resetting), a routine that calls itself has its moves recorded in
the unknown state, an error handler starts where any statement of its
routine or of a routine it calls may have left off and what it leaves
behind flows on (after RETRY/TRYNEXT, into every statement of the body,
to a fixed point), a label may be reached from any GOTO (unknown state),
a TRAP that switches supervision or displacement, or calls something not
known statically, makes that unknown everywhere, and a call whose target
is not known statically (%...%, CallByVar, a procedure or function no
given module declares) makes everything unknown after it.

Per target use it records the state before it: each component is the set
of values it may have, and the previous move as the set of uses that may
have run last (None: unknown; PROGRAM_START: the program starts there,
where --start says the robot is; RESUME: where an error stopped it). The
moves of a run of plain moves share one state, whose previous move is
each one's own move before (AFTER: Flow.state reads it as that set).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from ..construct import maker
from ..rapid import ast as A
from ..rapid.model import Module, ParsedFile, RoutineTable
from ..rapid.motions import (BUILTIN_FUNCTIONS, BUILTIN_INSTRUCTIONS, DISPLACEMENT_OFF,
                             DISPLACEMENT_ON, MOVES_OTHERWISE, SUPERVISION, TRACK_OFFSET_OFF,
                             TRACK_OFFSET_ON, UNKNOWN_TARGET_CALLS, motion_spec)
from ..rapid.refs import calls_in, loop_names, plain_args

ON, OFF = "on", "off"
BOTH = frozenset((ON, OFF))
# Program displacement set at run time (PDispOn without \ExeP reads where
# the robot is; \ExeP, ProgPoint or PDispSet's frame a value the program
# does not fix: a search's result, CRobT()): if the robot measured it, its
# thermal error is in the displacement already (State.pdisp).
MEASURED = "measured"
# The functions that read where the controller has the robot: a value made
# with one (a PDispSet frame, an \ExeP) changes when a move before it is
# compensated.
POSITION_READERS = frozenset(("crobt", "cpos", "cjointt"))
# Not moves, in State.last: the program starts here (the robot is where
# --start says, else unknown), and: where an error stopped the robot.
PROGRAM_START = ("program start",)
RESUME = ("resume",)
# State.last of a move inside a run of plain moves (_Walker._moves): the
# move just before it in the run, Flow.previous[its key]. The run's moves
# share one State (a CAM program's 1e5: not a State and a set each); read
# through Flow.state/Flow.last, never as a set of keys.
AFTER = frozenset((("the move before",),))
# A call whose routine is not known statically (in the names of calls).
LATE = "%late-bound call%"
# Statement visits (loops unrolled, routines walked per call site) beyond
# which the flow is not followed: everything is then unknown.
MAX_VISITS = 3_000_000


@dataclass(frozen=True)
class State:
    confj: frozenset
    confl: frozenset
    pdisp: frozenset
    eoffs: frozenset           # external axis offset (displaces only with a track)
    last: frozenset | None     # use keys that may have run last; None: unknown position

    def join(self, other: "State | None") -> "State":
        if other is None or other is self:
            return self
        # (An equal state joins to itself: main's second cycle meets each of
        # a CAM program's 1e5 moves in the state the first left there.)
        if (self.last == other.last and self.confl == other.confl
                and self.confj == other.confj and self.pdisp == other.pdisp
                and self.eoffs == other.eoffs):
            return self
        # (Equal sets kept as they are: AFTER stays AFTER.)
        last = (None if self.last is None or other.last is None else
                self.last if self.last == other.last else self.last | other.last)
        return State(self.confj | other.confj, self.confl | other.confl,
                     self.pdisp | other.pdisp, self.eoffs | other.eoffs, last)

    def with_last(self, last: frozenset | None) -> "State":
        """The same flags after a move (dataclasses.replace costs ~5x more,
        once per move; made as the class makes it, construct.py)."""
        return _new_state(self.confj, self.confl, self.pdisp, self.eoffs, last)

    def supervision(self, interpolation: str) -> frozenset:
        return self.confj if interpolation == "joint" else self.confl

    @property
    def may_be_displaced(self) -> bool:
        return ON in self.pdisp or self.measured or ON in self.eoffs

    @property
    def measured(self) -> bool:
        """Program displacement set at run time may be on: MEASURED (one
        not known), or (MEASURED, "file:line: why") of the one that set it."""
        return any(x is MEASURED or type(x) is tuple for x in self.pdisp)

    def measured_at(self) -> list[str] | None:
        """The "file:line: why" of each displacement set at run time that
        may be on; None where one not known may be."""
        if MEASURED in self.pdisp:
            return None
        return sorted(x[1] for x in self.pdisp if type(x) is tuple)


_new_state = maker(State)
_ON, _OFF = frozenset((ON,)), frozenset((OFF,))
START = State(_ON, _ON, _OFF, _OFF, frozenset((PROGRAM_START,)))
UNKNOWN = State(BOTH, BOTH, BOTH, BOTH, None)
# No flags at all: walked from this, a handler's RETRY state holds only what
# the handler itself switches.
_SWITCHES = State(frozenset(), frozenset(), frozenset(), frozenset(), frozenset((RESUME,)))


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
    # The state of a use the walk never reached: as a routine entered from
    # outside (its supervision and position unknown).
    entry: State = UNKNOWN
    # Where program displacement is set at run time ("file:line"; MEASURED).
    measured: list = field(default_factory=list)
    # Use key -> where a displacement set at run time may read where that
    # move left the robot ("file:line"); anywhere: where such a one may
    # read where any move left it (in a TRAP or an error handler), or "".
    read_by: dict = field(default_factory=dict)
    anywhere: str = ""
    # Use key -> the use just before it, where its state's last is AFTER.
    previous: dict = field(default_factory=dict)

    def state(self, key) -> State:
        """The state before use `key`, its last a set of keys."""
        st = self.before.get(key, self.entry)
        return st if st.last is not AFTER else st.with_last(frozenset((self.previous[key],)))

    def last(self, key, st: State) -> frozenset | None:
        """st.last, st the state held before use `key`."""
        return frozenset((self.previous[key],)) if st.last is AFTER else st.last

    def one_before(self, key, st: State):
        """The one key in last(key, st), or None (none, several, unknown)."""
        last = st.last
        if last is AFTER:
            return self.previous[key]
        return next(iter(last)) if last is not None and len(last) == 1 else None


_NO_NAMES = frozenset()


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
    RETRYs leave, the join of every state inside it and inside what it
    calls (where an error handler may start), and the floor: what a
    RETRY may bring back before any statement of the body."""

    rt: _Routine
    stack: tuple
    floor: State | None = None
    # Label name -> the states GOTOs brought there on the previous walk of
    # the body (None: labels are not followed; a label is then entered in
    # the unknown state).
    labels: dict | None = None
    returns: list = field(default_factory=list)
    retries: list = field(default_factory=list)
    gotos: dict = field(default_factory=dict)     # label name -> states of its GOTOs
    inside: State | None = None
    # The variables of the FOR loops around the statement walked (a loop's
    # bounds may name them: not fixed then, targets.loop_range).
    fors: list = field(default_factory=list)

    def absorb(self, st: State | None) -> None:
        # Only the flags: where an error handler starts, the position is
        # unknown anyway (and a union of positions would grow with the body).
        if st is None:
            return
        if self.inside is None:
            self.inside = st.with_last(None)
        elif not _within(st, self.inside):
            self.inside = self.inside.join(st.with_last(None))


class _Walker:
    def __init__(self, files, n_written: int, resolver, track: bool):
        self.files = files
        self.n_written = n_written
        self.resolver = resolver
        self.track = track
        self.flow = Flow()
        # What nothing is known of: as UNKNOWN, and where the task sets
        # program displacement at run time, that too (run()).
        self.unknown = UNKNOWN
        # The state a BACKWARD or UNDO handler runs in (run()).
        self.stepped = UNKNOWN
        # id(PDispOn/PDispSet statement) -> why its displacement is set at
        # run time (_find_measured, which sees every one before the walk).
        self.run_time: dict = {}
        # Of those, the ones that may read where the moves before them left
        # the robot (_reads_position).
        self.reads: set = set()
        self._position_read: bool | None = None
        # Whether one of those is a frame or an \\ExeP that may be made of a
        # position read (CRobT()...): then each read is one (walk()).
        self.made_of_reads = False
        # id(statement) -> the position read its expressions call, or None.
        self.position_reads: dict = {}
        self.called: dict[int, tuple[str, ...]] = {}   # id(routine node) -> names it calls
        self.visits = 0
        self.memo: dict = {}
        # (id(statements), index) -> (state in, end, state out) of a run
        # of plain moves walked (_moves).
        self.runs: dict = {}
        self.recursed: set = set()
        self.cycle_ends: list = []
        self.table = RoutineTable()
        self.motion_index: dict[tuple[int, int], int] = {}
        self.target_names: dict[tuple[int, int], list] = {}
        self.functions: dict[int, tuple] = {}     # id(statement) -> its expressions' calls
        self.routines: list[_Routine] = []
        for fi, pf in enumerate(files):
            mi = 0
            for m in pf.modules:
                for r in m.routines:
                    rt = _Routine(fi, pf, m, r.node)
                    self.routines.append(rt)
                    self.table.add(m, r, rt)
                for mo in m.motions:
                    self.motion_index[(fi, mo.span.start)] = mi
                    # (A move in no loop, a CAM program's 1e5: no loop names.)
                    self.target_names[(fi, mi)] = [
                        (t.role, loop_names(t.expr, mo.loops) if mo.loops else _NO_NAMES)
                        for t in mo.targets if t.role != "search"]
                    mi += 1

    def callee(self, module: Module, name: str) -> _Routine | None:
        return self.table.find(module, name)

    def known(self, rt: _Routine, name: str) -> bool:
        """A call the flow can follow: a built-in or a given routine."""
        return name != LATE and name not in UNKNOWN_TARGET_CALLS and (
            builtin(name) or self.callee(rt.module, name) is not None)

    def called_names(self, node: A.Routine) -> tuple[str, ...]:
        """The distinct names a routine calls, once per routine (a CAM
        routine calls MoveL 1e5 times)."""
        names = self.called.get(id(node))
        if names is None:
            names = self.called[id(node)] = tuple(dict.fromkeys(_called_names(node)))
        return names

    # ------------------------------------------------------------ entry
    def run(self) -> Flow:
        called = set()
        names = set()
        unknown_calls = False
        for rt in self.routines:
            for name in self.called_names(rt.node):
                names.add(name)
                c = self.callee(rt.module, name)
                if c is not None and c is not rt:
                    called.add(id(c.node))
                elif c is None and not self.known(rt, name):
                    unknown_calls = True
        has_pdisp = bool(names & DISPLACEMENT_ON)
        has_eoffs = self.track and bool(names & TRACK_OFFSET_ON)
        if has_pdisp:
            self._find_measured()
        # A routine entered from outside: supervision unknown, displacement
        # unknown where something switches it on; the program starts there.
        entry = State(BOTH, BOTH, self.unknown.pdisp if has_pdisp else _OFF,
                      BOTH if has_eoffs else _OFF, frozenset((PROGRAM_START,)))
        self.flow.entry = replace(entry, last=None)
        # Stepping backwards may come at any point of the program: a
        # BACKWARD or UNDO handler's moves run with supervision and the
        # robot's position unknown, and a displacement where anything may
        # switch one on (something does, or a call not known statically
        # may); where nothing can, none (as at entry).
        self.stepped = (self.unknown if unknown_calls else
                        State(BOTH, BOTH, entry.pdisp, entry.eoffs, None))
        main = next((rt for rt in self.routines if rt.fi < self.n_written
                     and rt.node.kind == "PROC"
                     and rt.node.name.lower() == self.resolver.entry.lower()), None)
        others = [rt for rt in self.routines if rt is not main and id(rt.node) not in called]
        try:
            if main is not None:
                self.main(main)
            for rt in others:
                self.routine(rt, entry, (), None)
        except (_TooLarge, RecursionError) as exc:
            # (Blocks or calls nested thousands deep, past the frames Python
            # has: as a flow too large, the safe choice for every move.)
            what = (f"more than {MAX_VISITS} statement visits" if isinstance(exc, _TooLarge)
                    else "blocks or calls nested thousands of levels deep")
            self.flow = Flow(notes=[f"the task's control flow is too large to follow ({what}): "
                                    "configuration supervision, program displacement and the "
                                    "previous position of every move are treated as unknown"],
                             entry=self.unknown, measured=self.flow.measured,
                             read_by=self.flow.read_by, anywhere=self.flow.anywhere)
            return self.flow
        self.interrupts(others)
        self.notes(others, has_pdisp)
        return self.flow

    def main(self, main: _Routine) -> None:
        """main from program start; then again from the state a cycle ends
        in (continuous run restarts main without resetting supervision or
        displacement, the robot where the cycle left it), until nothing new
        is reached."""
        state = START
        for _ in range(4):
            self.cycle_ends = []
            out = self.routine(main, state, (), None)
            ends = join(out, *self.cycle_ends)
            if ends is None:
                return
            nxt = state.join(ends)
            if nxt == state:
                return
            state = nxt

    def interrupts(self, others: list[_Routine]) -> None:
        """A TRAP may run between any two statements: what it switches
        (supervision, displacement) is unknown everywhere; a TRAP that calls
        something not known statically may switch anything."""
        switched: set[str] = set()
        on = False                   # (displacement may be switched on, not only off)
        for rt in others:
            if rt.node.kind != "TRAP":
                continue
            for r, name in self._reachable_calls(rt):
                if name in SUPERVISION:
                    switched.add(name)
                elif name in DISPLACEMENT_ON or name in DISPLACEMENT_OFF:
                    switched.add("pdisp")
                    on = on or name in DISPLACEMENT_ON
                elif name in TRACK_OFFSET_ON or name in TRACK_OFFSET_OFF:
                    switched.add("eoffs")
                elif not self.known(r, name):
                    switched.update(("confj", "confl", "pdisp", "eoffs"))
                    on = True
        if not self.track:
            switched.discard("eoffs")
        if not switched:
            return
        # What a state may hold grows by what the TRAP may set (a union:
        # a displacement set at run time before stays possible).
        widen = {k: (self.unknown.pdisp if on else _OFF) if k == "pdisp" else BOTH
                 for k in switched}
        # (A state shared by a run's uses stays shared: widened once.)
        widened: dict = {}
        for key, st in self.flow.before.items():
            got = widened.get(id(st))
            if got is None:
                got = widened[id(st)] = (st, replace(st, **{k: getattr(st, k) | v
                                                           for k, v in widen.items()}))
            self.flow.before[key] = got[1]
        self.flow.entry = replace(self.flow.entry, **{k: getattr(self.flow.entry, k) | v
                                                      for k, v in widen.items()})
        what = {"confj": "ConfJ", "confl": "ConfL", "pdisp": "program displacement",
                "eoffs": "the external axis offset"}
        self.flow.notes.append("an interrupt routine (TRAP) switches "
                               + ", ".join(what[k] for k in sorted(switched))
                               + " (or calls what may): it may run anywhere, so that state is "
                                 "unknown everywhere")

    def _find_measured(self) -> None:
        """Each PDispOn/PDispSet whose displacement is set at run time, in
        flow.measured and self.run_time; if there is one, it may be on
        wherever nothing is known (self.unknown)."""
        # (Routines an interrupt may run: there, as in an error handler,
        # where the robot is may be where any move left it.)
        interrupted = {id(r.node) for t in self.routines if t.node.kind == "TRAP"
                       for r, _ in self._reachable_calls(t)}
        for rt in self.routines:
            if not set(self.called_names(rt.node)) & DISPLACEMENT_ON:
                continue
            handlers = {id(s) for s in _statements_in([h.body for h in rt.node.handlers])}
            for s in statements(rt.node):
                why = (self._set_at_run_time(s, rt) if type(s) is A.ProcCall
                       and s.name.lower() in DISPLACEMENT_ON else None)
                if why is None:
                    continue
                self.run_time[id(s)] = why
                at = f"{rt.pf.source.display_path}:{rt.pf.line(s.span)}"
                if f"{at}: {why}" not in self.flow.measured:
                    self.flow.measured.append(f"{at}: {why}")
                if not self._reads_position(s):
                    continue
                self.reads.add(id(s))
                if not (s.name.lower() == "pdispon" and _arg(s, "exep") is None):
                    self.made_of_reads = True
                if (id(rt.node) in interrupted or id(s) in handlers) and not self.flow.anywhere:
                    self.flow.anywhere = f"{at}, in an interrupt routine or an error handler"
        if self.made_of_reads and not self.flow.anywhere:
            # A position read a displacement may be made of, where it may
            # run after any move: an interrupt routine, an error handler,
            # another task (CRobT(\\TaskName:=...)).
            self.flow.anywhere = self._read_anywhere(interrupted)
        if self.flow.measured:
            self.unknown = State(BOTH, BOTH, BOTH | {MEASURED}, BOTH, None)

    def _read_anywhere(self, interrupted: set) -> str | None:
        """Where a position read runs after any move (see _find_measured),
        or None."""
        for rt in self.routines:
            handlers = {id(s) for s in _statements_in([h.body for h in rt.node.handlers])}
            inside = rt.node.kind == "TRAP" or id(rt.node) in interrupted
            for s in statements(rt.node):
                read = _position_read(s) if inside or id(s) in handlers else None
                if read is not None:
                    return (f"{rt.pf.source.display_path}:{rt.pf.line(s.span)}, its "
                            f"{read}() in an interrupt routine or an error handler")
        hit = _first_position_read(getattr(self.resolver, "observers", ()))
        if hit is not None:
            pf, s, name = hit
            return f"{pf.source.display_path}:{pf.line(s.span)}, another task's {name}()"
        return None

    def _read_here(self, s, st: State, rt: _Routine, what: str = "") -> None:
        """The moves that may have left the robot where statement s is read
        where it is (st.last): compensated, a displacement made of what s
        reads would move with them."""
        at = f"{rt.pf.source.display_path}:{rt.pf.line(s.span)}{what}"
        for key in st.last or ():
            if key is not PROGRAM_START and key is not RESUME:
                self.flow.read_by.setdefault(key, at)

    def _reads_position(self, s: A.ProcCall) -> bool:
        """Whether the displacement a run-time PDispOn/PDispSet sets may
        depend on where the moves before it left the robot: PDispOn without
        \\ExeP reads it; a PDispSet frame or an \\ExeP may have been made
        with CRobT(), CPos() or CJointT() where the task calls one (else it
        is a search's result, an input, another task's value: none of them
        moves with a compensated move before it)."""
        if s.name.lower() == "pdispon" and _arg(s, "exep") is None:
            return True
        if self._position_read is None:
            # (Another task's too: PERS data are shared, and CRobT() takes
            # \\TaskName.)
            self._position_read = _first_position_read(
                (*self.files, *getattr(self.resolver, "observers", ()))) is not None
        return self._position_read

    def _set_at_run_time(self, s: A.ProcCall, rt: _Routine) -> str | None:
        """Why the displacement PDispOn/PDispSet s sets is known only at
        run time (PDispOn without \\ExeP reads where the robot is; an
        \\ExeP, ProgPoint or PDispSet frame not a value the program fixes),
        or None."""
        fixed = self.resolver.fixed
        where = (rt.module, rt.node.name)
        if s.name.lower() == "pdispset":
            frame = _arg(s, "dispframe", 0)
            if frame is None or not fixed(frame, *where, "pose"):
                return "PDispSet's frame is not a value the program fixes"
            return None
        exe, prog = _arg(s, "exep"), _arg(s, "progpoint", 0)
        if exe is None:
            return "PDispOn without \\ExeP reads where the robot is"
        text = rt.pf.source.text
        for name, value in (("\\ExeP", exe), ("ProgPoint", prog)):
            if value is None or not fixed(value, *where, "robtarget"):
                shown = "" if value is None else f" {text[value.span.start:value.span.end]}"
                return f"its {name}{shown} is not a value the program fixes"
        return None

    def _reachable_calls(self, rt: _Routine) -> set:
        """(routine, name) of every call reachable from rt."""
        seen, out, todo = set(), set(), [rt]
        while todo:
            r = todo.pop()
            if id(r.node) in seen:
                continue
            seen.add(id(r.node))
            for name in self.called_names(r.node):
                out.add((r, name))
                c = self.callee(r.module, name)
                if c is not None:
                    todo.append(c)
        return out

    def notes(self, others: list[_Routine], has_pdisp: bool) -> None:
        moving = [rt for rt in others if rt.fi < self.n_written and _has_motion(rt.node)]
        if moving:
            names = ", ".join(rt.node.name for rt in moving)
            disp = "" if not has_pdisp else ", program displacement"
            self.flow.notes.append(
                f"not called by any given routine, so entered from outside what was given "
                f"(PP to routine, another module, an interrupt or a late-bound call): {names}; "
                f"followed with configuration supervision{disp} unknown and the robot where "
                "the program starts (--start, else unknown)"
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
    def routine(self, rt: _Routine, state: State, stack: tuple,
                caller: _Frame | None) -> State | None:
        """The state a routine leaves, entered in `state`; what happens
        inside it joins the caller's inside (an error it does not handle
        goes to the caller's handler)."""
        key = (id(rt.node), state)
        hit = self.memo.get(key)
        if hit is None:
            if id(rt.node) in stack:
                # Recursion: this entry's state is not followed into the body;
                # its moves are recorded once more with everything unknown.
                if id(rt.node) not in self.recursed:
                    self.recursed.add(id(rt.node))
                    self.routine(rt, self.unknown, (), None)
                hit = (state.join(self.unknown), self.unknown)
            else:
                hit = self._body(rt, state, stack + (id(rt.node),))
                self.memo[key] = hit
        exit_state, inside = hit
        if caller is not None:
            caller.absorb(inside)
        return exit_state

    def _body(self, rt: _Routine, state: State, stack: tuple) -> tuple:
        """(exit state, inside) of a routine's walk with its handlers."""
        for h in rt.node.handlers:
            if h.kind != "ERROR":
                # BACKWARD and UNDO run only when stepping backwards or
                # leaving the routine: their moves in the state that may
                # hold anywhere (run()).
                self.walk(h.body, self.stepped, {}, _Frame(rt, stack))
        handlers = [h for h in rt.node.handlers if h.kind == "ERROR"]
        floor = None
        labels: dict = {}
        for attempt in range(9):
            frame = _Frame(rt, stack, floor, labels)
            out = self.walk(rt.node.body, state, {}, frame)
            # A GOTO back to a label: the body again, until what the GOTOs
            # bring to every label is already there.
            grown = False
            for name, states in frame.gotos.items():
                got = join(labels.get(name), *states)
                if got != labels.get(name):
                    labels[name], grown = got, True
            if attempt == 7 and grown:
                labels = {name: replace(self.unknown, last=None) for name in labels}
            exit_state = join(out, *frame.returns)
            inside = frame.inside
            retries = []
            for h in handlers:
                # An error may stop the routine at any statement (of it or of
                # what it calls): the handler starts from there, the robot
                # wherever it stopped.
                hframe = _Frame(rt, stack)
                start = replace(frame.inside or state, last=frozenset((RESUME,)))
                h_out = self.walk(h.body, start, {}, hframe)
                exit_state = join(exit_state, h_out, *hframe.returns)
                inside = join(inside, hframe.inside)
                if hframe.retries:
                    # What the handler switches on its way to RETRY/TRYNEXT:
                    # walked again from no flags at all, what it may set.
                    eframe = _Frame(rt, stack)
                    self.walk(h.body, _SWITCHES, {}, eframe)
                    retries += eframe.retries
            retry = join(*retries)
            if retry is None:
                if grown:
                    continue
                break
            # RETRY/TRYNEXT resume the body at (or after) the statement that
            # failed, in its state plus what the handler may have switched;
            # the robot resumes from where it stopped (on the path the body
            # describes) unless the handler moved it.
            last = None if retry.last is None else retry.last - {RESUME}
            nxt = replace(retry, last=last)
            nxt = nxt if floor is None else floor.join(nxt)
            if attempt == 7:
                nxt = replace(self.unknown, last=None)
            if floor is not None and nxt == floor and not grown:
                break
            floor = nxt
        return exit_state, inside

    def walk(self, stmts, st: State | None, env: dict, frame: _Frame) -> State | None:
        i, n = 0, len(stmts)
        while i < n:
            s = stmts[i]
            i += 1
            t = type(s)
            if st is None:
                if t is A.Simple and s.kind == "LABEL":
                    # Reached by a GOTO only.
                    st = self.label(s, None, frame)
                continue
            if frame.floor is not None:
                st = st.join(frame.floor)
            frame.absorb(st)
            self.visits += 1
            if self.visits > MAX_VISITS:
                raise _TooLarge
            if t is A.ProcCall and (s.plain or self._calls_nothing(s)):
                # A call of names and literals calls no function (a CAM
                # program's 1e5 moves: not remembered one by one); nor does
                # one of built-in functions alone (MoveL Offs(p, 0, 0, 10),
                # ...), where no position read may make a displacement.
                spec = motion_spec(s.name)
                if spec is not None:
                    st = self.motion(s, spec, st, env, frame.rt)
                    if not env and frame.floor is None and i < n:
                        i, st = self._moves(stmts, i, st, frame.rt)
                    continue
            else:
                fcalls = self._fcalls(s)
                for name in fcalls:
                    st = self.function(name, s, st, frame)
                if self.made_of_reads and st.last:
                    read = self.position_reads.get(id(s), False)
                    if read is False:
                        read = self.position_reads[id(s)] = _position_read(s)
                    if read is not None:
                        # What a displacement set at run time may be made
                        # of: CRobT() here reads where the moves before
                        # left the robot.
                        self._read_here(s, st, frame.rt, f", where {read}() reads it")
            if t is A.ProcCall:
                st = self.call(s, st, env, frame)
            elif t is A.LateCall:
                st = self.unknown_call(LATE, s, frame)
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
                elif s.kind == "GOTO":
                    frame.gotos.setdefault((s.name or "").lower(), []).append(st)
                    st = None
                elif s.kind in ("EXIT", "RAISE"):
                    st = None
                elif s.kind == "LABEL":
                    st = self.label(s, st, frame)
        return st

    def label(self, s: A.Simple, st: State | None, frame: _Frame) -> State | None:
        """The state at a label: what falls through to it and what its
        GOTOs bring (where labels are not followed: unknown)."""
        if frame.labels is None:
            return replace(self.unknown, last=None)
        return join(st, frame.labels.get((s.name or "").lower()))

    def for_loop(self, s: A.For, st: State, env: dict, frame: _Frame) -> State | None:
        rt = frame.rt
        values = self.resolver.loop_range(s, rt.module, rt.node.name, around=frame.fors)
        frame.fors.append(s.var)
        try:
            if values is None:
                return self.loop(s.body, st, env, frame)
            var = s.var.lower()
            for v in values:
                st = self.walk(s.body, st, {**env, var: v}, frame)
                if st is None:
                    return None
            return st
        finally:
            frame.fors.pop()

    def loop(self, body, st: State, env: dict, frame: _Frame) -> State:
        head = st
        for _ in range(8):
            out = self.walk(body, head, env, frame)
            nxt = head.join(out) if out is not None else head
            if nxt == head:
                return head
            head = nxt
        return replace(head.join(self.unknown), last=None)

    # ------------------------------------------------------------ calls
    def unknown_call(self, name: str, s, frame: _Frame) -> State:
        rt = frame.rt
        self.flow.unknown_calls.setdefault(name, f"{rt.pf.source.display_path}:"
                                                 f"{rt.pf.line(s.span)}")
        frame.absorb(self.unknown)
        return self.unknown

    def function(self, name: str, s, st: State, frame: _Frame) -> State:
        """A function an expression of statement s calls (not a built-in)."""
        callee = self.callee(frame.rt.module, name)
        if callee is None:
            return self.unknown_call(name, s, frame)
        out = self.routine(callee, st, frame.stack, frame)
        # A function that never returns normally raises: the statement does
        # not complete, but its handler's paths are followed from inside.
        return out if out is not None else st

    def call(self, s: A.ProcCall, st: State, env: dict, frame: _Frame) -> State | None:
        rt = frame.rt
        name = s.name.lower()
        spec = motion_spec(name)
        if spec is not None:
            return self.motion(s, spec, st, env, rt)
        if name in SUPERVISION:
            flags = {a.name.lower() for a in s.args if a.kind == "opt"}
            value = _OFF if "off" in flags else _ON if "on" in flags else None
            if value is None:
                return st
            return replace(st, **{name: value})
        if name in DISPLACEMENT_ON:
            # (Set at run time: MEASURED, found by run(). PDispOn adds its
            # displacement to one active; PDispSet sets its frame.)
            kept = (frozenset(x for x in st.pdisp if x is MEASURED or type(x) is tuple)
                    if name == "pdispon" else frozenset())
            why = self.run_time.get(id(s))
            if why is None:
                return replace(st, pdisp=_ON | kept)
            # It may read where the moves before it left the robot (PDispOn
            # without \ExeP does; a frame or \ExeP made with CRobT() may:
            # _reads_position): a compensated one would change the
            # displacement with it.
            # (Where the flow does not know the position, no move it
            # follows put the robot there: a search, a routine not given;
            # in an error handler or a TRAP any may have, found by run().)
            at = f"{rt.pf.source.display_path}:{rt.pf.line(s.span)}"
            if id(s) in self.reads:
                self._read_here(s, st, rt)
            prog = _arg(s, "progpoint", 0)
            if (name == "pdispon" and _arg(s, "exep") is None and st.last
                    and PROGRAM_START not in st.last and RESUME not in st.last
                    and prog is not None
                    and self.resolver.fixed(prog, rt.module, rt.node.name, "robtarget")):
                # Where moves the flow follows left the robot, each left as
                # written: it reads their programmed positions, nothing
                # measured.
                return replace(st, pdisp=_ON | kept)
            return replace(st, pdisp=frozenset(((MEASURED, f"{at}: {why}"),)))
        if name in DISPLACEMENT_OFF:
            return replace(st, pdisp=_OFF)
        if name in TRACK_OFFSET_ON:
            # Without a track carrying the robot the offset moves other axes.
            return replace(st, eoffs=_ON) if self.track else st
        if name in TRACK_OFFSET_OFF:
            return replace(st, eoffs=_OFF)
        if name == "exitcycle":
            # The cycle ends here and main starts again (see main()).
            self.cycle_ends.append(st)
            return None
        if name in MOVES_OTHERWISE:
            return st.with_last(None)
        if name in UNKNOWN_TARGET_CALLS:
            return self.unknown_call(s.name, s, frame)
        callee = self.callee(rt.module, name)
        if callee is not None:
            return self.routine(callee, st, frame.stack, frame)
        if name in BUILTIN_INSTRUCTIONS:
            return st
        return self.unknown_call(s.name, s, frame)

    def _moves(self, stmts, i: int, st: State, rt: _Routine) -> tuple[int, State]:
        """walk() of the plain moves from stmts[i] on (a CAM program's run of
        1e5, outside any loop): what walk() and motion() do for each, with
        what they look up once. Their state differs only in the move before
        (`last`), so each is absorbed into the frame as the first was; a
        search or a move of external axes ends the run. Returns where the
        run ends and the state after it."""
        # The run walked again in the state it was walked in before (main's
        # second cycle meets a CAM program's 1e5 moves so): each move joins
        # the state it was reached in then, which changes nothing, and the
        # run ends where and as it did.
        start = i
        again = self.runs.get((id(stmts), start))
        if again is not None and again[0] == st:
            self.visits += again[1] - start
            if self.visits > MAX_VISITS:
                raise _TooLarge
            return again[1], again[2]
        entered = st
        fi = rt.fi
        written = fi < self.n_written
        index, names, reach, after = self.motion_index, self.target_names, self._reach, \
            self._after
        n = len(stmts)
        # The run's first use is reached as any; each after it in the state
        # `inner` (its flags, last AFTER: the use before it).
        inner = prev = None
        tail = False
        while i < n:
            s = stmts[i]
            if type(s) is not A.ProcCall or not (s.plain or self._calls_nothing(s)):
                break
            spec = motion_spec(s.name)
            if spec is None or spec.interpolation == "external" or "search" in spec.roles:
                break
            self.visits += 1
            if self.visits > MAX_VISITS:
                raise _TooLarge
            mi = index[(fi, s.span.start)]
            for role, _ in names[(fi, mi)]:
                key = (fi, mi, role, ())
                if inner is None:
                    st = reach(key, st, written)
                    if written:
                        inner = st.with_last(AFTER)
                else:
                    after(key, prev, inner)
                    tail = True
                prev = key
            i += 1
        if tail:
            st = st.with_last(frozenset((prev,)))
        self.runs[(id(stmts), start)] = (entered, i, st)
        return i, st

    def _fcalls(self, s) -> tuple:
        """_function_calls(s), once per statement."""
        fcalls = self.functions.get(id(s))
        if fcalls is None:
            fcalls = self.functions[id(s)] = _function_calls(s)
        return fcalls

    def _calls_nothing(self, s: A.ProcCall) -> bool:
        """A call that is walked as a plain one: its expressions call no
        function the flow follows (built-ins only), and nothing reads a
        position a displacement may be made of (walk() then looks)."""
        if self.made_of_reads:
            return False
        args = s.args
        if type(args) is A.TailArgs and type(args.first) is A.Call:
            # (A move lexed as one token whose first argument is a call of
            # names and numbers (build._fast_func): that function is all
            # it calls. Every move of an Offs- or RelTool-relative CAM
            # program: not remembered one by one.)
            return args.first.name.lower() in BUILTIN_FUNCTIONS
        return not self._fcalls(s)

    def _after(self, key: tuple, prev: tuple, inner: State) -> None:
        """_reach() of a use inside a run of plain moves, `prev` the use
        before it, `inner` the run's flags with last AFTER."""
        flow = self.flow
        old = flow.before.get(key)
        if old is None:
            flow.order.append(key)
            flow.before[key] = inner
            flow.previous[key] = prev
        elif old is not inner:
            # (A use's previous is the statement before it: the same in
            # every run it is inside of.)
            flow.before[key] = old.join(inner if old.last is AFTER
                                        else inner.with_last(frozenset((prev,))))

    def _reach(self, key: tuple, st: State, written: bool) -> State:
        """The use `key` reached in state st (joined with the states it was
        reached in before, where its file is written); the state after it."""
        if not written:
            return st.with_last(None)
        before = self.flow.before
        old = before.get(key)
        if old is None:
            self.flow.order.append(key)
            before[key] = st
        else:
            if old.last is AFTER:
                # (Reached inside a run before, here not: its last as a set.)
                old = old.with_last(frozenset((self.flow.previous.pop(key),)))
            before[key] = old.join(st)
        return st.with_last(frozenset((key,)))

    def motion(self, s: A.ProcCall, spec, st: State, env: dict, rt: _Routine) -> State:
        if spec.interpolation == "external":
            return st
        fi = rt.fi
        mi = self.motion_index[(fi, s.span.start)]
        written = fi < self.n_written
        for role, names in self.target_names[(fi, mi)]:
            envr = tuple(sorted((k, v) for k, v in env.items() if k in names)) if env else ()
            st = self._reach((fi, mi, role, envr), st, written)
        if "search" in spec.roles:
            # A search stops where the sensor triggers: position unknown.
            st = st.with_last(None)
        return st


def _within(a: State, b: State) -> bool:
    """a's flags are among b's."""
    return (a.confj <= b.confj and a.confl <= b.confl and a.pdisp <= b.pdisp
            and a.eoffs <= b.eoffs)


def _heads(s) -> tuple:
    """The expressions a statement evaluates itself (not its bodies) that
    may call a function."""
    t = type(s)
    if t is A.Assign:
        return (s.target, s.value)
    if t is A.ProcCall:
        # (A plain call's arguments are names and literals: nothing a caller
        # of this looks for, calls; a CAM move's are made when read.)
        return () if s.plain else s.args
    if t is A.LateCall:
        return (s.proc, s.args)
    if t is A.If:
        return tuple(c for c, _ in s.branches)
    if t is A.CompactIf or t is A.While:
        return (s.cond,)
    if t is A.For:
        return (s.start, s.stop, s.step)
    if t is A.Test:
        return (s.expr,) + tuple(v for values, _ in s.cases for v in values)
    if t is A.Simple:
        return (s.expr,)
    return ()


def _first_position_read(files) -> tuple | None:
    """(file, statement, the function's name as written) of the first
    CRobT(), CPos() or CJointT() a routine of the files calls, or None."""
    for pf in files:
        for m in pf.modules:
            for r in m.routines:
                for s in statements(r.node):
                    name = _position_read(s)
                    if name is not None:
                        return pf, s, name
    return None


def _position_read(s) -> str | None:
    """The first of CRobT(), CPos() or CJointT() a statement's own
    expressions call (its name as written), or None."""
    return next((c.name for c in calls_in(_heads(s)) if c.name.lower() in POSITION_READERS),
                None)


def _function_calls(s) -> tuple:
    """Names of the functions (not built-ins) a statement's own expressions
    call, each once."""
    if type(s) is A.ProcCall:
        if s.plain:
            return ()             # a move of a CAM program: asked 1e5 times
        calls = _plain_calls(s.args)
        if calls is not None:
            return calls
    out: dict = {}
    for c in calls_in(_heads(s)):
        if c.name.lower() not in BUILTIN_FUNCTIONS:
            out.setdefault(c.name.lower(), c.name)
    return tuple(out.values())


def _plain_calls(args) -> tuple | None:
    """_function_calls of a call whose every argument is a plain name, a
    literal or a call of such (MoveL Offs(p, 0, 0, 10), ...: a hand-written
    or Offs-relative CAM program's every move), in the order the general
    walk finds them (last argument first); None for any other argument."""
    out: dict = {}
    if type(args) is A.TailArgs:
        # (A move lexed as one token: after its first argument only names,
        # numbers and \Opt, no call; those not made from their text.)
        args = (args.first,)
    else:
        args = [arg.value for arg in args]
    for v in reversed(args):
        t = type(v)
        if t is A.Call:
            if not plain_args(v.args):
                return None
            if v.name.lower() not in BUILTIN_FUNCTIONS:
                out.setdefault(v.name.lower(), v.name)
        elif not (v is None or t is A.NumAgg or t is A.Num or t is A.Str or t is A.Bool
                  or (t is A.Ref and not v.selectors)):
            return None
    return tuple(out.values())


def builtin(name: str) -> bool:
    """A RAPID instruction or function (lower case), not a routine of the
    task."""
    return (name in BUILTIN_INSTRUCTIONS or name in BUILTIN_FUNCTIONS
            or name in MOVES_OTHERWISE or motion_spec(name) is not None)


# Moves that run a procedure, named by their last argument (a string), at
# their point.
SYNC_MOVES = frozenset(("movejsync", "movelsync", "movecsync"))


def calls_of(node: A.Routine):
    """(offset of the statement, lower-case name or LATE) of each call a
    routine makes that is not a built-in, handlers' too; the procedure a
    MoveLSync runs at its point too (LATE where its name is not a literal)."""
    syncs = None
    for at, name in _calls(node):
        if name in UNKNOWN_TARGET_CALLS:                # (CallByVar)
            yield at, LATE
        elif name in SYNC_MOVES:
            if syncs is None:
                syncs = {x.span.start: x for x in statements(node)
                         if type(x) is A.ProcCall and x.name.lower() in SYNC_MOVES}
            args = syncs[at].args
            last = args[-1].value if args else None
            yield at, last.value.lower() if type(last) is A.Str else LATE
        elif not builtin(name):
            yield at, name


def _arg(s: A.ProcCall, name: str, k: int = -1):
    """The value of s's argument `name` (lower case), named or optional,
    or its k-th positional argument; None if it has none."""
    for a in s.args:
        if a.kind in ("named", "optval") and a.name and a.name.lower() == name:
            return a.value
    pos = [a.value for a in s.args if a.kind == "pos"]
    return pos[k] if 0 <= k < len(pos) else None


def _called_names(node: A.Routine):
    """Lower-case names of the procedures and functions a routine calls
    (statically; LATE for a late-bound call)."""
    return (name for _, name in _calls(node))


def _calls(node: A.Routine):
    """(offset of the statement, lower-case name, or LATE for a late-bound
    call) of each call a routine makes, built-ins too, handlers' too."""
    for s in statements(node):
        at = s.span.start
        for name in _function_calls(s):
            yield at, name.lower()
        t = type(s)
        if t is A.ProcCall:
            yield at, s.name.lower()
        elif t is A.LateCall:
            yield at, LATE


def statements(node: A.Routine):
    """Every statement of a routine, those in blocks and handlers too."""
    return _statements_in([node.body] + [h.body for h in node.handlers])


def _statements_in(bodies: list):
    """Every statement of these statement lists, those in blocks too."""
    stack = list(bodies)
    while stack:
        stmts = stack.pop()
        for s in stmts:
            yield s
            t = type(s)
            if t is A.If:
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
