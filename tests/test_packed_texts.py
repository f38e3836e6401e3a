"""EditColumns packs its replacements as fixed-width ASCII bytes when
every one is short ASCII without NUL (a CAM program's 7e5 numbers: no
str object each; edits._packed). Oracle: the same edits as a list of
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


def _packable(reps) -> bool:
    joined = "".join(reps)
    return bool(reps) and joined.isascii() and "\x00" not in joined and \
        max(map(len, reps)) <= E.PACK_WIDTH


def test_packed_columns_read_as_the_edits_they_are_made_of():
    rnd = random.Random(14)
    packed = 0
    for _ in range(600):
        text = "".join(rnd.choice("ab,[]\n\r9 ") for _ in range(rnd.randint(0, 50)))
        pool = SHORT if rnd.random() < 0.6 else SHORT + [rnd.choice(OTHER)]
        edits = _edits(rnd, text, pool)
        reps = [e.replacement for e in edits]
        cols = EditColumns.of(edits)
        assert (cols._texts.dtype.kind == "S") == _packable(reps)
        packed += cols._texts.dtype.kind == "S"
        assert list(cols) == edits and all(type(e.replacement) is str for e in cols)
        assert cols.texts() == reps and cols.joined() == "".join(reps)
        assert cols.lengths().tolist() == [len(r) for r in reps]
        assert cols.lengths().dtype == np.int64
        for k in range(len(edits)):
            assert cols.text(k) == reps[k] and type(cols.text(k)) is str
            assert cols[k] == edits[k]
            assert cols.texts(k, k + 2) == reps[k:k + 2]
        order = rnd.sample(range(len(edits)), len(edits))
        assert list(cols.take(order)) == [edits[k] for k in order]
        assert apply_edits(text, cols) == apply_edits(text, tuple(edits))
        # The diff reads the line breaks of the replacements joined.
        ordered = sorted(edits, key=E.BY_SPAN)
        if all(a.end <= b.start for a, b in zip(ordered, ordered[1:])):
            assert D.unified_diff(text, cols, "a", "b") == D.unified_diff(text, edits, "a", "b")
    assert 150 < packed < 550


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
        assert got._texts.dtype.kind in "SO"
        blocks = [EditColumns.of(want[:2]), EditColumns.of(want[2:])]
        assert list(EditColumns.concat(blocks)) == want
    assert len(EditColumns.concat([])) == 0


def test_unpacked_when_asked():
    cols = EditColumns([0], [1], ["7"], ["w"], pack=False)
    assert cols._texts.dtype == object and list(cols) == [SpanEdit(0, 1, "7", "w")]
    assert EditColumns([0], [1], ["7"], ["w"])._texts.dtype.kind == "S"
