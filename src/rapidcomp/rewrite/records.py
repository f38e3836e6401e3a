"""Text of compensated robtarget/jointtarget values.

Two ways to write a value: as edits of the numeric fields of an existing
literal (only fields whose value really changed; the rest keep their
text), or as a complete new literal for a new declaration. Both keep the
external axes exactly as written in the source.
"""

from __future__ import annotations

import math

import numpy as np

from ..edits import SpanEdit
from ..kinematics.frames import (matrix_to_quat_wxyz, rotation_log, unit_quat_matrices,
                                 unit_wxyz)
from ..rapid.values import JointTarget, RobTarget
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
    return np.array([math.sqrt(v.dot(v)) for v in rotation_log(rel)])


def robtarget_texts(record: RobTarget, R: np.ndarray, p: np.ndarray,
                    conf) -> list[str]:
    """The 17 field texts of `record` with pose (R, p) and confdata `conf`:
    a field keeps its text unless its value changes beyond what the new
    text could express."""
    return robtarget_texts_many([record], np.asarray(R)[None], np.asarray(p)[None],
                                np.asarray(conf)[None])[0][0]


def robtarget_texts_many(recs: list[RobTarget], R: np.ndarray, p: np.ndarray,
                         conf: np.ndarray) -> list[tuple[list[str], list[tuple]]]:
    """robtarget_texts of many records at once (a CAM program has 1e5), each
    with its changed fields as (start, end, new text) in the source, what
    field_edits gives (each literal lexed once for both): the rotations
    compared and converted as one batch, the positions' texts formatted as
    one."""
    if not recs:
        return []
    q_old = np.array([r.quat_wxyz for r in recs], float)
    turned = (_rotation_angles(q_old, R) > numbers.ROT_KEEP_RAD).tolist()
    quats = numbers.quaternions(matrix_to_quat_wxyz(R), like=q_old)
    p = np.asarray(p, float)
    mm = numbers.fmt_many(p.ravel().tolist(), numbers.MM_DECIMALS)
    out = []
    for j, (rec, pj, cj, moved, q) in enumerate(zip(recs, p.tolist(), np.asarray(conf).tolist(),
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
        out.append((texts, changed_fields(rec.span.start, regs, old, texts)))
    return out


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


def absj_texts(q_deg, source: RobTarget) -> list[str]:
    """Field texts of the jointtarget that replaces a robtarget: new joints,
    the robtarget's external axes as written."""
    return [numbers.joint(float(v)) for v in q_deg] + list(source.texts[11:17])
