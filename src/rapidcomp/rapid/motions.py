"""Catalogue of RAPID motion instructions: what each positional argument is.

Roles: "to"/"cir" robot targets (or joint targets for MoveAbsJ-like
instructions), "search" (the INOUT result of a search), "speed", "zone",
"tool", and "other" for process data (signals, triggers, seam/weld data).
Optional arguments (\\WObj, \\V, \\Z, \\Conc, ...) are recognised by name.
Signatures from ABB's "Technical reference manual - RAPID Instructions".
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class MotionSpec:
    name: str
    roles: tuple[str, ...]
    joint_space: bool = False  # targets are jointtarget


_SPECS = [
    MotionSpec("MoveJ", ("to", "speed", "zone", "tool")),
    MotionSpec("MoveL", ("to", "speed", "zone", "tool")),
    MotionSpec("MoveC", ("cir", "to", "speed", "zone", "tool")),
    MotionSpec("MoveAbsJ", ("to", "speed", "zone", "tool"), joint_space=True),
    MotionSpec("MoveExtJ", ("to", "speed", "zone"), joint_space=True),
    MotionSpec("MoveJDO", ("to", "speed", "zone", "tool", "other", "other")),
    MotionSpec("MoveLDO", ("to", "speed", "zone", "tool", "other", "other")),
    MotionSpec("MoveCDO", ("cir", "to", "speed", "zone", "tool", "other", "other")),
    MotionSpec("MoveJAO", ("to", "speed", "zone", "tool", "other", "other")),
    MotionSpec("MoveLAO", ("to", "speed", "zone", "tool", "other", "other")),
    MotionSpec("MoveCAO", ("cir", "to", "speed", "zone", "tool", "other", "other")),
    MotionSpec("MoveJGO", ("to", "speed", "zone", "tool", "other", "other")),
    MotionSpec("MoveLGO", ("to", "speed", "zone", "tool", "other", "other")),
    MotionSpec("MoveCGO", ("cir", "to", "speed", "zone", "tool", "other", "other")),
    MotionSpec("MoveJSync", ("to", "speed", "zone", "tool", "other")),
    MotionSpec("MoveLSync", ("to", "speed", "zone", "tool", "other")),
    MotionSpec("MoveCSync", ("cir", "to", "speed", "zone", "tool", "other")),
    MotionSpec("TriggJ", ("to", "speed", "other", "zone", "tool")),
    MotionSpec("TriggL", ("to", "speed", "other", "zone", "tool")),
    MotionSpec("TriggC", ("cir", "to", "speed", "other", "zone", "tool")),
    MotionSpec("TriggJIOs", ("to", "speed", "zone", "tool")),
    MotionSpec("TriggLIOs", ("to", "speed", "zone", "tool")),
    MotionSpec("SearchL", ("other", "search", "to", "speed", "tool")),
    MotionSpec("SearchC", ("other", "search", "cir", "to", "speed", "tool")),
    MotionSpec("SearchExtJ", ("other", "search", "to", "speed"), joint_space=True),
    MotionSpec("ArcL", ("to", "speed", "other", "other", "zone", "tool")),
    MotionSpec("ArcLStart", ("to", "speed", "other", "other", "zone", "tool")),
    MotionSpec("ArcLEnd", ("to", "speed", "other", "other", "zone", "tool")),
    MotionSpec("ArcC", ("cir", "to", "speed", "other", "other", "zone", "tool")),
    MotionSpec("ArcCStart", ("cir", "to", "speed", "other", "other", "zone", "tool")),
    MotionSpec("ArcCEnd", ("cir", "to", "speed", "other", "other", "zone", "tool")),
    MotionSpec("SpotJ", ("to", "speed", "other", "tool")),
    MotionSpec("SpotL", ("to", "speed", "other", "tool")),
    MotionSpec("PaintL", ("to", "speed", "zone", "tool")),
    MotionSpec("PaintC", ("cir", "to", "speed", "zone", "tool")),
    MotionSpec("DispL", ("to", "speed", "other", "zone", "tool")),
    MotionSpec("DispC", ("cir", "to", "speed", "other", "zone", "tool")),
]

MOTIONS: dict[str, MotionSpec] = {s.name.lower(): s for s in _SPECS}


def motion_spec(name: str) -> MotionSpec | None:
    return MOTIONS.get(name.lower())
