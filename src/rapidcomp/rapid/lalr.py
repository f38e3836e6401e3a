"""Table-driven LALR(1) parsing of RAPID with Lark's compiled grammar.

Lark compiles grammars/rapid.lark into terminals, rules and an LALR parse
table. This module drives that table with a tight loop of its own, because
Lark's generic driver (Token objects, per-token asserts, wrapper chains per
reduction) spends ~14 us per token, and CAM programs have hundreds of
thousands of tokens. The semantics are Lark's: anonymous punctuation is
dropped, `_rule`/EBNF helper rules are spliced into their parent, `?rule`
with one child is replaced by that child, `-> alias` names the callback.

The lexer is one regex alternation built from the grammar's own terminals
(ordered as Lark orders them: priority, then longest pattern); keywords are
recognised by a dict lookup on the upper-cased identifier, which is also what
makes them case-insensitive.
"""

from __future__ import annotations

import re

from lark.lexer import PatternStr

_IDENT = re.compile(r"[A-Za-z][A-Za-z0-9_]*")
# A FAST_CALL's instruction name and the blanks after it (the builder
# splits the statement there too).
FAST_NAME = re.compile(r"([A-Za-z][A-Za-z0-9_]*)[ \t]+")
# Identifiers not inside a number (the E of 9E+09 is no word).
_WORD = re.compile(r"(?<![\w.])[A-Za-z][A-Za-z0-9_]*")


_BLANKS = re.compile(r"\s*")


class Tok:
    """A token: terminal name, text and half-open character span."""

    __slots__ = ("type", "value", "start_pos", "end_pos")

    def __init__(self, type_: str, value: str, start: int, end: int):
        self.type = type_
        self.value = value
        self.start_pos = start
        self.end_pos = end

    def __repr__(self) -> str:
        return f"Tok({self.type}, {self.value!r}, {self.start_pos})"


class LexFailure(Exception):
    def __init__(self, pos: int):
        super().__init__(pos)
        self.pos = pos


class ParseFailure(Exception):
    def __init__(self, token: Tok, expected: frozenset[str], previous: Tok | None):
        super().__init__(token)
        self.token = token
        self.expected = expected
        self.previous = previous


class _Splice(list):
    """Children of an EBNF helper rule, to be spliced into the parent."""


# The one-token statement and declaration, and what each becomes (the
# builder's callback; parse's shortcut makes it so).
_LISTED = {"FAST_CALL": lambda engine, tok: engine._build.fast_call([tok]),
           "FAST_CIRC": lambda engine, tok: engine._build.fast_call([tok]),
           "FAST_DECL": lambda engine, tok: engine._build.fast_decl([tok])}
# The one-token forms, which the plain lexer (_master_plain) leaves out.
_ONE_TOKEN = ("FAST_CALL", "FAST_CIRC", "FAST_DECL")


def _spans(node, tok) -> bool:
    """A node built of the token alone."""
    span = getattr(node, "span", None)
    return span is not None and span.start == tok.start_pos and span.end == tok.end_pos


def _as_splice(children):
    # The list grown in place by left recursion is returned as is (no copy).
    return children if type(children) is _Splice else _Splice(children)


def _single_child_only(name):
    def fail(children):
        raise TypeError(f"?{name} reduced with {len(children)} children and no callback")
    return fail


class Engine:
    def __init__(self, lark, builder):
        self._build = builder
        terms = lark.lexer_conf.terminals
        ignore = set(lark.lexer_conf.ignore)
        keywords: dict[str, str] = {}
        regular = []
        for term in terms:
            pattern = term.pattern
            if isinstance(pattern, PatternStr) and _IDENT.fullmatch(pattern.value):
                keywords[pattern.value.upper()] = term.name
            else:
                regular.append(term)
        regular.sort(key=lambda t: (-t.priority, -t.pattern.max_width,
                                    -len(t.pattern.value), t.name))
        ws = next(t.pattern.to_regexp() for t in terms if t.name == "WS")
        # The blanks before a token are matched with it (a hand-written
        # program's indentation and line breaks: ~40 % of its matches
        # otherwise). Where no token follows them (the text's end, a
        # character no terminal takes), the pattern gives them back and
        # they match as WS alone: the next match fails where the other
        # does.
        self._master = re.compile(f"(?:{ws})?(?:" + "|".join(
            f"(?P<{t.name}>{t.pattern.to_regexp()})" for t in regular) + ")")
        # Same alternation without the one-token statements, for when a
        # FAST_CALL/FAST_DECL match has a reserved word where an identifier
        # must be, and must be lexed token by token.
        self._master_plain = re.compile("|".join(
            f"(?P<{t.name}>{t.pattern.to_regexp()})" for t in regular
            if t.name not in _ONE_TOKEN))
        self._keywords = keywords
        # Reserved words, upper case (a name that is one is no identifier).
        self.reserved = frozenset(keywords)
        self._tails: dict[str, bool] = {}      # _keyword_in's verdicts on argument lists
        # A run of FAST_CALL statements of one instruction and one argument
        # list after the target (`MoveL <target>,v100,z1,tool1\\WObj:=wobj1;`
        # on 1e5 lines of a CAM program), or of FAST_DECL declarations with
        # the same text before the name: (kind, that part) -> the pattern
        # of the next one (_run).
        self._runs: dict[tuple, re.Pattern] = {}
        # How often each such (kind, part) began a statement before it has
        # a pattern: one is compiled (~1 ms: NUMAGG is long) only for a part
        # met again, not for each line of a program whose every line has
        # arguments of its own (\ID:=n of a MultiMove program: 2e4 lines
        # took 23 s), and only where the next statement may continue the
        # run (_may_follow).
        self._met: dict[tuple, int] = {}
        self._ws = ws
        numagg = next(t.pattern.to_regexp() for t in terms if t.name == "NUMAGG")
        # The runs' NUMAGG: first tried without its optional whitespace
        # (each \s* deleted: a part of NUMAGG's language, the aggregates a
        # CAM program writes, matched ~20 % faster), then as it is: the
        # same language, and a match ends where NUMAGG's would (at the
        # statement's ';').
        plain = numagg.replace(r"\s*", "")
        self._numagg = f"(?:{plain}|{numagg})"
        # The parser's shortcut for a statement (or declaration) that
        # follows one of its kind in a list (parse): the top three states ->
        # whether the table's actions there append the one before to the
        # list below it and come back to the same states.
        self._appends: dict[tuple, bool] = {}
        self._ignore = frozenset(ignore)
        self.terminal_names = frozenset(t.name for t in terms)

        table = lark.parser.parser.parser.parse_table
        self._start = table.start_states["start"]
        self._end = table.end_states["start"]
        reduce_info = {}
        for rule in lark.rules:
            reduce_info[rule] = self._compile_rule(rule, builder)
        states = {}
        for state, actions in table.states.items():
            row = {}
            for symbol, (action, arg) in actions.items():
                if action.name == "Shift":
                    row[symbol] = (True, arg)
                else:
                    row[symbol] = (False, reduce_info[arg])
            states[state] = row
        self._states = states

    @staticmethod
    def _compile_rule(rule, builder):
        plan = []
        for sym in rule.expansion:
            if sym.is_term:
                plan.append("drop" if sym.filter_out else "keep")
            elif sym.name.startswith("_"):
                plan.append("splice")
            else:
                plan.append("keep")
        simple = all(p == "keep" for p in plan)
        origin = rule.origin.name
        if origin.startswith("_"):
            fn = _as_splice
            expand1 = False
        else:
            name = rule.alias or origin
            expand1 = bool(rule.options.expand1 and not rule.alias)
            fn = getattr(builder, name, None)
            if fn is None:
                if not expand1:
                    raise TypeError(f"node builder has no callback for grammar rule {name!r}")
                fn = _single_child_only(name)
        return (len(plan), origin, None if simple else tuple(plan), fn, expand1)

    # ------------------------------------------------------------------ lexer
    def tokens(self, text: str, runs: bool = False):
        """The tokens of text. runs: a FAST_CALL statement followed by more
        of the same instruction and argument list after the target (a CAM
        program's 1e5 moves) is lexed with a pattern of that statement
        (_call_run), a FAST_DECL declaration followed by more of the same
        storage and type likewise (_decl_run): the same tokens as one by
        one."""
        match = self._master.match
        keywords = self._keywords
        ignore = self._ignore
        pos = 0
        end = len(text)
        tried: dict = {}              # (_run's counts in this text)
        while pos < end:
            m = match(text, pos)
            if m is None:
                raise LexFailure(pos)
            kind = m.lastgroup
            stop = m.end()
            if kind in ignore:
                pos = stop
                continue
            # (Where the token begins: past the blanks matched with it.)
            pos = m.start(kind)
            run = None
            if kind == "FAST_CALL" or kind == "FAST_CIRC":
                if self._keyword_in(m.group(kind)):
                    m = self._master_plain.match(text, pos)
                    kind, stop = m.lastgroup, m.end()
                elif kind == "FAST_CALL":
                    run = self._call_run
            elif kind == "FAST_DECL":
                # Only type and name must be identifiers: the last two words
                # before := (the aggregate after it has no word; the E of
                # 9E+09 follows a digit).
                decl = m.group(kind)
                if any(w.upper() in keywords
                       for w in _WORD.findall(decl, 0, decl.index(":="))[-2:]):
                    m = self._master_plain.match(text, pos)
                    kind, stop = m.lastgroup, m.end()
                else:
                    run = self._decl_run
            if run is not None and runs:
                first = m.group(kind)
                yield Tok(kind, first, pos, stop)
                pos = stop
                for tok in run(text, first, pos, tried):
                    yield tok
                    pos = tok.end_pos
                continue
            value = m.group(kind)
            if kind == "NAME":
                kind = keywords.get(value.upper(), "NAME")
            yield Tok(kind, value, pos, stop)
            pos = stop
        yield Tok("$END", "", end, end)

    def _call_run(self, text: str, first: str, pos: int, tried: dict):
        """The FAST_CALL tokens that follow the statement `first` right
        after pos (only whitespace between), each the same instruction name
        and the same text after its target. The pattern is FAST_CALL's with
        those parts fixed (its target NUMAGG or a name, which must not be a
        reserved word), so it matches where FAST_CALL matches: the master
        pattern would find these very tokens (nothing before FAST_CALL in
        it matches a call; the name and the arguments' words are the
        first's, which _keyword_in accepted)."""
        head = FAST_NAME.match(first)
        at = head.end()
        if first[at] == "[":
            after = first.rindex("]") + 1
        elif not first[at].isalpha():
            # (A number (WaitTime 0.2;): no run's target; lexed one by one.)
            return iter(())
        else:
            after = _IDENT.match(first, at).end()
            if first[after] == "(":
                # A function (rcTcR(p10, p10_dq)): each statement's own
                # arguments; lexed one by one.
                return iter(())
        key = (head.group(1), first[after:])
        return self._run("FAST_CALL", key, lambda: (
            f"{re.escape(key[0])}[ \t]+(?:{self._numagg}|([A-Za-z][A-Za-z0-9_]*))"
            f"{re.escape(key[1])}"), text, pos, tried)

    def _decl_run(self, text: str, first: str, pos: int, tried: dict):
        """The FAST_DECL tokens that follow the declaration `first` right
        after pos (only whitespace between), each with the same text before
        its name (`CONST robtarget `, on 5e4 lines of a CAM program). The
        pattern is FAST_DECL's with that part fixed (its name must not be a
        reserved word; the type's was checked in `first`), so it matches
        where FAST_DECL matches: the master pattern would find these very
        tokens (of the patterns that could begin a declaration's text, only
        FAST_CALL is tried as early, and it needs a comma or backslash after
        its second word)."""
        name = list(_WORD.finditer(first, 0, first.index(":=")))[-1]
        key = first[:name.start()]
        return self._run("FAST_DECL", key, lambda: (
            f"{re.escape(key)}([A-Za-z][A-Za-z0-9_]*)[ \t]*:=[ \t]*{self._numagg}[ \t]*;"),
            text, pos, tried)

    def _run(self, kind: str, key, regex, text: str, pos: int, tried: dict):
        """Tokens of `kind` one after the other from pos (only whitespace
        between), each matched by the pattern regex() gives (its group 1
        the token, group 2 a name that must not be a reserved word, or
        None), compiled once per (kind, key) met a second time (the first
        time nothing is matched here: the next statement is lexed on its
        own). tried: per (kind, key) of this text, [times a pattern was
        tried, tokens it matched]; one tried 16 times or more that matched
        fewer tokens than a quarter of its tries is not tried again in this
        text (a hand-written program's: seldom two moves alike in a row,
        and each try costs a match). The tokens are the same either way."""
        pattern = self._runs.get((kind, key))
        if pattern is None:
            if len(self._met) >= 4096:       # bounded: many programs in one process
                self._met.clear()
            met = self._met[kind, key] = self._met.get((kind, key), 0) + 1
            if met < 2 or not self._may_follow(kind, key, text, pos):
                return                       # (the next statement is lexed on its own)
            if len(self._runs) >= 4096:
                self._runs.clear()
            pattern = self._runs[kind, key] = re.compile(f"(?:{self._ws})?({regex()})")
        counts = tried.get((kind, key))
        if counts is None:
            counts = tried[kind, key] = [0, 0]
        elif counts[0] >= 16 and counts[1] * 4 < counts[0]:
            return
        counts[0] += 1
        match = pattern.match
        keywords = self._keywords
        while True:
            m = match(text, pos)
            if m is None:
                return
            name = m.group(2)
            if name is not None and name.upper() in keywords:
                return
            counts[1] += 1
            yield Tok(kind, m.group(1), m.start(1), m.end())
            pos = m.end()

    def _may_follow(self, kind: str, key, text: str, pos: int) -> bool:
        """Whether the statement after pos may be one more of the run
        (kind, key): it begins with the instruction's name (the
        declaration's words) and, a call, its line holds the text after
        the target. A part met again elsewhere but never twice in a row (a
        hand-written program's speeds and tools change from move to move)
        gets no pattern: each costs ~2 ms to compile."""
        at = _BLANKS.match(text, pos).end()
        if kind == "FAST_DECL":
            return text.startswith(key, at)
        name, tail = key
        if not text.startswith(name, at):
            return False
        # (Within the next line only: a search to the text's end would make
        # the lexing of a long program quadratic.)
        nl = text.find("\n", at)
        return text.find(tail, at, nl if nl >= 0 else len(text)) >= 0

    def _keyword_in(self, call: str) -> bool:
        """A FAST_CALL holds a reserved word (as a whole identifier, in any
        letter case). Its numeric aggregate, if any, holds none (the E of
        9E+09 follows a digit): only the name before it and the arguments
        after it are looked at, upper-cased at once (the text is ASCII); a
        function's arguments (its first argument rcTcR(..)), all of it.
        The arguments after the first (`,v100,z1,tool1\\WObj:=wobj1;`, the
        same on 1e5 lines of a CAM program) are looked at once per text:
        they begin at a comma, where no word begins either way."""
        if "(" in call:
            # A function's arguments (rcTcR(p, p_dq), rcTcR([[...]], p_dq),
            # RelTool(p, 0, 0, -10 \Rz:=45)): words may lie between its
            # aggregates, and its text is each line's own: every word up to
            # its ')' is looked at (no word begins inside an aggregate: see
            # _WORD); the arguments after it are the cache's.
            cut = call.rfind(")") + 1
            head, tail = call[:cut], call[cut:]
        elif (cut := call.rfind("]")) >= 0:
            head, tail = call[:call.index("[")], call[cut + 1:]
        else:
            comma = call.find(",")
            head, tail = (call, "") if comma < 0 else (call[:comma], call[comma:])
        tails = self._tails
        hit = tails.get(tail)
        if hit is None:
            if len(tails) >= 4096:
                tails.clear()
            hit = tails[tail] = not self.reserved.isdisjoint(_WORD.findall(tail.upper()))
        return hit or not self.reserved.isdisjoint(_WORD.findall(head.upper()))

    def _shifts(self, state_stack: list, term: str) -> bool:
        """Whether `term` is taken from this stack (shifted, or $END
        accepted), after the reductions the table makes on it (simulated on
        a copy of the states)."""
        states = self._states
        action = states[state_stack[-1]].get(term)
        if action is None or action[0]:
            return action is not None
        stack = list(state_stack)
        while True:
            action = states[stack[-1]].get(term)
            if action is None:
                return False
            is_shift, arg = action
            if is_shift:
                return True
            size, origin = arg[0], arg[1]
            if size:
                del stack[-size:]
            goto = states[stack[-1]].get(origin)
            if goto is None:
                return False
            stack.append(goto[1])
            if term == "$END" and stack[-1] == self._end:
                return True

    def _plain(self, text: str, tok: Tok) -> list[Tok]:
        """The tokens of a FAST_CALL/FAST_DECL token's text, lexed as the
        lexer lexes text without those two (its text ends at ';': no token
        of the general lexer crosses its ends)."""
        out = []
        match = self._master_plain.match
        keywords = self._keywords
        ignore = self._ignore
        pos, end = tok.start_pos, tok.end_pos
        while pos < end:
            m = match(text, pos, end)
            if m is None:
                raise LexFailure(pos)
            kind, stop = m.lastgroup, m.end()
            if kind not in ignore:
                value = m.group()
                if kind == "NAME":
                    kind = keywords.get(value.upper(), "NAME")
                out.append(Tok(kind, value, pos, stop))
            pos = stop
        return out

    # ------------------------------------------------------------------ parser
    def _viable(self, state_stack: list) -> frozenset[str]:
        """Terminals that could really come next.

        An LALR row also lists lookaheads merged in from other contexts
        (after `x := 1`, ']' is in the row because an aggregate could end
        there elsewhere). Simulating the reductions for each candidate keeps
        only those that lead to a shift, so messages say what fits here.
        """
        return frozenset(term for term in self._states[state_stack[-1]]
                         if (term.isupper() or term == "$END") and self._shifts(state_stack, term))

    def parse(self, text: str):
        states = self._states
        end_state = self._end
        appends = self._appends
        state_stack = [self._start]
        value_stack: list = []
        previous = None
        stream = self.tokens(text, runs=True)
        # A one-token statement (declaration) where the table has no action
        # for it (its first word ends something else: `IF bFlag MoveL(p10),
        # v100,z1,tool0;`): its text's own tokens, as the general lexer makes
        # them, go in its place (reversed: popped from the end).
        again: list = []
        while True:
            tok = again.pop() if again else next(stream)
            ttype = tok.type
            check = None
            if (ttype in _LISTED and previous is not None and previous.type == ttype
                    and len(state_stack) > 2):
                # A statement (declaration) after one of its kind: where the
                # table has been seen to reduce the one before into the list
                # below it and shift this one into the same states, that is
                # done at once (a CAM program's 1e5 moves: four reductions
                # each). The actions depend on these three states only.
                key = (state_stack[-3], state_stack[-2], state_stack[-1])
                verdict = appends.get(key)
                if verdict:
                    value_stack[-2].append(_LISTED[ttype](self, value_stack[-1]))
                    value_stack[-1] = tok
                    previous = tok
                    continue
                if verdict is None:
                    below = value_stack[-2]
                    check = (key, len(state_stack), below,
                             len(below) if type(below) is _Splice else -1)
                    lowest = len(state_stack)
            if ttype in _LISTED and not self._shifts(state_stack, ttype):
                # (Decided before any reduction: the table may reduce on
                # this lookahead and only then find no action.)
                again = self._plain(text, tok)[::-1]
                continue
            while True:
                try:
                    is_shift, arg = states[state_stack[-1]][ttype]
                except KeyError:
                    raise ParseFailure(tok, self._viable(state_stack), previous) from None
                if is_shift:
                    state_stack.append(arg)
                    value_stack.append(tok)
                    break
                size, origin, plan, fn, expand1 = arg
                if size:
                    children = value_stack[-size:]
                    del state_stack[-size:]
                    del value_stack[-size:]
                    if check is not None and len(state_stack) < lowest:
                        lowest = len(state_stack)
                else:
                    children = []
                if plan is not None:
                    assembled = None
                    for child, how in zip(children, plan):
                        if how == "keep":
                            if assembled is None:
                                assembled = []
                            assembled.append(child)
                        elif how == "splice":
                            if assembled is None:
                                # Left recursion (item* lists): grow the helper's
                                # own list in place instead of copying it, or
                                # long statement lists would be quadratic.
                                assembled = child
                            else:
                                assembled.extend(child)
                    children = assembled if assembled is not None else []
                if expand1 and len(children) == 1:
                    value = children[0]
                else:
                    value = fn(children)
                state_stack.append(states[state_stack[-1]][origin][1])
                value_stack.append(value)
                if ttype == "$END" and state_stack[-1] == end_state:
                    return value_stack[-1]
            if check is not None:
                # (The reductions read no state below the three of the key:
                # the stack never went lower than the key's first; then the
                # same three states always lead to the same actions.)
                key, depth, below, n = check
                appends[key] = (n >= 0 and len(state_stack) == depth and lowest >= depth - 2
                                and tuple(state_stack[-3:]) == key and value_stack[-2] is below
                                and len(below) == n + 1 and value_stack[-1] is tok
                                and _spans(below[-1], previous))
            previous = tok
        raise AssertionError("parser ended without accepting")  # pragma: no cover
