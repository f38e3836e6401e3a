"""EditColumns packs its replacements as fixed-width ASCII bytes, those
that are not short ASCII without NUL kept aside as str (a CAM program's 7e5
numbers and a declaration inserted: no str object per number;
edits.Texts). Oracle: the same edits as a list of
SpanEdit (str replacements, the loop of apply_edits and the diff's own),
on seeded random replacements of every kind: numbers, empty, non-ASCII,
a NUL (which the bytes' padding would swallow), line breaks str sees and
bytes do not (\\x0b, \\x1c, \\x85), and texts longer than PACK_WIDTH."""

import random

import numpy as np

from rapidcomp import edits as E
from rapidcomp.edits import EditColumns, SpanEdit, apply_edits, columns_of
from rapidcomp.rewrite import diff as D

SHORT = ["", "0", "-12.5", "1E+09", "[1,2]", ";", "x" * E.PACK_WIDTH, "\t", " "]
OTHER = ["\u00e9", "a\x00", "\x00", "1\x0b2", "\x1c", "\x85", "x" * (E.PACK_WIDTH + 1),
         "\r\n  CONST jointtarget jt:=[[1,2,3,4,5,6],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];"]


def _edits(rnd, text, pool):
    cuts = sorted(rnd.sample(range(len(text) + 1), rnd.randint(0, min(30, len(text) + 1))))
    return [SpanEdit(a, b if rnd.random() < 0.7 else a, rnd.choice(pool), f"e{a}")
            for a, b in zip(cuts[::2], cuts[1::2])]


def _aside(reps) -> list[str]:
    return [r for r in reps if not (r.isascii() and "\x00" not in r and len(r) <= E.PACK_WIDTH)]


def test_packed_columns_read_as_the_edits_they_are_made_of():
    rnd = random.Random(14)
    with_aside = 0
    for _ in range(600):
        text = "".join(rnd.choice("ab,[]\n\r9 ") for _ in range(rnd.randint(0, 50)))
        pool = SHORT if rnd.random() < 0.6 else SHORT + [rnd.choice(OTHER)]
        edits = _edits(rnd, text, pool)
        reps = [e.replacement for e in edits]
        cols = EditColumns.of(edits)
        assert cols._texts.is_packed and cols._texts.wide == _aside(reps)
        with_aside += bool(cols._texts.wide)
        assert list(cols) == edits and all(type(e.replacement) is str for e in cols)
        assert cols.texts() == reps and cols.joined() == "".join(reps)
        assert cols.lengths().tolist() == [len(r) for r in reps]
        assert cols.lengths().dtype == np.int64
        for k in range(len(edits)):
            assert cols.text(k) == reps[k] and type(cols.text(k)) is str
            assert cols[k] == edits[k]
            assert cols.texts(k, k + 2) == reps[k:k + 2]
        order = rnd.sample(range(len(edits)), len(edits)) * 2
        assert list(cols.take(order)) == [edits[k] for k in order]
        mask = [rnd.random() < 0.5 for _ in edits]
        assert list(cols.take(np.array(mask, bool))) == [e for e, m in zip(edits, mask) if m]
        assert list(cols[1::2]) == edits[1::2] and list(cols[::-1]) == edits[::-1]
        if edits:
            assert cols.text(-1) == reps[-1] and cols[-1] == edits[-1]
        taken = cols.take(order)
        assert taken.joined() == "".join(reps[k] for k in order)
        assert taken.lengths().tolist() == [len(reps[k]) for k in order]
        assert apply_edits(text, cols) == apply_edits(text, tuple(edits))
        # The diff reads the line breaks of the replacements joined.
        ordered = sorted(edits, key=E.BY_SPAN)
        if all(a.end <= b.start for a, b in zip(ordered, ordered[1:])):
            assert D.unified_diff(text, cols, "a", "b") == D.unified_diff(text, edits, "a", "b")
    assert 40 < with_aside < 300


def test_packed_and_unpacked_parts_join_in_order():
    """columns_of and concat of blocks packed and not, and runs of them:
    one EditColumns of str replacements in order (bytes and str never mix)."""
    rnd = random.Random(7)
    for _ in range(200):
        parts, want = [], []
        for _ in range(rnd.randint(1, 5)):
            pool = SHORT if rnd.random() < 0.5 else OTHER
            edits = [SpanEdit(i, i, rnd.choice(pool), "w") for i in range(rnd.randint(0, 4))]
            block = EditColumns.of(edits)
            if edits and rnd.random() < 0.5:
                i = rnd.randrange(len(edits))
                parts.append(E.EditRun(block, i, len(edits)))
                want += edits[i:]
            else:
                parts.extend(edits)
                want += edits
        got = columns_of(parts)
        assert list(got) == want and got.texts() == [e.replacement for e in want]
        assert got._texts.is_packed or not want
        blocks = [EditColumns.of(want[:2]), EditColumns.of(want[2:])]
        assert list(EditColumns.concat(blocks)) == want
    assert len(EditColumns.concat([])) == 0


def test_unpacked_when_asked():
    cols = EditColumns([0], [1], ["7"], ["w"], pack=False)
    assert cols._texts.packed.dtype == object and list(cols) == [SpanEdit(0, 1, "7", "w")]
    packed = EditColumns([0], [1], ["7"], ["w"])
    assert packed._texts.packed.dtype.kind == "S"
    # Bytes given as such are texts, packed or not (never bytes read back).
    again = EditColumns(packed.starts, packed.ends, packed._texts.packed, packed.whys,
                        pack=False)
    assert again.texts() == ["7"] and list(again) == list(packed)
    edits = [SpanEdit(0, 1, "7", "w"), SpanEdit(2, 2, "x" * (E.PACK_WIDTH + 1), "v")]
    loose = EditColumns.of(edits, pack=False)
    assert loose._texts.packed.dtype == object and list(loose) == edits
    assert loose.joined() == "7" + "x" * (E.PACK_WIDTH + 1) and loose.lengths().tolist() == [1, 25]


def test_a_cam_program_with_a_declaration_inserted_stays_packed():
    """One long text among many numbers (a MoveJ turned into MoveAbsJ on a
    new jointtarget in a CAM program): the numbers stay packed, through
    columns_of, take and concat, and read back in order."""
    nums = EditColumns.of([SpanEdit(10 * k, 10 * k + 3, f"{k}.5", "n") for k in range(1000)])
    decl = SpanEdit(5, 5, "\n  CONST jointtarget jt_p0:=[[1,2,3,4,5,6],[9E+09,9E+09,9E+09,"
                    "9E+09,9E+09,9E+09]];", "d")
    got = columns_of([E.EditRun(nums, 0, 1), decl, E.EditRun(nums, 1, 1000)])
    want = [nums[0], decl] + list(nums)[1:]
    assert list(got) == want and got._texts.is_packed and got._texts.wide == [decl.replacement]
    assert got._texts.wide_at.tolist() == [1] and got._texts.packed.dtype.itemsize == 5
    assert got.joined() == "".join(e.replacement for e in want)
    assert got.text(1) == decl.replacement and got.texts(1, 2) == [decl.replacement]
    assert apply_edits("x" * 10000, got) == apply_edits("x" * 10000, want)
