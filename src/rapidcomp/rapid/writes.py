"""Which data a task may change while it runs, and where.

A target whose data is changed at run time is not a static value: the
compensation of its literal would be wrong the moment it changes. Data is
changed by an assignment, a search instruction's result, a built-in
instruction or function that fills an argument (GetDataVal, StrToVal, ...),
an argument passed to an INOUT/VAR/PERS parameter of a given routine that
the routine may write (assigns, fills, or passes on to a parameter that
may be written; a routine only reading it, as a tool passed to a PERS
tooldata parameter for its moves, changes nothing), any argument of a
routine no given module declares or of a late-bound call (they may change
it), SetDataVal by name, and, with a name computed at run time,
SetDataVal/SetAllDataVal may change anything.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from . import ast as A
from .model import ParsedFile, RoutineTable
from .motions import BUILTIN_FUNCTIONS, BUILTIN_INSTRUCTIONS, motion_spec
from .refs import Usage, load_only, nodes, searched

# Built-in instructions and functions that write an argument: name -> the
# positions among the required arguments it writes (RAPID Instructions and
# Functions manuals). GetSysData fills a tool or work object with the
# current one; the calibrations fill a tool.
WRITING_BUILTINS = {
    "getdataval": (1,), "readanybin": (1,), "unpackrawbytes": (2,), "getsysdata": (0,),
    "mtooltcpcalib": (4,), "stooltcpcalib": (4,), "mtoolrotcalib": (2,), "stoolrotcalib": (3,),
    "strtoval": (1,), "getnextsym": (0, 1), "testandset": (0,),
    # (Data of any type: a message's from another task, RMQGetMsgData msg,
    # pTarget; a subscription's, updated while the program runs,
    # SiGetCyclic device, pTarget, 64.)
    "rmqgetmsgdata": (1,), "sigetcyclic": (1,),
    # (Their INOUT argument: Add extj.eax_a, 100; Incr n; TPReadNum x, "...".)
    "add": (0,), "incr": (0,), "decr": (0,), "clear": (0,), "bitset": (0,), "bitclear": (0,),
    "tpreadnum": (0,), "tpreaddnum": (0,), "tpreadfk": (0,), "readcfgdata": (2,),
    "gettrapdata": (0,), "readerrdata": (1, 2, 3), "readrawbytes": (1,), "packrawbytes": (1,),
    "copyrawbytes": (2,), "clearrawbytes": (0,),
}
# Assignments a reason names by line, at most.
MAX_LINES = 5
# (Those that change the value it has, rather than fill it.)
_CHANGING = frozenset(("add", "incr", "decr", "clear", "bitset", "bitclear", "clearrawbytes"))


@dataclass(frozen=True)
class Writes:
    by_name: dict            # lower-case name -> (ParsedFile, Span, how it is written)
    anything: tuple | None   # (ParsedFile, Span, instruction) writing a name computed at run time
    # Names written only by assigning a literal, whole or to one component:
    # name -> [(ParsedFile, Assign)] (RoboDK posts assign a tool or work
    # object its own declared value at the top of every program, which
    # changes nothing, or its frame before the moves that use it:
    # rdkTool.tframe := [...]).
    literal: dict = field(default_factory=dict)
    # Every assignment of a name in its first file (Spans, in text order):
    # why() names each line, not one of them.
    assigned: dict = field(default_factory=dict)

    def why(self, name: str, literal_ok: bool = False) -> str | None:
        """Why data of this name may change at run time, or None
        (literal_ok: its whole-literal assignments are known to change
        nothing)."""
        hit = self.by_name.get(name.lower())
        if literal_ok and name.lower() in self.literal:
            hit = None
        if hit is not None:
            pf, span, how = hit
            spans = self.assigned.get(name.lower()) if how == "assigned" else None
            lines = (sorted({pf.line(s) for s in spans}) if spans and spans[0] == span
                     else [pf.line(span)])
            shown = ", ".join(map(str, lines[:MAX_LINES])) + (", ..." if len(lines) > MAX_LINES
                                                              else "")
            return f"{name} is {how} at run time ({pf.source.display_path}:{shown})"
        if self.anything is not None:
            pf, span, what = self.anything
            return (f"{name} may be changed at run time by {what} with a name computed at run "
                    f"time ({pf.source.display_path}:{pf.line(span)})")
        return None


def task_writes(files: list[ParsedFile], usages: dict) -> Writes:
    """usages: id(Module) -> refs.Usage of every module of files."""
    routines = RoutineTable()
    for pf in files:
        for m in pf.modules:
            for r in m.routines:
                routines.add(m, r, r.node)
    changed = _params_written(files, routines)
    by_name: dict = {}
    assigned: dict = {}
    anything = None
    literal: dict = {}
    other: set = set()          # names written other than by a whole literal

    def written(name: str, pf, span, how: str) -> None:
        by_name.setdefault(name, (pf, span, how))
        other.add(name)

    for pf in files:
        for m in pf.modules:
            us: Usage | None = usages.get(id(m))
            if us is None:
                continue
            for name, spans in us.writes.items():
                # (The first in the text: the one a reader meets first.)
                spans = sorted(spans)
                if name not in by_name:
                    by_name[name] = (pf, spans[0], "assigned")
                    assigned[name] = spans
                whole = [a for a in (*us.assigns.get(name, ()), *us.parts.get(name, ()))
                         if type(a.value) in (A.Agg, A.NumAgg)]
                if len(whole) == len(spans):
                    literal.setdefault(name, []).extend((pf, a) for a in whole)
                else:
                    other.add(name)
            for call in us.calls:
                got = _call_writes(call, m, routines, changed)
                if got is None:
                    if anything is None:
                        anything = (pf, call.span, call.name)
                    continue
                for span, name, how in got:
                    written(name, pf, span, how)
    return Writes(by_name, anything, {n: v for n, v in literal.items() if n not in other},
                  assigned)


def _passed_written(args, params, changed):
    """(argument, the lower-case name it passes) of each argument naming
    data (a Ref) passed where it may be changed: to a parameter of
    `params` among `changed` (lower-case names: those the routine may
    write), or anywhere where params is None (a routine not given, a
    late-bound call)."""
    required = [p for p in params if not p.optional] if params is not None else None
    k = 0
    for a in args:
        # (A required argument, positional or named (pt:=p1), holds its
        # place among the required ones; an optional one (\T:=x) none.)
        place = a.kind in ("pos", "named")
        if isinstance(a.value, A.Ref):
            if params is None:
                is_written = True
            elif a.kind == "pos":
                p = required[k] if k < len(required) else None
                is_written = p is not None and p.name.lower() in changed
            else:
                p = next((p for p in params if p.name.lower() == (a.name or "").lower()), None)
                is_written = p is not None and p.name.lower() in changed
            if is_written and not load_only(a.value):
                yield a, a.value.name.lower()
        k += place


_WRITABLE = frozenset(("INOUT", "VAR", "PERS"))


def _params_written(files: list[ParsedFile], routines: RoutineTable) -> dict:
    """id(routine node) -> the lower-case names of its INOUT/VAR/PERS
    parameters its body may write: assigned (whole or a component), a
    search's result, filled by a built-in (WRITING_BUILTINS), set by
    SetDataVal (any, with a name computed at run time), passed to a
    routine no given module declares or a late-bound call, or passed on
    to a given routine's parameter that may be written (to a fixed point:
    a routine calling itself writes what some path of it writes). Only
    routines with such parameters are walked (a CAM program's path has
    none)."""
    found: list = []          # (node, its module, its writable parameters, calls in it)
    out: dict = {}
    for pf in files:
        for m in pf.modules:
            for r in m.routines:
                node = r.node
                mine = frozenset(p.name.lower() for p in node.params if p.access in _WRITABLE)
                if not mine or id(node) in out:
                    continue
                direct: set = set()
                calls = []
                for n in nodes((node.decls, node.body, node.handlers)):
                    t = type(n)
                    if t is A.Assign:
                        if not load_only(n.target):
                            direct.add(n.target.name.lower())
                    elif t is A.ProcCall or t is A.Call or t is A.LateCall:
                        spec = motion_spec(n.name) if t is A.ProcCall else None
                        if spec is None:
                            calls.append(n)
                        elif "search" in spec.roles:
                            direct.update(name for name, _ in searched(n, spec))
                out[id(node)] = frozenset(direct & mine)
                found.append((node, m, mine, calls))
    while True:
        grew = False
        for node, m, mine, calls in found:
            have = out[id(node)]
            now = set(have)
            for call in calls:
                got = _call_writes(call, m, routines, out)
                now.update(mine if got is None else mine.intersection(n for _, n, _ in got))
            if len(now) > len(have):
                out[id(node)] = frozenset(now)
                grew = True
        if not grew:
            return out


def _call_writes(call, m, routines: RoutineTable, changed: dict) -> list | None:
    """What a call (in module m) may write among its arguments: (span,
    lower-case name, how) of each, with `changed` for the given routines'
    parameters (_params_written); None: any data (SetDataVal, SetAllDataVal
    with a name computed at run time)."""
    if isinstance(call, A.LateCall):
        return [(a.span, n, "passed to a late-bound call")
                for a, n in _passed_written(call.args, None, ())]
    name = call.name.lower()
    if name in ("setdataval", "setalldataval"):
        first = next((a for a in call.args if a.kind == "pos"), None)
        if name == "setdataval" and first is not None and isinstance(first.value, A.Str):
            return [(call.span, first.value.value.lower(), "set by SetDataVal")]
        return None
    node = routines.find(m, name)
    if node is not None:
        return [(a.span, n, f"passed to {node.name}, which may change it")
                for a, n in _passed_written(call.args, node.params, changed.get(id(node), ()))]
    if name in WRITING_BUILTINS:
        positional = [a for a in call.args if a.kind in ("pos", "named")]
        how = f"{'changed' if name in _CHANGING else 'filled'} by {call.name}"
        return [(positional[k].span, positional[k].value.name.lower(), how)
                for k in WRITING_BUILTINS[name]
                if k < len(positional) and isinstance(positional[k].value, A.Ref)
                and not load_only(positional[k].value)]
    if name not in BUILTIN_INSTRUCTIONS and name not in BUILTIN_FUNCTIONS:
        kind = "function " if isinstance(call, A.Call) else ""
        how = f"passed to {kind}{call.name}, which no given module declares (it may change it)"
        return [(a.span, n, how) for a, n in _passed_written(call.args, None, ())]
    return []
