"""Parse RAPID source into the frozen model; translate failures to messages."""

from __future__ import annotations

import re
import time

from dataclasses import replace
from pathlib import Path

from ..collector import paused
from ..construct import maker
from ..errors import InputError
from ..source import SourceText, read_source
from . import ast as A
from . import predecode
from .build import NumberOutOfRange
from .grammar import compiled, engine
from .lalr import LexFailure, ParseFailure
from .model import Declaration, Loop, Module, Motion, ParsedFile, Roles, RoutineInfo, TargetArg
from .motions import motion_spec
from .values import DECODED_TYPES, DecodeIssue, decode, decode_array


def parse_file(path: str | Path, display_path: str | None = None) -> ParsedFile:
    return parse_source(read_source(path, display_path))


def parse_text(text: str, display_path: str = "<text>") -> ParsedFile:
    return parse_source(SourceText.from_text(text, display_path))


def parse_source(source: SourceText) -> ParsedFile:
    if len(source.text) >= A.SPAN_LIMIT:
        # (A node's span holds offsets below it: ast.Span.)
        raise source.error(0, f"{len(source.text)} characters: more than the "
                           f"{A.SPAN_LIMIT - 1} of the largest module rapidcomp reads")
    # Parsing allocates millions of small acyclic objects (~30% of the time
    # otherwise goes to the cyclic collector).
    with paused():
        # A large text's literals are decoded by a second process meanwhile
        # (predecode.py; a small one's here, in _build_module).
        children: list = []
        began = time.monotonic()
        try:
            predecode.start(source.text, children)
            try:
                header, nodes = engine().parse(source.text)
            except LexFailure as exc:
                ch = source.text[exc.pos]
                if ch == '"':
                    # (A string's closing quote is on its own line: RAPID's
                    # strings do not go on past it.)
                    raise source.error(exc.pos, "a string not closed on its line: expected a "
                                       "closing '\"' before the end of the line") from None
                raise source.error(exc.pos,
                                   f"unexpected character {_shown_char(ch)}: not part of "
                                   "RAPID") from None
            except ParseFailure as exc:
                raise _syntax_error(source, exc) from None
            except NumberOutOfRange as exc:
                shown = (exc.text if len(exc.text) <= 40 else
                         f"{exc.text[:20]}... ({len(exc.text)} characters)")
                raise source.error(exc.pos, f"number {shown} is out of range (a num holds "
                                   "+-3.4E38, a dnum +-1.8E308)") from None
            # (The child's work is a fraction of the parse's: it is waited
            # for as long as the parse took, and a second more, at most.)
            known = (children[0].result(time.monotonic() - began + 1.0) if children
                     else None)
        finally:
            for child in children:
                child.close()
        try:
            modules = tuple(_build_module(source, node, known) for node in nodes)
        except RecursionError:
            # (Blocks nested deeper than Python's frames go: generated code
            # no controller runs either; said where, not only that.)
            depth, at = _deepest(nodes)
            raise source.error(at, f"blocks nest {depth} levels deep here (IF, FOR, WHILE, "
                               "TEST): more than rapidcomp follows") from None
    return ParsedFile(source, header.value if header else None, modules,
                      known.words if known is not None else None)


def _shown_char(ch: str) -> str:
    """A character as a message shows it: beyond ASCII with its code point
    too (the Kelvin sign looks like a K, a no-break space like a blank)."""
    return repr(ch) if ch.isascii() else f"{ch!r} (U+{ord(ch):04X})"


# ---------------------------------------------------------------- model building

def _const_ints(node: A.ModuleNode) -> dict[str, int]:
    """Module-level CONST num with literal integer values (array sizes)."""
    out = {}
    for item in node.items:
        if (isinstance(item, A.DataDecl) and item.storage == "CONST"
                and item.type_name.lower() == "num" and isinstance(item.init, A.Num)
                and float(item.init.value).is_integer()):
            out[item.name.lower()] = int(item.init.value)
    return out


def _dims(dims, consts) -> tuple[int | None, ...]:
    out = []
    for d in dims:
        if isinstance(d, A.Num) and float(d.value).is_integer():
            out.append(int(d.value))
        elif isinstance(d, A.Ref) and not d.selectors and d.name.lower() in consts:
            out.append(consts[d.name.lower()])
        else:
            out.append(None)
    return tuple(out)


def _declaration(source: SourceText, decl: A.DataDecl, routine: str | None,
                 consts, known=None, aliases=None) -> Declaration:
    type_ = decl.type_name.lower()
    if aliases:
        type_ = aliases.get(type_, type_)
    dims = _dims(decl.dims, consts)
    value = None
    issue = None
    if type_ in DECODED_TYPES:
        if decl.init is None:
            issue = "declared without a value"
        elif None in dims:
            issue = "array size is not a literal or a CONST num of this module"
        else:
            try:
                if dims:
                    value = decode_array(type_, decl.init, dims, decl.name, known)
                else:
                    value = decode(type_, decl.init, decl.name, known)
            except DecodeIssue as exc:
                if exc.illegal:
                    raise source.error(exc.span.start, f"{exc.reason} (a {type_} value)") \
                        from None
                issue = exc.reason
    return _new_decl(decl, routine, type_, dims, value, issue, decl.name)


# (A CAM program's 1e5 moves and 5e4 declarations: made as their classes
# make them, construct.py.)
_new_motion, _new_target, _new_decl = maker(Motion), maker(TargetArg), maker(Declaration)
_TARGET_ROLES = frozenset(("to", "cir", "search"))


def _motion(source: SourceText, call: A.ProcCall, spec, routine: str, loops,
            known=None) -> Motion:
    args = call.args
    if type(args) is tuple:
        shape = tuple((a.kind, a.name.lower() if a.name else None) for a in args)
    else:
        # (A move lexed as one token: its shape is its shared tail's, its
        # nodes not made.)
        shape = args.tail
    roles = _ROLES.get((spec, shape))
    if roles is None:
        kinds = shape if type(args) is tuple else tuple(
            (a.kind, a.name.lower() if a.name else None) for a in args)
        roles = _roles_of(spec, kinds)
        if len(_ROLES) >= 4096:        # bounded: many programs in one process
            _ROLES.clear()
        _ROLES[(spec, shape)] = roles
    targets = []
    for role, j in roles.targets:
        value = A.arg_value(args, j)
        decoded = issue = None
        if role != "search" and isinstance(value, (A.Agg, A.NumAgg)):
            t = "jointtarget" if spec.joint_space else "robtarget"
            try:
                decoded = decode(t, value, f"inline {t}", known)
            except DecodeIssue as exc:
                if exc.illegal:
                    raise source.error(exc.span.start, f"{exc.reason} (the {t} of "
                                       f"{call.name})") from None
                issue = exc.reason
        targets.append(_new_target(role, value, decoded, issue))
    return _new_motion(call.name, spec, call.span, routine, tuple(loops), args,
                       tuple(targets), roles)


# Roles of the arguments of the moves parsed: (spec, shape) -> Roles. The
# shape of a move lexed as one token is its shared tail (build._Tail: its
# first argument is positional); of any other, every argument's kind and
# lower-case name.
_ROLES: dict = {}


def _roles_of(spec, kinds: tuple) -> Roles:
    """Which argument is which, from each argument's (kind, lower-case
    name): positional (or named) ones take the spec's roles in order (a
    role given twice: the last), \\WObj the work object, other optional
    ones are optional."""
    roles = spec.roles
    slots = {}
    targets = []
    wobj = -1
    optional = []
    to_point = False
    k = 0
    for j, (kind, name) in enumerate(kinds):
        if kind == "pos" or kind == "named":
            if kind == "named" and name == "topoint":
                to_point = True
            if k < len(roles):
                role = roles[k]
                slots[role] = j
                if role in _TARGET_ROLES:
                    targets.append((role, j))
            k += 1
        elif (kind == "optval" or kind == "cond") and name == "wobj":
            wobj = j
        else:
            optional.append(j)
    get = slots.get
    return Roles(tuple(targets), get("speed", -1), get("zone", -1), get("tool", -1), wobj,
                 tuple(optional), to_point)


def _walk(source, stmts, routine: str, loops: list, out: list, cond: int = 0,
          known=None) -> None:
    """Motions in statement order. cond: how many of the enclosing loops
    hold a condition (IF, TEST, WHILE) around the statements: a move
    behind one may not run for every value of their variables. known:
    values decoded ahead (predecode.py)."""
    for s in stmts:
        t = type(s)
        if t is A.ProcCall:
            spec = motion_spec(s.name)
            if spec is not None:
                # (Outside any loop, as a CAM program's 1e5 moves are: no
                # list made per move.)
                guarded = ([replace(lp, guarded=k < cond) for k, lp in enumerate(loops)]
                           if loops else ())
                out.append(_motion(source, s, spec, routine, guarded, known))
        elif t is A.For:
            loops.append(Loop(s.var, s.start, s.stop, s.step, s.span))
            _walk(source, s.body, routine, loops, out, cond, known)
            loops.pop()
        elif t is A.While:
            loops.append(Loop(None, None, None, None, s.span))
            _walk(source, s.body, routine, loops, out, len(loops), known)
            loops.pop()
        elif t is A.If:
            for _, body in s.branches:
                _walk(source, body, routine, loops, out, len(loops), known)
            _walk(source, s.orelse, routine, loops, out, len(loops), known)
        elif t is A.CompactIf:
            _walk(source, (s.stmt,), routine, loops, out, len(loops), known)
        elif t is A.Test:
            for _, body in s.cases:
                _walk(source, body, routine, loops, out, len(loops), known)
            if s.default:
                _walk(source, s.default, routine, loops, out, len(loops), known)


def _own_aliases(node: A.ModuleNode) -> dict[str, str]:
    """The module's ALIAS types (lower case) -> the type each names."""
    return {a.name.lower(): a.type_name.lower() for a in node.items
            if isinstance(a, A.AliasDecl)}


def _followed(alias_of: dict[str, str]) -> dict[str, str]:
    """Each alias -> the type it comes to: data of an alias of robtarget is
    robtarget data (an alias of an alias, which RAPID does not allow, is
    followed as far as it goes)."""
    out = dict(alias_of)
    for name in out:
        seen = {name}
        while out[name] in out and out[name] not in seen:
            seen.add(out[name])
            out[name] = out[out[name]]
    return out


def with_task_aliases(files: list[ParsedFile]) -> list[ParsedFile]:
    """The files of one task with the data of a global ALIAS type another
    module declares as data of the type it names (a task is one namespace:
    _build_module resolved each module's own aliases only). The files
    themselves where no module declares a global alias."""
    aliases = {a.name.lower(): a.type_name.lower() for pf in files for m in pf.modules
               for a in m.aliases if (a.scope or "").upper() != "LOCAL"}
    if not aliases:
        return files
    out = []
    for pf in files:
        modules = []
        for m in pf.modules:
            alias_of = _followed({**aliases, **_own_aliases(m.node)})
            if not any(d.type in alias_of for d in m.declarations):
                modules.append(m)
                continue
            consts = _const_ints(m.node)
            modules.append(replace(m, declarations=tuple(
                _declaration(pf.source, d.node, d.routine, consts, None, alias_of)
                if d.type in alias_of else d for d in m.declarations)))
        out.append(replace(pf, modules=tuple(modules)))
    return out


# The longest name the controller loads (RAPID identifiers: 32 characters).
MAX_NAME = 32


def _check_names(source: SourceText, node: A.ModuleNode) -> None:
    """What the controller refuses to load in a module's names: one longer
    than MAX_NAME characters; two module-level declarations (data or
    routines) of one name, or two of one routine's data."""
    def at(name: str, span) -> int:
        # (The name after its keyword, or its FUNC's type, or ALIAS's type:
        # not the same letters inside PROC.)
        m = re.compile(rf"(?:PROC|TRAP|RECORD|FUNC\s+\w+|ALIAS\s+\w+)\s+({re.escape(name)})\b",
                       re.IGNORECASE).search(source.text, span.start, span.end)
        return m.start(1) if m else span.start

    def check(name: str, start: int, seen: dict, where: str) -> None:
        if len(name) > MAX_NAME:
            raise source.error(start, f"the name {name[:40]}{'...' if len(name) > 40 else ''} "
                               f"has {len(name)} characters: the controller loads names of "
                               f"at most {MAX_NAME}")
        first = seen.setdefault(name.lower(), start)
        if first != start:
            raise source.error(start, f"{name} is declared twice {where} (first at line "
                               f"{source.position(first)[0]}): the controller does not load it")

    check(node.name, node.name_span.start, {}, "")
    names: dict = {}
    for item in node.items:
        if isinstance(item, A.DataDecl):
            check(item.name, item.name_span.start, names, f"in module {node.name}")
        elif isinstance(item, A.Routine):
            check(item.name, at(item.name, item.span), names, f"in module {node.name}")
            own: dict = {}
            for d in item.decls:
                check(d.name, d.name_span.start, own, f"in routine {item.name}")
        elif isinstance(item, (A.RecordDecl, A.AliasDecl)):
            check(item.name, at(item.name, item.span), {}, "")


def _build_module(source: SourceText, node: A.ModuleNode, known=None) -> Module:
    _check_names(source, node)
    consts = _const_ints(node)
    alias_of = _followed(_own_aliases(node))
    decls = []
    routines = []
    motions: list[Motion] = []
    records = []
    aliases = []
    for item in node.items:
        if isinstance(item, A.DataDecl):
            decls.append(_declaration(source, item, None, consts, known, alias_of))
        elif isinstance(item, A.Routine):
            routines.append(RoutineInfo(item))
            for d in item.decls:
                decls.append(_declaration(source, d, item.name, consts, known, alias_of))
            _walk(source, item.body, item.name, [], motions, known=known)
            for h in item.handlers:
                _walk(source, h.body, item.name, [], motions, known=known)
        elif isinstance(item, A.RecordDecl):
            records.append(item)
        elif isinstance(item, A.AliasDecl):
            aliases.append(item)
    return Module(node, tuple(decls), tuple(routines), tuple(motions), tuple(records),
                  tuple(aliases))


# ---------------------------------------------------------------- error messages

def _bodies(s) -> tuple:
    """The statement lists a statement holds."""
    t = type(s)
    if t is A.If:
        return tuple(b for _, b in s.branches) + (s.orelse,)
    if t is A.For or t is A.While:
        return (s.body,)
    if t is A.CompactIf:
        return ((s.stmt,),)
    if t is A.Test:
        return tuple(b for _, b in s.cases) + ((s.default,) if s.default else ())
    return ()


def _deepest(nodes) -> tuple[int, int]:
    """(how many blocks deep, where it begins) the most deeply nested
    statement is (found without recursion)."""
    best = (0, nodes[0].span.start if nodes else 0)
    for node in nodes:
        for item in node.items:
            if not isinstance(item, A.Routine):
                continue
            stack = [(s, 0) for body in (item.body, *(h.body for h in item.handlers))
                     for s in body]
            while stack:
                s, depth = stack.pop()
                if depth > best[0]:
                    best = (depth, s.span.start)
                for body in _bodies(s):
                    stack.extend((x, depth + 1) for x in body)
    return best


_STATEMENT_STARTS = {"NAME", "FAST_CALL", "FAST_CIRC", "IF", "FOR", "WHILE", "TEST", "GOTO",
                     "RETURN", "RAISE", "RETRY", "TRYNEXT", "EXIT", "CONNECT", "LATE",
                     "PLACEHOLDER"}
_EXPR_STARTS = {"NAME", "NUMBER", "STRING", "NUMAGG", "LBRACK", "LPAR", "TRUE", "FALSE",
                "NOT", "ADDOP", "PLACEHOLDER"}
_OPERATORS = {"ADDOP", "STAR", "SLASH", "DIV", "MOD", "RELOP", "EQ", "AND", "OR", "XOR"}
_NAMES = {
    "NAME": "an identifier", "NUMBER": "a number", "STRING": "a string",
    "NUMAGG": "'['", "FAST_CALL": "a statement", "FAST_CIRC": "a statement",
    "FAST_DECL": "a declaration",
    "$END": "end of file",
    "HEADER": "a %%% header", "PLACEHOLDER": "a placeholder such as <SMT>",
    "RELOP": "a comparison", "ADDOP": "'+' or '-'", "BACKSLASH": "an optional argument '\\'",
}


def _describe_terminal(name: str) -> str:
    if name in _NAMES:
        return _NAMES[name]
    term = _terminals().get(name)
    if term is not None and term.pattern.type == "str":
        value = term.pattern.value
        return value.upper() if value.isalpha() else f"'{value}'"
    return name


_TERMS = None


def _terminals():
    global _TERMS
    if _TERMS is None:
        _TERMS = {t.name: t for t in compiled().lexer_conf.terminals}
    return _TERMS


def describe_expected(expected: frozenset[str]) -> str:
    rest = set(expected)
    parts = []
    if {"IF", "FOR", "WHILE"} <= rest:
        parts.append("a statement")
        rest -= _STATEMENT_STARTS
    if {"NUMBER", "STRING", "NAME"} <= rest:
        parts.append("an expression")
        rest -= _EXPR_STARTS
    if len(rest & _OPERATORS) >= 4:
        parts.append("an operator")
        rest -= _OPERATORS
    if {"VAR", "PERS", "CONST"} <= rest:
        parts.insert(0, "a declaration")
        rest -= {"VAR", "PERS", "CONST", "LOCAL", "TASK", "FAST_DECL"}
    # (Each once: two one-token forms are "a statement" each.)
    parts.extend(d for d in sorted({_describe_terminal(t) for t in rest}) if d not in parts)
    if len(parts) > 8:
        parts = parts[:8] + ["..."]
    if len(parts) == 1:
        return parts[0]
    return ", ".join(parts[:-1]) + " or " + parts[-1]


def _describe_token(tok) -> str:
    if tok.type == "$END":
        return "end of file"
    if tok.type == "NAME":
        return f"identifier '{tok.value}'"
    if tok.type in ("FAST_CALL", "FAST_CIRC"):
        return f"'{tok.value.split()[0]}'"
    if tok.type == "NUMBER":
        return f"number {tok.value}"
    # (A token of several lines, an aggregate, on one.)
    value = _LINE_BREAKS.sub(" ", tok.value)
    shown = value if len(value) <= 20 else value[:17] + "..."
    return f"'{shown}'"


_LINE_BREAK = re.compile(r"[\r\n]")
_LINE_BREAKS = re.compile(r"[ \t]*(?:\r\n|\r|\n)[ \t]*")


def _syntax_error(source: SourceText, exc: ParseFailure) -> InputError:
    tok, expected, prev = exc.token, exc.expected, exc.previous
    if prev is not None and prev.type == "ENDMODULE" and tok.type != "MODULE":
        msg = f"text after ENDMODULE: {_describe_token(tok)}; expected end of file"
    elif prev is not None and prev.type == "MODULE" and tok.type == "NUMBER":
        msg = (f"module name must start with a letter, found {_describe_token(tok)}; "
               "expected an identifier")
    elif tok.type == "$END":
        msg = f"unexpected end of file; expected {describe_expected(expected)}"
        if "ENDMODULE" in expected:
            msg += " (is ENDMODULE missing?)"
    elif ("SEMI" in expected and prev is not None
          and _LINE_BREAK.search(source.text, prev.end_pos, tok.start_pos)):
        # (A statement that could end on its line but runs on into the next:
        # the ';' is missing where the line ends, not where the next starts.)
        rest = expected - {"SEMI"}
        # (Where a ',' may follow too, the line may just as well lack one.)
        missing = "';' or ','" if "COMMA" in expected else "';'"
        return source.error(prev.end_pos, (
            f"{missing} missing after {_describe_token(prev)}: the next line goes on with "
            f"{_describe_token(tok)}; expected ';'"
            + (f" or {describe_expected(rest)}" if rest else "") + " here"))
    else:
        msg = f"unexpected {_describe_token(tok)}; expected {describe_expected(expected)}"
        if "RBRACK" in expected:
            msg += " (an aggregate '[' is not closed)"
        elif tok.type == "LPAR" and prev is not None and prev.type == "NAME":
            msg += f" ('{prev.value}' cannot be followed by parentheses here)"
    return source.error(tok.start_pos, msg)
