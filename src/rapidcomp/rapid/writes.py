"""Which data a task may change while it runs, and where.

A target whose data is changed at run time is not a static value: the
compensation of its literal would be wrong the moment it changes. Data is
changed by an assignment, a search instruction's result, a built-in
instruction or function that fills an argument (GetDataVal, StrToVal, ...),
an argument passed to an INOUT/VAR/PERS parameter of a given routine, any
argument of a routine no given module declares or of a late-bound call
(they may change it), SetDataVal by name, and, with a name computed at run
time, SetDataVal/SetAllDataVal may change anything.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from . import ast as A
from .model import ParsedFile, RoutineTable
from .motions import BUILTIN_FUNCTIONS, BUILTIN_INSTRUCTIONS
from .refs import Usage

# Built-in instructions and functions that write an argument: name -> the
# positions among the required arguments it writes (RAPID Instructions and
# Functions manuals). GetSysData fills a tool or work object with the
# current one; the calibrations fill a tool.
WRITING_BUILTINS = {
    "getdataval": (1,), "readanybin": (1,), "unpackrawbytes": (2,), "getsysdata": (0,),
    "mtooltcpcalib": (4,), "stooltcpcalib": (3,), "mtoolrotcalib": (2,), "stoolrotcalib": (3,),
    "strtoval": (1,), "getnextsym": (0, 1), "testandset": (0,),
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
                if isinstance(call, A.LateCall):
                    _args_written(written, pf, call.args, None, "passed to a late-bound call")
                    continue
                name = call.name.lower()
                if name in ("setdataval", "setalldataval"):
                    first = next((a for a in call.args if a.kind == "pos"), None)
                    if name == "setdataval" and first is not None and isinstance(
                            first.value, A.Str):
                        written(first.value.value.lower(), pf, call.span, "set by SetDataVal")
                    elif anything is None:
                        anything = (pf, call.span, call.name)
                    continue
                node = routines.find(m, name)
                if node is not None:
                    _args_written(written, pf, call.args, node.params,
                                  f"passed to {node.name}, which may change it")
                elif name in WRITING_BUILTINS:
                    positional = [a for a in call.args if a.kind in ("pos", "named")]
                    for k in WRITING_BUILTINS[name]:
                        if k < len(positional) and isinstance(positional[k].value, A.Ref):
                            written(positional[k].value.name.lower(), pf, positional[k].span,
                                    f"{'changed' if name in _CHANGING else 'filled'} by "
                                    f"{call.name}")
                elif name not in BUILTIN_INSTRUCTIONS and name not in BUILTIN_FUNCTIONS:
                    kind = "function " if isinstance(call, A.Call) else ""
                    _args_written(written, pf, call.args, None,
                                  f"passed to {kind}{call.name}, which no given module "
                                  "declares (it may change it)")
    return Writes(by_name, anything, {n: v for n, v in literal.items() if n not in other},
                  assigned)


def _args_written(written, pf, args, params, how: str) -> None:
    required = [p for p in params if not p.optional] if params is not None else None
    k = 0
    for a in args:
        if a.value is None or not isinstance(a.value, A.Ref):
            if a.kind == "pos":
                k += 1
            continue
        if params is None:
            is_written = True
        elif a.kind == "pos":
            p = required[k] if k < len(required) else None
            is_written = p is not None and p.access in ("INOUT", "VAR", "PERS")
        else:
            p = next((p for p in params if p.name.lower() == (a.name or "").lower()), None)
            is_written = p is not None and p.access in ("INOUT", "VAR", "PERS")
        if a.kind == "pos":
            k += 1
        if is_written:
            written(a.value.name.lower(), pf, a.span, how)
