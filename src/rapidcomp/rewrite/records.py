"""Text of compensated robtarget/jointtarget values.

Two ways to write a value: as edits of the numeric fields of an existing
literal (only fields whose value really changed; the rest keep their
text), or as a complete new literal for a new declaration. Both keep the
external axes exactly as written in the source.
"""

from __future__ import annotations

import numpy as np

from ..edits import SpanEdit
from ..kinematics.frames import matrix_to_quat_wxyz, quat_wxyz_to_matrix, rotation_log
from ..rapid.values import JointTarget, RobTarget
from . import numbers


def _rotation_angle(q_old, R_new) -> float:
    return float(np.linalg.norm(rotation_log(quat_wxyz_to_matrix(np.asarray(q_old, float)).T
                                             @ R_new)))


def robtarget_texts(record: RobTarget, R: np.ndarray, p: np.ndarray,
                    conf) -> list[str]:
    """The 17 field texts of `record` with pose (R, p) and confdata `conf`:
    a field keeps its text unless its value changes beyond what the new
    text could express."""
    texts = list(record.texts)
    for i in range(3):
        if abs(float(p[i]) - record.values[i]) > numbers.MM_KEEP:
            texts[i] = numbers.mm(float(p[i]))
    if _rotation_angle(record.quat_wxyz, R) > numbers.ROT_KEEP_RAD:
        texts[3:7] = numbers.quaternion(matrix_to_quat_wxyz(R), like=record.quat_wxyz)
    for i in range(4):
        if int(conf[i]) != record.values[7 + i]:
            texts[7 + i] = numbers.integer(conf[i])
    return texts


def jointtarget_texts(record: JointTarget, q_deg) -> list[str]:
    texts = list(record.texts)
    for i in range(6):
        if abs(float(q_deg[i]) - record.values[i]) > numbers.JOINT_KEEP_DEG:
            texts[i] = numbers.joint(float(q_deg[i]))
    return texts


def field_edits(record: RobTarget | JointTarget, texts: list[str], why: str) -> list[SpanEdit]:
    base = record.span.start
    return [SpanEdit(base + s, base + e, new, why)
            for (s, e), old, new in zip(record.regs, record.texts, texts) if new != old]


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
