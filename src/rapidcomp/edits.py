"""The rewriter primitive: splice span edits into source text.

Output text = original text with exactly the edited spans replaced
(sqlfluff-style fix patches). Overlapping edits are a programming error of
the caller and are refused rather than silently merged.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from operator import attrgetter
from typing import NamedTuple

import numpy as np


class SpanEdit(NamedTuple):
    """Replace text[start:end] with replacement (why: for messages).
    Immutable; a NamedTuple, not a frozen dataclass: a CAM program makes
    7e5 of them, and a frozen dataclass's __init__ costs three times as
    much."""

    start: int
    end: int
    replacement: str
    why: str = ""


# The order edits are applied in (a C-level key: 1e5-target programs sort
# 1e6 edits more than once).
BY_SPAN = attrgetter("start", "end")


# Edits spliced per block by _apply_columns.
APPLY_BLOCK = 65536


class OverlappingEdits(ValueError):
    pass


# A SpanEdit from a (start, end, replacement, why) tuple, made by tuple's
# own constructor as SpanEdit's is (1e6 of them without a Python call each).
span_edit = functools.partial(tuple.__new__, SpanEdit)


class EditColumns(Sequence):
    """Span edits as columns: a sequence of SpanEdit (as a tuple of them
    is, and equal to that tuple), each made when it is read; a slice is
    EditColumns again. A CAM program's compensation is 7e5 edits of
    numbers; as columns they are spliced, shifted and counted by array
    operations, and no tuple and two ints per edit outlive the batch that
    made them. starts/ends: int64 arrays; whys: an object array of str;
    the replacements (read by texts/text/joined/lengths) packed (_packed)
    where they are short ASCII texts, as a CAM program's numbers are; copies
    of what they are made from, read-only."""

    __slots__ = ("starts", "ends", "_texts", "whys")

    def __init__(self, starts, ends, replacements, whys, pack: bool = True):
        self.starts = np.array(starts, np.int64)
        self.ends = np.array(ends, np.int64)
        self._texts = _packed(replacements) if pack else _objects(replacements)
        self.whys = _objects(whys)
        for a in (self.starts, self.ends, self._texts, self.whys):
            a.flags.writeable = False

    @classmethod
    def of(cls, edits) -> "EditColumns":
        edits = list(edits)
        return cls(np.fromiter((e.start for e in edits), np.int64, len(edits)),
                   np.fromiter((e.end for e in edits), np.int64, len(edits)),
                   [e.replacement for e in edits], [e.why for e in edits])

    def take(self, index) -> "EditColumns":
        return EditColumns(self.starts[index], self.ends[index], self._texts[index],
                           self.whys[index])

    @classmethod
    def concat(cls, parts: list["EditColumns"]) -> "EditColumns":
        """The edits of `parts`, one after the other."""
        if not parts:
            return cls([], [], [], [])
        texts = [c._texts for c in parts]
        if any(t.dtype.kind != "S" for t in texts):
            # (Packed bytes and str objects do not mix in one array.)
            texts = [_objects(c.texts()) for c in parts]
        return cls(np.concatenate([c.starts for c in parts]),
                   np.concatenate([c.ends for c in parts]), np.concatenate(texts),
                   np.concatenate([c.whys for c in parts]))

    def texts(self, i: int = 0, j: int | None = None) -> list[str]:
        """The replacements of edits [i, j), as str."""
        t = self._texts[i:j]
        return t.astype(str).tolist() if t.dtype.kind == "S" else t.tolist()

    def text(self, k: int) -> str:
        t = self._texts[k]
        return t.decode("ascii") if type(t) is np.bytes_ else t

    def joined(self) -> str:
        """Every replacement, one after the other, as one str."""
        if self._texts.dtype.kind == "S":
            # (Packed texts hold no NUL: the padding is all there is.)
            return self._texts.tobytes().replace(b"\0", b"").decode("ascii")
        return "".join(self._texts.tolist())

    def lengths(self) -> np.ndarray:
        """len() of each replacement (int64)."""
        if self._texts.dtype.kind == "S":
            return np.char.str_len(self._texts).astype(np.int64)
        return np.fromiter(map(len, self._texts), np.int64, len(self._texts))

    def __len__(self) -> int:
        return len(self.starts)

    def __iter__(self):
        return map(span_edit, zip(self.starts.tolist(), self.ends.tolist(),
                                  self.texts(), self.whys.tolist()))

    def __getitem__(self, i):
        if isinstance(i, slice):
            return self.take(i)
        return SpanEdit(int(self.starts[i]), int(self.ends[i]), self.text(i), self.whys[i])

    def __eq__(self, other) -> bool:
        if isinstance(other, (EditColumns, tuple)):
            return len(self) == len(other) and all(a == b for a, b in zip(self, other))
        return NotImplemented

    def __hash__(self) -> int:
        return hash(tuple(self))

    def __repr__(self) -> str:
        return f"EditColumns({len(self)} edits)"


def _objects(texts) -> np.ndarray:
    out = np.empty(len(texts), object)
    out[:] = texts if isinstance(texts, np.ndarray) else list(texts)
    return out


# The widest replacement packed as bytes: a number's text (wider ones, a
# line inserted, stay str objects: every slot is as wide as the widest).
PACK_WIDTH = 24


def _packed(texts) -> np.ndarray:
    """Replacements as one array of fixed-width ASCII bytes when every one
    is ASCII, holds no NUL (the padding) and is at most PACK_WIDTH long, so
    that they are decoded back to the same str; else an object array of
    str. A CAM program's 7e5 numbers: ~9 bytes each, not a str object each
    (~40 MB at 1e5 targets)."""
    if isinstance(texts, np.ndarray) and texts.dtype.kind == "S":
        return np.array(texts)
    objs = _objects(texts)
    if not len(objs):
        return objs
    every = objs.tolist()
    joined = "".join(every)
    if (not joined.isascii() or "\0" in joined
            or max(map(len, every)) > PACK_WIDTH):
        return objs
    return np.array(every, dtype="S")


class EditRun:
    """Edits [i, j) of an EditColumns: the field edits of one literal of a
    batch, where a list of SpanEdit was (iterated, counted, compared with
    such a list; empty: false)."""

    __slots__ = ("block", "i", "j")

    def __init__(self, block: EditColumns, i: int, j: int):
        self.block, self.i, self.j = block, i, j

    def __len__(self) -> int:
        return self.j - self.i

    def __iter__(self):
        return iter(self.block[self.i:self.j])

    def __eq__(self, other) -> bool:
        if isinstance(other, (EditRun, EditColumns, tuple, list)):
            return list(self) == list(other)
        return NotImplemented

    __hash__ = None


def columns_of(items) -> EditColumns:
    """One EditColumns of SpanEdits and EditRuns in order: the consecutive
    runs of one block by one gather, consecutive edits by one conversion."""
    parts: list[EditColumns] = []
    runs: list = []
    edits: list = []

    def flush():
        if runs:
            block = runs[0].block
            i = np.fromiter((r.i for r in runs), np.int64, len(runs))
            j = np.fromiter((r.j for r in runs), np.int64, len(runs))
            size = j - i
            # The indices i..j-1 of every run, in order, as one array.
            parts.append(block.take(np.arange(int(size.sum()))
                                    + np.repeat(i - (np.cumsum(size) - size), size)))
            runs.clear()
        if edits:
            parts.append(EditColumns.of(edits))
            edits.clear()
    for item in items:
        if type(item) is EditRun:
            if edits or (runs and item.block is not runs[0].block):
                flush()
            runs.append(item)
        else:
            if runs:
                flush()
            edits.append(item)
    flush()
    return EditColumns.concat(parts)


def sorted_columns(cols: EditColumns) -> EditColumns:
    """cols in the order BY_SPAN sorts them (stable: equal spans keep
    their order)."""
    order = np.lexsort((cols.ends, cols.starts))
    if (order == np.arange(len(order))).all():
        return cols
    return cols.take(order)


def apply_edits(text: str, edits) -> str:
    """Return `text` with every edit applied (a sequence of SpanEdit, or
    EditColumns). No edits -> `text` itself."""
    if not edits:
        return text
    if type(edits) is EditColumns:
        return _apply_columns(text, sorted_columns(edits))
    ordered = sorted(edits, key=BY_SPAN)
    parts: list[str] = []
    pos = 0
    for edit in ordered:
        if edit.start < pos or edit.end < edit.start or edit.end > len(text):
            raise OverlappingEdits(
                f"edit {edit.start}:{edit.end} ({edit.why}) overlaps the previous edit "
                f"ending at {pos} or lies outside the text")
        parts.append(text[pos:edit.start])
        parts.append(edit.replacement)
        pos = edit.end
    parts.append(text[pos:])
    return "".join(parts)


def _apply_columns(text: str, cols: EditColumns) -> str:
    """apply_edits of sorted columns: the same checks and message, then the
    text between the edits and their replacements joined in one pass."""
    s, e = cols.starts, cols.ends
    before = np.concatenate(([0], e[:-1]))
    bad = np.flatnonzero((s < before) | (e < s) | (e > len(text)))
    if len(bad):
        k = int(bad[0])
        raise OverlappingEdits(
            f"edit {int(s[k])}:{int(e[k])} ({cols.whys[k]}) overlaps the previous edit "
            f"ending at {int(before[k])} or lies outside the text")
    # A block of edits at a time: the offsets of 7e5 edits as ints, the
    # texts between them and the list of them are not all alive at once
    # (1e5 targets' print peaked ~50 MB higher).
    out = []
    pos = 0
    for at in range(0, len(s), APPLY_BLOCK):
        a, b = s[at:at + APPLY_BLOCK].tolist(), e[at:at + APPLY_BLOCK].tolist()
        parts: list = [None] * (2 * len(a))
        parts[0::2] = [text[x:y] for x, y in zip([pos] + b[:-1], a)]
        parts[1::2] = cols.texts(at, at + APPLY_BLOCK)
        out.append("".join(parts))
        pos = b[-1]
    out.append(text[pos:])
    return "".join(out)
