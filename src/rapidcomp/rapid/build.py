"""Lark transformer that builds frozen syntax nodes while the LALR parser runs.

No parse tree is built: each grammar rule's callback receives its children
(tokens and nodes already built) and returns a node with an exact span.
Anonymous punctuation is filtered by Lark, so rules keep named terminals
(SEMI, RPAR, RBRACK, ...) wherever a span has to end on one.
"""

from __future__ import annotations

import re
import sys


from ..construct import made_as, maker
from . import ast as A
from .ast import Span
from .lalr import FAST_NAME, Tok
from .refs import plain_args


# A FAST_DECL up to its value: scope, storage, type, name (verify reads the
# editor's new declarations with it too).
DECL_HEAD = re.compile(r"(?:(LOCAL|TASK)[ \t]+)?(CONST|PERS|VAR)[ \t]+([A-Za-z][A-Za-z0-9_]*)"
                       r"[ \t]+([A-Za-z][A-Za-z0-9_]*)[ \t]*:=[ \t]*", re.IGNORECASE)
# A FAST_CALL's argument after its first (and an optional argument of its
# function): \Opt:=value (groups 1, 2), a name (3), a number (4); a sign
# right before a number is part of it, as the parser folds it (signed).
_FAST_ITEM = re.compile(
    r"\\([A-Za-z][A-Za-z0-9_]*)(?:[ \t]*:=[ \t]*"
    r"([A-Za-z][A-Za-z0-9_]*|[-+]?[0-9]+(?:\.[0-9]*)?))?"
    r"|([A-Za-z][A-Za-z0-9_]*)|([-+]?[0-9]+(?:\.[0-9]*)?)")


# A numeric aggregate (the grammar's NUMAGG nests lists two deep at most):
# where a FAST_CIRC's first one ends.
_AGG = re.compile(r"\[(?:[^\[\]]|\[[^\[\]]*\])*\]")

_INF = float("inf")
# A plain decimal number argument of a FAST_CALL's function (the grammar's
# _FAST_NUM: at most 30 digits each side, never beyond a num's range).
_FAST_NUM = re.compile(r"[-+]?(?:[0-9]{1,30}(?:\.[0-9]{0,30})?|\.[0-9]{1,30})(?![\w.])")


def _span(se, _new=int.__new__, _Span=Span) -> Span:
    """Span(*se) (a pair of offsets), without a call of its __new__."""
    return _new(_Span, (se[0] << 32) | se[1])


# The nodes of one-token statements and declarations, made as their classes
# make them (construct.py; a CAM program's 1e5 moves and 5e4 declarations).
_arg, _ref, _num, _call, _decl, _numagg, _func, _tail_args = (
    maker(c) for c in (A.Arg, A.Ref, A.Num, A.ProcCall, A.DataDecl, A.NumAgg, A.Call,
                       A.TailArgs))

# The arguments after a FAST_CALL's first, by their text: a CAM program
# repeats ",v100,z1,tool1\\WObj:=wobj1;" 1e5 times. Lexed once; the names'
# strings shared by every call that has them.
_TAILS: dict[str, "_Tail"] = {}
# Uses of one argument text after which its nodes are made by a function
# written for it (~0.4 ms to write; then each call's nodes ~1 us faster). A
# program whose every line has a text of its own (\ID:=n of a MultiMove
# program) never pays for one.
COMPILE_AFTER = 256


class _Tail:
    """The arguments in `tail`, a FAST_CALL's text after its first: nodes(at)
    makes their Arg nodes for the text found at offset `at`, value(at, j)
    the value node of the j-th alone (A.TailArgs reads them so)."""

    __slots__ = ("items", "uses", "make", "size", "names")

    def __init__(self, tail: str):
        items = []
        for m in _FAST_ITEM.finditer(tail):
            opt, val, word, number = m.group(1, 2, 3, 4)
            if word is not None:
                items.append((None, None, word, m.start(3), m.end(3), 0, 0, False, None))
            elif number is not None:
                # (A positional number: no option, its text as val.)
                items.append((None, number, None, m.start(), m.end(), m.start(), m.end(),
                              True, signed(number)))
            else:
                is_num = val is not None and not val[0].isalpha()
                items.append((opt, val, None, m.start(), m.end(),
                              m.start(2), m.end(2), is_num,
                              signed(val) if is_num else None))
        self.items = tuple(items)
        self.size = len(items)
        # The data names among them, lower case, and where each starts (from
        # `at`), last first: where refs.usage finds a move's references
        # without making its nodes (the values' nodes made once, at 0).
        values = [self.value(0, j) for j in reversed(range(self.size))]
        self.names = tuple((v.name.lower(), v.span.start) for v in values if type(v) is A.Ref)
        self.uses = 0
        self.make = None

    def nodes(self, at: int) -> tuple:
        make = self.make
        if make is not None:
            return make(at)
        self.uses += 1
        if self.uses >= COMPILE_AFTER:
            self.make = _tail_maker(self.items)
        args = []
        for opt, val, word, s0, e0, s2, e2, is_num, num in self.items:
            if word is not None:
                span = _span((at + s0, at + e0))
                args.append(_arg("pos", None, _ref(word, (), span), span))
            elif opt is None:
                span = _span((at + s0, at + e0))
                args.append(_arg("pos", None, _num(num, val, span), span))
            elif val is None:
                args.append(_arg("opt", opt, None, _span((at + s0, at + e0))))
            else:
                vspan = _span((at + s2, at + e2))
                value = _num(num, val, vspan) if is_num else _ref(val, (), vspan)
                args.append(_arg("optval", opt, value, _span((at + s0, at + e0))))
        return tuple(args)

    def value(self, at: int, j: int):
        """The value node nodes(at)[j] holds (None for an \\Opt alone), made
        as nodes() makes it."""
        opt, val, word, s0, e0, s2, e2, is_num, num = self.items[j]
        if word is not None:
            return _ref(word, (), _span((at + s0, at + e0)))
        if opt is None:
            return _num(num, val, _span((at + s0, at + e0)))
        if val is None:
            return None
        vspan = _span((at + s2, at + e2))
        return _num(num, val, vspan) if is_num else _ref(val, (), vspan)


_NUMBER_START = frozenset("+-.0123456789")


def signed(text: str) -> float:
    """The value of a decimal number with at most a sign before it, as the
    parser makes it (NodeBuilder.unop folds the sign into the number)."""
    value = number_value(text.lstrip("+-"))
    return -value if text[0] == "-" else value


def _fast_number(text: str, base: int, pos: int) -> tuple:
    """The Num a FAST_CALL's number at text[pos] is (the grammar's
    _FAST_NUM), its sign folded in as the parser folds it; and where it
    ends in text."""
    end = _FAST_NUM.match(text, pos).end()
    written = text[pos:end]
    return _num(signed(written), written, _span((base + pos, base + end))), end


def _fast_func(text: str, base: int, start: int, name_end: int) -> tuple:
    """The function call a FAST_CALL's first argument is (its name at
    text[start:name_end], then '(' arguments ')': names, numeric
    aggregates and plain decimal numbers, blanks around commas; the
    grammar's _FAST_FUNC), as
    func_call makes it; and where it ends in text."""
    args = []
    pos = name_end + 1
    while True:
        while text[pos] in " \t":
            pos += 1
        if text[pos] == "\\":
            # (\Opt or \Opt:=name|number: as the tail's; grammar's _FAST_OPT.)
            m = _FAST_ITEM.match(text, pos)
            opt, val, end = m.group(1), m.group(2), m.end()
            if val is None:
                args.append(_arg("opt", opt, None, _span((base + pos, base + end))))
            else:
                vspan = _span((base + m.start(2), base + m.end(2)))
                value = (_ref(val, (), vspan) if val[0].isalpha()
                         else _num(signed(val), val, vspan))
                args.append(_arg("optval", opt, value, _span((base + pos, base + end))))
            pos = end
            while text[pos] in " \t":
                pos += 1
            if text[pos] == ")":
                return (_func(text[start:name_end], tuple(args),
                              _span((base + start, base + pos + 1))), pos + 1)
            if text[pos] == ",":
                pos += 1
            continue
        if text[pos] == "[":
            # (A numeric aggregate: it ends where its brackets close.)
            depth, end = 0, pos
            while True:
                c = text[end]
                depth += (c == "[") - (c == "]")
                end += 1
                if depth == 0:
                    break
            span = _span((base + pos, base + end))
            node = _numagg(text[pos:end], span)
        elif text[pos] in _NUMBER_START:
            # (As the parser makes it: a sign right before the number folded
            # into it, its span from the sign.)
            node, end = _fast_number(text, base, pos)
            span = node.span
        else:
            end = _FAST_ITEM.match(text, pos).end()
            span = _span((base + pos, base + end))
            node = _ref(text[pos:end], (), span)
        args.append(_arg("pos", None, node, span))
        pos = end
        while text[pos] in " \t":
            pos += 1
        if text[pos] == ")":
            return _func(text[start:name_end], tuple(args), _span((base + start, base + pos + 1))), \
                pos + 1
        if text[pos] == ",":
            pos += 1
        # (else a '\\': an optional argument right after this one)


def _fast_tail(tail: str) -> _Tail:
    hit = _TAILS.get(tail)
    if hit is None:
        if len(_TAILS) >= 4096:        # bounded: many programs in one process
            _TAILS.clear()
        hit = _TAILS[tail] = _Tail(tail)
    return hit


def _tail_maker(items: tuple):
    """make(at): _Tail.nodes of these items, written as code (their words,
    values and relative spans constants; each node made as construct.maker
    makes it, without a call per node)."""
    ns: dict = {"_t": int.__new__, "_Span": Span}

    def node(cls, var: str, values: list[str]) -> list[str]:
        # var = cls(*values), made as construct.maker makes it.
        return ["    " + line for line in made_as(cls, var, values, ns)]

    lines = ["def make(at):"]
    out = []
    for j, (opt, val, word, s0, e0, s2, e2, is_num, num) in enumerate(items):
        ns[f"opt{j}"], ns[f"val{j}"], ns[f"word{j}"], ns[f"num{j}"] = opt, val, word, num
        if word is not None:
            lines.append(f"    s{j} = _t(_Span, ((at + {s0}) << 32) | (at + {e0}))")
            lines += node(A.Ref, f"r{j}", [f"word{j}", "()", f"s{j}"])
            lines += node(A.Arg, f"a{j}", ["'pos'", "None", f"r{j}", f"s{j}"])
        elif opt is None:
            lines.append(f"    s{j} = _t(_Span, ((at + {s0}) << 32) | (at + {e0}))")
            lines += node(A.Num, f"r{j}", [f"num{j}", f"val{j}", f"s{j}"])
            lines += node(A.Arg, f"a{j}", ["'pos'", "None", f"r{j}", f"s{j}"])
        elif val is None:
            lines.append(f"    s{j} = _t(_Span, ((at + {s0}) << 32) | (at + {e0}))")
            lines += node(A.Arg, f"a{j}", ["'opt'", f"opt{j}", "None", f"s{j}"])
        else:
            lines.append(f"    v{j} = _t(_Span, ((at + {s2}) << 32) | (at + {e2}))")
            lines += (node(A.Num, f"r{j}", [f"num{j}", f"val{j}", f"v{j}"]) if is_num
                      else node(A.Ref, f"r{j}", [f"val{j}", "()", f"v{j}"]))
            lines.append(f"    s{j} = _t(_Span, ((at + {s0}) << 32) | (at + {e0}))")
            lines += node(A.Arg, f"a{j}", ["'optval'", f"opt{j}", f"r{j}", f"s{j}"])
        out.append(f"a{j}")
    lines.append(f"    return ({''.join(a + ', ' for a in out)})")
    exec("\n".join(lines) + "\n", ns)
    return ns["make"]


class NumberOutOfRange(Exception):
    """A number literal beyond every RAPID numeric type (num, dnum)."""

    def __init__(self, pos: int, text: str):
        super().__init__(text)
        self.pos = pos
        self.text = text


# A hexadecimal, octal or binary literal is an integer; no RAPID numeric
# type holds one beyond 2^52 (dnum's exact integers).
MAX_BASED = 2 ** 52


def number_value(text: str) -> float:
    """Value of a RAPID num literal in any spelling the kernel allows
    (infinite when no RAPID numeric type holds it)."""
    if len(text) > 2 and text[0] == "0" and text[1] in "xXoObB":
        value = int(text, 0)
        return float(value) if value <= MAX_BASED else _INF
    return float(text)


def _start(x) -> int:
    return x.start_pos if isinstance(x, Tok) else x.span.start


def _end(x) -> int:
    return x.end_pos if isinstance(x, Tok) else x.span.end


class _Tag(tuple):
    """A tagged intermediate value (scope, storage, dims...) between rules."""


def _tag(name, *values):
    return _Tag((name, *values))


class NodeBuilder:
    # ------------------------------------------------------------ module level
    def start(self, c):
        header = c[0] if c and isinstance(c[0], Tok) else None
        modules = [m for m in c if isinstance(m, A.ModuleNode)]
        return header, modules

    def module(self, c):
        name = c[1]
        attrs: tuple[str, ...] = ()
        items = []
        for x in c[2:-1]:
            if isinstance(x, _Tag) and x[0] == "attrs":
                attrs = x[1]
            else:
                items.append(x)
        return A.ModuleNode(name.value, Span(name.start_pos, name.end_pos), attrs,
                            tuple(items), Span(c[0].start_pos, c[-1].end_pos))

    def module_attrs(self, c):
        return _tag("attrs", tuple(t.value.upper() for t in c))

    def placeholder_item(self, c):
        t = c[0]
        return A.Placeholder(t.value, Span(t.start_pos, t.end_pos))

    # ------------------------------------------------------------ data
    def scope(self, c):
        return _tag("scope", c[0].value.upper(), c[0].start_pos)

    def storage(self, c):
        return _tag("storage", c[0].value.upper(), c[0].start_pos)

    def dims(self, c):
        return _tag("dims", tuple(c))

    def init(self, c):
        return _tag("init", c[0])

    def data_decl(self, c):
        scope = None
        i = 0
        start = None
        if c[0][0] == "scope":
            scope, start = c[0][1], c[0][2]
            i = 1
        storage = c[i][1]
        if start is None:
            start = c[i][2]
        type_tok, name_tok = c[i + 1], c[i + 2]
        dims: tuple = ()
        init = None
        for x in c[i + 3:-1]:
            if x[0] == "dims":
                dims = x[1]
            else:
                init = x[1]
        return A.DataDecl(scope, storage, type_tok.value, name_tok.value,
                          Span(name_tok.start_pos, name_tok.end_pos), dims, init,
                          Span(start, c[-1].end_pos))

    def record_comp(self, c):
        return (c[0].value, c[1].value)

    def record_decl(self, c):
        scope = c[0][1] if isinstance(c[0], _Tag) else None
        rest = c[1:] if scope else c
        start = c[0][2] if scope else rest[0].start_pos
        return A.RecordDecl(scope, rest[1].value, tuple(rest[2:-1]),
                            Span(start, rest[-1].end_pos))

    def alias_decl(self, c):
        scope = c[0][1] if isinstance(c[0], _Tag) else None
        rest = c[1:] if scope else c
        start = c[0][2] if scope else rest[0].start_pos
        return A.AliasDecl(scope, rest[1].value, rest[2].value, Span(start, rest[-1].end_pos))

    # ------------------------------------------------------------ routines
    def access(self, c):
        return _tag("access", c[0].value.upper())

    def dims_star(self, c):
        return _tag("star", len(c))

    def param(self, c):
        access = None
        if isinstance(c[0], _Tag):
            access = c[0][1]
            c = c[1:]
        array = c[2][1] if len(c) > 2 else 0
        return A.Param(access, c[0].value, c[1].value, False, array)

    def opt_params(self, c):
        return [A.Param(p.access, p.type_name, p.name, True, p.array) for p in c]

    def params(self, c):
        out = []
        for x in c:
            if isinstance(x, list):
                out.extend(x)
            else:
                out.append(x)
        return _tag("params", tuple(out))

    def body(self, c):
        decls = tuple(x for x in c if isinstance(x, A.DataDecl))
        stmts = next(x for x in c if isinstance(x, _Tag) and x[0] == "stmts")[1]
        handlers = tuple(x for x in c if isinstance(x, A.Handler))
        return _tag("body", decls, stmts, handlers)

    def stmt_list(self, c):
        return _tag("stmts", tuple(c))

    def backward(self, c):
        return A.Handler("BACKWARD", (), c[1][1])

    def undo(self, c):
        return A.Handler("UNDO", (), c[1][1])

    def error_handler(self, c):
        errors = c[1][1] if len(c) == 3 else ()
        return A.Handler("ERROR", errors, c[-1][1])

    def error_list(self, c):
        return _tag("errors", tuple(c[:-1]))

    def _routine(self, kind, c, return_type_at=None):
        scope = None
        start = None
        if isinstance(c[0], _Tag):
            scope, start = c[0][1], c[0][2]
            c = c[1:]
        if start is None:
            start = c[0].start_pos
        return_type = c[1].value if return_type_at else None
        name = c[2] if return_type_at else c[1]
        params: tuple = ()
        body = None
        for x in c:
            if isinstance(x, _Tag):
                if x[0] == "params":
                    params = x[1]
                elif x[0] == "body":
                    body = x
        return A.Routine(kind, scope, name.value, return_type, params, body[1], body[2],
                         body[3], Span(start, c[-1].end_pos))

    def proc(self, c):
        return self._routine("PROC", c)

    def func(self, c):
        return self._routine("FUNC", c, return_type_at=1)

    def trap(self, c):
        return self._routine("TRAP", c)

    # ------------------------------------------------------------ statements
    def assign(self, c):
        return A.Assign(c[0], c[1], Span(c[0].span.start, c[2].end_pos))

    def call(self, c):
        name = c[0]
        args = c[1] if len(c) == 3 else ()
        return A.ProcCall(name.value, args, Span(name.start_pos, c[-1].end_pos),
                          plain_args(args))

    def fast_call(self, c):
        """A FAST_CALL token: split it into name and arguments (see grammar)."""
        tok = c[0]
        text = tok.value
        base = tok.start_pos
        head = FAST_NAME.match(text)
        # (Interned: "MoveL" 1e5 times in a CAM program is one string.)
        name = sys.intern(head.group(1))
        pos = head.end()
        if tok.type == "FAST_CIRC":
            # An aggregate or a name (a declared circle point), then an
            # aggregate, a comma between (blanks around it); the second ends
            # at the statement's last ']'. Their Args made now, with the
            # nodes of the arguments after them (as _fast_func's).
            if text[pos] == "[":
                mid = _AGG.match(text, pos).end()
                span = _span((base + pos, base + mid))
                first = _numagg(text[pos:mid], span)
            else:
                mid = _FAST_ITEM.match(text, pos).end()
                span = _span((base + pos, base + mid))
                first = _ref(text[pos:mid], (), span)
            at = text.index("[", mid)
            end = text.rindex("]") + 1
            second = _numagg(text[at:end], _span((base + at, base + end)))
            every = (_arg("pos", None, first, span), _arg("pos", None, second, second.span),
                     *_fast_tail(text[end:]).nodes(base + end))
            return _call(name, every, _span((base, base + len(text))), plain_args(every))
        if text[pos] == "[":
            # The aggregate ends at the statement's last ']' (nothing after
            # it has brackets).
            end = text.rindex("]") + 1
            first = _numagg(text[pos:end], _span((base + pos, base + end)))
            pos = end
        elif text[pos] in _NUMBER_START:
            # A number (WaitTime 0.2;).
            first, pos = _fast_number(text, base, pos)
        else:
            word = _FAST_ITEM.match(text, pos)      # a name
            end = word.end()
            if text[end] == "(":
                # A function of names and numeric aggregates (rcTcR(p, p_dq),
                # Offs(p, 0, 0, 10)): the first argument's value node, the
                # arguments after it made when read (A.TailArgs) as a plain
                # move's (an Offs-relative program's 1e5 moves: ~1 KB each
                # kept otherwise); a call, so not plain.
                func, pos = _fast_func(text, base, pos, end)
                return _call(name, _tail_args(func, _fast_tail(text[pos:]), base + pos),
                             _span((base, base + len(text))), False)
            first = _ref(word.group(3), (), _span((base + pos, base + end)))
            pos = end
        # (Plain by construction: names, a numeric aggregate, numbers, \Opt,
        # \Opt:=name or number. The first argument's value node kept, the
        # arguments after it made when read: A.TailArgs.)
        return _call(name, _tail_args(first, _fast_tail(text[pos:]), base + pos),
                     _span((base, base + len(text))), True)

    def fast_decl(self, c):
        """A FAST_DECL token: one-line declaration with a numeric aggregate."""
        tok = c[0]
        text = tok.value
        base = tok.start_pos
        m = DECL_HEAD.match(text)
        scope = m.group(1).upper() if m.group(1) else None
        agg_end = text.rindex("]") + 1
        start = m.end()
        init = _numagg(text[start:agg_end], _span((base + start, base + agg_end)))
        # (Storage and type interned: "CONST" and "robtarget" 5e4 times.)
        storage, type_name = sys.intern(m.group(2).upper()), sys.intern(m.group(3))
        return _decl(scope, storage, type_name, m.group(4),
                     _span((base + m.start(4), base + m.end(4))), (), init,
                     _span((base, base + len(text))))

    def late_call(self, c):
        args = c[3] if len(c) == 5 else ()
        return A.LateCall(c[1], args, Span(c[0].start_pos, c[-1].end_pos))

    def _simple(self, kind, c, name=None, expr=None):
        return A.Simple(kind, name, expr, Span(_start(c[0]), _end(c[-1])))

    def goto_stmt(self, c):
        return self._simple("GOTO", c, name=c[1].value)

    def label(self, c):
        return self._simple("LABEL", c, name=c[0].value)

    def return_stmt(self, c):
        return self._simple("RETURN", c, expr=c[1] if len(c) == 3 else None)

    def raise_stmt(self, c):
        return self._simple("RAISE", c, expr=c[1] if len(c) == 3 else None)

    def retry_stmt(self, c):
        return self._simple("RETRY", c)

    def trynext_stmt(self, c):
        return self._simple("TRYNEXT", c)

    def exit_stmt(self, c):
        return self._simple("EXIT", c)

    def connect_stmt(self, c):
        return self._simple("CONNECT", c, name=c[3].value, expr=c[1])

    def placeholder_stmt(self, c):
        return self._simple("PLACEHOLDER", c, name=c[0].value)

    def elseif(self, c):
        return _tag("elseif", c[1], c[3][1])

    def else_part(self, c):
        return _tag("else", c[1][1])

    def if_stmt(self, c):
        branches = [(c[1], c[3][1])]
        orelse: tuple = ()
        for x in c[4:-1]:
            if x[0] == "elseif":
                branches.append((x[1], x[2]))
            else:
                orelse = x[1]
        return A.If(tuple(branches), orelse, Span(c[0].start_pos, c[-1].end_pos))

    def compact_if(self, c):
        return A.CompactIf(c[1], c[2], Span(c[0].start_pos, c[2].span.end))

    def step(self, c):
        return _tag("step", c[1])

    def for_stmt(self, c):
        step = c[6][1] if isinstance(c[6], _Tag) and c[6][0] == "step" else None
        body = c[-2][1]
        return A.For(c[1].value, c[3], c[5], step, body, Span(c[0].start_pos, c[-1].end_pos))

    def while_stmt(self, c):
        return A.While(c[1], c[3][1], Span(c[0].start_pos, c[-1].end_pos))

    def case(self, c):
        return _tag("case", tuple(c[1:-1]), c[-1][1])

    def default(self, c):
        return _tag("default", c[1][1])

    def test_stmt(self, c):
        cases = []
        default = None
        for x in c[2:-1]:
            if x[0] == "case":
                cases.append((x[1], x[2]))
            else:
                default = x[1]
        return A.Test(c[1], tuple(cases), default, Span(c[0].start_pos, c[-1].end_pos))

    # ------------------------------------------------------------ arguments
    def args(self, c):
        Arg = A.Arg
        return tuple(x if type(x) is Arg else Arg("pos", None, x, x.span) for x in c)

    def named_arg(self, c):
        return A.Arg("named", c[0].value, c[1], Span(c[0].start_pos, c[1].span.end))

    def opt_arg(self, c):
        return A.Arg("opt", c[1].value, None, Span(c[0].start_pos, c[1].end_pos))

    def opt_arg_value(self, c):
        return A.Arg("optval", c[1].value, c[2], Span(c[0].start_pos, c[2].span.end))

    def opt_arg_cond(self, c):
        return A.Arg("cond", c[1].value, c[2], Span(c[0].start_pos, c[2].span.end))

    # ------------------------------------------------------------ expressions
    def binop(self, c):
        left, op, right = c
        return A.Binary(op.value.upper(), left, right, Span(left.span.start, right.span.end))

    def unop(self, c):
        op, operand = c
        sign = op.value.upper()
        # "-5" is one number to a user: fold it so its span covers the sign.
        if sign in "+-" and isinstance(operand, A.Num) and op.end_pos == operand.span.start:
            value = -operand.value if sign == "-" else operand.value
            return A.Num(value, sign + operand.text, Span(op.start_pos, operand.span.end))
        return A.Unary(sign, operand, Span(op.start_pos, operand.span.end))

    def num(self, c):
        t = c[0]
        value = number_value(t.value)
        if value in (_INF, -_INF):
            raise NumberOutOfRange(t.start_pos, t.value)
        return A.Num(value, t.value, Span(t.start_pos, t.end_pos))

    def string(self, c):
        t = c[0]
        return A.Str(t.value[1:-1].replace('""', '"'), Span(t.start_pos, t.end_pos))

    def true(self, c):
        t = c[0]
        return A.Bool(True, Span(t.start_pos, t.end_pos))

    def false(self, c):
        t = c[0]
        return A.Bool(False, Span(t.start_pos, t.end_pos))

    def numagg(self, c):
        t = c[0]
        return A.NumAgg(t.value, Span(t.start_pos, t.end_pos))

    def aggregate(self, c):
        return A.Agg(tuple(c[1:-1]), Span(c[0].start_pos, c[-1].end_pos))

    def func_call(self, c):
        name = c[0]
        args = c[2] if len(c) == 4 else ()
        return A.Call(name.value, args, Span(name.start_pos, c[-1].end_pos))

    def paren(self, c):
        return A.Paren(c[1], Span(c[0].start_pos, c[2].end_pos))

    def placeholder(self, c):
        t = c[0]
        return A.Placeholder(t.value, Span(t.start_pos, t.end_pos))

    def ref(self, c):
        name = c[0]
        return A.Ref(name.value, tuple(c[1:]), Span(name.start_pos, _end(c[-1])))

    def component(self, c):
        t = c[0]
        return A.Component(t.value, Span(t.start_pos, t.end_pos))

    def index(self, c):
        return A.Index(tuple(c[:-1]), Span(c[0].span.start, c[-1].end_pos))
