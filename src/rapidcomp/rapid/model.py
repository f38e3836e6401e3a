"""The frozen model of a parsed RAPID file: declarations, routines, motions.

Built from the syntax nodes after parsing. Line numbers are derived from
spans through the SourceText, so the model never goes stale against it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

from ..source import SourceText
from . import ast as A
from .ast import Span
from .motions import MotionSpec
from .values import Record


@dataclass(frozen=True, slots=True)
class Loop:
    """An enclosing FOR loop (WHILE loops are recorded with var=None)."""

    var: str | None
    start: A.Expr | None
    stop: A.Expr | None
    step: A.Expr | None
    span: Span
    # An IF, TEST or WHILE inside the loop holds the move: it may not run
    # for every value of the variable.
    guarded: bool = False


@dataclass(frozen=True, slots=True)
class TargetArg:
    role: str               # "to", "cir" or "search"
    expr: A.Expr
    value: Record | None    # decoded inline literal, if it is one
    issue: str | None       # why an inline aggregate could not be decoded


class Roles(NamedTuple):
    """Which argument of a move is which (index into its args, -1: none):
    a function of the arguments' kinds and names alone, shared by every
    move written alike (parse.py)."""

    targets: tuple[tuple[str, int], ...]   # (role, index) of "to", "cir", "search"
    speed: int
    zone: int
    tool: int
    wobj: int
    optional: tuple[int, ...]   # optional arguments other than \WObj
    # The move names its target parameter (`MoveL ToPoint:=p10,...`).
    to_point: bool


@dataclass(frozen=True, slots=True)
class Motion:
    instruction: str        # as written
    spec: MotionSpec
    span: Span
    routine: str
    loops: tuple[Loop, ...]
    # (A.TailArgs where the move was lexed as one token: speed, zone, tool
    # and work object made when asked, not kept.)
    args: "tuple[A.Arg, ...] | A.TailArgs"
    targets: tuple[TargetArg, ...]
    roles: Roles

    @property
    def name_span(self) -> Span:
        """The instruction's name, where its statement starts."""
        return Span(self.span.start, self.span.start + len(self.instruction))

    def _value(self, j: int):
        return None if j < 0 else A.arg_value(self.args, j)

    @property
    def speed(self) -> A.Expr | None:
        return self._value(self.roles.speed)

    @property
    def zone(self) -> A.Expr | None:
        return self._value(self.roles.zone)

    @property
    def tool(self) -> A.Expr | None:
        return self._value(self.roles.tool)

    @property
    def wobj(self) -> A.Expr | None:
        return self._value(self.roles.wobj)

    @property
    def optional(self) -> tuple[A.Arg, ...]:
        """Optional arguments other than \\WObj."""
        js = self.roles.optional
        if not js:
            return ()
        args = tuple(self.args)
        return tuple(args[j] for j in js)

    @property
    def to_point(self) -> bool:
        return self.roles.to_point


@dataclass(frozen=True, slots=True)
class Declaration:
    node: A.DataDecl
    routine: str | None            # None at module level
    type: str                      # lower-case type name
    dims: tuple[int | None, ...]   # None: a dimension that is not a literal
    value: Record | tuple[Record, ...] | None  # tuple for arrays (row-major)
    issue: str | None              # why a value of a decoded type is not known
    # node.name, kept (asked of every group and literal of a CAM program).
    name: str

    @property
    def storage(self) -> str:
        return self.node.storage

    @property
    def scope(self) -> str | None:
        return self.node.scope

    @property
    def span(self) -> Span:
        return self.node.span


@dataclass(frozen=True, slots=True)
class RoutineInfo:
    node: A.Routine

    @property
    def name(self) -> str:
        return self.node.name

    @property
    def kind(self) -> str:
        return self.node.kind


@dataclass(frozen=True)
class Module:
    node: A.ModuleNode
    declarations: tuple[Declaration, ...]
    routines: tuple[RoutineInfo, ...]
    motions: tuple[Motion, ...]
    records: tuple[A.RecordDecl, ...]
    aliases: tuple[A.AliasDecl, ...]

    @property
    def name(self) -> str:
        return self.node.name

    @property
    def attributes(self) -> tuple[str, ...]:
        return self.node.attributes


@dataclass(frozen=True)
class ParsedFile:
    source: SourceText
    header: str | None
    modules: tuple[Module, ...]
    # Every word of the text, lower case (rewrite/names.words), where the
    # parse found them already (a large module's: rapid/predecode.py).
    words: frozenset[str] | None = field(default=None, compare=False, repr=False)

    @property
    def module(self) -> Module:
        return self.modules[0]

    def line(self, span: Span) -> int:
        return self.source.position(span.start)[0]

    def text(self, node) -> str:
        span = node.span if hasattr(node, "span") else node
        return self.source.text[span.start:span.end]


class RoutineTable:
    """A task's routines by name, as the controller resolves a call: the
    calling module's own (LOCAL ones included) first, then the global ones
    of every module (the first declared)."""

    def __init__(self) -> None:
        self._local: dict = {}
        self._global: dict = {}

    def add(self, module: Module, routine: RoutineInfo, value) -> None:
        name = routine.name.lower()
        self._local.setdefault((id(module), name), value)
        if routine.node.scope != "LOCAL":
            self._global.setdefault(name, value)

    def find(self, module: Module, name: str):
        name = name.lower()
        return self._local.get((id(module), name)) or self._global.get(name)
