"""Where each data name is used in a module, and where it is written.

The rewriter edits a declaration in place only when every use of the name
is one it rewrites; a name that is assigned (or filled by a search
instruction) is not a static value at all. Both questions need every data
reference of the module, which this walk collects once.
"""

from __future__ import annotations

from array import array
from dataclasses import dataclass, field, fields

from . import ast as A
from .motions import motion_spec

_FIELDS: dict[type, tuple[str, ...]] = {}


# Fields that never hold a node (a CAM program's walk visits 1e6 nodes:
# pushing their names and kinds too doubled it).
_SCALAR = frozenset({"str", "str | None", "int", "float", "bool", "Span"})


def _field_names(cls: type) -> tuple[str, ...]:
    names = _FIELDS.get(cls)
    if names is None:
        names = tuple(f.name for f in fields(cls) if f.name not in ("span", "name_span")
                      and str(f.type) not in _SCALAR)
        _FIELDS[cls] = names
    return names


@dataclass(frozen=True)
class Usage:
    # lower-case name -> where each reference starts (offsets: a CAM
    # program's 1e5 moves name the same speed, zone, tool and work object;
    # their nodes are made when read, A.TailArgs): an int where the name
    # is referred to once (a program of declared targets, each moved to
    # once: 1e5 names, no array each), else an array (reference_starts)
    refs: dict[str, "int | array"]
    writes: dict[str, list[A.Span]]       # lower-case name -> assignments / search results
    calls: tuple = ()                     # ProcCall/LateCall/Call: arguments may be written
                                          # (see writes.py)
    assigns: dict = field(default_factory=dict)  # lower-case name -> whole-value Assigns
    # lower-case name -> Assigns of one component of it (rdkTool.tframe := ...)
    parts: dict = field(default_factory=dict)


def nodes(root, plain_calls: bool = False):
    """Every syntax node below root (numeric aggregates hold no names);
    plain_calls: a plain ProcCall (names and literals only), and a call
    lexed as one token whose first argument is a call (Offs), without the
    nodes below them: the caller reads their arguments (usage())."""
    stack: list = [root]
    while stack:
        node = stack.pop()
        t = type(node)
        if t is tuple or t is list or t is A.TailArgs:
            stack.extend(node)
        elif t is A.Ref:      # the commonest nodes first, their fields known
            yield node
            if node.selectors:
                stack.append(node.selectors)
        elif t is A.Arg:
            yield node
            stack.append(node.value)
        elif t is A.ProcCall and node.plain:
            # A CAM move (names and literals only): its nodes in the order
            # the general walk gives them (last argument first), without
            # a push and pop per node.
            yield node
            if plain_calls:
                continue
            for arg in reversed(node.args):
                yield arg
                v = arg.value
                if v is not None and type(v) is not A.NumAgg:
                    yield v
        elif t is A.Call or t is A.ProcCall:
            # (Their one field that holds nodes: Offs(p, 0, 0, 10) in every
            # move of a hand-written or Offs-relative program.)
            yield node
            # (A move lexed as one token, its first argument a call of
            # names and numbers (build._fast_func): with plain_calls, the
            # caller reads that call and its references, and those after it
            # (A.TailArgs' text has them, no node made).)
            if not (plain_calls and type(node.args) is A.TailArgs):
                stack.append(node.args)
        elif t is A.Num:
            yield node
        elif not (t is A.NumAgg or node is None or t in (str, int, float, bool)):
            yield node
            if hasattr(t, "__dataclass_fields__"):
                for name in _field_names(t):
                    stack.append(getattr(node, name))


def plain_args(args) -> bool:
    """Every argument is a plain name or a literal (or none): the call's
    arguments call nothing and hold no further node. (One call per move,
    not one per argument: asked 3e5 times of a CAM program.)"""
    for arg in args:
        v = arg.value
        t = type(v)
        if not (type(arg) is A.Arg and (v is None or t is A.NumAgg or t is A.Num or t is A.Str
                                        or (t is A.Ref and not v.selectors))):
            return False
    return True


def usage(module: A.ModuleNode) -> Usage:
    refs: dict[str, array] = {}
    writes: dict[str, list[A.Span]] = {}
    assigns: dict[str, list[A.Assign]] = {}
    parts: dict[str, list[A.Assign]] = {}
    calls = []
    for node in nodes(module.items, plain_calls=True):
        t = type(node)
        if t is A.Ref:
            _referred(refs, node)
        elif t is A.Arg:      # (the next commonest: its value comes as a node of its own)
            continue
        elif t is A.Assign:
            if load_only(node.target):
                continue
            writes.setdefault(node.target.name.lower(), []).append(node.span)
            selectors = node.target.selectors
            if not selectors:
                assigns.setdefault(node.target.name.lower(), []).append(node)
            elif len(selectors) == 1 and type(selectors[0]) is A.Component:
                parts.setdefault(node.target.name.lower(), []).append(node)
        elif t is A.ProcCall:
            first = None
            if node.plain:
                # (A CAM move, 1e5 of them: its references, in the order the
                # walk gives them, read here; those after its first where
                # its text has them, A.TailArgs, no node made.)
                args = node.args
                if type(args) is A.TailArgs:
                    _tail_refs(refs, args)
                    if type(args.first) is A.Ref:
                        _referred(refs, args.first)
                    args = ()
                for arg in reversed(args):
                    v = arg.value
                    if type(v) is A.Ref:
                        _referred(refs, v)
            elif type(node.args) is A.TailArgs:
                # (MoveL Offs(p, 0, 0, 10),v100,...: those after its first,
                # then the call and its names (nodes() goes no further), in
                # the order the walk would meet them.)
                _tail_refs(refs, node.args)
                first = node.args.first
                for arg in reversed(first.args):
                    if type(arg.value) is A.Ref:
                        _referred(refs, arg.value)
            spec = motion_spec(node.name)
            if spec is None:
                calls.append(node)
            elif "search" in spec.roles:
                _search_writes(node, spec, writes)
            if first is not None:
                calls.append(first)
        elif t is A.LateCall or t is A.Call:
            calls.append(node)
    return Usage(refs, writes, tuple(calls), assigns, parts)


def _tail_refs(refs: dict, args: A.TailArgs) -> None:
    """The references after a one-token call's first argument, from its
    shared tail's names (last first, as the general walk finds them)."""
    at = args.at
    for name, start in args.tail.names:
        # (_refer written out: 4e5 references of a CAM program.)
        starts = refs.get(name)
        if type(starts) is array:
            starts.append(at + start)
        elif starts is None:
            refs[name] = at + start
        else:
            refs[name] = array("q", (starts, at + start))


def _referred(refs: dict, ref: A.Ref) -> None:
    _refer(refs, ref.name.lower(), ref.span.start)


def _refer(refs: dict, name: str, start: int) -> None:
    """One more reference to `name` (lower case), at `start` (Usage.refs)."""
    starts = refs.get(name)
    if starts is None:
        refs[name] = start
    elif type(starts) is int:
        refs[name] = array("q", (starts, start))
    else:
        starts.append(start)


def reference_starts(starts: "int | array") -> "tuple[int] | array":
    """Where the references of a name of Usage.refs start."""
    return (starts,) if type(starts) is int else starts


def load_only(ref: A.Ref) -> bool:
    """Whether writing `ref` writes a tool's load alone (tool1.tload.mass,
    tools{2}.tload): no part of the frames rapidcomp reads (a program that
    sets its tool's load after a grip changes no pose). Only tooldata has
    a tload."""
    for sel in ref.selectors:
        if type(sel) is A.Component:
            return sel.name.lower() == "tload"
    return False


def _search_writes(node: A.ProcCall, spec, writes: dict) -> None:
    """A search instruction writes the robtarget it names as its result."""
    for name, span in searched(node, spec):
        writes.setdefault(name, []).append(span)


def searched(node: A.ProcCall, spec) -> list:
    """(lower-case name, its argument's span) of the robtarget a search
    instruction names as its result: it writes it."""
    positional = [a for a in node.args if a.kind in ("pos", "named")]
    return [(arg.value.name.lower(), arg.span) for role, arg in zip(spec.roles, positional)
            if role == "search" and isinstance(arg.value, A.Ref)]


def calls_in(expr):
    """The function calls in an expression (nested ones too)."""
    return [node for node in nodes(expr) if type(node) is A.Call]


def literal_leaves(expr) -> tuple | None:
    """The values of a literal aggregate in order (numbers, strings,
    booleans), or None when it holds anything but literals: two literals
    with equal leaves are the same value however their digits are written."""
    out = []
    stack = [expr]
    while stack:
        node = stack.pop()
        t = type(node)
        if t is A.Agg or t is A.NumAgg:
            stack.extend(reversed(node.items))
        elif t is A.Num or t is A.Str or t is A.Bool:
            out.append(node.value)
        elif t is A.Unary and node.op == "-" and type(node.operand) is A.Num:
            out.append(-node.operand.value)
        else:
            return None
    return tuple(out)


def names_in(expr) -> set[str]:
    """Lower-case names of the data an expression refers to."""
    return {node.name.lower() for node in nodes(expr) if type(node) is A.Ref}


def loop_names(expr, loops) -> set[str] | frozenset:
    """The names of expr that a variable of its enclosing loops may be
    among: none outside every loop (loop variables are lexical: no loop
    environment reaches a statement outside its loops; a CAM move is in
    none). The flow's use keys and the resolver's are made from these."""
    return names_in(expr) if loops else frozenset()
