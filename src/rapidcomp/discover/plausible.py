"""What a real robot can have: bounds on every effect's parameters.

An effect that fits only with a value no real robot has is not an effect of
the robot: the measuring point was not given (--tool), the data are not in
millimetres or not in the robot's base frame, or the robot model is the
wrong one. discover never names such a fit; it says the model and the data
are far apart (select.py). The bounds are the profile reader's
(kinematics/profile.py), so every profile discover writes loads in `fix`
and `check` without --force:

  joint_displacement     |d| <= 5 mm
  link_elongation        |epsilon| <= 5e-3 (its shift, epsilon x length, <= 5 mm)
  joint_scale            |scale| <= 5e-3
  joint_offset, axis_tilt  <= 1 deg
  gravity_compliance     0 <= c <= 0.01 deg per N m
  cyclic                 amplitude sqrt(a^2 + b^2) <= 0.1 deg (a gear stage's
                         transmission error is arc minutes); never written
  base_frame, tool_offset  |d| <= 10 mm, rotations <= 1 deg; as the model's
                         first effect (a frame registration error, the largest
                         thing a campaign can get wrong) up to 50 mm and 5 deg,
                         named but not written into a profile
"""

from __future__ import annotations

import math

from ..kinematics.profile import (MAX_COMPLIANCE_DEG_PER_NM, MAX_FRAME_SHIFT_MM,
                                  MAX_ROTATION_DEG, MAX_SCALE, MAX_SHIFT_MM)
from .effects import Effect

FIRST_FRAME_FACTOR = 5.0
MAX_CYCLIC_DEG = 0.1
FRAMES = ("base_frame", "tool_offset")


def bounds(effect: Effect, first: bool = False, factor: float = 1.0
           ) -> tuple[float, float, float]:
    """(mm, deg, plain number) limits of one effect's parameters (factor:
    --force's FORCE_FACTOR times them)."""
    if effect.kind in FRAMES:
        k = (FIRST_FRAME_FACTOR if first else 1.0) * factor
        return MAX_FRAME_SHIFT_MM * k, MAX_ROTATION_DEG * k, 0.0
    if effect.kind == "gravity_compliance":
        return 0.0, 0.0, MAX_COMPLIANCE_DEG_PER_NM * factor
    return MAX_SHIFT_MM * factor, MAX_ROTATION_DEG * factor, MAX_SCALE * factor


def implausible(effect: Effect, user: dict[str, float], first: bool = False,
                factor: float = 1.0) -> str | None:
    """Why these values are beyond what a real robot has (factor 1), or
    beyond what --force allows (FORCE_FACTOR), or None."""
    mm, deg, num = bounds(effect, first, factor)
    shift = math.sqrt(sum(v * v for k, v in user.items() if k.endswith("_mm")))
    turn = max([abs(v) for k, v in user.items() if k.endswith("_deg")] or [0.0])
    plain = max([abs(v) for k, v in user.items()
                 if not k.endswith(("_mm", "_deg"))] or [0.0])
    if effect.kind == "link_elongation":
        shift = 0.0
    if effect.kind == "cyclic":
        amplitude = math.hypot(*user.values())
        if amplitude > MAX_CYCLIC_DEG * factor:
            return (f"{effect.id} needs a cyclic error of {amplitude:.3g} deg (a real robot's "
                    f"gears: <= {MAX_CYCLIC_DEG * factor:g} deg)")
        return None
    if shift > mm:
        return f"{effect.id} needs a shift of {shift:.3g} mm (a real robot: <= {mm:g} mm)"
    if turn > deg:
        return f"{effect.id} needs {turn:.3g} deg (a real robot: <= {deg:g} deg)"
    if plain > num:
        what = {"joint_scale": "a gear ratio off by", "link_elongation": "a link longer by",
                "gravity_compliance": "a compliance of"}.get(effect.kind, "a value of")
        unit = " deg per N m" if effect.kind == "gravity_compliance" else ""
        return f"{effect.id} needs {what} {plain:.3g}{unit} (a real robot: <= {num:g}{unit})"
    return None


def writable(effect: Effect, user: dict[str, float]) -> bool:
    """Within what a profile holds (a first frame effect may be larger)."""
    return implausible(effect, user, first=False) is None
