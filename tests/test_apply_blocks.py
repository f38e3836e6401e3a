"""Edits as columns are spliced APPLY_BLOCK at a time (edits.py): the same
text as the edits applied one by one (the SpanEdit path, a separate
loop), for blocks of 1 to 64 edits on seeded random edits: inserts,
deletions, adjacent edits, edits at both ends of the text; and the same
refusal of overlapping edits."""

import random

import pytest

from rapidcomp import edits as E
from rapidcomp.edits import EditColumns, OverlappingEdits, SpanEdit, apply_edits


def _edits(rnd, text):
    cuts = sorted(rnd.sample(range(len(text) + 1), rnd.randint(0, min(40, len(text) + 1))))
    out = []
    for a, b in zip(cuts[::2], cuts[1::2]):
        if rnd.random() < 0.3:
            b = a                       # an insert
        out.append(SpanEdit(a, b, rnd.choice(["", "x", "12.5", "[[1,2]]", "\u00e9"]),
                            f"edit {a}"))
    if rnd.random() < 0.3:
        out.append(SpanEdit(len(text), len(text), ";", "at the end"))
    rnd.shuffle(out)
    return out


@pytest.mark.parametrize("block", [1, 2, 3, 5, 64])
def test_blocks_splice_what_one_by_one_splices(monkeypatch, block):
    monkeypatch.setattr(E, "APPLY_BLOCK", block)
    rnd = random.Random(block)
    for _ in range(400):
        text = "".join(rnd.choice("ab,[]\n9 ") for _ in range(rnd.randint(0, 60)))
        edits = _edits(rnd, text)
        assert apply_edits(text, EditColumns.of(edits)) == apply_edits(text, tuple(edits))


@pytest.mark.parametrize("block", [1, 4])
def test_overlapping_edits_refused_alike(monkeypatch, block):
    monkeypatch.setattr(E, "APPLY_BLOCK", block)
    text = "0123456789"
    edits = [SpanEdit(0, 2, "a", "first"), SpanEdit(4, 6, "b", "second"),
             SpanEdit(5, 8, "c", "third")]
    with pytest.raises(OverlappingEdits) as one:
        apply_edits(text, tuple(edits))
    with pytest.raises(OverlappingEdits) as cols:
        apply_edits(text, EditColumns.of(edits))
    assert str(cols.value) == str(one.value)
