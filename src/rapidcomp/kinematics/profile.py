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

Extended format (written by `rapidcomp discover --out-profile`; the plain
file above is a valid extended file). Four optional columns and two more
row names carry the effects that are not frame displacements:

    joint,dx_mm,...,rz_deg,offset_deg,scale,compliance_deg_per_nm,mass_kg
    J2,0,0,0,0,0,0,0.004,0,1.2e-4,        joint-space terms of J2
    base,0.02,0,0,0,0,0.001,,,,           world_M_base = (Rz.Ry.Rx, d)
    payload,0,0,60,0,0,0,,,,2.5           flange load: CoM (flange frame), kg

offset/scale/compliance apply to joint rows only (jointmap.py:
q_actual = q_cmd (1 + scale) + offset + compliance * tau_gravity(q_cmd)),
mass_kg to the payload row only, whose dx..dz are the centre of mass. An
empty cell is 0.

A comment line `# tau_heat_min: 42.3` (discover writes it for a warm-up
campaign; `# tau_cool_min:` too when the campaign had stops) gives the
thermal time constants, which `fix --transient` takes when --tau-heat /
--tau-cool are not given.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..csvtable import header_and_rows, number
from ..errors import InputError
from ..source import not_a_file
from .frames import DEG, rpy_angles, rpy_matrix
from .gravity import NO_PAYLOAD, GravityModel, Payload
from .jointmap import JointMap
from .robot import RobotModel

COLUMNS = ("joint", "dx_mm", "dy_mm", "dz_mm", "rx_deg", "ry_deg", "rz_deg")
EXTRA_COLUMNS = ("offset_deg", "scale", "compliance_deg_per_nm", "mass_kg")
# What a real robot's errors can be (the profile reader's bounds and the
# plausibility rule of discover, discover/plausible.py): a joint frame
# shifted by at most 5 mm, a frame or joint angle turned by at most 1 deg, a
# gear ratio or link length off by at most 0.5 %, a joint yielding to
# gravity by at most 0.01 deg per N m; the base and flange (measuring-point)
# frames by at most 10 mm.
MAX_SHIFT_MM = 5.0
MAX_FRAME_SHIFT_MM = 10.0
MAX_ROTATION_DEG = 1.0
MAX_SCALE = 5e-3
MAX_COMPLIANCE_DEG_PER_NM = 0.01
# --force lifts the bounds above to this many times them, no further: a
# what-if of a robot far from any real one, still one the model can compute
# (a gear ratio of 0, a shift of 1e30 mm: no robot, no solution).
FORCE_FACTOR = 20.0
# A payload's centre of mass from the flange (mm): as --payload takes one
# (no tool on a 6 kg arm reaches further).
MAX_PAYLOAD_COM_MM = 2000.0


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

    @classmethod
    def from_se3(cls, M: pin.SE3) -> "Displacement":
        rx, ry, rz = rpy_angles(np.array(M.rotation))
        return cls(tuple(float(x) for x in M.translation),
                   (float(rx / DEG), float(ry / DEG), float(rz / DEG)))


ZERO = Displacement((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))


@dataclass(frozen=True, slots=True)
class JointTerms:
    offset_deg: float = 0.0
    scale: float = 0.0
    compliance_deg_per_nm: float = 0.0

    @property
    def is_zero(self) -> bool:
        return not (self.offset_deg or self.scale or self.compliance_deg_per_nm)


NO_TERMS = JointTerms()


@dataclass(frozen=True)
class ThermalProfile:
    """Displacement per joint name ("J1".."J6") and optionally "flange";
    the extended format's base frame, joint-space terms and payload."""

    displacements: tuple[tuple[str, Displacement], ...]
    source: str = "<profile>"
    base: Displacement = ZERO
    joint_terms: tuple[tuple[str, JointTerms], ...] = ()
    payload: Payload = NO_PAYLOAD
    tau_heat_min: float | None = None    # from a `# tau_heat_min: X` comment
    static_only: bool = False            # a `# static:` comment (see _marks)
    tau_cool_min: float | None = None    # from a `# tau_cool_min: X` comment

    def get(self, name: str) -> Displacement:
        for key, disp in self.displacements:
            if key.lower() == name.lower():
                return disp
        return ZERO

    def terms(self, name: str) -> JointTerms:
        for key, t in self.joint_terms:
            if key.lower() == name.lower():
                return t
        return NO_TERMS

    @property
    def is_zero(self) -> bool:
        return (all(d.is_zero for _, d in self.displacements) and self.base.is_zero
                and all(t.is_zero for _, t in self.joint_terms))

    @property
    def is_extended(self) -> bool:
        return (not self.base.is_zero or any(not t.is_zero for _, t in self.joint_terms)
                or self.payload.mass_kg > 0)


def parse_profile(text: str, source: str, joint_names=("J1", "J2", "J3", "J4", "J5", "J6"),
                  force: bool = False) -> ThermalProfile:
    # A URDF arm's joints are named by its URDF; J1..J6 (chain order) name
    # them too, so one profile serves the built-in model and the URDF.
    allowed = {f"j{i + 1}": n for i, n in enumerate(joint_names)}
    allowed |= {n.lower(): n for n in joint_names} | {
        "flange": "flange", "base": "base", "payload": "payload"}
    # (Every number of a profile moves the compensation: a column it does
    # not know, a misspelt offset_deg, is not passed over in silence.)
    header, body = header_and_rows(text, source, COLUMNS, "profile",
                                   known=COLUMNS + EXTRA_COLUMNS)
    columns = COLUMNS + tuple(c for c in EXTRA_COLUMNS if c in header)
    index = {c: header.index(c) for c in columns}
    seen: dict[str, tuple[int, str]] = {}
    disps, terms = [], []
    base, payload = ZERO, NO_PAYLOAD
    if not body:
        raise InputError(source, "no rows: a profile lists at least one joint, flange or base "
                         "row (a row of zeros for a joint that does not move)")
    for line, row in body:
        if len(row) < len(header) or any(c.strip() for c in row[len(header):]):
            raise InputError(source, f"{len(row)} values, expected {len(header)}", line)
        name = row[index["joint"]].strip()
        key = allowed.get(name.lower())
        if key is None:
            aliases = [] if list(joint_names) == [f"J{i + 1}" for i in range(len(joint_names))] \
                else [f"J1..J{len(joint_names)}"]
            raise InputError(source, f"unknown joint {name!r}; expected one of "
                             + ", ".join([*joint_names, *aliases, "flange", "base", "payload"]),
                             line)
        if key in seen:
            first, as_named = seen[key]
            raise InputError(source, f"duplicate row for {key} (first on line {first}"
                             + ("; J1..J6 and the URDF's joint names name the same joints)"
                                if as_named.lower() != name.lower() else ")"), line)
        seen[key] = (line, name)
        v = {}
        for col in columns[1:]:
            cell = row[index[col]].strip()
            try:
                v[col] = number(cell) if cell else 0.0
            except ValueError:
                raise InputError(source, f"{col} is {cell!r}, expected a number", line) from None
            if not math.isfinite(v[col]):
                raise InputError(source, f"{col} is {cell}, expected a finite number", line)
        extra = {c: v.get(c, 0.0) for c in EXTRA_COLUMNS}
        is_joint = key not in ("flange", "base", "payload")
        for col in EXTRA_COLUMNS[:3] if not is_joint else ():
            if extra[col]:
                raise InputError(source, f"{col} applies to joint rows only, not {key}", line)
        if key != "payload" and extra["mass_kg"]:
            raise InputError(source, f"mass_kg applies to the payload row only, not {key}", line)
        d = (v["dx_mm"], v["dy_mm"], v["dz_mm"])
        r = (v["rx_deg"], v["ry_deg"], v["rz_deg"])
        if key == "payload":
            if any(r):
                raise InputError(source, "the payload row takes a centre of mass (dx_mm, dy_mm, "
                                 "dz_mm) and mass_kg; its rotations must be 0", line)
            if not 0 <= extra["mass_kg"] <= 1000:
                raise InputError(source, f"mass_kg is {extra['mass_kg']}, expected 0..1000", line)
            if not all(abs(c) <= MAX_PAYLOAD_COM_MM for c in d):
                raise InputError(source, "the payload's centre of mass [" + ", ".join(
                    f"{c:g}" for c in d) + f"] mm is not within {MAX_PAYLOAD_COM_MM:g} mm of the "
                    "flange", line)
            payload = Payload(extra["mass_kg"], d)
            continue
        _check_size(source, line, key, d, r, extra, FORCE_FACTOR if force else 1.0)
        if extra["compliance_deg_per_nm"] < 0:
            raise InputError(source, f"{key} compliance_deg_per_nm is "
                             f"{extra['compliance_deg_per_nm']}, expected >= 0 (a joint yields "
                             "to gravity, it does not push against it)", line)
        if key == "base":
            base = Displacement(d, r)
            continue
        disps.append((key, Displacement(d, r)))
        if is_joint:
            jt = JointTerms(extra["offset_deg"], extra["scale"], extra["compliance_deg_per_nm"])
            if not jt.is_zero:
                terms.append((key, jt))
    tau, tau_cool, static = _marks(text, source)
    return ThermalProfile(tuple(disps), source, base, tuple(terms), payload, tau, static,
                          tau_cool)


_TAU = re.compile(r"^\s*#\s*(tau_heat_min|tau_cool_min)\s*[:=]\s*(.*?)\s*$", re.IGNORECASE)
_STATIC = re.compile(r"^\s*#\s*static\s*:", re.IGNORECASE)


def _marks(text: str, source: str) -> tuple[float | None, float | None, bool]:
    """The comment lines discover writes: `# tau_heat_min: X`, `#
    tau_cool_min: X` (minutes) and `# static: ...` (effects of a campaign
    in which nothing changed over time)."""
    taus: dict[str, float] = {}
    seen: dict[str, int] = {}
    static = False
    for n, line in enumerate(text.splitlines(), 1):
        static = static or bool(_STATIC.match(line))
        m = _TAU.match(line)
        if not m:
            continue
        key = m.group(1).lower()
        if key in seen:
            raise InputError(source, f"{key} given twice (first on line {seen[key]})", n)
        seen[key] = n
        try:
            tau = float(m.group(2))
        except ValueError:
            tau = float("nan")
        if not (math.isfinite(tau) and 0.001 <= tau <= 100_000):
            raise InputError(source, f"{key} is {m.group(2)!r}, expected minutes as a number "
                             f"(0.001 to 100000), e.g. # {key}: 42.3", n)
        taus[key] = tau
    return taus.get("tau_heat_min"), taus.get("tau_cool_min"), static


def _amount(x: float, limit: float | None = None, spec: str | None = None) -> str:
    """A number for a message: three decimals, or four digits when huge
    (spec: that format instead); past `limit`, as many digits as tell it
    from the limit (5.0000001 is not "5.000 mm exceeds 5.0 mm")."""
    text = format(x, spec) if spec else f"{x:.3f}" if abs(x) < 1e6 else f"{x:.4g}"
    if limit is not None and abs(float(text)) <= limit:
        return repr(float(x))
    return text


def _check_size(source, line, key, d, r, extra, factor: float = 1.0) -> None:
    """The bounds of a real robot's values (factor 1), or with --force
    FORCE_FACTOR times them."""
    hint = ("use --force if intended" if factor == 1.0 else
            f"--force allows {FORCE_FACTOR:g} times the bound of a real robot, no more")
    limit = (MAX_FRAME_SHIFT_MM if key in ("base", "flange") else MAX_SHIFT_MM) * factor
    if math.hypot(*d) > limit:
        raise InputError(source, f"{key} shift of {_amount(math.hypot(*d), limit)} mm exceeds "
                         f"{limit} mm (thermal shifts are microns; {hint})", line)
    rot = max(abs(a) for a in (*r, extra["offset_deg"]))
    if rot > MAX_ROTATION_DEG * factor:
        raise InputError(source, f"{key} rotation of "
                         f"{_amount(rot, MAX_ROTATION_DEG * factor, '.6g')} deg "
                         f"exceeds {MAX_ROTATION_DEG * factor} deg ({hint})", line)
    if abs(extra["scale"]) > MAX_SCALE * factor:
        raise InputError(source, f"{key} scale of "
                         f"{_amount(extra['scale'], MAX_SCALE * factor, '.6g')} exceeds "
                         f"{MAX_SCALE * factor} ({hint})", line)
    if extra["compliance_deg_per_nm"] > MAX_COMPLIANCE_DEG_PER_NM * factor:
        most = MAX_COMPLIANCE_DEG_PER_NM * factor
        raise InputError(source, f"{key} compliance of "
                         f"{_amount(extra['compliance_deg_per_nm'], most, '.6g')} "
                         "deg/N m "
                         f"exceeds {MAX_COMPLIANCE_DEG_PER_NM * factor} ({hint})", line)


def read_profile(path: str | Path, force: bool = False, joint_names=None) -> ThermalProfile:
    if not str(path):
        raise InputError("--profile", "no file named: expected a profile CSV")
    path = Path(path)
    not_a_file(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise InputError(str(path), f"cannot read profile: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise InputError(str(path), "profile is not UTF-8 text") from None
    kwargs = {"joint_names": joint_names} if joint_names else {}
    return parse_profile(text, str(path), force=force, **kwargs)


def _num(x: float) -> str:
    # 12 significant digits: far below a micron or a microdegree, and the
    # written file reproduces the model it describes (tested).
    text = format(float(x), ".12g")
    return "0" if text in ("0", "-0") else text


def format_profile(profile: ThermalProfile, joint_names, comments=()) -> str:
    """CSV text of a profile: the plain 7 columns unless an extended term is
    non-zero, then the extended header (parse_profile reads both)."""
    extended = profile.is_extended
    header = COLUMNS + (EXTRA_COLUMNS if extended else ())
    lines = [f"# {c}" for c in comments] + [",".join(header)]

    def row(name, disp: Displacement, extra=("", "", "", "")):
        cells = [name, *map(_num, disp.d_mm), *map(_num, disp.r_deg)]
        return ",".join(cells + (list(extra) if extended else []))

    for name in joint_names:
        t = profile.terms(name)
        lines.append(row(name, profile.get(name), (_num(t.offset_deg), _num(t.scale),
                                                   _num(t.compliance_deg_per_nm), "")))
    if not profile.get("flange").is_zero:
        lines.append(row("flange", profile.get("flange")))
    if not profile.base.is_zero:
        lines.append(row("base", profile.base))
    if profile.payload.mass_kg > 0:
        lines.append(row("payload", Displacement(profile.payload.com_mm, (0.0, 0.0, 0.0)),
                         ("", "", "", _num(profile.payload.mass_kg))))
    return "\n".join(lines) + "\n"


def joint_map(robot: RobotModel, profile: ThermalProfile) -> JointMap | None:
    """The profile's joint-space terms for `robot`, None when there are none."""
    names = robot.joint_names
    t = [profile.terms(n) for n in names]
    if all(x.is_zero for x in t):
        return None
    comp = np.array([x.compliance_deg_per_nm for x in t]) * DEG
    gravity = GravityModel.from_robot(robot, profile.payload) if np.any(comp) else None
    return JointMap(np.array([x.offset_deg for x in t]) * DEG, np.array([x.scale for x in t]),
                    comp, gravity)


def scaled(profile: ThermalProfile, s: float) -> ThermalProfile:
    """s . profile: the deformation at thermal state s (0 cold, 1 the
    measured steady state). Every number of the profile is a deformation
    and is multiplied by s (displacements, rotation angles, base frame,
    joint offsets, scales, compliances); the payload is a load, not a
    deformation, and is kept."""
    def disp(d: Displacement) -> Displacement:
        return Displacement(tuple(s * x for x in d.d_mm), tuple(s * x for x in d.r_deg))
    return ThermalProfile(
        tuple((name, disp(d)) for name, d in profile.displacements), profile.source,
        disp(profile.base),
        tuple((name, JointTerms(s * t.offset_deg, s * t.scale, s * t.compliance_deg_per_nm))
              for name, t in profile.joint_terms),
        profile.payload)


def deform(robot: RobotModel, profile: ThermalProfile) -> RobotModel:
    """A deformed copy of `robot`; the nominal model is left untouched."""
    model = robot.copy_model()
    for jid in range(1, model.njoints):
        disp = profile.get(model.names[jid])
        if not disp.is_zero:
            model.jointPlacements[jid] = model.jointPlacements[jid] * disp.se3()
    if not profile.base.is_zero:
        model.jointPlacements[1] = profile.base.se3() * model.jointPlacements[1]
    flange = profile.get("flange")
    if not flange.is_zero:
        frame = model.frames[robot.flange_frame]
        frame.placement = frame.placement * flange.se3()
        model.frames[robot.flange_frame] = frame
    return RobotModel(robot.name + "+thermal", model, robot.flange_frame,
                      robot.lower_deg, robot.upper_deg, joint_map(robot, profile),
                      robot.limits_set)
