"""The review report of a fix: Markdown and JSON with the same content.

Deterministic (no timestamps, no absolute paths: modules are named by
their path inside the task), so a report can be committed next to the
program it reviews. One report covers a task: its summary and notes, then
per module the diff and the rows of its motions.
"""

from __future__ import annotations

import json
import re

from collections.abc import Iterable, Iterator
from itertools import islice

import numpy as np

from ..rapid.ast import NAME_PATTERN
from .fix import FixResult
from .plan import line_ranges
from .rows import BASE_FIELDS, FIELDS, UNTOUCHED, Rows, UseRow, number_columns


def _num(x, fmt: str) -> str:
    return "-" if x is None else format(x, fmt)


_ROW_FORMATS: dict = {}


def _joints(q, fmt: str = ".4f") -> str:
    """The values of q, each format(v, fmt), space separated: with one %
    operation (the same conversion; a CAM report has 3e5 of these)."""
    if q is None:
        return "-"
    f = _ROW_FORMATS.get((len(q), fmt))
    if f is None:
        f = _ROW_FORMATS[(len(q), fmt)] = " ".join(["%" + fmt] * len(q))
    return f % tuple(q)


def _conf(c) -> str:
    if c is None:
        return "-"
    # (A CAM report's 2e5 confdata cells hold a few values: each written once.
    # A row's confdata are ints: equal tuples, equal texts.)
    text = _CONF_TEXTS.get(c)
    if text is None:
        if len(_CONF_TEXTS) >= 4096:
            _CONF_TEXTS.clear()
        text = _CONF_TEXTS[c] = "[" + ",".join(map(str, c)) + "]"
    return text


_CONF_TEXTS: dict[tuple, str] = {}


def summary_lines(result: FixResult) -> list[str]:
    s = result.summary()
    untouched = sum(s["untouched"].values())
    out = [f"{s['compensated']} of {s['target_uses']} target uses compensated, "
           f"{s['not_compensated']} not compensated, {untouched} untouched"]
    several = len(result.modules) > 1
    rows = result.rows
    out += untouched_lines(rows, s["untouched"], several)
    out += failure_lines([rows[k] for k, status in enumerate(rows.column("status"))
                          if status == "not compensated"], several)
    if s["error_before_um"]:
        b, a = s["error_before_um"], s["residual_after_um"]
        of = ("" if s["compensated"] == s["target_uses"]
              else f" (the {s['compensated']} compensated uses; the others keep theirs)")
        out.append(f"predicted TCP error on the warm robot{of}: max {b['max']:.1f} um, mean "
                   f"{b['mean']:.1f} um -> after: max {a['max']:.3f} um, mean {a['mean']:.3f} um")
    if several:
        out.append(f"{s['modules_changed']} of {len(result.modules)} modules changed")
    return out


def untouched_lines(rows: Rows, untouched: dict, several: bool) -> list[str]:
    """A line per reason of the untouched rows (untouched: reason -> how
    many, as summary() counts them), with their places (the console's
    line is what a user reads first)."""
    by_reason: dict[str, list[UseRow]] = {}
    if untouched:
        for k, (status, reason) in enumerate(zip(rows.column("status"), rows.column("reason"))):
            if status == UNTOUCHED:
                by_reason.setdefault(reason, []).append(rows[k])
    return [f"{UNTOUCHED} ({n}): {reason} [{_places(by_reason[reason], several)}]"
            for reason, n in untouched.items()]


def failure_lines(rows: list[UseRow], several: bool, label: str = "not compensated") -> list[str]:
    """One line per failure; failures sharing a reason (a missing module
    fails every move that uses it) in one line with their places; and
    failures whose reasons differ only in their numbers and the names of
    their own targets (a CAM program near the wrist singularity: each its
    own J5 and line; a missing data module: each its own target), in one
    line with the first one's reason where they would take more than ALIKE
    lines."""
    by_reason: dict[str, list[UseRow]] = {}
    for r in rows:
        by_reason.setdefault(r.reason, []).append(r)
    keys = {reason: _alike(reason, rs[0].target) for reason, rs in by_reason.items()}
    # The lines each key's reasons take one by one: a reason of one or two
    # failures a line each, of more one line.
    lines: dict[str, int] = {}
    for reason, rs in by_reason.items():
        lines[keys[reason]] = lines.get(keys[reason], 0) + (len(rs) if len(rs) <= 2 else 1)
    folded: dict[str, list[UseRow]] = {}
    for reason, rs in by_reason.items():
        if lines[keys[reason]] > ALIKE:
            folded.setdefault(keys[reason], []).extend(rs)
    out = []
    for reason, rs in by_reason.items():
        group = folded.get(keys[reason])
        if group is not None:
            if group[0] is not rs[0]:
                continue                              # (said with its first)
            at = (f"{group[0].file}:{group[0].line}" if several
                  else f"line {group[0].line}")
            own = ("numbers" if len({_NUMBERS.sub("#", r.reason or "") for r in group}) == 1
                   else "target and numbers")
            out.append(f"{label} ({len(group)} alike, each with {own} of its own; as {at}): "
                       f"{group[0].reason} [{_places(group, several)}]")
        elif len(rs) <= 2:
            for r in rs:
                where = f"{r.file}:{r.line}" if several else f"line {r.line}"
                out.append(f"{label}: {where} {r.instruction} {r.target}: {reason}")
        else:
            out.append(f"{label} ({len(rs)}): {reason} [{_places(rs, several)}]")
    return out


# Failures whose reasons differ in their numbers only are said one by one
# up to this many.
ALIKE = 10


def _places(rs: list[UseRow], several: bool) -> str:
    places: dict[str, list[int]] = {}
    for r in rs:
        places.setdefault(r.file, []).append(r.line)
    return "; ".join((f"{f} " if several else "") + ("line " if len(set(lines)) == 1 else "lines ")
                     + line_ranges(sorted(set(lines))) + _runs(rs, f, lines)
                     for f, lines in places.items())


def _runs(rs: list[UseRow], file: str, lines: list[int]) -> str:
    """Which runs of one statement in a loop they are, where that is all
    they are and they are few (line 9, i=1, i=2, i=4: a new user could not
    tell which elements of an array were refused with another)."""
    if len(set(lines)) != 1 or len(lines) > RUNS_SAID:
        return ""
    runs = [r.target.rsplit(" [", 1)[1][:-1] for r in rs
            if r.file == file and r.target.endswith("]") and " [" in r.target]
    return f" ({', '.join(runs)})" if len(runs) == len(lines) > 1 else ""


# Runs of a loop said by their index, at most (more: the report's rows).
RUNS_SAID = 8


# A reason's numbers (a joint's value, a line): reasons alike but for them
# are said in one line. (Not digits of a word: J1 and J5, pS21 are names.)
_NUMBERS = re.compile(r"(?<![\w.])[+-]?\d+(?:\.\d+)?(?!\w)")


def _alike(reason: str | None, target: str) -> str:
    """What reasons alike but for their numbers and the names their own
    target is written with (p0 is not declared ..., p1 is not declared ...;
    Offs(p7, 0, 0, 10): p7 ...) share."""
    reason = reason or ""
    names = set(_NAME.findall(target))
    if names:
        # (One pass of one pattern: a regex per name, 1e5 distinct target
        # names of a program whose data module is missing, compiled each.)
        reason = _WHOLE_NAME.sub(lambda m: "<name>" if m.group() in names else m.group(),
                                 reason)
    return _NUMBERS.sub("#", reason)


# A name in a target's text (p10, pPath_3, Offs); in a reason, a whole one.
_NAME = re.compile(rf"(?<![\w.]){NAME_PATTERN}")
_WHOLE_NAME = re.compile(rf"(?<![\w.]){NAME_PATTERN}(?![\w])")


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def _notes(r: UseRow) -> str:
    parts = ([r.reason] if r.reason else []) + list(r.warnings)
    return _cell("; ".join(parts))


def markdown(result: FixResult, meta: dict, pieces: bool = False) -> str | Iterator[str]:
    """The Markdown report; pieces: the same text as an iterator of pieces
    (a CAM program's report, ~75 MB, is written as it is made)."""
    out = _pieces(_markdown_lines(result, meta))
    return out if pieces else "".join(out)


# A report rendered in pieces is written as such (a CAM program's Markdown
# report has 3e5 lines, its JSON 4e6: not held whole as text and bytes):
# lines per piece of the Markdown, targets per piece of the JSON.
CHUNK_LINES = 4096
CHUNK_TARGETS = 4096


def _pieces(lines: Iterable[str]) -> Iterator[str]:
    """Each CHUNK_LINES lines, each line ended by a line break."""
    it = iter(lines)
    while True:
        batch = list(islice(it, CHUNK_LINES))
        if not batch:
            return
        yield "\n".join(batch) + "\n"


def _markdown_lines(result: FixResult, meta: dict) -> Iterator[str]:
    out = [f"# rapidcomp fix: {result.program}", ""]
    out += ["| | |", "|---|---|"]
    for k, v in meta.items():
        out.append(f"| {k} | {_cell(str(v))} |")
    out += ["", "## Summary", ""]
    out += [f"- {line}" for line in summary_lines(result)]
    if result.notes:
        out += ["", "## Notes", ""] + [f"- {n}" for n in result.notes]
    yield from out
    several = len(result.modules) > 1
    rows = result.rows
    cells = result.cells if result.cells is not None else [None] * len(rows)
    files = rows.column("file")
    for m in result.modules:
        ks = [k for k, file in enumerate(files) if file == m.path]
        if several:
            yield from ["", f"## {m.path}"]
            if not ks and not m.edits:
                yield from ["", "No motion instructions; written byte for byte as it was."]
                continue
        level = "###" if several else "##"
        yield from ["", f"{level} Diff", ""]
        if m.diff:
            yield "```diff"
            yield from m.diff
            yield "```"
        else:
            yield "No change."
        yield from ["", f"{level} Targets", ""]
        yield from _table(rows, ks, cells, "transient" in meta)


def _table(rows: Rows, ks: list[int], cells, transient: bool = False) -> Iterator[str]:
    """The table of rows ks; each row with its number cells when made
    already (number_cells; cells[k] of row k), else None."""
    if not ks:
        yield "No motion instructions."
        return
    after = ("after = the written values as the controller computes them at run time "
             "(float32), the worst over the thermal states s = 0, 0.25, 0.5, 0.75, 1, each on "
             "the robot deformed by s x profile; compensated joints = the warm robot's (s = 1)."
             if transient else
             "after = the written values (rounded to float32 as the controller stores them) on "
             "the warm robot.")
    out = ["Joints in degrees; rule = how the controller chooses the joints (confdata, or "
           "the solution closest to the previous move where configuration supervision is "
           "off); error = TCP position error of the uncompensated program on the warm robot; "
           + after, "",
           "| line | instruction | target | status | rule | action | nominal joints | "
           "compensated joints | delta joints | error um | error deg | after um | "
           "conf before | conf after | notes |",
           "|---:|---|---|---|---|---|---|---|---|---:|---:|---:|---|---|---|"]
    yield from out
    # (Each block's fields taken from the columns at once.)
    for at in range(0, len(ks), _TABLE_BLOCK):
        block = ks[at:at + _TABLE_BLOCK]
        yield from (_row_of(rows, k, cells[k], b) for k, b in zip(block, rows.bases(block)))


_TABLE_BLOCK = 4096


# A row with every number (a CAM report has 1e5): two % operations, the same
# conversions as format() (tested against _row_general). Its numbers from
# the nominal joints to the error are _CELLS, which number_cells makes too.
_CELLS = (" ".join(["%.4f"] * 6) + " | " + " ".join(["%.4f"] * 6) + " | "
          + " ".join(["%+.5f"] * 6) + " | %.1f | %.4f")
_FULL_ROW = "| %s | %s | %s | %s | %s | %s | %s | %.3f | %s | %s | %s |"


def _full(r: UseRow) -> bool:
    qn, qc, dq = r.nominal_deg, r.compensated_deg, r.delta_deg
    return not (qn is None or qc is None or dq is None or len(qn) != 6 or len(qc) != 6
                or len(dq) != 6 or r.error_um is None or r.error_deg is None
                or r.residual_um is None)


def _row(r: UseRow, cells: str | None = None) -> str:
    """r's line of the table; `cells`: its number cells when made already
    (number_cells, of r's own numbers)."""
    if not _full(r):
        return _row_general(r)
    if cells is None:
        cells = _CELLS % (*r.nominal_deg, *r.compensated_deg, *r.delta_deg, r.error_um,
                          r.error_deg)
    return _FULL_ROW % (r.line, r.instruction, _cell(r.target), r.status, _cell(r.rule or "-"),
                        _cell(r.action or "-"), cells, r.residual_um, _conf(r.conf_before),
                        _conf(r.conf_after), _notes(r))


# Where each field is in a row of Rows (Rows.base).
_AT_LINE, _AT_INSTRUCTION, _AT_TARGET, _AT_STATUS, _AT_RULE, _AT_ACTION = range(1, 7)
_AT_ERROR_UM, _AT_ERROR_DEG, _AT_RESIDUAL_UM = (BASE_FIELDS.index(f) for f in (
    "error_um", "error_deg", "residual_um"))
_AT_CONF_BEFORE, _AT_CONF_AFTER, _AT_WARNINGS, _AT_REASON = (BASE_FIELDS.index(f) for f in (
    "conf_before", "conf_after", "warnings", "reason"))
assert BASE_FIELDS[1:7] == ("line", "instruction", "target", "status", "rule", "action")


def _row_of(rows: Rows, k: int, cells: str | None = None, b: tuple | None = None) -> str:
    """_row(rows[k], cells), read from the row's fields (b: rows.base(k),
    when the caller has it) where it has every number (no UseRow nor
    tuples of joints made: a CAM report's 1e5)."""
    if not rows.full(k):
        return _row_general(rows[k])
    if b is None:
        b = rows.base(k)
    if cells is None:
        qn, qc, dq = rows.joints(k)
        cells = _CELLS % (*qn, *qc, *dq, b[_AT_ERROR_UM], b[_AT_ERROR_DEG])
    reason, warnings = b[_AT_REASON], b[_AT_WARNINGS]
    notes = _cell("; ".join(([reason] if reason else []) + list(warnings)))
    return _FULL_ROW % (b[_AT_LINE], b[_AT_INSTRUCTION], _cell(b[_AT_TARGET]), b[_AT_STATUS],
                        _cell(b[_AT_RULE] or "-"), _cell(b[_AT_ACTION] or "-"), cells,
                        b[_AT_RESIDUAL_UM], _conf(b[_AT_CONF_BEFORE]), _conf(b[_AT_CONF_AFTER]), notes)


def number_cells(qn_deg, qc_deg, err_p, err_r) -> list[str | None]:
    """Of each solved target (Solved's q_deg rows, err_p, err_r): the
    table's cells from its nominal joints to its error, as _row writes
    them for a row of these numbers (rows.number_columns, which the rows
    take too); None where the joints have a NaN. A CAM report has 1e5:
    made beside the job (side.py) while it goes on."""
    if np.ndim(qn_deg) != 2 or np.shape(qn_deg)[1] != 6:
        return [None] * len(qn_deg)
    return [None if a is None or b is None or c is None else _CELLS % (*a, *b, *c, e, d)
            for a, b, c, e, d in zip(*number_columns(qn_deg, qc_deg, err_p, err_r))]


def _row_general(r: UseRow) -> str:
    return (f"| {r.line} | {r.instruction} | {_cell(r.target)} | {r.status} | "
            f"{_cell(r.rule or '-')} | {_cell(r.action or '-')} | {_joints(r.nominal_deg)} | "
            f"{_joints(r.compensated_deg)} | {_joints(r.delta_deg, '+.5f')} | "
            f"{_num(r.error_um, '.1f')} | {_num(r.error_deg, '.4f')} | "
            f"{_num(r.residual_um, '.3f')} | {_conf(r.conf_before)} | {_conf(r.conf_after)} | "
            f"{_notes(r)} |")


def as_json(result: FixResult, meta: dict, pieces: bool = False) -> str | Iterator[str]:
    """json.dumps(doc, indent=2) of the report, the targets last; pieces:
    the same text as an iterator of pieces (a CAM program's, ~150 MB, is
    written as it is made)."""
    out = _json_pieces(result, meta)
    return out if pieces else "".join(out)


def _json_pieces(result: FixResult, meta: dict) -> Iterator[str]:
    """Each target is encoded on its own and indented to its place (a JSON
    string holds no line break): the same text as json.dumps of the whole,
    without the one list of 1e7 pieces the encoder makes of a CAM
    program's 1e5 targets at once (~600 MB; tested against json.dumps of
    the whole)."""
    doc = {
        "program": result.program,
        **meta,
        "summary": result.summary(),
        "notes": list(result.notes),
        "modules": [{"path": m.path, "changed": bool(m.edits), "diff": list(m.diff)}
                    for m in result.modules],
    }
    head = json.dumps(doc, indent=2)
    if not result.rows:
        yield head[:-2] + ',\n  "targets": []\n}\n'
        return
    yield head[:-2] + ',\n  "targets": [\n    '
    rows = result.rows
    made = result.json_cells
    for at in range(0, len(rows), CHUNK_TARGETS):
        ks = range(at, min(at + CHUNK_TARGETS, len(rows)))
        block = _json_block_made(rows, ks, made) if made is not None else None
        piece = ",\n    ".join(block if block is not None else _json_block(rows.parts(ks)))
        yield piece if at == 0 else ",\n    " + piece
    yield "\n  ]\n}\n"


# One target of the JSON report as json.dumps(indent=2) writes it, indented
# to its place in the list: the field names and layout in one % template,
# each value as the encoder writes it (a CAM report has 1e5 targets; the
# encoder's Python code took ~40 us each). A value of another kind than
# the fields hold (a bool, a numpy number, a dict) goes to the encoder.
_ENCODE = json.JSONEncoder(indent=2).encode
_STR = json.encoder.encode_basestring_ascii         # (ensure_ascii, as the encoder)
_TARGET = "{\n" + ",\n".join(f'      "{name}": %s' for name in FIELDS) + "\n    }"
_ITEMS = ",\n        "
_INF = float("inf")
# A target's text from its nominal joints to its error (FIELDS[7:12]), the
# numbers the solve gives (json_cells: made beside the job), and the
# template that takes it whole in their place.
_MIDDLE = ",\n".join(f'      "{name}": %s' for name in FIELDS[7:12])
_TARGET_MADE = "{\n" + ",\n".join([*(f'      "{name}": %s' for name in FIELDS[:7]), "%s",
                                    *(f'      "{name}": %s' for name in FIELDS[12:])]) + "\n    }"
assert FIELDS[7:12] == ("nominal_deg", "compensated_deg", "delta_deg", "error_um", "error_deg")


class _Other(Exception):
    """A value the template does not write: the encoder does."""


def _text(x) -> str:
    if x is None:
        return "null"
    if type(x) is not str:
        raise _Other
    return _STR(x)


def _number(x) -> str:
    t = type(x)
    if t is float:
        # (json's own spelling of the non-finite ones)
        if x != x:
            return "NaN"
        if x == _INF:
            return "Infinity"
        if x == -_INF:
            return "-Infinity"
        return float.__repr__(x)
    if t is int:
        return int.__repr__(x)
    if x is None:
        return "null"
    raise _Other


def _array(xs, item) -> str:
    if xs is None:
        return "null"
    if type(xs) is not tuple and type(xs) is not list:
        raise _Other
    if not xs:
        return "[]"
    return "[\n        " + _ITEMS.join(map(item, xs)) + "\n      ]"


def _reals(xs) -> str:
    """_array(xs, _number) for a row's joints: a tuple of finite floats
    (1e5 rows, 3 of them each) as one join of float's repr (the encoder's
    text of a float, of a float subclass too). Anything else (an int or a
    bool raises TypeError in float's repr; a NaN or an infinity is the only
    repr with an n) goes value by value."""
    if type(xs) is tuple and xs:
        try:
            text = _ITEMS.join(map(float.__repr__, xs))
        except TypeError:
            return _array(xs, _number)
        if "n" not in text:
            return "[\n        " + text + "\n      ]"
    return _array(xs, _number)


def json_target(r: UseRow) -> str:
    """r as the JSON report's list holds it: the encoder's text of
    r.as_dict(), each line after the first indented by 4 more."""
    return _json_target(*(getattr(r, name) for name in FIELDS))


def _json_parts(b: tuple, qn, qc, dq) -> str:
    """json_target of a row's fields but its joints (Rows.parts) and its
    joints."""
    try:
        return _TARGET % (
            _text(b[0]), _number(b[1]), _text(b[2]), _text(b[3]), _text(b[4]), _text(b[5]),
            _text(b[6]), _reals(qn), _reals(qc), _reals(dq), _number(b[7]), _number(b[8]),
            _number(b[9]), _number(b[10]), _array(b[11], _number), _array(b[12], _number),
            _array(b[13], _text), _text(b[14]))
    except _Other:
        return _json_target(*b[:7], qn, qc, dq, *b[7:])


def _json_block(parts: list[tuple]) -> list[str]:
    """_json_parts of each of `parts` (Rows.parts: (fields but the joints,
    joints)), made a column at a time: a text column's distinct values
    encoded once (a CAM report's 1e5 rows name a few files, instructions,
    statuses and actions), a confdata or warnings column's distinct
    objects once (a row's are shared: one per confdata), the rest value by
    value; then each row's template. A value the template does not write:
    the block row by row (_json_parts, the encoder where it must)."""
    if not parts:
        return []
    try:
        joints = [[_reals(q[n]) for _, q in parts] for n in range(3)]
        head, numbers, tail = _base_columns([b for b, _ in parts], range(7, 11))
    except _Other:
        return [_json_parts(b, *q) for b, q in parts]
    return [_TARGET % row for row in zip(*head, *joints, *numbers, *tail)]


def _base_columns(bs: list[tuple], numbered) -> tuple[list, list, list]:
    """The JSON texts of rows' fields but their joints (Rows.base), a
    column at a time: (the seven before the joints, the numbers of the
    columns `numbered`, the four after the numbers: confdata before and
    after, warnings, reason). A text column's distinct values are encoded
    once, a confdata or warnings column's distinct objects once, the rest
    value by value; _Other where a value is not of the kinds the template
    writes."""
    cols = list(zip(*bs))
    head = [_distinct(cols[k], _text) if k != 1 else list(map(_number, cols[1]))
            for k in range(7)]
    numbers = [list(map(_number, cols[k])) for k in numbered]
    tail = [*(_same_objects(cols[k], _number) for k in (11, 12)),
            _same_objects(cols[13], _text), _distinct(cols[14], _text)]
    return head, numbers, tail


def json_cells(qn_deg, qc_deg, err_p, err_r) -> list[str | None]:
    """Of each solved target (Solved's q_deg rows, err_p, err_r): its JSON
    text from its nominal joints to its error (_MIDDLE), as json_target
    writes them for a row with all three joints (rows.number_columns,
    which the rows take too: the same numbers; a joints row with a NaN is
    null). A CAM report has 1e5: made beside the job (side.py) while it
    makes the rows and writes the Markdown report. None where the joints
    are not rows of six (the report makes those texts)."""
    if np.ndim(qn_deg) != 2 or np.shape(qn_deg)[1] != 6:
        return [None] * len(qn_deg)
    return [_MIDDLE % (_reals(a), _reals(b), _reals(c), _number(e), _number(d))
            for a, b, c, e, d in zip(*number_columns(qn_deg, qc_deg, err_p, err_r))]


def _json_block_made(rows: Rows, ks: range, made) -> list[str] | None:
    """_json_block of rows ks, each row's text from its nominal joints to
    its error taken from `made` (json_cells of its solved row: made[k] of
    row k) where the row has all three joints, else made here; None where
    a value is not of the kinds the template writes (the caller's
    _json_block: the encoder where it must)."""
    bs = rows.bases(ks)
    # (A code 2i + 1: all three joints of solved row i; -1 or 2i: not.)
    middles = [made[k] if c >= 0 and c & 1 else None for k, c in zip(ks, map(rows.code, ks))]
    try:
        for n in [n for n, m in enumerate(middles) if m is None]:
            (b, q), = rows.parts([ks[n]])
            middles[n] = _MIDDLE % (_reals(q[0]), _reals(q[1]), _reals(q[2]), _number(b[7]),
                                    _number(b[8]))
        head, numbers, tail = _base_columns(bs, (9, 10))
    except _Other:
        return None
    return [_TARGET_MADE % row for row in zip(*head, middles, *numbers, *tail)]


def _distinct(col, encode) -> list[str]:
    """encode() of each value of a text column, each distinct value once
    (equal values of a text column have one text: a str equals no other
    kind; one that is not hashable is not a text)."""
    try:
        memo = {x: encode(x) for x in set(col)}
    except TypeError:
        raise _Other from None
    return list(map(memo.__getitem__, col))


def _same_objects(col, item) -> list[str]:
    """_array(x, item) of each value of a column, once per object (not per
    equal value: (1, 0) and (1.0, 0) are equal, their texts are not)."""
    memo: dict = {}
    out = []
    for x in col:
        t = memo.get(id(x))
        if t is None:
            t = memo[id(x)] = _array(x, item)
        out.append(t)
    return out


def _json_target(file, line, instruction, target, status, rule, action, nominal_deg,
                 compensated_deg, delta_deg, error_um, error_deg, residual_um, residual_deg,
                 conf_before, conf_after, warnings, reason) -> str:
    """json_target of a row's fields (Rows.values: no UseRow made)."""
    try:
        return _TARGET % (
            _text(file), _number(line), _text(instruction), _text(target), _text(status),
            _text(rule), _text(action), _reals(nominal_deg), _reals(compensated_deg),
            _reals(delta_deg), _number(error_um), _number(error_deg), _number(residual_um),
            _number(residual_deg), _array(conf_before, _number), _array(conf_after, _number),
            _array(warnings, _text), _text(reason))
    except _Other:
        return _ENCODE(dict(zip(FIELDS, (
            file, line, instruction, target, status, rule, action, nominal_deg,
            compensated_deg, delta_deg, error_um, error_deg, residual_um, residual_deg,
            conf_before, conf_after, warnings, reason)))).replace("\n", "\n    ")
