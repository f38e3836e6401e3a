"""Stage 5 of `fix`: the written output, checked as the controller will run it.

Every edited module is parsed again (or, when every edit is numbers of
existing literals, the edited literals are lexed again where the output
holds them: relex); every compensated use is resolved on the output with
its numbers rounded to float32 (as the controller stores
them), turned into joints the way the controller does (MoveAbsJ: as
written; a robtarget: the ideal controller's IK, on the confdata's branch
or, where supervision is off, the solution closest to the previous move's
verified joints) and put through the deformed robot's FK. The residual
against the intended pose is what the report shows as "after".
"""

from __future__ import annotations

import re
from array import array
from typing import NamedTuple

import numpy as np

from .. import side
from ..edits import EditColumns
from ..errors import InternalError, RapidcompError
from ..kinematics.frames import DEG
from ..kinematics.ik import CHUNK, Solver
from ..rapid import ast as A
from ..rapid.ast import Span
from ..rapid.build import DECL_HEAD, NodeBuilder
from ..rapid.grammar import engine
from ..rapid.lalr import LexFailure
from ..rapid.model import ParsedFile
from ..rapid.parse import parse_text
from ..rapid.values import (JOINTTARGET_FRAME, NUM_MAX, ROBTARGET_FRAME, DecodeIssue,
                             JointTarget, RobTarget, decimal_chars, decode, frame_fields,
                             plain_bounds)
from ..rapid.values import relex as relex_record
from .plan import Plan
from .solve import Solved, tcp_of
from .targets import (MAX_JOINT_DEG, Resolver, Unresolved, Written, robtarget_flanges,
                      stacked_poses)
from .transient import FUNC_J, FUNC_R, states_values

# Literals decoded at once by relex (their field texts alive together).
RELEX_BLOCK = 8192
# Uses whose written values are checked at once (their arrays alive
# together): two of the IK's chunks, so that its two threads share each
# block (one chunk ran on one core).
VERIFY_BLOCK = 2 * CHUNK

# Acceptance of a written value, after float32 rounding.
VERIFY_UM = 1.0
VERIFY_DEG = 1e-4


def reparse(plan: Plan, texts: dict[int, str]) -> dict[int, ParsedFile]:
    """The output files that changed, parsed again."""
    out = {}
    for fi, text in texts.items():
        name = plan.files[fi].source.display_path
        try:
            out[fi] = parse_text(text, name)
        except RapidcompError as exc:
            raise InternalError(f"the compensated module does not parse: {exc}") from exc
    return out


def relex(plan: Plan, fields: dict, file_edits: dict, texts: dict[int, str]) -> Written | None:
    """When every edit replaces numeric fields of literals (fields: (file,
    offset) -> (record, its new field texts, or its new literal text)),
    the output has the input's structure: instead of parsing it again,
    each edited literal is lexed again where the output holds it, and must
    decode to the numbers the editor meant. Returns the records as
    written, by (id(file), offset), for the verification's resolver; None
    when a literal does not re-lex (the output is then parsed again). A
    robtarget the output writes as its wanted literal, or as its wanted
    texts in the frame of a literal without whitespace (what values.relex
    compares first), is a row of one array of numbers: the texts
    converted as values.relex converts them (values.decimals)."""
    by_file: dict = {}
    for (fi, start), item in fields.items():
        by_file.setdefault(fi, []).append((start, item))
    out = {}
    keys: list = []
    # Per row: its input record, the output's text, the literal's start and
    # end there (columns: no tuple per row).
    where: tuple = ([], [], [], [])
    recs, outs, starts, ends = where
    wants: list = []
    frame = ROBTARGET_FRAME
    for fi, items in by_file.items():
        # Offsets shift by what the edits before them add: a literal's
        # brackets lie outside every field edit.
        es, shift = _shifts(file_edits.get(fi, []))
        text = texts.get(fi, plan.files[fi].source.text)
        home = id(plan.files[fi])
        at = np.fromiter((start for start, _ in items), np.int64, len(items))
        to = np.fromiter((record.span.end for _, (record, _) in items), np.int64, len(items))
        at = (at + shift[np.searchsorted(es.ends, at, "right")]).tolist()
        to = (to + shift[np.searchsorted(es.ends, to, "right")]).tolist()
        for (start, (record, want)), a, b in zip(items, at, to):
            if type(record) is RobTarget and (text[a:b] == want if type(want) is str
                                              else text[a:b] == frame % tuple(want)):
                keys.append((home, start))
                recs.append(record)
                outs.append(text)
                starts.append(a)
                ends.append(b)
                wants.append(want)
                continue
            if type(want) is str:
                # (Written whole and plainly: the output holds it, or not
                # what was meant.)
                return None
            got = relex_record(record, text[a:b], want)
            if got is None:
                return None
            out[(home, start)] = got
    # (A block at a time: the 1.7e6 field texts of a CAM program are not
    # all alive at once. Each block's numbers go to its rows of one array,
    # not to a list of blocks then concatenated.)
    values = np.empty((len(wants), 17))
    decimal = True
    ats = range(0, len(wants), RELEX_BLOCK)
    # (Every other block decoded by the job's helper: side.py.)
    for at, block in zip(ats, side.alternate(_wanted_values, ((wants[at:at + RELEX_BLOCK],)
                                                              for at in ats))):
        if block is None:
            return None
        if block is False:
            decimal = False
        elif decimal:
            values[at:at + RELEX_BLOCK] = block
    if not decimal:
        # A kept field written otherwise than as a decimal number (0x1F in
        # a value the parser decoded field by field): values.relex's verdict.
        for key, record, text, a, b, want in zip(keys, *where, wants):
            got = relex_record(record, text[a:b], want if type(want) is not str
                               else frame_fields(want))
            if got is None:
                return None
            out[key] = got
        keys, where, values = [], ([], [], [], []), np.empty((0, 17))
    # (As values.relex: a number beyond a num's range does not re-lex.)
    if not (np.abs(values) <= NUM_MAX).all():
        return None
    return Written(out, keys, values, where)


def _shifts(es) -> tuple[EditColumns, np.ndarray]:
    """A file's edits as columns, and what the first k of them add to an
    offset, for each k: an input offset x lies at x + shift[k] in the
    output, k the number of edits ending at or before it (in the order
    BY_SPAN sorts them)."""
    if type(es) is not EditColumns:
        es = EditColumns.of(es, pack=False)
    grow = es.lengths() - (es.ends - es.starts)
    return es, np.concatenate(([0], np.cumsum(grow)))


def relex_absj(plan: Plan, converted: dict, file_edits: dict,
               texts: dict[int, str], copies: bool = False) -> "Converted | None":
    """When every structural edit turns a move into MoveAbsJ on a jointtarget
    of its own (Editor.converted: use key -> (use, that literal, the new
    declaration's name or None, the instruction's name as written, the
    file it is declared in or None)), each
    such statement and each new declaration is read again where the output
    holds it. The statement must be the input's with its instruction's name
    and its target replaced by those meant, character for character (so a
    statement of the grammar as the input's is: a name for a name, an
    aggregate for an aggregate); each new declaration one one-line
    declaration (FAST_DECL) built as the parser builds it, a CONST
    jointtarget the move sees (in the move's routine or else its module,
    or, from another module, a module's declaration not LOCAL: a task's
    data module holding the targets of another's moves), of the literal
    meant; a move on an element of a new array (that literal None, the
    name its reference, subscripts and all), that array's declaration read
    again (_array_decl). Returns use key -> its joints as the controller stores them
    (the literal decoded, float32, as the resolver reads a MoveAbsJ's), a
    Converted, or None where anything differs (the output is then parsed
    again). copies: targets copied for some of their uses are read again
    too (relex_copies): new robtarget declarations are no surprise."""
    eng, build = engine(), NodeBuilder()
    by_file: dict = {}
    for key in converted:
        by_file.setdefault(key[0], []).append(key)
    # The new declarations of each file the moves are in or a move's new
    # jointtarget is declared in (a task's data module): read once each.
    homes: dict = {}
    for fi in sorted(set(by_file) | {it[4] for it in converted.values() if it[4] is not None}):
        es, shift = _shifts(file_edits.get(fi, []))
        kinds: list | None = [] if copies else None
        wide: set = set()
        arrays: dict = {}
        declared = _declared(eng, build, es, shift, texts[fi], plan.files[fi],
                             COPY_TYPES if copies else ("jointtarget",), kinds=kinds,
                             wide=wide, arrays=arrays)
        if declared is None:
            return None
        names, scopes, aggs, declared_joints = declared
        homes[fi] = (names, np.frombuffer(scopes, np.int64), np.frombuffer(aggs, np.int64),
                     declared_joints, kinds, wide, arrays)
    # (A name new in two files, which the editor never writes: which one a
    # move sees is not looked into; the output is parsed again.)
    if len(homes) > 1:
        new: set = set()
        for names, *_, arrays in homes.values():
            if not new.isdisjoint(names) or not new.isdisjoint(arrays):
                return None
            new.update(names)
            new.update(arrays)
    keys: list = []
    rows: list = []
    for fi, file_keys in by_file.items():
        es, shift = _shifts(file_edits.get(fi, []))
        text, src = texts[fi], plan.files[fi].source.text
        # (Each move's joints a row of one array, not a tuple of floats; the
        # moves' offsets a block at a time, not 1e5 pairs of ints at once.)
        records = np.empty((len(file_keys), 6))
        blocks = []
        for first in range(0, len(file_keys), RELEX_BLOCK):
            block = file_keys[first:first + RELEX_BLOCK]
            items = [converted[key] for key in block]
            spans = _span_rows([it[0].motion.span for it in items])
            # (Where each statement's ends lie in the output.)
            moved = spans + shift[np.searchsorted(es.ends, spans, "right")]
            # Each statement as meant, the output's texts compared as one
            # list (a CAM program's 1e5: no check made move by move).
            if any(it[3].lower() != "moveabsj" for it in items):
                return None
            motions = [it[0].motion for it in items]
            exprs = [it[0].source.expr.span for it in items]
            if [text[at:to] for at, to in moved.tolist()] != [
                    called + src[m.span.start + len(m.instruction):e.start] + (name or literal)
                    + src[e.end:b]
                    for (_, literal, name, called, _), m, e, b in zip(
                        items, motions, exprs, spans[:, 1].tolist())]:
                return None
            # Each new declaration a move names: where the move sees it (in
            # the move's routine or else its module; from another module, a
            # module's declaration not LOCAL), of the literal meant (an
            # inline literal is checked below, with its block); the move's
            # joints the declaration's as read already, where its literal is
            # read so (the same text: the same joints), else decoded below.
            todo = [True] * len(items)
            # A move on an element of a new array (no literal of its own):
            # that element's row, the array where the move sees it and of
            # the input array's dimensions (the statement's subscripts are
            # the input's: the same element).
            for n, it in enumerate(items):
                if it[1] is not None:
                    continue
                u, home = it[0], it[4]
                got = homes[home][6].get(it[2].partition("{")[0].lower())
                if got is None:
                    return None
                (a, b), dims, joints, seen_wide = got
                seen = a <= spans[n, 0] and spans[n, 1] <= b if home == fi else seen_wide
                if not (seen and dims == u.source.decl.dims):
                    return None
                records[first + n] = joints[u.source.element]
                todo[n] = False
            named: dict = {}
            for n, it in enumerate(items):
                if it[2] is not None and it[1] is not None:
                    named.setdefault(it[4], []).append(n)
            for home, ns in named.items():
                names, scope2, at2, declared_joints, kinds, wide, _ = homes[home]
                found = [names.get(items[n][2].lower()) for n in ns]
                if None in found or (kinds is not None
                                     and any(kinds[k] != "jointtarget" for k in found)):
                    return None
                k2 = 2 * np.array(found, np.int64)
                x = at2[k2]
                lits = [items[n][1] for n in ns]
                size = np.fromiter(map(len, lits), np.int64, len(lits))
                seen = (((scope2[k2] <= spans[ns, 0]) & (spans[ns, 1] <= scope2[k2 + 1]))
                        if home == fi else np.array([k in wide for k in found], bool))
                if not (seen & (at2[k2 + 1] - x == size)).all():
                    return None
                if not all(map(texts[home].startswith, lits, x.tolist())):
                    return None
                if declared_joints is not None:
                    records[[first + n for n in ns]] = declared_joints[found]
                    for n in ns:
                        todo[n] = False
            own = [n for n, t in enumerate(todo) if t]
            blocks.append((first, items, own, [items[n][1] for n in own]))
        # Each block's other literals, each the text of an aggregate of
        # numbers where the output holds it: decoded as the parser decodes
        # them (every other block by the job's helper, side.py).
        for (first, items, own, lits), rows_of in zip(blocks, side.alternate(
                _joint_rows, ((lits,) for _, _, _, lits in blocks))):
            # An inline one must lex as one aggregate of numbers (NUMAGG): so
            # does a plain jointtarget of decimal numbers (_plain_numaggs);
            # else each is lexed.
            inline = [it[1] for it in items if it[2] is None]
            if inline and not (rows_of is not None and _plain_numaggs(inline)):
                for literal in inline:
                    if [t.type for t in eng.tokens(literal)] != ["NUMAGG", "$END"]:
                        return None
            if rows_of is None:
                rows_of = _decoded_joints(lits)
                if rows_of is None:
                    return None
            records[[first + n for n in own]] = rows_of
        # (As the resolver reads a jointtarget: float32, then floats.)
        joints = records.astype(np.float32).astype(float)
        if not (np.abs(joints) <= MAX_JOINT_DEG).all():
            return None
        keys += file_keys
        rows.append(joints)
    return Converted(dict(zip(keys, range(len(keys)))),
                     np.concatenate(rows) if rows else np.empty((0, 6)))


# The new declarations relex_absj and relex_copies read together.
COPY_TYPES = ("jointtarget", "robtarget")


def _span_rows(spans: list[Span]) -> np.ndarray:
    """Spans as rows (n, 2) of their starts and ends (a Span is one int, its
    start the high 32 bits: read as such, no pair made of each)."""
    v = np.fromiter(spans, np.int64, len(spans))
    return np.stack([v >> 32, v & 0xFFFFFFFF], axis=1)


def relex_copies(plan: Plan, copies: dict, file_edits: dict, texts: dict[int, str],
                 written: Written) -> Written | None:
    """When targets are copied for some of their uses (Editor.copies: use
    key -> (the use, the copy's literal, its name, its type, the file it is
    declared in)), each statement naming a copy and each copy's
    declaration are read again where the output holds them. The statement
    must be the input's with each copied name replaced by its copy's,
    character for character; the copy one one-line CONST declaration
    (FAST_DECL) of its type, of the literal meant, that the move sees: in
    the move's routine or else its module, or, from another module, a
    module's declaration not LOCAL (a task's data module holding the
    targets of another's moves). Returns `written` with each such use's
    record as that literal decodes (Written.uses: the resolver takes it in
    place of its declaration's), or None where anything differs (the
    output is then parsed again)."""
    eng, build = engine(), NodeBuilder()
    by_file: dict = {}
    homes: set = set()
    for key, item in copies.items():
        by_file.setdefault(key[0], []).append(item)
        homes.add(item[4])
    # The new declarations of each file a copy is declared in.
    declared: dict = {}
    for fi in homes:
        es, shift = _shifts(file_edits.get(fi, []))
        kinds: list = []
        wide: set = set()
        # (Robtarget copies written plainly: their numbers read at once,
        # as relex reads the literals it edits; else each decoded below.)
        got = _declared(eng, build, es, shift, texts[fi], plan.files[fi], COPY_TYPES,
                        rows_of=_robtarget_rows, width=17, kinds=kinds, wide=wide)
        if got is None:
            return None
        names, scopes, aggs, values = got
        declared[fi] = (names, np.frombuffer(scopes, np.int64), np.frombuffer(aggs, np.int64),
                        kinds, wide, values)
    records: dict = {}
    decoded: dict = {}
    for fi, items in by_file.items():
        es, shift = _shifts(file_edits.get(fi, []))
        text, src = texts[fi], plan.files[fi].source.text
        # Each statement as meant: the input's, its copied names replaced
        # (MoveC: two targets of one statement).
        statements: dict = {}
        for u, _, name, _, _ in items:
            statements.setdefault(id(u.motion), (u.motion.span, set()))[1].add(
                (tuple(u.source.ref.span), name))
        spans = _span_rows([span for span, _ in statements.values()])
        moved = (spans + shift[np.searchsorted(es.ends, spans, "right")]).tolist()
        for ((a, b), refs), (x, y) in zip(statements.values(), moved):
            meant, pos = [], a
            for (start, end), name in sorted(refs):
                meant += [src[pos:start], name]
                pos = end
            meant.append(src[pos:b])
            if text[x:y] != "".join(meant):
                return None
        for u, literal, name, type_name, home in items:
            names, scope2, at2, kinds, wide, values = declared[home]
            k = names.get(name.lower())
            if k is None or kinds[k] != type_name:
                return None
            span, x = u.motion.span, int(at2[2 * k])
            seen = (scope2[2 * k] <= span.start and span.end <= scope2[2 * k + 1]
                    if home == fi else k in wide)
            if not (seen and at2[2 * k + 1] - x == len(literal)
                    and texts[home].startswith(literal, x)):
                return None
            if values is not None and type_name == "robtarget":
                # (Its numbers a row of the array read: Written.copy.)
                records[u.key] = (values, k, texts[home], x, x + len(literal))
                continue
            record = decoded.get((literal, type_name))
            if record is None:
                try:
                    record = decode(type_name, A.NumAgg(literal, u.source.record.span))
                except DecodeIssue:
                    return None
                decoded[(literal, type_name)] = record
            records[u.key] = record
    written.uses = records
    return written


def _robtarget_rows(lits: list[str]) -> np.ndarray | None:
    """The numbers of robtarget literals each written in its plain frame
    with decimal numbers (relex's first way: the decoder's numbers), as
    rows (n, 17); else None (each is lexed, and decoded, on its own)."""
    rows = _plain_values(lits)
    return rows if isinstance(rows, np.ndarray) else None


def relex_transient(plan: Plan, calls: dict, file_edits: dict,
                    texts: dict[int, str]) -> "Calls | None":
    """relex_absj for a transient output whose every edit turns a move's
    target into rcTcR/rcTcJ(<cold>, <dq>) (Editor.calls): a robtarget
    move's rcTcR of its robtarget as written and a pose; a MoveAbsJ's rcTcJ
    of its jointtarget as written and a jointtarget; a move turned into
    MoveAbsJ, its name too, on rcTcJ of a new cold jointtarget. Each such
    statement must be the input's with its targets and name so replaced,
    character for character, a target after no letter, digit or '_' (a
    call for a name or an aggregate, nothing joined to a word before it);
    each new declaration a one-line CONST of the type meant, of the literal
    meant, that the move sees: in its routine or module, or in any module
    when neither LOCAL nor in a routine; each inline literal an aggregate
    of decimal numbers. Returns each use's correction and new cold value
    (as the parser decodes their literals; any other cold value is the
    use's target as the input holds it, which the output holds as it
    was), a Calls, or None where anything differs (the output is then
    parsed again)."""
    eng, build = engine(), NodeBuilder()
    by_file: dict = {}
    for key in calls:
        by_file.setdefault(key[0], []).append(key)
    # The new declarations of every edited file, by name (a move may name
    # one of another module's: its target's home): file -> lower-case name
    # -> k.
    found: dict = {}
    decls: dict = {}
    for fi in file_edits:
        es, shift = _shifts(file_edits[fi])
        wide: set = set()
        kinds: list = []
        declared = _declared(eng, build, es, shift, texts[fi], plan.files[fi],
                             ("pose", "jointtarget"), _dq_rows, 7, wide, kinds)
        if declared is None:
            return None
        names, scopes, aggs, rows = declared
        if fi not in by_file and (es.starts != es.ends).any():
            return None                   # (an edit of no statement read here)
        # (As columns: the declarations a move names are checked a block at
        # a time, 2e5 of them in a transient output.)
        seen_wide = np.zeros(len(kinds), bool)
        seen_wide[list(wide)] = True
        decls[fi] = (np.frombuffer(scopes, np.int64).reshape(-1, 2),
                     np.frombuffer(aggs, np.int64).reshape(-1, 2), rows, seen_wide,
                     np.array(kinds))
        if not all(names.keys().isdisjoint(other) for other in found.values()):
            return None                   # (one name in two files: not as meant)
        found[fi] = names

    def declared_rows(fi: int, starts: np.ndarray, ends: np.ndarray, names: list,
                      literals: list, kind: str):
        """The numbers of the new declarations `names` that moves of file fi
        (their statements' starts and ends) name, each one's as rows (n, 7),
        if each is one of `kind`, the move sees, of its literal; else
        None."""
        names = [name.lower() for name in names]
        homes = np.full(len(names), -1, np.int64)
        ks = np.empty(len(names), np.int64)
        for dfi, table in found.items():
            got = np.fromiter((table.get(name, -1) for name in names), np.int64, len(names))
            hit = got >= 0
            homes[hit], ks[hit] = dfi, got[hit]
        if (homes < 0).any():
            return None
        out = np.empty((len(names), 7))
        for dfi in np.unique(homes).tolist():
            at = np.flatnonzero(homes == dfi)
            k = ks[at]
            scope, agg, declared_rows, wide, kinds = decls[dfi]
            if (kinds[k] != kind).any():
                return None
            seen = wide[k]
            if dfi == fi:
                seen = seen | ((scope[k, 0] <= starts[at]) & (ends[at] <= scope[k, 1]))
            if not seen.all():
                return None
            these = [literals[n] for n in at.tolist()]
            x = agg[k, 0]
            if not np.array_equal(agg[k, 1] - x, np.fromiter(map(len, these), np.int64, len(at))):
                return None
            if not all(map(texts[dfi].startswith, these, x.tolist())):
                return None
            if declared_rows is not None:
                out[at] = declared_rows[k]
                continue
            got = _dq_rows(these)
            if got is None or not _plain_numaggs(these):
                return None
            out[at] = got
        return out

    def inline_rows(lits: list) -> np.ndarray | None:
        """_dq_rows of inline literals of decimal numbers (_plain_rows), a
        block at a time, every other one read by the job's helper
        (side.py)."""
        out = []
        for got in side.alternate(_plain_rows, ((_dq_rows, lits[at:at + RELEX_BLOCK])
                                                for at in range(0, len(lits), RELEX_BLOCK))):
            if got is None:
                return None
            out.append(got)
        return np.concatenate(out)

    keys: list = []
    dqs: list = []
    colds: list = []
    for fi, file_keys in by_file.items():
        es, shift = _shifts(file_edits.get(fi, []))
        text, src = texts[fi], plan.files[fi].source.text
        entries = [calls[key] for key in file_keys]
        uses = [c[0] for c in entries]
        n = len(entries)
        for u, (_, _, _, _, func, span, called, _) in zip(uses, entries):
            if (u.kind, type(u.source.record), func, called is not None) not in _CALLED:
                return None
            before = src[span.start - 1:span.start]
            if before.isalnum() or before == "_":
                return None
        # Each statement as meant: the input's, each of its targets replaced
        # (a MoveC has two; a move in a loop is one statement of several
        # uses: the same replacement), and the name of a move turned into
        # MoveAbsJ. Its uses' spans as the rows of one array (statement,
        # span replaced, use, what), sorted: read a block at a time.
        starts = np.fromiter((u.motion.span.start for u in uses), np.int64, n)
        ends = np.fromiter((u.motion.span.end for u in uses), np.int64, n)
        at = np.arange(n)
        renamed = np.fromiter((c[6] is not None for c in entries), bool, n)
        cols = np.concatenate([
            np.stack([starts, ends, np.fromiter((c[5].start for c in entries), np.int64, n),
                      np.fromiter((c[5].end for c in entries), np.int64, n), at,
                      np.zeros(n, np.int64)], axis=1),
            np.stack([starts, ends, starts,
                      starts + np.fromiter((len(u.motion.instruction) for u in uses), np.int64,
                                           n), at, np.ones(n, np.int64)], axis=1)[renamed]])
        cols = cols[np.lexsort(cols.T[::-1])]
        checked = _Statements(text, src, es, shift)
        for first in range(0, len(cols), RELEX_BLOCK):
            for a, b, x, y, k, what in cols[first:first + RELEX_BLOCK].tolist():
                call = entries[k]
                if not checked.add(a, b, x, y, call[6] if what else _call_text(call)):
                    return None
        # (Every other edit is an insert: the declarations read above.)
        if not checked.done() or np.count_nonzero(es.starts != es.ends) != checked.edited:
            return None
        cols = checked = None
        # Each correction, and each new cold value: a new declaration's the
        # move sees, of its type and the literal meant, or an inline literal.
        inline, named, cold_inline, cold_named = [], [], [], []
        for k, (_, cold_text, name, _, _, _, _, cold_literal) in enumerate(entries):
            (inline if name is None else named).append(k)
            if cold_literal is not None:      # (else the input's target: as it was)
                (cold_inline if cold_text == cold_literal else cold_named).append(k)
        rows = np.empty((n, 7))
        cold = np.full((n, 6), np.nan)
        for func in (FUNC_J, FUNC_R):
            these = [k for k in named if entries[k][4] == func]
            if these:
                got = declared_rows(fi, starts[these], ends[these],
                                    [entries[k][2] for k in these],
                                    [entries[k][3] for k in these], _CORRECTION[func])
                if got is None:
                    return None
                rows[these] = got
        if cold_named:
            got = declared_rows(fi, starts[cold_named], ends[cold_named],
                                [entries[k][1] for k in cold_named],
                                [entries[k][7] for k in cold_named], "jointtarget")
            if got is None or not np.isnan(got[:, 6]).all():
                return None
            cold[cold_named] = got[:, :6]
        if cold_inline:
            got = inline_rows([entries[k][7] for k in cold_inline])
            if got is None or not np.isnan(got[:, 6]).all():
                return None
            cold[cold_inline] = got[:, :6]
        if inline:
            got = inline_rows([entries[k][3] for k in inline])
            if got is None:
                return None
            rows[inline] = got
            # (An inline literal is of its function's type: its count of
            # numbers, which _dq_rows reads, says which.)
            if (np.isnan(rows[inline, 6]) != np.fromiter(
                    (entries[k][4] == FUNC_J for k in inline), bool, len(inline))).any():
                return None
        entries = uses = None
        keys += file_keys
        dqs.append(rows)
        colds.append(cold)
    if not keys:
        return None
    return Calls(dict(zip(keys, range(len(keys)))), np.concatenate(dqs), np.concatenate(colds),
                 np.fromiter((calls[key][4] == FUNC_J for key in keys), bool, len(keys)))


# What each function is called on (the use's kind, its value's class, the
# function, whether the move became MoveAbsJ), and the type of its
# correction.
_CALLED = frozenset({("robtarget", RobTarget, FUNC_R, False),
                     ("jointtarget", JointTarget, FUNC_J, False),
                     ("robtarget", RobTarget, FUNC_J, True)})     # (turned into MoveAbsJ)
_CORRECTION = {FUNC_R: "pose", FUNC_J: "jointtarget"}


class _Statements:
    """Edited statements of a file, checked against the output a block at
    a time (not 1e5 texts of each alive at once): add() each target's
    replacement in order of statement and target, then done(). Each
    statement is the input's text with its targets replaced; a target met
    again (a statement of several uses) must have the same replacement.
    False where anything differs. edited: the spans replaced."""

    def __init__(self, text: str, src: str, es: EditColumns, shift: np.ndarray):
        self.text, self.src, self.es, self.shift = text, src, es, shift
        self.spans: list = []
        self.want: list = []
        self.edited = 0
        self._at = None              # (start, end) of the statement being built
        self._parts: list = []
        self._from = 0               # where the input's text goes on in it
        self._last = None            # its last target's span

    def add(self, a: int, b: int, x: int, y: int, rep: str) -> bool:
        if self._at != (a, b):
            if self._at is not None and not self._close():
                return False
            self._at, self._parts, self._from, self._last = (a, b), [], a, None
        if (x, y) == self._last:
            return rep == self._parts[-1]          # (one target, one replacement)
        if x < self._from or y > b:
            return False
        self._parts += [self.src[self._from:x], rep]
        self._from, self._last = y, (x, y)
        self.edited += 1
        return True

    def _close(self) -> bool:
        a, b = self._at
        self._parts.append(self.src[self._from:b])
        self.spans.append((a, b))
        self.want.append("".join(self._parts))
        return len(self.spans) < RELEX_BLOCK or self._compare()

    def _compare(self) -> bool:
        moved = np.array(self.spans, np.int64).reshape(-1, 2)
        moved = (moved + self.shift[np.searchsorted(self.es.ends, moved, "right")]).tolist()
        same = [self.text[x:y] for x, y in moved] == self.want
        self.spans, self.want = [], []
        return same

    def done(self) -> bool:
        if self._at is not None and not self._close():
            return False
        self._at = None
        return self._compare() if self.spans else True


def _call_text(call: tuple) -> str:
    """rcTcR/rcTcJ(<cold>, <dq>) of an Editor.calls entry, as the editor
    wrote it."""
    _, cold, name, literal, func = call[:5]
    return f"{func}({cold}, {name if name is not None else literal})"


class Calls:
    """What relex_transient read of each rcTcR/rcTcJ(cold, dq), by use key:
    its row of arrays: the correction's numbers (rcTcR's pose: position,
    quaternion RAPID order; rcTcJ's jointtarget: its 6 joints, then NaN);
    a new cold value's joints (NaN: the cold value is the use's target, its
    text the input's); whether it is rcTcJ."""

    def __init__(self, rows: dict, dq: np.ndarray, cold: np.ndarray, joint: np.ndarray):
        self.rows, self.dq, self.cold, self.joint = rows, dq, cold, joint


# A pose literal written plainly (Editor._pose_literal).
_POSE_FRAME = "[[%s,%s,%s],[%s,%s,%s,%s]]"


def _dq_rows(lits: list[str]) -> np.ndarray | None:
    """The corrections of a transient output, each a pose literal (7
    numbers) or a jointtarget (12: _joint_rows's 6 joints, then NaN), as
    rows (n, 7), each read as its kind is (_pose_rows, _joint_rows); None
    where one is not."""
    joint = np.fromiter((lit.count(",") == 11 for lit in lits), bool, len(lits))
    out = np.full((len(lits), 7), np.nan)
    for pick, read, width in ((~joint, _pose_rows, 7), (joint, _joint_rows, 6)):
        at = np.flatnonzero(pick).tolist()
        if at:
            got = read([lits[n] for n in at])
            if got is None:
                return None
            out[at, :width] = got
    return out


def _pose_rows(lits: list[str]) -> np.ndarray | None:
    """decode("pose", literal)'s position and quaternion of each literal,
    as rows (n, 7), when every one is written in its plain frame (no
    whitespace) with numbers float() reads within a num's range (as
    _joint_rows reads jointtargets); else None."""
    n = len(lits)
    if not n:
        return None
    joined = ",".join(lits)
    fields = frame_fields(joined)
    if (len(fields) != 7 * n or joined != ",".join([_POSE_FRAME] * n) % tuple(fields)
            or not np.array_equal(
                np.fromiter(map(len, fields), np.int64, 7 * n).reshape(n, 7).sum(axis=1)
                + len(_POSE_FRAME % (("",) * 7)), np.fromiter(map(len, lits), np.int64, n))):
        return None
    try:
        values = np.fromiter(map(float, fields), float, 7 * n)
    except ValueError:
        return None
    if not (np.abs(values) <= NUM_MAX).all():
        return None
    return values.reshape(n, 7)


class Converted:
    """The joints of each move turned into MoveAbsJ as relex_absj read them,
    by use key: rows of one array (a CAM program has 1e5; no tuple of six
    floats each until asked for)."""

    def __init__(self, rows: dict, joints: np.ndarray):
        self.rows, self.joints = rows, joints

    def __len__(self) -> int:
        return len(self.rows)

    def get(self, key, default=None):
        n = self.rows.get(key)
        return default if n is None else tuple(self.joints[n].tolist())


def _joint_rows(lits: list[str]) -> np.ndarray | None:
    """decode("jointtarget", literal).joints of each literal, as rows (n, 6),
    when every one is written in its plain frame (no whitespace) with
    numbers float() reads within a num's range: the decoder's first way,
    the same floats (a CAM program's 1e5 MoveAbsJ at once). Else None: the
    literals are decoded one by one. Each literal is its joints' part up to
    the first '],[' and its external axes' part after it (the frame's
    parts, where its fields hold no bracket or comma); the external axes
    repeat from target to target, and each distinct text of them is read
    once."""
    n = len(lits)
    if not n:
        return None
    parts = [lit.partition("],[") for lit in lits]
    heads = ",".join([part[0] for part in parts])
    fields = frame_fields(heads)
    # The heads joined are the heads' frames joined, and each head is as
    # long as its own frame: each is the frame with its 6 fields.
    if (len(fields) != 6 * n
            or heads != ",".join([_JOINTS_FRAME] * n) % tuple(fields)
            or not np.array_equal(
                np.fromiter(map(len, fields), np.int64, 6 * n).reshape(n, 6).sum(axis=1)
                + len(_JOINTS_FRAME % (("",) * 6)),
                np.fromiter((len(part[0]) for part in parts), np.int64, n))):
        return None
    tails: dict = {}
    for part in parts:
        tails.setdefault(part[2], None)
    for tail in tails:
        axes = frame_fields(tail)
        if len(axes) != 6 or tail != _AXES_FRAME % tuple(axes):
            return None
        tails[tail] = axes
    try:
        values = np.fromiter(map(float, fields), float, 6 * n)
        axes = np.fromiter(map(float, [a for axes in tails.values() for a in axes]), float,
                           6 * len(tails))
    except ValueError:
        return None
    # (No NaN, no infinity: those the decoder reads another way.)
    if not ((np.abs(values) <= NUM_MAX).all() and (np.abs(axes) <= NUM_MAX).all()):
        return None
    return values.reshape(n, 6)


# JOINTTARGET_FRAME up to its first "],[" and after it.
_JOINTS_FRAME, _AXES_FRAME = JOINTTARGET_FRAME.split("],[")
assert _JOINTS_FRAME + "],[" + _AXES_FRAME == JOINTTARGET_FRAME


# The characters of an aggregate of decimal numbers without whitespace.
_NUMAGG_CHARS = str.maketrans("", "", "0123456789.eE+-,[]")


def _plain_numaggs(lits: list[str]) -> bool:
    """Each literal, a jointtarget written in its plain frame whose fields
    float() reads (_joint_rows said so), is written with decimal characters
    only: then each field is a number as the lexer's NUMAGG reads it
    (values.decimal_chars), and the literal lexes as one NUMAGG."""
    return not ",".join(lits).translate(_NUMAGG_CHARS)


# One new declaration as the editor writes it (Editor.declare): the head
# the builder reads of a FAST_DECL (scope, storage, type, name), then its
# aggregate taken up to the ';' (a plain jointtarget of decimal numbers
# there, checked at once, is the NUMAGG FAST_DECL reads).
_PLAIN_DECL = re.compile(r"[ \t\f\r\n\ufeff]*(?:" + DECL_HEAD.pattern + r")(\[[^;]*\])[ \t]*;",
                         re.IGNORECASE)


class _Plain(NamedTuple):
    """_plain_declared's reading of the inserted texts: per declaration, in
    order (as columns: a transient output inserts 2e5), the text it is in
    (its index), its type and name (lower case), its aggregate's start and
    end in the output (at 2k, 2k + 1), whether it is LOCAL or TASK; the
    storage words met (as written); the numbers of each, as rows."""
    piece: array
    type: list
    name: list
    bounds: array
    scoped: bytearray
    storage: set
    rows: np.ndarray


def _plain_declared(eng, text: str, starts: list[int], lengths: list[int], rows_of=None,
                    width: int = 6) -> _Plain | None:
    """What _declared's lexing reads in each inserted text (text[start:
    start + length] of the output), when every one is one-line declarations
    written plainly (_PLAIN_DECL, their words no reserved ones, their
    aggregates plain jointtargets of decimal numbers), a _Plain: the
    numbers of each as _joint_rows reads them (rows_of: another such
    reader, of `width` numbers). None: the texts are lexed one by one."""
    rows_of = rows_of or _joint_rows
    reserved = eng.reserved
    match = _PLAIN_DECL.match
    piece, types, names = array("q"), [], []
    bounds, scoped, storage = array("q"), bytearray(), set()
    lower: dict = {}                 # (a type as written: its lower case, once)
    plain = [True]

    def blocks():
        """The declarations read, their aggregates a block at a time (not
        all their texts alive at once)."""
        block: list = []
        for j, (at, n) in enumerate(zip(starts, lengths)):
            pos, end = at, at + n
            while pos < end:
                m = match(text, pos, end)
                if m is None:
                    plain[0] = False
                    return
                scope, word, type_, name, agg = m.group(1, 2, 3, 4, 5)
                low = lower.get(type_)
                if low is None:
                    if type_.upper() in reserved:
                        plain[0] = False
                        return
                    low = lower[type_] = type_.lower()
                if name.upper() in reserved:
                    plain[0] = False
                    return
                piece.append(j)
                types.append(low)
                names.append(name.lower())
                bounds.extend(m.span(5))
                scoped.append(scope is not None)
                storage.add(word)
                block.append(agg)
                pos = m.end()
                if len(block) == RELEX_BLOCK:
                    yield (block,)
                    block = []
        if block:
            yield (block,)

    # Each block's numbers read by the job's helper, as it is handed, while
    # this process reads the next block's declarations (the helper has
    # nothing else to do meanwhile); without one, here.
    if side.helps():
        pending = [side.run(_plain_rows, rows_of, block) for block, in blocks()]
        made = (p.get() for p in pending)
    else:
        made = (_plain_rows(rows_of, block) for block, in blocks())
    rows = []
    for got in made:
        if got is None:
            return None
        rows.append(got)
    if not plain[0]:
        return None
    return _Plain(piece, types, names, bounds, scoped, storage,
                  np.concatenate(rows) if rows else np.empty((0, width)))


def _plain_rows(rows_of, block: list[str]) -> np.ndarray | None:
    """rows_of(block), where the block's aggregates are of decimal numbers
    (_plain_numaggs); else None."""
    got = rows_of(block)
    return got if got is not None and _plain_numaggs(block) else None


def _declared(eng, build, es: EditColumns, shift: np.ndarray, text: str,
              pf: ParsedFile, types: tuple = ("jointtarget",), rows_of=None,
              width: int = 6, wide: set | None = None, kinds: list | None = None,
              arrays: dict | None = None
              ) -> tuple[dict, array, array, np.ndarray | None] | None:
    """The new declarations of a file read again where the output holds
    them: (lower-case name -> k; the (start, end) in the input of its scope
    (its routine's, else its module's) at [2k, 2k + 1]; the (start, end) of
    its value, an aggregate of numbers, in the output, likewise: offsets
    in arrays, not a node and a tuple each; where every one is written
    plainly (_plain_declared), the numbers of each at row k, else None).
    None where an inserted text
    is not CONST declarations of `types` (jointtarget; a transient output's
    pose and jointtarget, rows_of _dq_rows of width 7) each a one-line
    statement, or is
    not where a declaration may follow: right after a declaration, or at
    the end of a line that ends with one (and a comment), as the editor
    puts them (Editor._anchor; after a line that goes on with a statement,
    the output would not parse). wide, when given, receives the k of
    each declaration other modules see (not LOCAL, not in a routine);
    kinds, each one's type (lower case), at k. arrays, when given, receives
    each new array of jointtargets (_array_decl): lower-case name -> (the
    (start, end) in the input of its scope, its dimensions, the joints of
    its elements as rows, row-major, whether other modules see it); without
    it such a text is not read.
    """
    out: dict = {}
    scopes, aggs = array("q"), array("q")
    inserts = np.flatnonzero(es.starts == es.ends)
    if not len(inserts):
        return out, scopes, aggs, None
    # (Each insert's offset in the input and in the output, and its length,
    # as arrays: 5e4 of them in a CAM program turned into MoveAbsJ.)
    at_in = es.starts[inserts]
    at_out = at_in + shift[inserts]
    src = pf.source.text
    ends = np.array(sorted(d.node.span.end for m in pf.modules for d in m.declarations),
                    np.int64)
    # The declaration each insert follows: right after it (a CAM program's
    # every one), or with blanks and a comment between on its line; or, in
    # a module with no declaration before its routines, the end of its
    # MODULE line (its attributes and a comment before it).
    heads = np.array(sorted(line.end() if line is not None else -1
                            for line in (_MODULE_LINE.match(src, m.node.name_span.end)
                                         for m in pf.modules)), np.int64)
    head = np.isin(at_in, heads)
    last = np.searchsorted(ends, at_in, "right") - 1
    if (last[~head] < 0).any():
        return None
    after = ends[np.maximum(last, 0)] if len(ends) else at_in
    away = (after != at_in) & ~head
    for at, end in zip(at_in[away].tolist(), after[away].tolist()):
        rest = src[end:at].lstrip(" \t")
        if "\n" in rest or "\r" in rest or rest[:1] not in ("", "!"):
            return None
    in_scope = _scopes(pf, at_in)
    if in_scope is None:
        return None
    modules = {(m.node.span.start, m.node.span.end) for m in pf.modules}
    at_out, lengths = at_out.tolist(), es.lengths()[inserts].tolist()
    plain = _plain_declared(eng, text, at_out, lengths, rows_of, width)
    if plain is not None:
        # Every insert's declarations written plainly (a CAM program's 5e4,
        # one each; a transient output's 1e5 pairs): as the loop below
        # reads them, at once, in order (k: a declaration's place among
        # all, the row of its numbers).
        if (not {word.upper() for word in plain.storage} <= {"CONST"}
                or not set(plain.type) <= set(types)):
            return None
        if kinds is not None:
            kinds.extend(plain.type)
        # (A later one of the same name wins, as a dict's last value.)
        out = dict(zip(plain.name, range(len(plain.name))))
        piece = np.frombuffer(plain.piece, np.int64)
        scopes.frombytes(np.array(in_scope, np.int64).reshape(-1, 2)[piece].tobytes())
        aggs.extend(plain.bounds)
        if wide is not None:
            seen = np.array([scope in modules for scope in in_scope], bool)[piece]
            seen &= ~np.frombuffer(plain.scoped, bool)
            wide.update(np.flatnonzero(seen).tolist())
        return out, scopes, aggs, plain.rows
    for scope, a, n in zip(in_scope, at_out, lengths):
        piece = text[a:a + n]
        decls = []
        try:
            toks = list(eng.tokens(piece))
        except LexFailure:
            return None
        at = 0
        while toks[at].type != "$END":
            tok = toks[at]
            if tok.type == "FAST_DECL":
                node = build.fast_decl([tok])
                if node.dims or type(node.init) is not A.NumAgg:
                    return None
                decls.append((node.storage, node.type_name, node.name,
                              node.init.span.start, node.init.span.end, node.scope))
                at += 1
                continue
            got = _array_decl(toks, at) if arrays is not None else None
            if got is None:
                return None
            at, name, dims, leaves, local = got
            # (A name declared twice among the new ones: parsed again.)
            if name.lower() in arrays or name.lower() in out:
                return None
            arrays[name.lower()] = (scope, dims, leaves,
                                    not local and scope in modules)
        for storage, declared, name, x, y, local in decls:
            if not (storage == "CONST" and declared.lower() in types):
                return None
            if arrays is not None and name.lower() in arrays:
                return None
            if kinds is not None:
                kinds.append(declared.lower())
            # (A later one of the same name wins, as a dict's last value.)
            if wide is not None and local is None and scope in modules:
                wide.add(len(scopes) // 2)
            out[name.lower()] = len(scopes) // 2
            scopes.extend(scope)
            aggs.extend((a + x, a + y))
    if arrays:
        for name, (scope, dims, leaves, seen_wide) in arrays.items():
            rows = _jointtarget_rows(leaves)
            if rows is None:
                return None
            arrays[name] = (scope, dims, rows, seen_wide)
    return out, scopes, aggs, None


def _array_decl(toks: list, at: int) -> tuple[int, str, tuple, list[str], bool] | None:
    """A new array declaration as the editor writes it (Editor.declare of
    an array's jointtargets), read in the tokens of its text from toks[at]:
    [LOCAL] CONST jointtarget <name>{<d1>,...}:=<aggregate>; whose
    aggregate nests, to the dimensions' depth, aggregates of d1, d2, ...
    items, each innermost one an aggregate of numbers (NUMAGG). Returns
    (the index past its ';', its name, its dimensions, the texts of its
    elements in row-major order, whether it is LOCAL), or None where the
    tokens are anything else (the output is then parsed again)."""
    types = [t.type for t in toks[at:at + 3]]
    local = types[:1] == ["LOCAL"]
    if local:
        at += 1
        types = [t.type for t in toks[at:at + 3]]
    if (types != ["CONST", "NAME", "NAME"] or toks[at + 1].value.lower() != "jointtarget"
            or toks[at + 3].type != "LBRACE"):
        return None
    name = toks[at + 2].value
    at += 4
    dims = []
    while True:
        tok = toks[at]
        if tok.type != "NUMBER" or not tok.value.isdigit() or int(tok.value) < 1:
            return None
        dims.append(int(tok.value))
        if toks[at + 1].type == "RBRACE":
            break
        if toks[at + 1].type != "COMMA":
            return None
        at += 2
    at += 2
    if toks[at].value != ":=":
        return None
    leaves: list[str] = []
    at = _nested(toks, at + 1, dims, leaves)
    if at is None or toks[at].type != "SEMI":
        return None
    return at + 1, name, tuple(dims), leaves, local


def _nested(toks: list, at: int, dims: list[int], leaves: list[str]) -> int | None:
    """An aggregate of dims[0] items from toks[at], each one nesting
    dims[1:] likewise, the innermost NUMAGGs (their texts appended to
    leaves, in order); the index past it, or None."""
    if toks[at].type != "LBRACK":
        return None
    n = dims[0]
    if len(dims) == 1:
        # (The 1e5 items of a CAM path's array: checked by slices.)
        items = toks[at + 1:at + 2 * n]
        if (len(items) != 2 * n - 1 or any(t.type != "NUMAGG" for t in items[::2])
                or any(t.type != "COMMA" for t in items[1::2])
                or toks[at + 2 * n].type != "RBRACK"):
            return None
        leaves += [t.value for t in items[::2]]
        return at + 2 * n + 1
    at += 1
    for i in range(n):
        if i and toks[at].type != "COMMA":
            return None
        at = _nested(toks, at + (1 if i else 0), dims[1:], leaves)
        if at is None:
            return None
    return at + 1 if toks[at].type == "RBRACK" else None


def _jointtarget_rows(lits: list[str]) -> np.ndarray | None:
    """decode("jointtarget", literal).joints of each literal (each lexed as
    a NUMAGG), as rows: the plain ones a block at a time as _joint_rows
    reads them (every other block by the job's helper), any other decoded
    one by one; None where one does not decode."""
    rows = np.empty((len(lits), 6))
    ats = range(0, len(lits), RELEX_BLOCK)
    for at, got in zip(ats, side.alternate(_joint_rows, ((lits[at:at + RELEX_BLOCK],)
                                                         for at in ats))):
        block = lits[at:at + RELEX_BLOCK]
        if got is None or not _plain_numaggs(block):
            got = _decoded_joints(block)
            if got is None:
                return None
        rows[at:at + len(block)] = got
    return rows


def _decoded_joints(lits: list[str]) -> np.ndarray | None:
    """decode("jointtarget", literal).joints of each literal, one by one,
    as rows (n, 6); None where one does not decode."""
    rows = np.empty((len(lits), 6))
    for n, literal in enumerate(lits):
        try:
            rows[n] = decode("jointtarget", A.NumAgg(literal, Span(0, len(literal)))).joints
        except DecodeIssue:
            return None
    return rows


# The rest of a MODULE line after the module's name: its attributes and a
# comment, up to the line's end (where Editor._anchor puts a declaration in a
# module with none before its routines).
_MODULE_LINE = re.compile(r"[ \t]*(?:\([^()\r\n]*\))?[ \t]*(?:![^\r\n]*)?(?=\r|\n|$)")


def _scopes(pf: ParsedFile, ats: np.ndarray) -> list[tuple[int, int]] | None:
    """(start, end) of the routine, else the module, holding each input
    offset of `ats`: where a declaration inserted there is seen; None where
    one is in neither."""
    spans = sorted((r.node.span.start, r.node.span.end) for m in pf.modules for r in m.routines)
    choice = np.full(len(ats), -1, np.int64)
    if spans:
        # (The last routine starting at or before the offset, if it holds it.)
        k = np.searchsorted(np.array([a for a, _ in spans], np.int64), ats, "right") - 1
        inside = (k >= 0) & (ats < np.array([b for _, b in spans], np.int64)[np.maximum(k, 0)])
        choice[inside] = k[inside]
    for m in pf.modules:                 # (the first module holding it)
        span = m.node.span
        free = (choice < 0) & (span.start <= ats) & (ats < span.end)
        if free.any():
            choice[free] = len(spans)
            spans.append((span.start, span.end))
    if (choice < 0).any():
        return None
    return [spans[c] for c in choice.tolist()]


def _flat_texts(wants: list) -> list[str] | None:
    """The field texts of every wanted robtarget, in order. A literal's are
    what lies between its brackets and commas (one split of all of them),
    when every literal is a plain one (values.plain_bounds; None where
    not)."""
    lits = [w for w in wants if type(w) is str]
    if not lits:
        return [t for w in wants for t in w]
    bounds = plain_bounds(lits)
    if bounds is None:
        return None
    flat = frame_fields(bounds[0])
    if len(lits) == len(wants):
        return flat
    out: list[str] = []
    n = 0
    for w in wants:
        if type(w) is str:
            out.extend(flat[n:n + 17])
            n += 17
        else:
            out.extend(w)
    return out


def _wanted_values(wants: list):
    """The numbers of a block of wanted robtargets (literals given whole,
    or field texts) as rows (n, 17): None where one is not written
    plainly (_flat_texts), False where a field is not a decimal number
    (_decimals)."""
    if all(type(w) is str for w in wants):
        return _plain_values(wants)
    flat = _flat_texts(wants)
    if flat is None:
        return None
    block = _decimals(flat)
    return False if block is None else block


def _plain_values(lits: list[str]):
    """_decimals(_flat_texts(lits)) of literals given whole: None where
    _flat_texts gives None (a literal not written plainly), False where
    _decimals does (a field not a decimal number). Each literal's text
    from the ']' after its quaternion on (confdata and external axes,
    ten fields) is converted once per distinct text: a CAM program's 1e5
    literals have a few (the same texts, the same float() of each)."""
    bounds = plain_bounds(lits)
    if bounds is None:
        return None
    cut = bounds[3][:, 6].tolist()          # where each literal's q4 ends
    heads = frame_fields(",".join([lit[:c] for lit, c in zip(lits, cut)]))
    index: dict = {}
    rows = [index.setdefault(lit[c:], len(index)) for lit, c in zip(lits, cut)]
    # ("],[c1,c2,c3,c4],[e1,...,e6]]": an empty text, then the ten fields.)
    tails = [t for tail in index for t in frame_fields(tail)[1:]]
    if not (decimal_chars(heads) and decimal_chars(tails)):
        return False
    try:
        head = np.fromiter(map(float, heads), float, len(heads))
        tail = np.fromiter(map(float, tails), float, len(tails))
    except ValueError:
        return False
    out = np.empty((len(lits), 17))
    out[:, :7] = head.reshape(-1, 7)
    out[:, 7:] = tail.reshape(-1, 10)[rows]
    return out


def _decimals(texts: list[str]) -> np.ndarray | None:
    """values.decimals as one array (n, 17) of a flat list of robtargets'
    texts (no tuple of 1.7e6 floats)."""
    if not decimal_chars(texts):
        return None
    try:
        return np.fromiter(map(float, texts), float, len(texts)).reshape(-1, 17)
    except ValueError:
        return None


class _Written(NamedTuple):
    kind: str
    R: np.ndarray | None
    p: np.ndarray | None
    conf: tuple | None
    joints_deg: tuple | None
    reason: str | None

    @classmethod
    def of(cls, u) -> "_Written":
        """What the check needs of a use resolved again (not the TargetUse)."""
        return cls(u.kind, u.R, u.p, u.conf, u.joints_deg, u.reason)


def verify(plan: Plan, solved: Solved, keys: list, out_files: dict[int, ParsedFile],
           solver: Solver, written: Written | None = None,
           converted: "Converted | None" = None) -> dict:
    """Residual (um, deg) of each compensated use (by key), evaluated on
    the written output: out_files parsed again, or (written) the input's
    structure with the records as relex() read them, but for the moves
    turned into MoveAbsJ (converted: use key -> its joints as relex_absj()
    read them)."""
    res = _resolver(plan, out_files, written)
    if written is not None:
        # The structure is the input's but for the moves turned into
        # MoveAbsJ (relex() and relex_absj() made sure every other edit is
        # numbers of a literal): each other use's source, tool and work
        # object are the plan's, evaluated again on the numbers as written,
        # and checked VERIFY_BLOCK uses at a time (each use's residual its
        # own: a CAM program's arrays and records alive for one block, not
        # for 1e5).
        rows = sorted(solved.row[k] for k in keys)
        converted = converted or {}
        out: dict = {}
        for at in range(0, len(rows), VERIFY_BLOCK):
            block = rows[at:at + VERIFY_BLOCK]
            # A MoveAbsJ's joints as written; the others evaluated again.
            found = {}
            again = []
            for i in block:
                joints = converted.get(solved.uses[i].key)
                if joints is None:
                    again.append(i)
                else:
                    found[solved.uses[i].key] = _Written("jointtarget", None, None, None,
                                                         joints, None)
            uses = [solved.uses[i] for i in again]
            # Robtargets evaluated as arrays (again_many): their solved rows
            # and (R, p, conf), kept as arrays to the IK.
            done, R, p, conf = res.again_many(uses)
            many = [(R, p, conf)] if done else []
            many_rows = [again[n] for n in done]
            done = set(done)
            batch = [res.again(u) for n, u in enumerate(uses) if n not in done]
            res.poses()
            found.update({o.key: _Written.of(o) for o in batch})
            out.update(_residuals(solved, solver, block, many_rows, many, found))
        return out
    return _residuals(solved, solver, sorted((solved.row[k] for k in keys)), [], [],
                      _resolved(plan, res, keys))


def verify_states(plan: Plan, solved: Solved, keys: list, out_files: dict[int, ParsedFile],
                  solvers: dict) -> dict:
    """verify() of a transient output (out_files: parsed again) at every
    thermal state s (solvers: s -> Solver of the robot deformed by s .
    profile), each rcTcJ/rcTcR(cold, dq) evaluated as the controller does at
    s (targets.Resolver): s -> residual (um, deg) by use key. One resolver
    for every state: each call's cold value and correction are read once,
    and its values at every state computed at once."""
    res = _resolver(plan, out_files, None, tuple(solvers))
    rows = sorted(solved.row[k] for k in keys)
    out = {}
    uses: list = []
    for s, solver in solvers.items():
        res.state = s
        if not uses:
            # The first state: every use resolved on the output (what it
            # reads, its checks), kept for the others.
            out[s] = _residuals(solved, solver, rows, [], [], _resolved(plan, res, keys, uses))
            continue
        # The others: each call's values at s into the same arrays (its
        # cold value, tool and work object as the first state read them);
        # a use they do not take is resolved again.
        done, R, p, conf, joints = res.state_many(uses)
        found = {uses[n].key: _Written("jointtarget", None, None, None, q, None)
                 for n, q in joints.items()}
        taken = set(done) | set(joints)
        again = [u.key for n, u in enumerate(uses) if n not in taken]
        if again:
            found.update(_resolved(plan, res, again))
        out[s] = _residuals(solved, solver, rows, [solved.row[uses[n].key] for n in done],
                            [(R, p, conf)] if done else [], found)
    return out


def verify_states_relexed(plan: Plan, solved: Solved, keys: list, calls: Calls,
                          solvers: dict) -> tuple[list, np.ndarray, np.ndarray] | None:
    """verify_states of a transient output relex_transient read (calls):
    each use's rcTcR/rcTcJ(cold, dq) at every state from those numbers, as
    arrays (Resolver.state_many's arithmetic: the same as resolving each
    call on the output parsed again, bit for bit), a robtarget through the
    tool and work object the input's move names (the output's: the input's
    text). Returns (the use keys, um and deg (states, uses)): row n of each
    is state n's residuals, as verify_states gives them for those keys.
    None where a use is not one of calls, a robtarget's tool or work object
    does not resolve, a value would be stopped or noted by a check, or with
    a track (the caller parses the output again and verifies it so)."""
    res = _resolver(plan, {}, None, tuple(solvers))
    if res.track:
        return None
    rows = sorted(solved.row[k] for k in keys)
    uses = [solved.uses[i] for i in rows]
    at = [calls.rows.get(u.key) for u in uses]
    if None in at:
        return None
    joint = calls.joint[at]
    tools, wobjs = [None] * len(uses), [None] * len(uses)
    for n in np.flatnonzero(~joint).tolist():
        tool, wobj = res._tool_wobj(uses[n].motion, uses[n].module)
        if type(tool) is Unresolved or type(wobj) is Unresolved:
            return None
        tools[n], wobjs[n] = tool[1], wobj[1]
    states = tuple(solvers)
    um, deg = np.empty((len(solvers), len(rows))), np.empty((len(solvers), len(rows)))
    made: list = []                 # (state, block's slice, its robtarget rows), in order

    def parts():
        """_state_residuals' arguments of each block at each state, each
        part its own arrays (the next is made before one is checked)."""
        # (VERIFY_BLOCK uses at a time, as verify() checks them: their
        # arrays alive for a block.)
        for first in range(0, len(rows), VERIFY_BLOCK):
            sl = slice(first, first + VERIFY_BLOCK)
            block, picked, block_uses = rows[sl], np.array(at[sl], np.int64), uses[sl]
            js = joint[sl]
            rob = np.flatnonzero(~js).tolist()
            jts = np.flatnonzero(js).tolist()
            # A MoveAbsJ's joints at each state, as the controller stores
            # them (a value beyond a joint's bound: the output parsed again
            # says so).
            q_joint = None
            if jts:
                # (A move turned into MoveAbsJ: its new cold value's; else
                # its jointtarget's.)
                cold = calls.cold[picked[jts]]
                for m, n in enumerate(jts):
                    if np.isnan(cold[m, 0]):
                        cold[m] = block_uses[n].source.record.values[:6]
                q_joint = states_values(cold, calls.dq[picked[jts], :6], states,
                                        True).astype(float)
                if not (np.abs(q_joint) <= MAX_JOINT_DEG).all():
                    raise _Unserved
            # A robtarget's pose at each state, through its tool and work
            # object, and the joints the ideal controller gives it.
            by_state = cold = None
            closest, prev = [], None
            rob_rows = [block[n] for n in rob]
            if rob:
                cold = np.array([block_uses[n].source.record.values for n in rob],
                                float).reshape(-1, 17)
                by_state = states_values(cold[:, :7], calls.dq[picked[rob]], states, False)
                # (What every state's check shares, as _residuals makes it.)
                closest, prev = _closest(solved, rob_rows)
            poses = (res.base, [tools[first + m] for m in rob], [wobjs[first + m] for m in rob])
            R_want, p_want, tcp = solved.R[block], solved.p[block], tcp_of(block_uses)
            for n, solver in enumerate(solvers.values()):
                q = np.empty((len(block), 6))
                if jts:
                    q[jts] = q_joint[n]
                values = None
                if rob:
                    values = np.empty((len(rob), 17))
                    values[:, 7:] = cold[:, 7:]
                    values[:, :7] = by_state[n]
                made.append((n, sl, rob_rows))
                yield (solver, values, poses, q, rob, R_want, p_want, tcp, closest, prev)
    # (Every other part checked by the job's helper, side.py, while this
    # process checks the one before: its IK's threads and this process's
    # own work leave a core free for much of a part.)
    try:
        for got in side.alternate(_state_residuals, parts()):
            n, sl, rob_rows = made.pop(0)
            if got is None:
                return None
            if type(got[0]) is str:
                u = solved.uses[rob_rows[got[1]]]
                raise InternalError(f"{u.file.source.display_path}:{u.line}: the ideal "
                                    "controller finds no solution for the written target of "
                                    f"{u.label}")
            um[n, sl], deg[n, sl] = got
    except _Unserved:
        return None
    return [u.key for u in uses], um, deg


class _Unserved(Exception):
    """A value the numbers read do not serve (the output is parsed again)."""


def _state_residuals(solver: Solver, values, poses, q, rob: list, R_want, p_want, tcp,
                     closest: list, prev) -> tuple | None:
    """One thermal state's residuals (um, deg) of a block of uses: the
    ideal controller's joints of its robtargets' values (rows `rob` of q;
    poses: the base and each one's tool and work object), the others'
    joints as q holds them, on the robot deformed to that state (solver).
    None where a check would stop or note a value; ("no solution", k)
    where the controller finds none for rob[k]. A function of numbers
    (verify_states_relexed hands every other block and state to the job's
    helper)."""
    if rob:
        base, tools, wobjs = poses
        Rf, pf, conf, ok = robtarget_flanges(values, stacked_poses([base] * len(rob)),
                                             stacked_poses(wobjs), stacked_poses(tools), True)
        if not ok.all():
            return None
        # (As Resolver._flanges gives them: each row kept taken.)
        keep = np.flatnonzero(ok)
        got = _ideal(solver, Rf[keep], pf[keep], conf[keep].astype(int), closest, prev)
        bad = np.flatnonzero(np.isnan(got).any(axis=1))
        if len(bad):
            return "no solution", int(bad[0])
        q[rob] = got
    err_p, err_r = solver.deformed_pose_error(q * DEG, R_want, p_want, tcp)
    return err_p * 1000, err_r / DEG


def _resolver(plan: Plan, out_files: dict, written: Written | None,
              states: tuple = ()) -> Resolver:
    """The resolver of the output (float32, as the controller stores
    numbers): out_files where parsed again, else the input's files (with
    `written`, the records as written)."""
    files = [out_files.get(fi, pf) for fi, pf in enumerate(plan.task.files)]
    files += list(plan.task.context)
    # Run-time writes were ruled out on the input; the output adds none. A
    # tool or work object a routine assigns is taken where the plan took it.
    res = Resolver(files, float32=True, usages=plan.resolver.usages, writes=False,
                   track=plan.track, base=plan.resolver.base, written=written,
                   like=plan.resolver, states=states, unreadable=plan.resolver.unreadable,
                   unlisted=plan.resolver.unlisted)
    res.site_names = frozenset(plan.resolver.site_map())
    return res


def _resolved(plan: Plan, res: Resolver, keys: list, uses: list | None = None) -> dict:
    """Each use of `keys` resolved on the output res reads (parsed again),
    as what the check needs of it (use key -> _Written); `uses`, when
    given, receives the uses themselves."""
    wanted = set(keys)
    motions = {k[:2] for k in keys}
    found: dict = {}
    batch: list = []

    def keep():
        # Only what the check needs, a block at a time (not 1e5 TargetUse;
        # verify_states keeps the first state's uses, for the others).
        res.poses()
        for o in batch:
            found[o.key] = _Written.of(o)
        if uses is not None:
            uses.extend(batch)
        batch.clear()
    for fi, pf in enumerate(res.files[:plan.n_written]):
        mi = 0
        for m in pf.modules:
            for motion in m.motions:
                if (fi, mi) in motions:
                    batch.extend(o for o in res.resolve(pf, m, motion, (fi, mi))
                                 if o.key in wanted)
                    if len(batch) >= 8192:
                        keep()
                mi += 1
    keep()
    return found


def _residuals(solved: Solved, solver: Solver, rows: list, many_rows: list, many: list,
               found: dict) -> dict:
    """Residual (um, deg) of the uses of solved rows `rows` (sorted): the
    robtargets evaluated as arrays (many: (R, p, conf) blocks of the rows
    many_rows), the others as found resolved again (use key -> _Written)."""
    # Every robtarget's (R, p, conf) in one stack: the array blocks, then
    # the others; at[row] is its place in it.
    at = {i: n for n, i in enumerate(many_rows)}
    q = {}
    others = []
    for i in rows:
        if i in at:
            continue
        u = solved.uses[i]
        o = found.get(u.key)
        if o is None or o.reason is not None:
            raise InternalError(f"{u.file.source.display_path}:{u.line}: the written target of "
                                f"{u.label} does not resolve ({o.reason if o else 'missing'})")
        if o.kind == "jointtarget":
            q[i] = np.array(o.joints_deg)
        else:
            at[i] = len(many_rows) + len(others)
            others.append(o)
    if others:
        many.append((np.array([o.R for o in others]), np.array([o.p for o in others]),
                     np.array([o.conf for o in others])))
    rob = [i for i in rows if i not in q]
    if rob:
        R_all, p_all, conf_all = (np.concatenate([b[n] for b in many]) for n in range(3))
        order = [at[i] for i in rob]
        got = _ideal_joints(solved, solver, rob, R_all[order], p_all[order], conf_all[order],
                            *_closest(solved, rob))
        qa = np.empty((len(rows), 6))
        place = {i: n for n, i in enumerate(rows)}
        qa[[place[i] for i in rob]] = got
        for i, qi in q.items():
            qa[place[i]] = qi
    else:
        qa = np.array([q[i] for i in rows]).reshape(-1, 6)
    err_p, err_r = solver.deformed_pose_error(qa * DEG, solved.R[rows], solved.p[rows],
                                              tcp_of([solved.uses[i] for i in rows]))
    return dict(zip([solved.uses[i].key for i in rows],
                    zip((err_p * 1000).tolist(), (err_r / DEG).tolist())))


def _closest(solved: Solved, rob: list) -> tuple[list, np.ndarray | None]:
    """Which of the robtargets of solved rows `rob` the controller moves to
    by the solution closest to the previous move's (supervision off, and
    circle points), by their place in rob, and those joints: the
    previous move's nominal solution (its compensated joints are within
    the joint-change bound of them: no other solution is that close)."""
    picks = solved.picks
    closest = [n for n, i in enumerate(rob) if picks.kind[i] == "closest"]
    return closest, (np.array([picks.closest[rob[n]][0] for n in closest]) if closest
                     else None)


def _ideal(solver: Solver, R, p, conf, closest: list, prev) -> np.ndarray:
    """The joints the ideal controller gives robtargets (R, p, conf): by
    their confdata, or (closest, prev: _closest) the solution closest to
    the previous move's; NaN where it finds none."""
    got = solver.solve_nominal(R, p, conf).q_deg
    if closest:
        got = got.copy()
        got[closest] = solver.closest(solver.candidates(R[closest], p[closest]), prev)
    return got


def _ideal_joints(solved: Solved, solver: Solver, rob: list, R, p, conf, closest: list,
                  prev) -> np.ndarray:
    """The joints the ideal controller gives the written robtargets (R, p,
    conf) of solved rows `rob`: by their confdata, or (closest, prev:
    _closest) the solution closest to the previous move's."""
    got = _ideal(solver, R, p, conf, closest, prev)
    for n in np.flatnonzero(np.isnan(got).any(axis=1))[:1].tolist():
        u = solved.uses[rob[n]]
        raise InternalError(f"{u.file.source.display_path}:{u.line}: the ideal "
                            "controller finds no solution for the written target of "
                            f"{u.label}")
    return got


