"""How new numbers are written.

The controller stores every num as a 32-bit float (about 7 significant
digits), so more decimals than below buy nothing; fewer would cost accuracy:
joint angles with 6 decimals (5e-7 deg ~ 0.01 um at a 1 m reach),
positions with 6 decimals (1 nm), quaternion components with 9 decimals
(rounding error ~1e-9 rad) written from a normalized quaternion.
Trailing zeros are dropped so that a reviewer sees 41.85, not 41.850000.
"""

from __future__ import annotations

import re

import numpy as np

from ..kinematics.frames import row_dots

JOINT_DECIMALS = 6
MM_DECIMALS = 6
QUAT_DECIMALS = 9

# Below these a field keeps its original text: the difference is smaller
# than the precision the new text would be written with.
JOINT_KEEP_DEG = 5e-7
MM_KEEP = 5e-7
ROT_KEEP_RAD = 1e-9


def fmt(value: float, decimals: int) -> str:
    text = f"{value:.{decimals}f}"
    if "." in text:
        text = text.rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


_TRAILING_ZEROS = re.compile("0+\x00")


def fmt_many(values, decimals: int) -> list[str]:
    """fmt() of each of `values` (Python floats): one formatting of all of
    them, then C-level passes over the joined text (a CAM program writes
    7e5). Each number ends in \x00; every finite one has a '.' (decimals
    > 0), so only a fraction's zeros are stripped."""
    if not values:
        return []
    if decimals <= 0:
        return [fmt(v, decimals) for v in values]
    text = "\x00" + (f"%.{decimals}f\x00" * len(values)) % tuple(values)
    text = _TRAILING_ZEROS.sub("\x00", text).replace(".\x00", "\x00")
    # A lone -0 (twice: a replace does not see a match that overlaps the
    # one before it).
    text = text.replace("\x00-0\x00", "\x000\x00").replace("\x00-0\x00", "\x000\x00")
    return text[1:-1].split("\x00")


def joint(value: float) -> str:
    return fmt(value, JOINT_DECIMALS)


def mm(value: float) -> str:
    return fmt(value, MM_DECIMALS)


def quaternion(q_wxyz, like=None) -> tuple[str, str, str, str]:
    """A unit quaternion in RAPID order. q and -q are the same rotation: the
    sign is the one nearer `like` (the value it replaces, so the diff shows
    only the change), else the one with w >= 0."""
    return quaternions(np.asarray(q_wxyz, float)[None],
                       None if like is None else np.asarray(like, float)[None])[0]


def quaternions(q_wxyz, like=None) -> list[tuple[str, str, str, str]]:
    """quaternion() of many (n, 4) at once. Norms as one quaternion's is
    (row_dots: a batch reduction may differ in the last bit, and a 9th
    decimal on a rounding boundary with it); signs from one batch of dot
    products, row by row where one is near 0."""
    q = np.asarray(q_wxyz, float)
    q = q / np.sqrt(row_dots(q))[:, None]
    ref = np.broadcast_to(np.asarray(like, float) if like is not None
                          else np.array([1.0, 0, 0, 0]), q.shape)
    # The sign from one batch of dot products; where one is near 0 (the
    # batch's sum could differ from a @ b in the last bits) row by row.
    dots = np.einsum("ij,ij->i", q, ref)
    flip = dots < 0
    for i in np.flatnonzero(np.abs(dots) < 1e-9).tolist():
        flip[i] = q[i] @ ref[i] < 0
    q = np.where(flip[:, None], -q, q)
    texts = fmt_many(q.ravel().tolist(), QUAT_DECIMALS)
    return [tuple(texts[i:i + 4]) for i in range(0, len(texts), 4)]


def integer(value: int) -> str:
    return str(int(value))
