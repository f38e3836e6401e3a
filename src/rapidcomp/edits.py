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
    the replacements a Texts column (read by texts/text/joined/lengths);
    copies of what they are made from, read-only."""

    __slots__ = ("starts", "ends", "_texts", "whys")

    def __init__(self, starts, ends, replacements, whys, pack: bool = True):
        self.starts = np.array(starts, np.int64)
        self.ends = np.array(ends, np.int64)
        self._texts = Texts.of(replacements, pack)
        self.whys = _objects(whys)
        for a in (self.starts, self.ends, self.whys):
            a.flags.writeable = False

    @classmethod
    def of(cls, edits, pack: bool = True) -> "EditColumns":
        """pack=False: columns read once and let go (packing them would be
        work for nothing)."""
        edits = list(edits)
        if not edits:
            return cls([], [], [], [], pack)
        # (The four columns by one transposition: 2.5e5 edits of a CAM
        # program turned into MoveAbsJ.)
        starts, ends, texts, whys = zip(*edits)
        return cls(starts, ends, texts, whys, pack)

    def take(self, index) -> "EditColumns":
        return EditColumns(self.starts[index], self.ends[index], self._texts.take(index),
                           self.whys[index])

    @classmethod
    def concat(cls, parts: list["EditColumns"]) -> "EditColumns":
        """The edits of `parts`, one after the other."""
        if not parts:
            return cls([], [], [], [])
        return cls(np.concatenate([c.starts for c in parts]),
                   np.concatenate([c.ends for c in parts]),
                   Texts.concat([c._texts for c in parts]),
                   np.concatenate([c.whys for c in parts]))

    def texts_column(self) -> "Texts":
        """The replacements as their column (EditColumns takes it back)."""
        return self._texts

    def texts(self, i: int = 0, j: int | None = None) -> list[str]:
        """The replacements of edits [i, j), as str."""
        return self._texts.list(i, j)

    def text(self, k: int) -> str:
        return self._texts.item(k)

    def joined(self) -> str:
        """Every replacement, one after the other, as one str."""
        return self._texts.joined()

    def lengths(self) -> np.ndarray:
        """len() of each replacement (int64)."""
        return self._texts.lengths()

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
# line inserted, are kept aside: every slot is as wide as the widest).
PACK_WIDTH = 24


class Texts:
    """A column of replacement texts. Packed (of(pack=True)): the short
    ASCII texts without NUL in `packed`, an 'S' array, NUL-padded (a CAM
    program's 7e5 numbers: ~9 bytes each, not a str object each, ~40 MB at
    1e5 targets), and the others (a declaration inserted; non-ASCII; a NUL,
    which the padding would lose) kept aside as str, at the sorted indices
    `wide_at` (their slots hold b""). Unpacked: `packed` an object array of
    str, none aside. Every reader gets str. Read-only; a take or a
    concatenation is a new column."""

    __slots__ = ("packed", "wide_at", "wide")

    def __init__(self, packed: np.ndarray, wide_at: np.ndarray, wide: list[str]):
        packed.flags.writeable = False
        self.packed, self.wide_at, self.wide = packed, wide_at, wide

    @classmethod
    def of(cls, texts, pack: bool = True) -> "Texts":
        if isinstance(texts, Texts):
            return texts
        if isinstance(texts, np.ndarray) and texts.dtype.kind == "S":
            return cls(np.array(texts), _NONE, [])
        objs = _objects(texts)
        if not pack:
            return cls(objs, _NONE, [])
        if not len(objs):
            return cls(np.zeros(0, "S1"), _NONE, [])
        every = objs.tolist()
        joined = "".join(every)
        if joined.isascii() and "\0" not in joined and max(map(len, every)) <= PACK_WIDTH:
            return cls(np.array(every, dtype="S"), _NONE, [])
        aside = [k for k, t in enumerate(every)
                 if not (t.isascii() and "\0" not in t and len(t) <= PACK_WIDTH)]
        wide = [every[k] for k in aside]
        for k in aside:
            every[k] = ""
        return cls(np.array(every, dtype="S"), np.array(aside, np.int64), wide)

    @property
    def is_packed(self) -> bool:
        return self.packed.dtype.kind == "S"

    def __len__(self) -> int:
        return len(self.packed)

    def take(self, index) -> "Texts":
        packed = self.packed[index]
        if not self.wide:
            return Texts(packed, _NONE, [])
        # Where each text aside went (an index array, a slice or a mask).
        at = np.arange(len(self.packed))[index]
        k = np.minimum(np.searchsorted(self.wide_at, at), len(self.wide_at) - 1)
        hit = np.flatnonzero(self.wide_at[k] == at)
        return Texts(packed, hit.astype(np.int64), [self.wide[j] for j in k[hit].tolist()])

    @classmethod
    def concat(cls, parts: list["Texts"]) -> "Texts":
        # (Bytes and str objects do not mix in one array: a column of str
        # is packed first, its long texts aside.)
        parts = [p if p.is_packed else cls.of(p.list()) for p in parts]
        offsets = np.cumsum([0] + [len(p) for p in parts[:-1]])
        return cls(np.concatenate([p.packed for p in parts]),
                   np.concatenate([p.wide_at + o for p, o in zip(parts, offsets)] + [_NONE]),
                   [t for p in parts for t in p.wide])

    def list(self, i: int = 0, j: int | None = None) -> list[str]:
        """The texts [i, j) as str."""
        t = self.packed[i:j]
        if not self.is_packed:
            return t.tolist()
        out = t.astype(str).tolist()
        if self.wide:
            i, j, _ = slice(i, j).indices(len(self.packed))
            a, b = np.searchsorted(self.wide_at, (i, j)).tolist()
            for k, text in zip(self.wide_at[a:b].tolist(), self.wide[a:b]):
                out[k - i] = text
        return out

    def item(self, k: int) -> str:
        t = self.packed[k]
        if type(t) is not np.bytes_:
            return t
        if self.wide:
            k = range(len(self.packed))[k]           # (a negative k as its place)
            n = int(np.searchsorted(self.wide_at, k))
            if n < len(self.wide_at) and self.wide_at[n] == k:
                return self.wide[n]
        return t.decode("ascii")

    def joined(self) -> str:
        """Every text, one after the other, as one str."""
        if not self.is_packed:
            return "".join(self.packed.tolist())
        # The packed runs between the texts aside, each as its bytes (packed
        # texts hold no NUL: the padding is all there is), the texts aside
        # between them.
        out = []
        at = 0
        for k, text in zip(self.wide_at.tolist() + [len(self.packed)], self.wide + [""]):
            out += [self.packed[at:k].tobytes().replace(b"\0", b"").decode("ascii"), text]
            at = k + 1
        return "".join(out)

    def lengths(self) -> np.ndarray:
        """len() of each text (int64)."""
        if not self.is_packed:
            return np.fromiter(map(len, self.packed), np.int64, len(self.packed))
        out = np.char.str_len(self.packed).astype(np.int64)
        if self.wide:
            out[self.wide_at] = [len(t) for t in self.wide]
        return out


_NONE = np.zeros(0, np.int64)


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
    texts = cols.texts_column()
    if text.isascii() and texts.is_packed and not texts.wide:
        return _apply_bytes(text, s, e, texts.packed)
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


def _apply_bytes(text: str, s: np.ndarray, e: np.ndarray, packed: np.ndarray) -> str:
    """_apply_columns of an ASCII text whose replacements are all packed
    (a CAM program's 7e5 numbers): spliced as bytes by array operations,
    no str object per edit. A block of edits at a time, each block's
    output laid out as runs: the text's bytes between the edits, each
    edit's replacement; each run's bytes selected by a mask repeated from
    the run lengths. (Packed texts hold no NUL: the padding is all there
    is, and a replacement's length its count of other bytes.)"""
    src = np.frombuffer(text.encode("ascii"), np.uint8)
    out = []
    pos = 0
    for at in range(0, len(s), APPLY_BLOCK):
        a, b = s[at:at + APPLY_BLOCK], e[at:at + APPLY_BLOCK]
        block = np.ascontiguousarray(packed[at:at + APPLY_BLOCK])
        grid = block.view(np.uint8).reshape(len(block), block.dtype.itemsize)
        filled = grid != 0
        runs = np.empty(2 * len(a), np.int64)
        runs[0::2] = a - np.concatenate(([pos], b[:-1]))       # the text between
        flags = np.zeros(2 * len(a), bool)
        flags[0::2] = True
        runs[1::2] = b - a                                      # what each edit replaces
        kept = src[pos:b[-1]][np.repeat(flags, runs)]
        runs[1::2] = filled.sum(axis=1)                         # what it writes
        between = np.repeat(flags, runs)
        spliced = np.empty(len(between), np.uint8)
        spliced[between] = kept
        spliced[~between] = grid[filled]
        out.append(str(spliced, "ascii"))
        pos = int(b[-1])
    out.append(text[pos:])
    return "".join(out)
