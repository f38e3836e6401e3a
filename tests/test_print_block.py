"""A CAM program's literals printed by block (issue #14): the edits of a
batch of plain robtarget literals kept as columns (EditColumns) from the
batch to the splice, the verification and the result, and each literal's
new text as one string. Oracles: the loop over literals
(robtarget_texts_many without its columns), the SpanEdit list functions,
and the whole `fix` with the block switched off.
"""

import random
from pathlib import Path

import numpy as np

import pytest

from rapidcomp.compensate import fix as F
from rapidcomp.compensate import report
from rapidcomp.compensate.load import load_solver
from rapidcomp.compensate.plan import Plan, Task
from rapidcomp.edits import (BY_SPAN, EditColumns, EditRun, OverlappingEdits, SpanEdit,
                             apply_edits, columns_of, sorted_columns)
from rapidcomp.kinematics.frames import quat_wxyz_to_matrix
from rapidcomp.rapid.parse import parse_text
from rapidcomp.rewrite import diff as D
from rapidcomp.rewrite import numbers, records

ROOT = Path(__file__).resolve().parents[1]


def _literals(n: int, seed: int):
    """n robtarget declarations in many spellings, and poses and confdata
    for them: positions both sides of MM_KEEP, rotations kept and turned
    (both signs), confdata kept and changed."""
    rng = np.random.default_rng(seed)
    i = np.arange(n)
    xyz = np.round(rng.uniform(-900, 900, (n, 3)), 3)
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    conf = np.concatenate([rng.integers(-3, 4, (n, 3)), rng.integers(0, 8, (n, 1))], axis=1)
    forms = ["{:.3f}", "{:.6f}", "{:g}", "{:.2E}", "{:.0f}", "{:.1f}0"]
    body = "".join(
        f"  CONST robtarget p{k}:=[["
        + ",".join(forms[(k + j) % 6].format(v) for j, v in enumerate(xyz[k])) + "],["
        + ",".join(("{:.9f}" if k % 3 else "{:.6f}").format(v) for v in q[k]) + "],["
        + ",".join(map(str, conf[k])) + "],[9E+09,9E+09,0,-0,1.5E3,9E9]];\n" for k in range(n))
    text = "MODULE M\n" + body + "ENDMODULE\n"
    recs = [d.value for d in parse_text(text, "m.mod").module.declarations]
    values = np.array([r.values for r in recs])
    step = np.array([0.0, 4.9e-7, 5.1e-7, -5.1e-7, 1e-3, 0.25])[i % 6]
    P = values[:, :3] + np.stack([step, -step / 2, np.where(i % 4, 0.0, step)], axis=1)
    w = values[:, 3:7] / np.linalg.norm(values[:, 3:7], axis=1)[:, None]
    w = w + np.where((i % 5 == 1)[:, None], rng.normal(scale=1e-4, size=(n, 4)), 0.0)
    w = np.where((i % 7 == 2)[:, None], -w, w)
    R = np.array([quat_wxyz_to_matrix(x / np.linalg.norm(x)) for x in w])
    C = values[:, 7:11].copy()
    C[i[i % 3 == 0], (i % 4)[i % 3 == 0]] += 1
    return text, recs, R, P, C


def test_block_gives_the_loops_edits_and_literals(monkeypatch):
    text, recs, R, P, C = _literals(500, 5)
    whys = [f"p{j} compensated" for j in range(len(recs))]
    block = records.robtarget_block(recs, R, P, C, whys)
    monkeypatch.setattr(records, "_plain_fields", lambda recs: None)
    loop = records.robtarget_texts_many(recs, R, P, C, whys)
    assert block is not None and len(block.literals) == len(recs) == len(block.at) - 1
    assert list(block.edits) == [e for _, es in loop for e in es]
    assert all(type(e) is SpanEdit for e in block.edits)
    for j, (texts, es) in enumerate(loop):
        assert list(block.edits[block.at[j]:block.at[j + 1]]) == es
        assert block.literals[j] == records.robtarget_literal(texts)
    # Every kind of field is rewritten somewhere, and kept somewhere.
    fields = {(e.start - r.span.start, len(es) > 0)
              for r, (_, es) in zip(recs, loop) for e in es}
    assert len(fields) > 9 and any(not es for _, es in loop)
    # The literals with their edits applied are the block's literals.
    out = apply_edits(text, block.edits)
    for r, lit, j in zip(recs, block.literals, range(len(recs))):
        shift = sum(len(e.replacement) - (e.end - e.start)
                    for e in block.edits[:block.at[j]])
        assert out[r.span.start + shift:r.span.start + shift + len(lit)] == lit


@pytest.mark.parametrize("change", [" ", "\t", "\xa0", "\r\n", "tuple"])
def test_block_declines_literals_not_written_plainly(change):
    text, recs, R, P, C = _literals(40, 6)
    if change == "tuple":
        # A literal the parser lexed field by field (its texts and spans).
        recs[7] = type(recs[7])(recs[7].values, recs[7].lex(), recs[7].span)
    else:
        text = text.replace("],[", "]," + change + "[", 1)
        recs = [d.value for d in parse_text(text, "m.mod").module.declarations]
        assert any(change in r.lexed for r in recs if type(r.lexed) is str)
    assert records.robtarget_block(recs, R, P, C, ["w"] * len(recs)) is None


def _edits(rng: random.Random, text: str) -> list[SpanEdit]:
    out = []
    for _ in range(rng.randint(0, 5)):
        a = rng.randint(0, len(text))
        b = min(len(text) + rng.randint(0, 1), a + rng.randint(-1, 4))
        out.append(SpanEdit(a, b, rng.choice(["", "9", "ab", "\n"]), f"w{len(out)}"))
    return out


def test_columns_splice_and_sort_as_the_list_does():
    rng = random.Random(4)
    ok = refused = 0
    for _ in range(3000):
        text = "".join(rng.choice("ab\nc") for _ in range(rng.randint(0, 30)))
        edits = _edits(rng, text)
        cols = EditColumns.of(edits)
        assert list(sorted_columns(cols)) == sorted(edits, key=BY_SPAN)
        try:
            want = apply_edits(text, edits)
        except OverlappingEdits as exc:
            with pytest.raises(OverlappingEdits) as got:
                apply_edits(text, cols)
            assert str(got.value) == str(exc)
            refused += 1
            continue
        assert apply_edits(text, cols) == want
        ok += 1
    assert ok > 1000 and refused > 500
    # Two insertions at one place keep their order (a stable sort).
    same = [SpanEdit(2, 2, "x", "1"), SpanEdit(0, 1, "y", "2"), SpanEdit(2, 2, "z", "3")]
    assert apply_edits("abc", EditColumns.of(same)) == apply_edits("abc", same) == "ybxzc"


def test_columns_are_a_sequence_of_span_edits():
    from collections.abc import Sequence
    edits = [SpanEdit(1, 2, "x", "a"), SpanEdit(4, 6, "", "b"), SpanEdit(7, 7, "yz", "c")]
    cols = EditColumns.of(edits)
    assert len(cols) == 3 and list(cols) == edits and cols == tuple(edits) == cols.take([0, 1, 2])
    assert cols[1] == edits[1] and type(cols[1]) is SpanEdit and type(cols[1].start) is int
    assert list(cols[1:]) == edits[1:] and cols != tuple(edits[:2]) and not EditColumns.of([])
    assert hash(cols) == hash(tuple(edits)) and cols[-1] == edits[-1]
    # As the tuple it stands for: a Sequence, not equal to a list.
    assert isinstance(cols, Sequence) and cols.index(edits[2]) == 2 and edits[0] in cols
    assert cols != edits and list(reversed(cols)) == edits[::-1]
    with pytest.raises(ValueError):
        cols.starts[0] = 5            # read-only: a result's edits cannot change
    # Its own copies: what it was made from stays the caller's.
    starts, reps = np.array([1, 4]), np.array(["x", ""], dtype=object)
    made = EditColumns(starts, [2, 6], reps, ["a", "b"])
    starts[0], reps[0] = 0, "q"
    assert list(made) == edits[:2] and starts.flags.writeable
    run = EditRun(cols, 1, 3)
    assert run and len(run) == 2 and list(run) == edits[1:] and run == edits[1:]   # (a list's place)
    assert not EditRun(cols, 2, 2) and list(EditRun(cols, 2, 2)) == []
    # Runs of two blocks and edits, in any order: one EditColumns in that order.
    other = EditColumns.of([SpanEdit(9, 9, "q", "d")])
    parts = [EditRun(cols, 2, 3), SpanEdit(0, 0, "s", "e"), SpanEdit(3, 3, "t", "f"),
             EditRun(cols, 0, 1), EditRun(other, 0, 1), EditRun(cols, 1, 2),
             EditRun(cols, 1, 1)]
    want = [edits[2], SpanEdit(0, 0, "s", "e"), SpanEdit(3, 3, "t", "f"), edits[0],
            other[0], edits[1]]
    assert list(columns_of(parts)) == want and len(columns_of([])) == 0


def test_diff_of_columns_is_the_diff_of_the_list():
    rng = random.Random(8)
    for _ in range(500):
        lines = [f"    MoveL [[{rng.randint(0, 999)},{i}]],v100;" for i in range(20)]
        text = rng.choice(["\n", "\r\n"]).join(lines) + "\n"
        edits = []
        for k in sorted(rng.sample(range(20), 5)):
            start = text.index(f",{k}]]") + 1
            edits.append(SpanEdit(start, start + len(str(k)), str(rng.randint(0, 99)), "w"))
        if rng.random() < 0.3:
            edits.append(SpanEdit(0, 0, "  CONST num x:=1;\n", "new"))
        edits.sort(key=BY_SPAN)
        cols = EditColumns.of(edits)
        assert D.unified_diff(text, cols, "a", "b") == D.unified_diff(text, edits, "a", "b")


_EXT = "[9E9,9E9,9E9,9E9,9E9,9E9]"
TEXT = "\n".join([
    "MODULE Whole",
    f"  CONST robtarget pA:=[[300,-50,450],[0.707107,0,0.707107,0],[-1,0,-1,0],{_EXT}];",
    "  PROC run()",
    "    MoveJ pA,v200,z10,tool0;",
    f"    MoveL [[320,-40,460],[0.707107,0,0.707107,0],[-1,0,-1,0],{_EXT}],v200,z10,tool0;",
    "  ENDPROC",
    "ENDMODULE", ""])


def _whole(plan, x=("301.25", "321.5")):
    """Both literals with x rewritten, as the block gives them: each one's
    new text, the edits as columns."""
    recs = [plan.uses[0].source.record, plan.uses[1].source.record]
    fields, edits = {}, []
    for rec, v in zip(recs, x):
        texts = list(rec.texts)
        texts[0] = v
        fields[(0, rec.span.start)] = (rec, records.robtarget_literal(texts))
        s, e = rec.regs[0]
        edits.append(SpanEdit(rec.span.start + s, rec.span.start + e, v, "w"))
    return recs, fields, edits


@pytest.mark.parametrize("hexa", [False, True])
def test_relex_reads_whole_literals_as_their_field_texts(hexa):
    """verify.relex given a literal's new text reads it as it reads its
    field texts: the same records, with the edits as a list or as columns;
    a kept hex field (a literal the parser decoded field by field) is
    values.relex's verdict both ways (it does not re-lex)."""
    text = TEXT.replace(f"[-1,0,-1,0],{_EXT}],v200", "[-1,0,-1,0],[9E9,9E9,0x1F,9E9,9E9,9E9]],v200"
                        ) if hexa else TEXT
    assert ("0x1F" in text) == hexa
    pf = parse_text(text, "m.mod")
    plan = Plan(Task("m.mod", (pf,)))
    recs, fields, edits = _whole(plan)
    by_texts = {k: (rec, lit.replace("[", "").replace("]", "").split(","))
                for k, (rec, lit) in fields.items()}
    assert [len(t) for _, t in by_texts.values()] == [17, 17]
    out_text = apply_edits(text, edits)
    want = F.relex(plan, by_texts, {0: edits}, {0: out_text})
    assert (want is None) == hexa
    for es in (edits, EditColumns.of(edits)):
        got = F.relex(plan, fields, {0: es}, {0: out_text})
        if hexa:
            assert got is None
            continue
        for r in recs:
            a, b = got[(id(pf), r.span.start)], want[(id(pf), r.span.start)]
            assert (a.values, a.lexed, a.span) == (b.values, b.lexed, b.span)
        assert got[(id(pf), recs[0].span.start)].values[0] == 301.25


def test_relex_refuses_a_whole_literal_the_output_does_not_hold():
    pf = parse_text(TEXT, "m.mod")
    plan = Plan(Task("m.mod", (pf,)))
    _, fields, edits = _whole(plan)
    wrong = [edits[0], SpanEdit(edits[1].start, edits[1].end, "321.6")]
    assert F.relex(plan, fields, {0: edits}, {0: apply_edits(TEXT, wrong)}) is None
    # A literal meant with a field too many (in the frame's place): not
    # read as 17 numbers of some other split.
    (k0, (r0, lit0)), (k1, (r1, lit1)) = fields.items()
    bad = {k0: (r0, lit0.replace("[[301.25,", "[[301.25,1,")),
           k1: (r1, lit1.replace("[[321.5,-40,", "[[321.5,"))}
    whole = [SpanEdit(r.span.start, r.span.end, lit, "w") for r, lit in bad.values()]
    assert F.relex(plan, bad, {0: whole}, {0: apply_edits(TEXT, whole)}) is None
    # The same, each literal as meant: read.
    whole = [SpanEdit(r.span.start, r.span.end, lit, "w") for r, lit in fields.values()]
    assert F.relex(plan, fields, {0: whole}, {0: apply_edits(TEXT, whole)}) is not None


@pytest.mark.parametrize("wrong", [("],[", "]],"), ("],[", ",[["), ("],[", ",,,"),
                                   (",0,", "]0,"), (",0,", ",0["), ("[[", "[,")])
def test_plain_literals_have_the_frames_separators(wrong):
    """A literal is plain only with the frame's separators in the frame's
    places (counting them is not enough): relex does not read an output
    that holds one with others (which RAPID would not read as meant)."""
    from rapidcomp.rapid.values import plain_bounds
    pf = parse_text(TEXT, "m.mod")
    plan = Plan(Task("m.mod", (pf,)))
    _, fields, _ = _whole(plan)
    assert plain_bounds([lit for _, lit in fields.values()]) is not None
    bad = {k: (r, lit.replace(*wrong, 1)) for k, (r, lit) in fields.items()}
    lits = [lit for _, lit in bad.values()]
    assert lits != [lit for _, lit in fields.values()]
    assert plain_bounds(lits) is None and plain_bounds(lits[:1]) is None
    assert plain_bounds(lits[:1] * 17) is None
    whole = [SpanEdit(r.span.start, r.span.end, lit, "w") for r, lit in bad.values()]
    assert F.relex(plan, bad, {0: whole}, {0: apply_edits(TEXT, whole)}) is None


@pytest.fixture(scope="module")
def solver():
    return load_solver(str(ROOT / "fixtures" / "warm.csv"), None, False, ("J5=-120:120",))


@pytest.mark.parametrize("mode", ["robtarget", "auto", "absj"])
def test_fix_by_block_is_fix_by_literal(mode, solver, monkeypatch):
    """A CAM program fixed with its literals printed by block gives what
    the loop over literals gives: output, edits, rows, report; and the
    block serves (the result's edits are its columns)."""
    import sys
    sys.path.insert(0, str(ROOT / "bench"))
    from fix import cam_module
    text = cam_module(1500, 3).replace("  PROC Path()\n", "  PROC Path()\n    ConfL\\Off;\n")
    task = Task("cam.mod", (parse_text(text, "cam.mod"),))
    fast = F.fix(task, solver, mode)
    real_block = records.robtarget_block
    monkeypatch.setattr(records, "robtarget_block", lambda *args: None)
    # (Other edits are columns from COLUMNS_FROM of them on: not here.)
    from rapidcomp.compensate import edit as E
    monkeypatch.setattr(E, "COLUMNS_FROM", 10 ** 9)
    slow = F.fix(task, solver, mode)
    assert type(fast.modules[0].edits) is EditColumns
    assert type(slow.modules[0].edits) is tuple
    assert [m.text for m in fast.modules] == [m.text for m in slow.modules]
    assert fast.edits == slow.edits and len(fast.edits) > 1000
    assert fast.rows == slow.rows and fast.summary() == slow.summary()
    meta = {"mode": mode}
    assert report.markdown(fast, meta) == report.markdown(slow, meta)
    assert report.as_json(fast, meta) == report.as_json(slow, meta)
    assert numbers.MM_KEEP == 5e-7
    if mode == "robtarget":
        # The output read back in blocks of a few literals (a CAM program's
        # 1e5 in blocks of 8192): the same verification, row for row.
        from rapidcomp.compensate import verify as V
        served = []
        real = F.relex

        def spy(*args):
            out = real(*args)
            served.append(out is not None and len(out.rows) > 1000)
            return out
        monkeypatch.setattr(records, "robtarget_block", real_block)
        monkeypatch.setattr(V, "RELEX_BLOCK", 7)
        monkeypatch.setattr(F, "relex", spy)
        small = F.fix(task, solver, mode)
        assert served == [True] and type(small.modules[0].edits) is EditColumns
        assert small.rows == fast.rows and small.modules == fast.modules


@pytest.mark.parametrize("case", ["moveabsj", "unplain"])
def test_other_edits_as_columns_give_what_lists_give(case, solver, monkeypatch):
    """A file's edits other than a batch's literal fields (moves turned
    into MoveAbsJ and new declarations; or literals the batch refuses, here
    each with a hexadecimal external axis, edited field by field) are kept
    as EditColumns from COLUMNS_FROM of them on: the splice, the
    verification, the diff and the reports are what the list of SpanEdits
    gives."""
    import sys
    sys.path.insert(0, str(ROOT / "bench"))
    from fix import cam_module
    from rapidcomp.compensate import edit as E
    if case == "moveabsj":
        text, mode = cam_module(300, 5, main=True), "absj"
    else:
        text, mode = cam_module(300, 5).replace("9E+09]]", "0x218711A00]]"), "robtarget"
    task = Task("cam.mod", (parse_text(text, "cam.mod"),))
    monkeypatch.setattr(E, "COLUMNS_FROM", 1)
    cols = F.fix(task, solver, mode)
    monkeypatch.setattr(E, "COLUMNS_FROM", 10 ** 9)
    lists = F.fix(task, solver, mode)
    # (No batch wrote these edits: lists, unless COLUMNS_FROM says columns.)
    assert type(cols.modules[0].edits) is EditColumns
    assert type(lists.modules[0].edits) is tuple
    assert cols.failed == 0 and len(cols.rows) == 300
    assert [m.text for m in cols.modules] == [m.text for m in lists.modules]
    assert [m.diff for m in cols.modules] == [m.diff for m in lists.modules]
    assert cols.edits == lists.edits and len(cols.edits) >= 300
    assert cols.rows == lists.rows
    meta = {"mode": mode}
    assert report.markdown(cols, meta) == report.markdown(lists, meta)
    assert report.as_json(cols, meta) == report.as_json(lists, meta)
    out = cols.modules[0].text
    assert out.count("MoveAbsJ ") == (300 if case == "moveabsj" else 0)
    assert out.count("0x218711A00]]") == (0 if case == "moveabsj" else 300)
