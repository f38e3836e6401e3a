"""Unified diff of a splice, built from the edits themselves.

difflib would have to rediscover what changed by matching 1e5 lines; the
edits already say which lines they touch, so hunks are cut straight from
them (linear time). The output is what difflib.unified_diff(n=3,
lineterm="") prints for the same two texts; the tests check that.
"""

from __future__ import annotations

import re

from ..edits import EditColumns, SpanEdit, apply_edits, sorted_columns


def _line_starts(lines: list[str]) -> list[int]:
    """Where each line (splitlines(keepends=True)) starts, and the text's end."""
    import numpy as np
    return [0] + np.cumsum(np.fromiter(map(len, lines), np.int64, len(lines))).tolist()


# What ends a line for str.splitlines (and so for difflib's lines here).
_LINE_BREAK = re.compile("[\n\r\v\f\x1c\x1d\x1e\x85\u2028\u2029]")


def _range(start: int, length: int) -> str:
    if length == 1:
        return str(start + 1)
    return f"{start if not length else start + 1},{length}"


def unified_diff(text: str, edits: list[SpanEdit], old_name: str, new_name: str,
                 context: int = 3, new_text: str | None = None) -> list[str]:
    """new_text: the text with the edits applied, when the caller has it."""
    if not edits:
        return []
    if new_text is None:
        new_text = apply_edits(text, edits)
    lines = text.splitlines(keepends=True)
    # (As columns once for both ways: 2.5e5 edits of a CAM program turned
    # into MoveAbsJ.)
    if type(edits) is not EditColumns:
        edits = EditColumns.of(edits, pack=False)
    # (The lines without their line breaks, once: what the changes compare
    # and the hunks print; a form feed or NEL ends a line here too, as for
    # difflib.)
    plain = text.splitlines()
    changed = _changed_in_lines(text, lines, plain, edits, new_text)
    if changed is None:
        changed = _changed_blocks(text, lines, plain, edits, new_text)
    if not changed:
        return []
    return _hunks(plain, changed, old_name, new_name, context)


def handed_off(edits) -> tuple:
    """What unified_diff reads of `edits`, to hand to another process
    (side.py): EditColumns as their spans and texts (not their whys, 7e5
    of them in a CAM program); a list as it is. columns_diff takes it."""
    if type(edits) is EditColumns:
        return (edits.starts, edits.ends, edits.texts_column())
    return (edits,)


def columns_diff(text: str, edits: tuple, old_name: str, new_name: str) -> list[str]:
    """unified_diff(text, the edits handed_off gave, old_name, new_name).
    (The output is spliced again there: handing a 25 MB text over would
    cost the job's peak some 60 MB of pickles.)"""
    if len(edits) == 3:
        import numpy as np
        starts, ends, texts = edits
        edits = EditColumns(starts, ends, texts, np.full(len(starts), None, object), pack=False)
    else:
        edits = edits[0]
    return unified_diff(text, edits, old_name, new_name)


def _changed_in_lines(text: str, lines: list[str], plain: list[str], cols: EditColumns,
                      new_text: str) -> list | None:
    """The changes, when no edit touches a line break or follows a CR
    (fix's edits of numbers; None otherwise): line i of the output is line
    i of the input with its edits, and the lines an edit touches are
    compared as they are (no blocks to cut, no offsets to shift)."""
    import numpy as np
    if not lines:
        return None
    # The new texts first: a program turned into MoveAbsJ inserts lines, and
    # its 2.5e5 replaced spans need not be gathered to tell (0.4 s).
    if _LINE_BREAK.search(cols.joined()):
        return None
    at, ends = cols.starts.tolist(), cols.ends.tolist()
    if _LINE_BREAK.search("".join([text[a:b] for a, b in zip(at, ends)])):
        return None
    # Nor one right after a CR: between a CR and an LF it would split or
    # join a CRLF (a line more or less, with no line break in any edit).
    if "\r" in text and any(text[a - 1] == "\r" for a in at if a):
        return None
    new_lines = new_text.splitlines()
    if len(new_lines) != len(lines):
        return None
    starts = np.array(_line_starts(lines))
    at = np.array(at, np.int64)
    touched = np.unique(np.minimum(np.searchsorted(starts, at, side="right") - 1,
                                   len(lines) - 1)).tolist()
    changed: list[list] = []
    for i in touched:
        new = new_lines[i]
        if plain[i] == new:
            continue
        if changed and changed[-1][1] == i:   # adjacent: one change, as difflib sees it
            changed[-1][1] = i + 1
            changed[-1][2].append(new)
        else:
            changed.append([i, i + 1, [new]])
    return changed


def _changed_blocks(text: str, lines: list[str], plain: list[str], cols: EditColumns,
                    new_text: str) -> list:
    """[first old line, end old line (exclusive), new lines] of each change.
    The lines each edit touches, and the blocks of edits that touch the
    same lines, are found for all edits at once (a CAM program turned into
    MoveAbsJ has 2.5e5 edits); each block's lines are then compared."""
    import numpy as np
    cols = sorted_columns(cols)
    if not len(cols):
        return []
    starts = np.array(_line_starts(lines))
    at, ends = cols.starts, cols.ends
    # The last offset an edit touches: an edit that removes a line end joins
    # the next line to its block.
    last = np.maximum(ends - 1, at)
    breaks = [k for k, (a, b) in enumerate(zip(at.tolist(), ends.tolist()))
              if b > a and text[b - 1] in "\r\n"]
    last[breaks] = ends[breaks]
    top = len(lines) - 1
    a = np.minimum(np.searchsorted(starts, at, "right") - 1, top)
    b = np.minimum(np.maximum(a, np.searchsorted(starts, last, "right") - 1), top)
    # Blocks: edits merged while they touch lines of the block before.
    reach = np.maximum.accumulate(b)
    first = np.flatnonzero(np.concatenate(([True], a[1:] > reach[:-1])))
    block_a = a[first]
    block_b = reach[np.append(first[1:] - 1, len(a) - 1)]
    grow = np.add.reduceat(cols.lengths() - (ends - at), first)
    # Where each block's lines are in the output: shifted by what the
    # blocks before it add.
    shift = np.concatenate(([0], np.cumsum(grow)[:-1]))
    lo_new = (starts[block_a] + shift).tolist()
    hi_new = (starts[block_b + 1] + shift + grow).tolist()
    # New text of each block; lines an edit leaves as they were (e.g. the
    # line a declaration is inserted after) are context, as difflib has it.
    changed: list[list] = []  # [first old line, end old line (exclusive), new lines]
    for a, b, x, y in zip(block_a.tolist(), block_b.tolist(), lo_new, hi_new):
        old_lines = plain[a:b + 1]
        new_lines = new_text[x:y].splitlines()
        lo, hi_old, hi_new = 0, len(old_lines), len(new_lines)
        while lo < hi_old and lo < hi_new and old_lines[lo] == new_lines[lo]:
            lo += 1
        while hi_old > lo and hi_new > lo and old_lines[hi_old - 1] == new_lines[hi_new - 1]:
            hi_old -= 1
            hi_new -= 1
        if lo == hi_old and lo == hi_new:
            continue
        if changed and changed[-1][1] == a + lo:  # adjacent: one change, as difflib sees it
            changed[-1][1] = a + hi_old
            changed[-1][2].extend(new_lines[lo:hi_new])  # in place: linear, not quadratic
        else:
            changed.append([a + lo, a + hi_old, new_lines[lo:hi_new]])
    return changed


def _hunks(plain: list[str], changed: list, old_name: str, new_name: str,
           context: int) -> list[str]:
    """plain: the old text's lines without their line breaks."""
    out = [f"--- {old_name}", f"+++ {new_name}"]
    n = len(plain)
    delta = 0  # new line index minus old line index before the current hunk
    i = 0
    while i < len(changed):
        j = i
        while j + 1 < len(changed) and changed[j + 1][0] - changed[j][1] <= 2 * context:
            j += 1
        first = max(0, changed[i][0] - context)
        end = min(n, changed[j][1] + context)
        body: list[str] = []
        pos = first
        new_len = 0
        d = delta
        for a, b, new_lines in changed[i:j + 1]:
            for k in range(pos, a):
                body.append(" " + plain[k])
                new_len += 1
            body.extend("-" + plain[k] for k in range(a, b))
            body.extend("+" + s for s in new_lines)
            new_len += len(new_lines)
            d += len(new_lines) - (b - a)
            pos = b
        for k in range(pos, end):
            body.append(" " + plain[k])
            new_len += 1
        out.append(f"@@ -{_range(first, end - first)} +{_range(first + delta, new_len)} @@")
        out.extend(body)
        delta = d
        i = j + 1
    return out
