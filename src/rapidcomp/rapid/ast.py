"""Frozen syntax nodes of a RAPID module, each with its character span.

These are produced by the transformer while Lark parses (no parse tree is
built). Spans are half-open character offsets into SourceText.text.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Union

from ..construct import maker


class Span(int):
    """A half-open range of character offsets [start, end), read as a pair:
    `span.start`, `span.end`, `start, end = span`, span[0], span[1]. Held
    as one int, start << 32 | end: a node's span is one object of 48 bytes,
    not a tuple of two ints (128; a CAM program's nodes have 4e5-5e5
    spans, issue #14). It is that int in all else: ordered as the pair is,
    equal (and hashed) as a Span of the same range or that int, never as a
    tuple; arithmetic, json and numpy see the int (rows of spans:
    verify._span_rows). Offsets are 0 <= x < 2**32, not checked here:
    parse.py reads no larger text."""

    __slots__ = ()

    def __new__(cls, start: int, end: int):
        return int.__new__(cls, (start << 32) | end)

    @property
    def start(self) -> int:
        return self >> 32

    @property
    def end(self) -> int:
        return self & 0xFFFFFFFF

    def __iter__(self):
        return iter((self >> 32, self & 0xFFFFFFFF))

    def __getitem__(self, j):
        return (self >> 32, self & 0xFFFFFFFF)[j]

    def __len__(self) -> int:
        return 2

    def __bool__(self) -> bool:
        return True                         # (as a pair is, Span(0, 0) too)

    def __repr__(self) -> str:
        return f"Span(start={self >> 32}, end={self & 0xFFFFFFFF})"

    def __reduce__(self):
        return Span, (self >> 32, self & 0xFFFFFFFF)


# Offsets a Span holds are below this (parse.py refuses a larger text).
SPAN_LIMIT = 1 << 32


# ----------------------------------------------------------------- expressions

@dataclass(frozen=True, slots=True)
class Num:
    value: float
    text: str
    span: Span


@dataclass(frozen=True, slots=True)
class Str:
    value: str
    span: Span


@dataclass(frozen=True, slots=True)
class Bool:
    value: bool
    span: Span


@dataclass(frozen=True, slots=True)
class Agg:
    items: tuple["Expr", ...]
    span: Span


# A name as the grammar's NAME reads it: its letters ISO 8859-1's (a to z,
# A to Z and the accented letters, not the multiplication and division
# signs), then those, digits and '_'.
_LETTER = "A-Za-z\u00c0-\u00d6\u00d8-\u00f6\u00f8-\u00ff"
NAME_PATTERN = f"[{_LETTER}][{_LETTER}0-9_]*"

# (The grammar's _N: a number's digits split one way only, so a pattern
# that fails after many numbers is not tried again at every split.)
NUMBER_RE = re.compile(r"[+-]?(?:[0-9]{1,200}(?:\.[0-9]*)?|\.[0-9]+)"
                       r"(?:[eE][+-]?(?:0*[1-9][0-9]?|0+))?")
_TOKEN_RE = re.compile(r"\[|\]|" + NUMBER_RE.pattern)


class _Cached:
    """A slot for what a node computes when first asked (NumAgg.items)."""

    __slots__ = ("_items",)


@dataclass(frozen=True, slots=True)
class NumAgg(_Cached):
    """An aggregate made only of number literals, lexed as one token.

    Its items are decoded on demand: most CAM targets are only ever read by
    the typed-record decoder (values.py), which matches the text directly.
    (Slots: no dict per node, 1e5 of them in a CAM program.)
    """

    text: str
    span: Span

    @property
    def items(self) -> tuple["Expr", ...]:
        """The general view (Agg/Num nodes), for code that walks expressions."""
        try:
            return self._items
        except AttributeError:
            pass
        items = self._decoded()
        object.__setattr__(self, "_items", items)
        return items

    def _decoded(self) -> tuple["Expr", ...]:
        base = self.span.start
        stack: list[tuple[int, list]] = []
        top: list = []
        for m in _TOKEN_RE.finditer(self.text):
            tok = m.group()
            if tok == "[":
                stack.append((m.start(), top))
                top = []
            elif tok == "]":
                opened, parent = stack.pop()
                node = Agg(tuple(top), Span(base + opened, base + m.end()))
                parent.append(node)
                top = parent
            else:
                top.append(Num(float(tok), tok, Span(base + m.start(), base + m.end())))
        return top[0].items


@dataclass(frozen=True, slots=True)
class Component:
    name: str
    span: Span


@dataclass(frozen=True, slots=True)
class Index:
    indices: tuple["Expr", ...]
    span: Span


@dataclass(frozen=True, slots=True)
class Ref:
    """A data reference: name with optional components and array indices."""

    name: str
    selectors: tuple[Union[Component, Index], ...]
    span: Span


@dataclass(frozen=True, slots=True)
class Arg:
    """One argument of a call.

    kind: "pos" (required), "named" (Param:=value), "opt" (\\Name),
    "optval" (\\Name:=value) or "cond" (\\Name?var).
    """

    kind: str
    name: str | None
    value: "Expr | None"
    span: Span


@dataclass(frozen=True, slots=True)
class Call:
    name: str
    args: tuple[Arg, ...]
    span: Span


@dataclass(frozen=True, slots=True)
class Unary:
    op: str
    operand: "Expr"
    span: Span


@dataclass(frozen=True, slots=True)
class Binary:
    op: str
    left: "Expr"
    right: "Expr"
    span: Span


@dataclass(frozen=True, slots=True)
class Paren:
    expr: "Expr"
    span: Span


@dataclass(frozen=True, slots=True)
class Placeholder:
    text: str
    span: Span


Expr = Union[Num, Str, Bool, Agg, NumAgg, Ref, Call, Unary, Binary, Paren, Placeholder]


@dataclass(frozen=True, slots=True, eq=False)
class TailArgs:
    """The arguments of a call lexed as one token (a CAM move), read as a
    tuple of Arg nodes: the first argument's value node kept (`first`; its
    Arg, positional and of the same span, made when read), those after it
    made from their text each time they are read (`tail`, the parse's
    object for that text, which every call written with it shares:
    ",v100,z1,tool1\\WObj:=wobj1;" 1e5 times; `at`, where it starts here).
    Kept, they were 14 of a move's 22 objects, ~1 KB: a CAM program's 1e5
    moves, ~110 MB from the parse to the end of the job (issue #14). Nodes
    made at each read are equal, not the same objects: nothing may be keyed
    by their id(). A copy (pickle) is the tuple."""

    first: Expr
    tail: object                 # rapid/build.py's _Tail: nodes(at), value(at, j), size
    at: int

    def nodes(self) -> tuple[Arg, ...]:
        first = self.first
        return (_new_arg("pos", None, first, first.span),) + self.tail.nodes(self.at)

    def value(self, j: int):
        """Argument j's value node (made alone where it is in the tail)."""
        return self.first if j == 0 else self.tail.value(self.at, j - 1)

    def __iter__(self):
        return iter(self.nodes())

    def __reversed__(self):
        return reversed(self.nodes())

    def __len__(self) -> int:
        return 1 + self.tail.size

    def __getitem__(self, j):
        return self.nodes()[j]

    def __eq__(self, other) -> bool:
        if type(other) is TailArgs or type(other) is tuple:
            return self.nodes() == tuple(other)
        return NotImplemented

    def __hash__(self) -> int:
        return hash(self.nodes())

    def __add__(self, other):
        return self.nodes() + tuple(other)

    def __radd__(self, other):
        return tuple(other) + self.nodes()

    def __repr__(self) -> str:
        return repr(self.nodes())

    def __reduce__(self):
        return tuple, (self.nodes(),)


# (TailArgs' first Arg, made as its class makes it: construct.py.)
_new_arg = maker(Arg)


def arg_value(args: "tuple[Arg, ...] | TailArgs", j: int):
    """The value node of a call's argument j (of TailArgs, made alone)."""
    return args[j].value if type(args) is tuple else args.value(j)


# ----------------------------------------------------------------- statements

@dataclass(frozen=True, slots=True)
class Assign:
    target: Ref
    value: Expr
    span: Span


@dataclass(frozen=True, slots=True)
class ProcCall:
    name: str
    args: "tuple[Arg, ...] | TailArgs"      # (TailArgs: a call lexed as one token)
    span: Span
    # Every argument a plain name or a literal (refs.plain_args), decided
    # once by the builder: a CAM move is asked three times.
    plain: bool = False

    @property
    def name_span(self) -> Span:
        """The procedure's name, where the statement starts (made when
        asked: a CAM program has 1e5 calls)."""
        return Span(self.span.start, self.span.start + len(self.name))


@dataclass(frozen=True, slots=True)
class LateCall:
    proc: Expr
    args: tuple[Arg, ...]
    span: Span


@dataclass(frozen=True, slots=True)
class If:
    branches: tuple[tuple[Expr, tuple["Stmt", ...]], ...]
    orelse: tuple["Stmt", ...]
    span: Span


@dataclass(frozen=True, slots=True)
class CompactIf:
    cond: Expr
    stmt: "Stmt"
    span: Span


@dataclass(frozen=True, slots=True)
class For:
    var: str
    start: Expr
    stop: Expr
    step: Expr | None
    body: tuple["Stmt", ...]
    span: Span


@dataclass(frozen=True, slots=True)
class While:
    cond: Expr
    body: tuple["Stmt", ...]
    span: Span


@dataclass(frozen=True, slots=True)
class Test:
    expr: Expr
    cases: tuple[tuple[tuple[Expr, ...], tuple["Stmt", ...]], ...]
    default: tuple["Stmt", ...] | None
    span: Span


@dataclass(frozen=True, slots=True)
class Simple:
    """GOTO, label, RETURN, RAISE, RETRY, TRYNEXT, EXIT, CONNECT, <SMT>."""

    kind: str
    name: str | None
    expr: Expr | None
    span: Span


Stmt = Union[Assign, ProcCall, LateCall, If, CompactIf, For, While, Test, Simple]


# ----------------------------------------------------------------- declarations

@dataclass(frozen=True, slots=True)
class DataDecl:
    scope: str | None      # "LOCAL", "TASK" or None
    storage: str           # "CONST", "PERS" or "VAR"
    type_name: str         # as written
    name: str
    name_span: Span
    dims: tuple[Expr, ...]
    init: Expr | None
    span: Span


@dataclass(frozen=True, slots=True)
class RecordDecl:
    scope: str | None
    name: str
    components: tuple[tuple[str, str], ...]
    span: Span


@dataclass(frozen=True, slots=True)
class AliasDecl:
    scope: str | None
    type_name: str
    name: str
    span: Span


@dataclass(frozen=True, slots=True)
class Param:
    access: str | None
    type_name: str
    name: str
    optional: bool
    array: int  # number of {*} dimensions


@dataclass(frozen=True, slots=True)
class Handler:
    kind: str  # "BACKWARD", "ERROR" or "UNDO"
    errors: tuple[Expr, ...]
    body: tuple[Stmt, ...]


@dataclass(frozen=True, slots=True)
class Routine:
    kind: str  # "PROC", "FUNC" or "TRAP"
    scope: str | None
    name: str
    return_type: str | None
    params: tuple[Param, ...]
    decls: tuple[DataDecl, ...]
    body: tuple[Stmt, ...]
    handlers: tuple[Handler, ...]
    span: Span


@dataclass(frozen=True, slots=True)
class ModuleNode:
    name: str
    name_span: Span
    attributes: tuple[str, ...]
    items: tuple[Union[DataDecl, RecordDecl, AliasDecl, Routine, Placeholder], ...]
    span: Span
