"""Typed RAPID data values decoded from literal aggregates.

Each numeric field keeps its source text and span, so a rewrite replaces
exactly those characters. A value that is not fully literal (a named
constant inside, an expression) is not guessed at: decoding raises
DecodeIssue with the reason and where.
"""

from __future__ import annotations

from dataclasses import dataclass
import re
from typing import NamedTuple, Union

import numpy as np

from ..construct import maker
from . import ast as A
from .ast import Span


class Field(NamedTuple):
    value: float | bool | str
    text: str
    span: Span


class DecodeIssue(Exception):
    """A value that is not decoded. illegal: it cannot be a value of its
    type at all (a position of 2 numbers, a string where a number goes, a
    number no RAPID num can hold): the controller would refuse the module.
    Otherwise it is legal RAPID whose value is not literal (a named
    constant, an expression): known only at run time."""

    def __init__(self, reason: str, span: Span, illegal: bool = False):
        super().__init__(reason)
        self.reason = reason
        self.span = span
        self.illegal = illegal


# A RAPID num is a 32-bit float.
NUM_MAX = 3.4028234663852886e38


@dataclass(frozen=True, slots=True)
class Pose:
    trans: tuple[Field, Field, Field]
    rot: tuple[Field, Field, Field, Field]  # quaternion, RAPID order q1..q4 = w, x, y, z
    span: Span

    @property
    def xyz(self) -> tuple[float, float, float]:
        return tuple(f.value for f in self.trans)

    @property
    def quat_wxyz(self) -> tuple[float, float, float, float]:
        return tuple(f.value for f in self.rot)


class _Numeric:
    """Shared storage of all-numeric records: values, texts, relative spans.

    Fields are materialised on access; CAM programs hold 1e5+ targets and
    most are only ever read as float tuples. A compact literal keeps only
    its text (the string the syntax tree holds already): the field texts
    and spans are lexed again when asked for (2.5 KB less per target).
    """

    __slots__ = ()

    @property
    def texts(self) -> tuple[str, ...]:
        if type(self.lexed) is tuple:
            return self.lexed[0]
        # (Without the spans: 1e5 literals' texts are asked for at once.)
        return _FAST[type(self).__name__.lower()].fullmatch(self.lexed).groups()

    @property
    def regs(self) -> tuple[tuple[int, int], ...]:
        """Spans of the fields, relative to span.start."""
        return self.lex()[1]

    def lex(self) -> tuple[tuple[str, ...], tuple[tuple[int, int], ...]]:
        """(texts, regs) at once."""
        if type(self.lexed) is tuple:
            return self.lexed
        m = _FAST[type(self).__name__.lower()].fullmatch(self.lexed)
        return m.groups(), m.regs[1:]

    def _fields(self, lo: int, hi: int) -> tuple[Field, ...]:
        texts, regs = self.lex()
        base = self.span.start
        return tuple(Field(self.values[i], texts[i], Span(base + regs[i][0], base + regs[i][1]))
                     for i in range(lo, hi))


@dataclass(frozen=True, slots=True)
class RobTarget(_Numeric):
    """robtarget: trans (mm), rot (quaternion w,x,y,z), robconf, extax.

    values/texts hold the 17 numbers in declaration order; regs their spans
    relative to span.start; lexed: the literal's text, or (texts, regs).
    """

    values: tuple[float, ...]
    lexed: str | tuple
    span: Span

    @property
    def trans(self) -> tuple[Field, ...]:
        return self._fields(0, 3)

    @property
    def rot(self) -> tuple[Field, ...]:
        return self._fields(3, 7)

    @property
    def robconf(self) -> tuple[Field, ...]:
        return self._fields(7, 11)

    @property
    def extax(self) -> tuple[Field, ...]:
        return self._fields(11, 17)

    @property
    def xyz(self) -> tuple[float, float, float]:
        return self.values[0:3]

    @property
    def quat_wxyz(self) -> tuple[float, float, float, float]:
        return self.values[3:7]

    @property
    def conf(self) -> tuple[int, int, int, int]:
        return tuple(map(int, self.values[7:11]))

    @property
    def ext(self) -> tuple[float, ...]:
        return self.values[11:17]


@dataclass(frozen=True, slots=True)
class JointTarget(_Numeric):
    """jointtarget: robax (deg, 6 axes) and extax; storage as in RobTarget."""

    values: tuple[float, ...]
    lexed: str | tuple
    span: Span

    @property
    def robax(self) -> tuple[Field, ...]:
        return self._fields(0, 6)

    @property
    def extax(self) -> tuple[Field, ...]:
        return self._fields(6, 12)

    @property
    def joints(self) -> tuple[float, ...]:
        return self.values[0:6]

    @property
    def ext(self) -> tuple[float, ...]:
        return self.values[6:12]


@dataclass(frozen=True, slots=True)
class LoadData:
    mass: Field
    cog: tuple[Field, Field, Field]
    aom: tuple[Field, Field, Field, Field]
    inertia: tuple[Field, Field, Field]
    span: Span


@dataclass(frozen=True, slots=True)
class ToolData:
    robhold: Field
    tframe: Pose
    tload: LoadData
    span: Span


@dataclass(frozen=True, slots=True)
class WobjData:
    robhold: Field
    ufprog: Field
    ufmec: Field
    uframe: Pose
    oframe: Pose
    span: Span


Record = Union[Pose, RobTarget, JointTarget, LoadData, ToolData, WobjData]

# Shapes: "n" number, "b" bool, "s" string, a tuple is an aggregate.
_POS = ("n",) * 3
_ORIENT = ("n",) * 4
_POSE = (_POS, _ORIENT)
_LOAD = ("n", _POS, _ORIENT, "n", "n", "n")
SHAPES: dict[str, tuple] = {
    "pos": _POS,
    "orient": _ORIENT,
    "confdata": ("n",) * 4,
    "extjoint": ("n",) * 6,
    "robjoint": ("n",) * 6,
    "pose": _POSE,
    "robtarget": (_POS, _ORIENT, ("n",) * 4, ("n",) * 6),
    "jointtarget": (("n",) * 6, ("n",) * 6),
    "loaddata": _LOAD,
    "tooldata": ("b", _POSE, _LOAD),
    "wobjdata": ("b", "b", "s", _POSE, _POSE),
}
# The components' names, as RAPID writes them (p1.trans.x, p1.extax.eax_a):
# per shape, (name, the names inside it) of each component, for messages.
_POS_N = (("x", None), ("y", None), ("z", None))
_ORIENT_N = tuple((f"q{i}", None) for i in range(1, 5))
_POSE_N = (("trans", _POS_N), ("rot", _ORIENT_N))
_LOAD_N = (("mass", None), ("cog", _POS_N), ("aom", _ORIENT_N), ("ix", None), ("iy", None),
           ("iz", None))
_CONF_N = tuple((c, None) for c in ("cf1", "cf4", "cf6", "cfx"))
_EAX_N = tuple((f"eax_{c}", None) for c in "abcdef")
_RAX_N = tuple((f"rax_{i}", None) for i in range(1, 7))
NAMES: dict[str, tuple] = {
    "pos": _POS_N,
    "orient": _ORIENT_N,
    "confdata": _CONF_N,
    "extjoint": _EAX_N,
    "robjoint": _RAX_N,
    "pose": _POSE_N,
    "robtarget": (("trans", _POS_N), ("rot", _ORIENT_N), ("robconf", _CONF_N), ("extax", _EAX_N)),
    "jointtarget": (("robax", _RAX_N), ("extax", _EAX_N)),
    "loaddata": _LOAD_N,
    "tooldata": (("robhold", None), ("tframe", _POSE_N), ("tload", _LOAD_N)),
    "wobjdata": (("robhold", None), ("ufprog", None), ("ufmec", None), ("uframe", _POSE_N),
                 ("oframe", _POSE_N)),
}
DECODED_TYPES = frozenset(("robtarget", "jointtarget", "tooldata", "wobjdata", "loaddata", "pose"))
_LEAF_NAMES = {"n": "a number", "b": "TRUE or FALSE", "s": "a string"}


def _items(expr) -> tuple | None:
    if isinstance(expr, (A.Agg, A.NumAgg)):
        return expr.items
    return None


_LITERALS = (A.Num, A.Str, A.Bool, A.Agg, A.NumAgg)


def _number(value: float, text: str, span: Span, where: str) -> Field:
    if not abs(value) <= NUM_MAX:
        raise DecodeIssue(f"{where} is {text}, beyond what a RAPID num holds (+-3.4E38)", span,
                          True)
    return Field(value, text, span)


def _leaf(kind: str, expr, where: str) -> Field:
    if kind == "n":
        if isinstance(expr, A.Num):
            return _number(expr.value, expr.text, expr.span, where)
        if (isinstance(expr, A.Unary) and expr.op in "+-" and isinstance(expr.operand, A.Num)):
            value = -expr.operand.value if expr.op == "-" else expr.operand.value
            return _number(value, expr.op + expr.operand.text, expr.span, where)
    elif kind == "b" and isinstance(expr, A.Bool):
        return Field(expr.value, "TRUE" if expr.value else "FALSE", expr.span)
    elif kind == "s" and isinstance(expr, A.Str):
        return Field(expr.value, expr.value, expr.span)
    if isinstance(expr, _LITERALS):   # a literal of another kind: a type error
        raise DecodeIssue(f"{where} is not {_LEAF_NAMES[kind]}", expr.span, True)
    raise DecodeIssue(f"{where} is not a literal ({_LEAF_NAMES[kind]} expected)", expr.span)


def _walk(shape, expr, where: str, names=None):
    """names: the components' (NAMES), for where a message points."""
    if isinstance(shape, str):
        return _leaf(shape, expr, where)
    items = _items(expr)
    if items is None:
        if isinstance(expr, _LITERALS):
            raise DecodeIssue(f"{where} is not an aggregate of {len(shape)} components",
                              expr.span, True)
        raise DecodeIssue(f"{where} is not a literal aggregate", expr.span)
    if len(items) != len(shape):
        raise DecodeIssue(f"{where} has {len(items)} components, expected {len(shape)}",
                          expr.span, True)
    return tuple(_walk(s, e, f"{where}.{names[i][0]}", names[i][1]) if names else
                 _walk(s, e, f"{where}.{i + 1}") for i, (s, e) in enumerate(zip(shape, items)))


def _shape_regex(counts: tuple[int, ...]) -> re.Pattern:
    num = f"({A.NUMBER_RE.pattern})"
    groups = [r"\[\s*" + r"\s*,\s*".join([num] * n) + r"\s*\]" for n in counts]
    return re.compile(r"\[\s*" + r"\s*,\s*".join(groups) + r"\s*\]")


_FAST = {"robtarget": _shape_regex((3, 4, 4, 6)), "jointtarget": _shape_regex((6, 6))}
# A literal's 17 (12) numbers in their frame (as written without whitespace).
ROBTARGET_FRAME = "[[%s,%s,%s],[%s,%s,%s,%s],[%s,%s,%s,%s],[%s,%s,%s,%s,%s,%s]]"
JOINTTARGET_FRAME = "[[%s,%s,%s,%s,%s,%s],[%s,%s,%s,%s,%s,%s]]"
_PLAIN = {RobTarget: ROBTARGET_FRAME, JointTarget: JOINTTARGET_FRAME}
_COMPACT = {"robtarget": RobTarget, "jointtarget": JointTarget}
# (A CAM program's 1e5 literals: made as their classes make them, construct.py.)
_MAKE = {cls: maker(cls) for cls in (RobTarget, JointTarget)}
_NAME = {RobTarget: "robtarget", JointTarget: "jointtarget"}
_COUNT = {RobTarget: 17, JointTarget: 12}
# Over these characters float() reads exactly what NUMBER_RE matches (a
# sign, digits, one '.', an exponent); hex, octal and binary have others.
_NOT_DECIMAL = str.maketrans("", "", "0123456789.eE+-,")


# What follows each of a plain robtarget literal's 17 fields up to the
# next one: ',' inside a group, '],[' between groups; and the separators
# of one literal and the ',' that joins it to the next, in order.
_GAPS = np.array([1, 1, 3, 1, 1, 1, 3, 1, 1, 1, 3, 1, 1, 1, 1, 1])
# Which bytes are separators, by byte value (a lookup: np.isin sorted 1.7e7
# bytes of a CAM program's literals).
_IS_SEPARATOR = np.zeros(256, bool)
_IS_SEPARATOR[np.frombuffer(b",[]", np.uint8)] = True
_FRAME_SEPARATORS = np.frombuffer(b"[[,,],[,,,],[,,,],[,,,,,]],", np.uint8)


def plain_bounds(lits: list[str]):
    """(the literals joined by ',', each one's offset in it (n,), each
    field's start and end in its literal (n, 17)) when every one is a
    robtarget literal written plainly, else None: in ASCII without
    whitespace, [[x,y,z],[q1,q2,q3,q4],[c1,c2,c3,c4],[e1,...,e6]] with
    each field a run of characters other than brackets and commas. One
    pass over the bytes of all of them (a CAM program's 1e5 literals, no
    string per field)."""
    joined = ",".join(lits)
    # (Not printable: every whitespace character but ' '.)
    if " " in joined or not joined.isprintable() or not joined.isascii():
        return None
    n = len(lits)
    chars = np.frombuffer(joined.encode("ascii"), np.uint8)
    sep = _IS_SEPARATOR[chars]
    # The separators are the frame's, in the frame's order: with the gaps
    # below, every literal is the frame with 17 fields in it.
    if not np.array_equal(chars[sep], np.tile(_FRAME_SEPARATORS, n)[:-1]):
        return None
    starts = np.flatnonzero(sep[:-1] & ~sep[1:]) + 1
    ends = np.flatnonzero(~sep[:-1] & sep[1:]) + 1
    if len(starts) != 17 * n or len(ends) != 17 * n or (n and not sep[0]):
        return None
    lengths = np.fromiter(map(len, lits), np.int64, n)
    off = np.cumsum(lengths + 1) - lengths - 1
    starts = starts.reshape(n, 17) - off[:, None]
    ends = ends.reshape(n, 17) - off[:, None]
    if not ((starts[:, 0] == 2).all() and (ends[:, 16] + 2 == lengths).all()
            and (starts[:, 1:] - ends[:, :-1] == _GAPS).all()):
        return None
    return joined, off, starts, ends


def frame_fields(text: str) -> list[str]:
    """What lies between the brackets and commas of an all-numeric literal
    (or of such literals joined by ','): its field texts, where it is
    written in its frame."""
    return text.replace("[", "").replace("]", "").split(",")


def decimal_chars(texts) -> bool:
    """Every text is written with those characters only: float() of it
    (where it succeeds) is what the regex reads (one C-level pass)."""
    return not ",".join(texts).translate(_NOT_DECIMAL)


def decimals(texts) -> tuple[float, ...] | None:
    """float() of each text when every one is a decimal number as NUMBER_RE
    writes it (the regex's verdict), else None."""
    if not decimal_chars(texts):
        return None
    try:
        return tuple(map(float, texts))
    except ValueError:
        return None


# A plain literal's last groups (a robtarget's confdata and external
# axes, a jointtarget's external axes) repeat from target to target in a
# CAM program: their floats are made once per distinct text and shared
# (1e5 targets: 1e6 floats, ~24 MB). Bounded: many programs in one process.
_TAIL_FLOATS: dict[str, tuple[float, ...]] = {}
TAIL_FLOATS_MAX = 4096
# (how many fields come before the shared ones; whether those end at the
# second ']' rather than the first)
_HEAD = {RobTarget: (7, True), JointTarget: (6, False)}


def head_size(cls) -> int:
    """How many fields of a plain literal come before its shared tail."""
    return _HEAD[cls][0]


def tail_text(cls, text: str) -> str:
    """A plain literal's text from the ']' that ends its head's fields on:
    the frame's tail with the shared fields in it (_floats)."""
    second = _HEAD[cls][1]
    cut = text.index("]")
    if second:
        cut = text.index("]", cut + 1)
    return text[cut:]


def share_tail(tail: str, floats: tuple[float, ...]) -> tuple[float, ...]:
    """The floats kept for a tail text: those kept already, else `floats`
    (kept from now on)."""
    shared = _TAIL_FLOATS.get(tail)
    if shared is None:
        if len(_TAIL_FLOATS) >= TAIL_FLOATS_MAX:
            _TAIL_FLOATS.clear()
        shared = _TAIL_FLOATS[tail] = floats
    return shared


def _floats(cls, fields: list[str], text: str) -> tuple[float, ...]:
    """float() of each field of a literal written in its plain frame:
    `text` is the frame with `fields` in it, so the text from the ']' that
    ends the head's fields on is the frame's tail with the other fields in
    it (equal tails, equal field texts, equal floats). ValueError as
    float's."""
    head = _HEAD[cls][0]
    tail = tail_text(cls, text)
    shared = _TAIL_FLOATS.get(tail)
    if shared is None:
        shared = share_tail(tail, tuple(map(float, fields[head:])))
    return tuple(map(float, fields[:head])) + shared


def plain_values(cls, fields: list[str], text: str) -> tuple[float, ...] | None:
    """The values of a literal `text` of class cls (RobTarget,
    JointTarget) written in its plain frame, `fields` its frame_fields:
    None where it is not (the count or the frame differs, a field is no
    number, or one is beyond what a num holds: the general decoding says
    which)."""
    # (A NumAgg's numbers are NUMBER_RE's, the lexer's NUMAGG matched
    # them, with whitespace around them that float() drops, but for
    # \x1c-\x1f: those go the regex's way.)
    if len(fields) != _COUNT[cls] or text != _PLAIN[cls] % tuple(fields):
        return None
    try:
        values = _floats(cls, fields, text)
    except ValueError:
        return None
    return values if max(map(abs, values)) <= NUM_MAX else None


def spaced_values(cls, text: str) -> tuple[float, ...] | None:
    """The values of an all-numeric literal `text` of class cls written
    otherwise than in its plain frame (blanks after its commas, as people
    write them), read by the shape's regex: None where it does not match or
    a number is beyond what a num holds (the general decoding says which)."""
    m = _FAST[_NAME[cls]].fullmatch(text)
    if m is None:
        return None
    values = tuple(map(float, m.groups()))
    return values if max(map(abs, values)) <= NUM_MAX else None


def _compact(t: str, expr, where: str, known=None) -> Record:
    """An all-numeric record, by its shape's frame when the value is a
    NumAgg: its numbers are what lies between its brackets and commas,
    and it has the shape when they, put back in the frame, give its text
    (whitespace around a number stays with it; float() drops it). A CAM
    program has 1e5: a third of the regex's time. Else by one regex match.
    known: plain_values (else spaced_values) of the literals of the text,
    computed ahead (predecode.py)."""
    cls = _COMPACT[t]
    if isinstance(expr, A.NumAgg):
        text = expr.text
        if known is not None:
            values = known.values(cls, expr.span)
            if values is not None:
                return _MAKE[cls](values, text, expr.span)
        values = plain_values(cls, frame_fields(text), text)
        if values is not None:
            return _MAKE[cls](values, text, expr.span)
        values = spaced_values(cls, text)
        if values is not None:
            return _MAKE[cls](values, text, expr.span)
        m = _FAST[t].fullmatch(text)
        if m is not None:
            # (Its shape, with a number beyond a num's range: which, and
            # where. No NaN: the regex's numbers.)
            texts = m.groups()
            k = next(i for i, x in enumerate(texts) if not abs(float(x)) <= NUM_MAX)
            s, e = m.regs[k + 1]
            raise DecodeIssue(f"{where} component {texts[k]} is beyond what a RAPID num "
                              "holds (+-3.4E38)",
                              Span(expr.span.start + s, expr.span.start + e), True)
    nested = _walk(SHAPES[t], expr, where, NAMES[t])
    fields = [f for group in nested for f in group]
    base = expr.span.start
    return cls(tuple(f.value for f in fields), (
        tuple(f.text for f in fields),
        tuple((f.span.start - base, f.span.end - base) for f in fields)), expr.span)


def relex(record: Record, text: str, want) -> Record | None:
    """`record` as `text` (the same literal with other numbers) writes it,
    or None when the text is not an all-numeric literal of its type with
    the field texts `want` (its span stays where the input holds it).
    The text is first compared with the texts `want` in the frame of a
    literal without whitespace: equal, and every text a decimal number,
    the regex would find them there (how the editor writes a literal the
    input writes so; 1e5 times in a CAM program, for a third of the time).
    A kept field may be written otherwise (0x1F in a value the parser
    decoded field by field): the regex's verdict."""
    values = decimals(want) if text == _PLAIN[type(record)] % tuple(want) else None
    if values is None:
        m = _FAST[type(record).__name__.lower()].fullmatch(text)
        if m is None or m.groups() != tuple(want):
            return None
        values = tuple(map(float, want))
    if not max(map(abs, values)) <= NUM_MAX:
        return None
    return type(record)(values, text, record.span)


def decode(type_name: str, expr, where: str | None = None, known=None) -> Record:
    """Decode a literal value of a supported type. Raises DecodeIssue.
    known: see _compact."""
    t = type_name.lower()
    where = where or t
    if t in _COMPACT:
        return _compact(t, expr, where, known)
    if t == "pose":
        v = _walk(SHAPES[t], expr, where, NAMES[t])
        return Pose(v[0], v[1], expr.span)
    if t == "loaddata":
        return _load(_walk(SHAPES[t], expr, where, NAMES[t]), expr.span)
    if t == "tooldata":
        v = _walk(SHAPES[t], expr, where, NAMES[t])
        return ToolData(v[0], Pose(v[1][0], v[1][1], expr.items[1].span),
                        _load(v[2], expr.items[2].span), expr.span)
    if t == "wobjdata":
        v = _walk(SHAPES[t], expr, where, NAMES[t])
        items = expr.items
        return WobjData(v[0], v[1], v[2], Pose(v[3][0], v[3][1], items[3].span),
                        Pose(v[4][0], v[4][1], items[4].span), expr.span)
    raise DecodeIssue(f"values of type {type_name} are not decoded", expr.span)


def _load(v, span: Span) -> LoadData:
    return LoadData(v[0], v[1], v[2], (v[3], v[4], v[5]), span)


def decode_array(type_name: str, expr, dims: tuple[int, ...], where: str, known=None):
    """Decode an array initializer into a flat row-major tuple of records."""
    if not dims:
        return (decode(type_name, expr, where, known),)
    items = _items(expr)
    if items is None:
        raise DecodeIssue(f"{where} is not a literal array aggregate", expr.span,
                          isinstance(expr, _LITERALS))
    if len(items) != dims[0]:
        raise DecodeIssue(f"{where} has {len(items)} elements, declared {dims[0]}", expr.span,
                          True)
    out: list = []
    for i, item in enumerate(items):
        out.extend(decode_array(type_name, item, dims[1:], f"{where}{{{i + 1}}}", known))
    return tuple(out)
