"""Thermal deformation profile: per-joint frame displacements, and the
deformed robot model built from them.

CSV format (the paper's Tables 1-2):

    joint,dx_mm,dy_mm,dz_mm,rx_deg,ry_deg,rz_deg
    J1,-0.0200698,0.000154,-0.05297,0,-0.011,-0.0137
    ...

Joint i's frame is displaced in its own zero-pose axes (= base axes for the
built-in model): placement_i' = placement_i . Delta_i with
Delta_i = (R, d), R = Rz(rz).Ry(ry).Rx(rx), d = (dx, dy, dz): rotate about
the joint's origin, then translate. Missing rows are zero; an optional
`flange` row displaces the flange frame.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import InputError
from .frames import DEG, rpy_matrix
from .robot import RobotModel

COLUMNS = ("joint", "dx_mm", "dy_mm", "dz_mm", "rx_deg", "ry_deg", "rz_deg")
MAX_SHIFT_MM = 5.0
MAX_ROTATION_DEG = 1.0


@dataclass(frozen=True, slots=True)
class Displacement:
    d_mm: tuple[float, float, float]
    r_deg: tuple[float, float, float]  # rx, ry, rz

    @property
    def is_zero(self) -> bool:
        return not any(self.d_mm) and not any(self.r_deg)

    def se3(self) -> pin.SE3:
        rx, ry, rz = (a * DEG for a in self.r_deg)
        return pin.SE3(rpy_matrix(rx, ry, rz), np.asarray(self.d_mm, dtype=float))


ZERO = Displacement((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))


@dataclass(frozen=True)
class ThermalProfile:
    """Displacement per joint name ("J1".."J6") and optionally "flange"."""

    displacements: tuple[tuple[str, Displacement], ...]
    source: str = "<profile>"

    def get(self, name: str) -> Displacement:
        for key, disp in self.displacements:
            if key.lower() == name.lower():
                return disp
        return ZERO

    @property
    def is_zero(self) -> bool:
        return all(d.is_zero for _, d in self.displacements)


def parse_profile(text: str, source: str, joint_names=("J1", "J2", "J3", "J4", "J5", "J6"),
                  force: bool = False) -> ThermalProfile:
    allowed = {n.lower(): n for n in joint_names} | {"flange": "flange"}
    rows = list(csv.reader(io.StringIO(text)))
    # Skip leading blank lines and '#' comments, but keep line numbers right.
    numbered = [(i + 1, r) for i, r in enumerate(rows) if r and not r[0].strip().startswith("#")]
    if not numbered:
        raise InputError(source, "empty profile; expected the header " + ",".join(COLUMNS), 1)
    head_line, header = numbered[0]
    header = [h.strip().lower() for h in header]
    missing = [c for c in COLUMNS if c not in header]
    if missing:
        raise InputError(source, f"missing column(s) {', '.join(missing)}; expected the header "
                         + ",".join(COLUMNS), head_line)
    index = {c: header.index(c) for c in COLUMNS}
    seen: dict[str, int] = {}
    out = []
    for line, row in numbered[1:]:
        if all(not cell.strip() for cell in row):
            continue
        if len(row) < len(header):
            raise InputError(source, f"{len(row)} values, expected {len(header)}", line)
        name = row[index["joint"]].strip()
        key = allowed.get(name.lower())
        if key is None:
            raise InputError(source, f"unknown joint {name!r}; expected one of "
                             + ", ".join([*joint_names, "flange"]), line)
        if key in seen:
            raise InputError(source, f"duplicate row for {key} (first on line {seen[key]})", line)
        seen[key] = line
        values = []
        for col in COLUMNS[1:]:
            cell = row[index[col]].strip()
            try:
                v = float(cell)
            except ValueError:
                raise InputError(source, f"{col} is {cell!r}, expected a number", line) from None
            if not math.isfinite(v):
                raise InputError(source, f"{col} is {cell}, expected a finite number", line)
            values.append(v)
        d, r = tuple(values[:3]), tuple(values[3:])
        if not force:
            if math.hypot(*d) > MAX_SHIFT_MM:
                raise InputError(source, f"{key} shift of {math.hypot(*d):.3f} mm exceeds "
                                 f"{MAX_SHIFT_MM} mm (thermal shifts are microns; use --force "
                                 "if this is intended)", line)
            if max(abs(a) for a in r) > MAX_ROTATION_DEG:
                raise InputError(source, f"{key} rotation of {max(abs(a) for a in r)} deg "
                                 f"exceeds {MAX_ROTATION_DEG} deg (use --force if intended)", line)
        out.append((key, Displacement(d, r)))
    return ThermalProfile(tuple(out), source)


def read_profile(path: str | Path, force: bool = False, joint_names=None) -> ThermalProfile:
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise InputError(str(path), f"cannot read profile: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise InputError(str(path), "profile is not UTF-8 text") from None
    kwargs = {"joint_names": joint_names} if joint_names else {}
    return parse_profile(text, str(path), force=force, **kwargs)


def deform(robot: RobotModel, profile: ThermalProfile) -> RobotModel:
    """A deformed copy of `robot`; the nominal model is left untouched."""
    model = robot.copy_model()
    for jid in range(1, model.njoints):
        disp = profile.get(model.names[jid])
        if not disp.is_zero:
            model.jointPlacements[jid] = model.jointPlacements[jid] * disp.se3()
    flange = profile.get("flange")
    if not flange.is_zero:
        frame = model.frames[robot.flange_frame]
        frame.placement = frame.placement * flange.se3()
        model.frames[robot.flange_frame] = frame
    return RobotModel(robot.name + "+thermal", model, robot.flange_frame,
                      robot.lower_deg, robot.upper_deg)
