"""Past verification in `fix`: a written value that misses its pose, taken
back where that changes nothing else.

A robtarget or jointtarget literal rewritten where it stands (a
declaration edited in place, or an inline aggregate: its numbers only) by a
group alone on it is read by that group's uses only: taking its edits back
leaves every other edit, every placement and every new name as they are,
and every other use's written numbers byte for byte as verified (each
use's check reads its own literal, tool, work object and the plan,
fix.py). That group then fails; the output is the rest of the first
round's edits spliced again, not a second round of every target (a CAM
program under ConfL\\Off: one value in 1e5 misses). fix.py asks where the
output was read back by re-lexing it (its edits numbers of literals, and
moves turned into MoveAbsJ on jointtargets of their own); any other case
(a literal shared by groups, a group with new declarations, an output
parsed again) goes round again as before.
"""

from __future__ import annotations

from collections import Counter

import numpy as np

from ..edits import EditColumns, apply_edits
from .place import Group, Singles
from .plan import Plan


def take_back(plan: Plan, gs: list[Group], failed: list[Group], file_edits: dict,
              texts: dict) -> tuple[dict, dict] | None:
    """(file_edits, texts) without the edits of the groups `failed` (their
    literals as the input has them), as a second round would make them;
    None where a second round could change more than that. Every group of
    `failed` has its failure set; the others' are as they were written."""
    # How many groups read each declaration and each inline aggregate (once,
    # not per group taken back: a CAM program may have thousands).
    # (A Singles' literals are each read by one use alone: none counted.)
    sharing = Counter(_literal_key(h) for h in gs if type(h) is not Singles)
    spans: dict[int, list[tuple[int, int]]] = {}
    for g in failed:
        literals = _own_literals(plan, g, sharing)
        if literals is None:
            return None
        for fi, a, b in literals:
            spans.setdefault(fi, []).append((a, b))
    edits = dict(file_edits)
    changed = set()
    for fi, ss in spans.items():
        es = edits.get(fi)
        if es is None:
            continue
        kept = _without(es, ss)
        if len(kept) == len(es):
            continue
        changed.add(fi)
        if len(kept):
            edits[fi] = kept
        else:
            del edits[fi]
    out = {fi: apply_edits(plan.files[fi].source.text, es) if fi in changed else texts[fi]
           for fi, es in edits.items()}
    return edits, out


def _literal_key(g: Group) -> tuple:
    """What a group's values are written into: its declaration, or its
    inline aggregate (file, span of the statement's target)."""
    if g.decl is not None:
        return ("decl", id(g.decl))
    return ("inline", g.uses[0].key[0], g.src.ref.span)


def _own_literals(plan: Plan, g: Group, sharing: Counter) -> list[tuple[int, int, int]] | None:
    """(file, start, end) of each literal group g wrote where it stands,
    where no other group reads or writes it (sharing: groups per
    _literal_key); else None."""
    if g.mode == "absj" or g.placement not in ("in place", "inline"):
        return None
    # In place: every reference to the declaration is its groups' (place.
    # place); alone on it, no other use reads its literals. Inline: other
    # groups of its statement (another tool or work object where its
    # routine is called) write it too.
    if sharing[_literal_key(g)] != 1:
        return None
    fi = plan.file_index[id(g.src.home)] if g.decl is not None else g.uses[0].key[0]
    out = []
    for k in g.elements:
        rec = g.src.record if k is None or k == g.src.element else g.decl.value[k]
        out.append((fi, rec.span.start, rec.span.end))
    return out


def _without(es, spans: list[tuple[int, int]]):
    """A file's edits (sorted by span) without those inside `spans`, of
    the kind they are (a few edits cut from columns stay columns)."""
    if type(es) is EditColumns:
        drop = np.zeros(len(es), bool)
        for a, b in spans:
            # (Sorted and not overlapping: those inside are one run.)
            i, j = np.searchsorted(es.starts, (a, b)).tolist()
            drop[i:j] |= es.ends[i:j] <= b
        return es.take(np.flatnonzero(~drop)) if drop.any() else es
    return [e for e in es if not any(a <= e.start < b and e.end <= b for a, b in spans)]
