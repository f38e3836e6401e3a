"""Text of compensated robtarget/jointtarget values.

Two ways to write a value: as edits of the numeric fields of an existing
literal (only fields whose value really changed; the rest keep their
text), or as a complete new literal for a new declaration. Both keep the
external axes exactly as written in the source.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..edits import EditColumns, SpanEdit, apply_edits, span_edit
from ..kinematics.frames import (matrix_to_quat_wxyz, rotation_log, row_dots,
                                 unit_quat_matrices, unit_wxyz)
from ..rapid.values import JointTarget, RobTarget, frame_fields, plain_bounds
from . import numbers


def _rotation_angles(q_old, R_new) -> np.ndarray:
    """Angles (rad) between the rotations of quaternions q_old (n, 4) and
    matrices R_new (n, 3, 3), each as one pair's would be (a field's
    keep-or-rewrite decision at ROT_KEEP_RAD depends on the last bit):
    the quaternions normalised one by one, the products as a stack with
    each left factor a transposed view (the layout of a.T @ b), the norms
    as np.linalg.norm computes one, sqrt(v . v) (tested against the pair
    by pair formulas)."""
    unit = [unit_wxyz(*q) for q in np.asarray(q_old, float).tolist()]
    rel = np.matmul(np.swapaxes(unit_quat_matrices(unit), -1, -2), R_new)
    return np.sqrt(row_dots(rotation_log(rel)))


def robtarget_texts(record: RobTarget, R: np.ndarray, p: np.ndarray,
                    conf) -> list[str]:
    """The 17 field texts of `record` with pose (R, p) and confdata `conf`:
    a field keeps its text unless its value changes beyond what the new
    text could express."""
    return robtarget_texts_many([record], np.asarray(R)[None], np.asarray(p)[None],
                                np.asarray(conf)[None])[0][0]


def robtarget_texts_many(recs: list[RobTarget], R: np.ndarray, p: np.ndarray,
                         conf: np.ndarray, whys: list[str] | None = None
                         ) -> list[tuple[list[str], list[tuple]]]:
    """robtarget_texts of many records at once (a CAM program has 1e5), each
    with its changed fields as (start, end, new text) in the source, or,
    given each record's why, as the SpanEdits field_edits gives (each
    literal lexed once for both): the rotations compared and converted as
    one batch, the positions' texts formatted as one."""
    if not recs:
        return []
    p = np.asarray(p, float)
    turned, quats, mm = _new_numbers(np.array([r.quat_wxyz for r in recs], float), R, p)
    turned = turned.tolist()
    conf = np.asarray(conf)
    lexed = _plain_fields(recs)
    if lexed is not None:
        return _columns(recs, lexed, p, conf, turned, quats, mm, whys)
    out = []
    for j, (rec, pj, cj, moved, q) in enumerate(zip(recs, p.tolist(), conf.tolist(),
                                                    turned, quats)):
        old, regs = rec.lex()
        texts = list(old)
        values = rec.values
        for i in range(3):
            if abs(pj[i] - values[i]) > numbers.MM_KEEP:
                texts[i] = mm[3 * j + i]
        if moved:
            texts[3:7] = q
        for i in range(4):
            if int(cj[i]) != values[7 + i]:
                texts[7 + i] = numbers.integer(cj[i])
        changed = changed_fields(rec.span.start, regs, old, texts)
        if whys is not None:
            changed = [SpanEdit(s, e, new, whys[j]) for s, e, new in changed]
        out.append((texts, changed))
    return out


def _new_numbers(q_old: np.ndarray, R: np.ndarray, p: np.ndarray):
    """What a batch's decisions compare and write: whether each rotation
    turned beyond ROT_KEEP_RAD from its quaternion q_old (n, 4), the new
    quaternions' texts (signed as q_old), the positions' texts."""
    turned = _rotation_angles(q_old, R) > numbers.ROT_KEEP_RAD
    quats = numbers.quaternions(matrix_to_quat_wxyz(R), like=q_old)
    return turned, quats, numbers.fmt_many(p.ravel().tolist(), numbers.MM_DECIMALS)


def _compact_texts(recs: list[RobTarget]) -> list[str] | None:
    """The records' literals' texts, when every one is a compact literal
    (its text kept, not lexed field by field), else None."""
    lits = [r.lexed for r in recs]
    return lits if all(type(t) is str for t in lits) else None


def _plain_bounds(recs: list[RobTarget]):
    """values.plain_bounds of the records' literals, when every one is a
    compact literal, else None."""
    lits = _compact_texts(recs)
    return None if lits is None else plain_bounds(lits)


def _plain_fields(recs: list[RobTarget]):
    """(the 17 field texts of every literal, one flat list; each field's
    start and end in its literal (n, 17)) when every literal is a plain
    one (_plain_bounds), else None."""
    bounds = _plain_bounds(recs)
    if bounds is None:
        return None
    joined, _, starts, ends = bounds
    return frame_fields(joined), starts, ends


def _touched(values, p, conf, turned, quats, mm):
    """The fields whose value changes beyond what its new text could
    express (a position beyond MM_KEEP, a rotation beyond ROT_KEEP_RAD, a
    confdata integer that differs), on the same float64 numbers: their
    flat indices in (n, 17), row by row, and their new texts (an object
    array)."""
    n = len(values)
    touched = np.zeros((n, 17), bool)
    touched[:, :3] = np.abs(p - values[:, :3]) > numbers.MM_KEEP
    touched[:, 3:7] = np.asarray(turned, bool)[:, None]
    c = conf.astype(np.int64)
    touched[:, 7:11] = c != values[:, 7:11]
    f = np.flatnonzero(touched)
    rows, fields = np.divmod(f, 17)
    new = np.empty(len(f), object)
    at = fields < 3
    new[at] = np.array(mm, dtype=object)[rows[at] * 3 + fields[at]]
    at = (fields >= 3) & (fields < 7)
    if at.any():
        new[at] = np.array(quats, dtype=object).reshape(n, 4)[rows[at], fields[at] - 3]
    at = fields >= 7
    new[at] = [numbers.integer(v) for v in c[rows[at], fields[at] - 7].tolist()]
    return f, new


def _columns(recs, lexed, p, conf, turned, quats, mm, whys=None):
    """The per-literal loop of robtarget_texts_many on plain literals, as
    columns (object arrays of the texts): the same decisions on the same
    numbers (_touched), the same texts; a field is changed where its new
    text differs from the old."""
    old, starts, ends = lexed
    n = len(recs)
    values = np.array([r.values for r in recs], float).reshape(n, 17)
    was = np.array(old, dtype=object)
    f, cand = _touched(values, p, conf, turned, quats, mm)
    new = was.copy()
    new[f] = cand
    f = f[cand != was[f]]
    base = np.array([r.span.start for r in recs], np.int64)[f // 17]
    spans = ((base + starts.ravel()[f]).tolist(), (base + ends.ravel()[f]).tolist(),
             new[f].tolist())
    if whys is None:
        fields = list(zip(*spans))
    else:
        fields = list(map(span_edit, zip(*spans, np.array(whys, dtype=object)[f // 17])))
    at = [0] + np.cumsum(np.bincount(f // 17, minlength=n)).tolist()
    return list(zip(new.reshape(n, 17).tolist(), [fields[i:j] for i, j in zip(at, at[1:])]))


class Printed(NamedTuple):
    """A batch of plain robtarget literals written again (robtarget_block)."""

    literals: list[str]      # each literal's new text
    edits: EditColumns       # every changed field, literal by literal, in the source
    at: list[int]            # literal j's edits are edits[at[j]:at[j + 1]]


def robtarget_block(recs: list[RobTarget], R: np.ndarray, p: np.ndarray, conf: np.ndarray,
                    whys: list[str]) -> Printed | None:
    """What robtarget_texts_many gives with whys, for literals written
    plainly (_plain_bounds; else None), as columns: the edits as one
    EditColumns, each literal's new text as one string made by splicing
    them into the literals (no list of 17 field texts per literal: the
    verification compares and decodes the literal as written)."""
    read = plain_inputs(recs)
    return None if read is None else plain_block(*read, R, p, conf, whys)


def plain_inputs(recs: list[RobTarget]) -> tuple | None:
    """What robtarget_block reads of the records (their literals' texts,
    values (n, 17) and offsets in their module), when every one is a
    compact literal (its text kept, not lexed field by field), else None."""
    lits = _compact_texts(recs)
    if not recs or lits is None:
        return None
    return (lits, np.array([r.values for r in recs], float).reshape(len(recs), 17),
            np.array([r.span.start for r in recs], np.int64))


def plain_block(lits: list[str], values: np.ndarray, offsets: np.ndarray, R: np.ndarray,
                p: np.ndarray, conf: np.ndarray, whys: list[str]) -> Printed | None:
    """robtarget_block of the records plain_inputs read (None: a literal
    is not written plainly); a function of numbers and texts, which a CAM
    program's job hands to its helper for every other block (side.py)."""
    bounds = plain_bounds(lits)
    if bounds is None:
        return None
    joined, off, starts, ends = bounds
    n = len(lits)
    p = np.asarray(p, float)
    turned, quats, mm = _new_numbers(np.ascontiguousarray(values[:, 3:7]), R, p)
    f, new = _touched(values, p, np.asarray(conf), turned, quats, mm)
    rows = f // 17
    a = off[rows] + starts.ravel()[f]
    b = off[rows] + ends.ravel()[f]
    # A field changes where its new text is not the text there (no string
    # made of the 7e5 texts that are there).
    size = np.fromiter(map(len, new), np.int64, len(new))
    changed = ~((size == b - a) & np.fromiter(map(joined.startswith, new, a.tolist()), bool,
                                              len(new)))
    rows, a, b, new, size = rows[changed], a[changed], b[changed], new[changed], size[changed]
    why = np.array(whys, dtype=object)[rows]
    shift = offsets[rows] - off[rows]
    edits = EditColumns(a + shift, b + shift, new, why)
    # (The texts as the edits packed them: spliced as bytes, edits.py.)
    spliced = apply_edits(joined, EditColumns(a, b, edits.texts_column(), why))
    grow = size - (b - a)
    # (Each literal's length as written: the distance to the next one's
    # offset, less the ',' joining them.)
    size = np.diff(off, append=len(joined) + 1) - 1 + np.bincount(
        rows, weights=grow, minlength=n).astype(np.int64)
    start = (np.cumsum(size + 1) - size - 1).tolist()
    literals = [spliced[x:x + k] for x, k in zip(start, size.tolist())]
    at = [0] + np.cumsum(np.bincount(rows, minlength=n)).tolist()
    return Printed(literals, edits, at)


def jointtarget_texts(record: JointTarget, q_deg) -> list[str]:
    texts = list(record.texts)
    for i in range(6):
        if abs(float(q_deg[i]) - record.values[i]) > numbers.JOINT_KEEP_DEG:
            texts[i] = numbers.joint(float(q_deg[i]))
    return texts


def changed_fields(base: int, regs, old, texts) -> list[tuple[int, int, str]]:
    """(start, end, new text) in the source of each field whose text
    changes: a literal at offset `base`, its fields at `regs` (relative)
    holding `old`, to hold `texts`."""
    return [(base + s, base + e, new) for (s, e), was, new in zip(regs, old, texts)
            if new != was]


def field_edits(record: RobTarget | JointTarget, texts: list[str], why: str) -> list[SpanEdit]:
    """The edits that give `record`'s fields `texts` (only those whose text
    changes)."""
    old, regs = record.lex()
    return [SpanEdit(s, e, new, why) for s, e, new in changed_fields(record.span.start, regs,
                                                                      old, texts)]


def robtarget_literal(texts: list[str]) -> str:
    t = texts
    return (f"[[{','.join(t[0:3])}],[{','.join(t[3:7])}],[{','.join(t[7:11])}],"
            f"[{','.join(t[11:17])}]]")


def jointtarget_literal(texts: list[str]) -> str:
    return f"[[{','.join(texts[0:6])}],[{','.join(texts[6:12])}]]"


def absj_literals(q_deg: np.ndarray, sources: list[RobTarget]) -> list[str]:
    """jointtarget_literal(absj_texts(q, source)) of each row of q_deg (n,
    6) and its source: the joints formatted as one batch (fmt_many's texts
    are each number's alone); the external axes of a literal written
    plainly (plain_bounds) are the text inside its last brackets."""
    return absj_literals_of(q_deg, absj_axes(sources))


def absj_axes(sources: list[RobTarget]) -> list[str]:
    """The external axes' text of each jointtarget that replaces a
    robtarget (absj_literals)."""
    if _plain_bounds(sources) is not None:
        return [lit[lit.rindex("[") + 1:-2] for lit in (src.lexed for src in sources)]
    return [",".join(src.texts[11:17]) for src in sources]


def absj_literals_of(q_deg: np.ndarray, axes: list[str]) -> list[str]:
    """absj_literals of joints and external axes' texts (absj_axes): a
    function of numbers and texts, which a CAM program's job hands to its
    helper for every other block (side.py)."""
    joints = numbers.fmt_many(np.asarray(q_deg, float).ravel().tolist(), numbers.JOINT_DECIMALS)
    joints = map(",".join, zip(*[iter(joints)] * 6))
    return [f"[[{j}],[{e}]]" for j, e in zip(joints, axes)]


def transient_joint_literals(cold: np.ndarray, dq: np.ndarray, axes: list[str]
                             ) -> list[tuple[str, str]]:
    """(cold value, correction) literals of moves turned into MoveAbsJ
    rcTcJ(cold, dq) (cold, dq (n, 6) deg; axes: the cold values' external
    axes, absj_axes): the cold one as absj_literals_of makes it, the
    correction's joints and six zero external axes; numbers formatted in
    one batch (a function of numbers and texts, which a CAM program's job
    hands to its helper for every other block: side.py)."""
    return list(zip(absj_literals_of(cold, axes), correction_literals(dq)))


def correction_literals(dq: np.ndarray) -> list[str]:
    """The jointtarget literals of transient corrections of joints (dq (n,
    6) deg): the joints, six zero external axes; numbers formatted in one
    batch."""
    dqs = numbers.fmt_many(np.asarray(dq, float).ravel().tolist(), numbers.JOINT_DECIMALS)
    return [f"[[{j}],[0,0,0,0,0,0]]" for j in map(",".join, zip(*[iter(dqs)] * 6))]


def pose_literals(d: np.ndarray, dq: np.ndarray) -> list[str]:
    """The pose literals [[dx,dy,dz],[dq1,dq2,dq3,dq4]] of transient
    corrections (d (n, 3) mm, dq (n, 4)), numbers formatted in one batch: a
    function of numbers, which a CAM program's job hands to its helper for
    every other block (side.py)."""
    mm = numbers.fmt_many(np.asarray(d, float).ravel().tolist(), numbers.MM_DECIMALS)
    qs = numbers.fmt_many(np.asarray(dq, float).ravel().tolist(), numbers.QUAT_DECIMALS)
    return ["[[" + ",".join(mm[3 * j:3 * j + 3]) + "],[" + ",".join(qs[4 * j:4 * j + 4]) + "]]"
            for j in range(len(d))]


def absj_texts(q_deg, source: RobTarget) -> list[str]:
    """Field texts of the jointtarget that replaces a robtarget: new joints,
    the robtarget's external axes as written."""
    # (The six as one formatting: 1e5 in a CAM program turned to MoveAbsJ.)
    return (numbers.fmt_many(np.asarray(q_deg, float).tolist(), numbers.JOINT_DECIMALS)
            + list(source.texts[11:17]))
