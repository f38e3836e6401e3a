"""How new numbers are written.

The controller stores every num as a 32-bit float (about 7 significant
digits), so more decimals than below buy nothing; fewer would cost accuracy:
joint angles with 6 decimals (5e-7 deg ~ 0.01 um at a 1 m reach),
positions with 6 decimals (1 nm), quaternion components with 9 decimals
(rounding error ~1e-9 rad) written from a normalized quaternion.
Trailing zeros are dropped so that a reviewer sees 41.85, not 41.850000.
"""

from __future__ import annotations

import numpy as np

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


def joint(value: float) -> str:
    return fmt(value, JOINT_DECIMALS)


def mm(value: float) -> str:
    return fmt(value, MM_DECIMALS)


def quaternion(q_wxyz, like=None) -> tuple[str, str, str, str]:
    """A unit quaternion in RAPID order. q and -q are the same rotation: the
    sign is the one nearer `like` (the value it replaces, so the diff shows
    only the change), else the one with w >= 0."""
    q = np.asarray(q_wxyz, float)
    q = q / np.linalg.norm(q)
    ref = np.asarray(like, float) if like is not None else np.array([1.0, 0, 0, 0])
    if float(q @ ref) < 0:
        q = -q
    return tuple(fmt(float(v), QUAT_DECIMALS) for v in q)


def integer(value: int) -> str:
    return str(int(value))
