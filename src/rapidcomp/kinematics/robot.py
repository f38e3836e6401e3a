"""Robot models on Pinocchio, the source of truth for kinematics.

Geometry is in millimetres (RAPID's unit), so no length is ever converted;
joint angles inside the model are radians, at the user edge degrees
(frames.py converts). The nominal model is read-only by convention: nothing
in rapidcomp mutates a RobotModel's pin.Model; a deformed model is a copy
(profile.py).
"""

from __future__ import annotations

import math
import os
import re
import sys
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import InputError
from ..source import not_a_file
from .frames import DEG, MM_PER_M, rot_y

FLANGE_FRAME = "tool0"


@dataclass(frozen=True, eq=False)
class RobotModel:
    """A 6-axis arm: Pinocchio model, flange frame, joint limits (deg)."""

    name: str
    model: pin.Model = field(repr=False)
    flange_frame: int
    lower_deg: tuple[float, ...]
    upper_deg: tuple[float, ...]
    # Joint-space terms of a deformed model (jointmap.JointMap): commanded ->
    # actual angles. None for a nominal model and plain thermal profiles.
    joint_map: object = None
    # Where each joint's limits come from, as a note says it: the --limit
    # option that set them, a URDF's <limit>; "" for the built-in model's.
    limits_set: tuple[str, ...] = ()

    @property
    def nq(self) -> int:
        return self.model.nq

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(self.model.names[1:])

    def with_limits(self, lower_deg=None, upper_deg=None, set_by=None) -> "RobotModel":
        """A copy with other joint limits (sources differ, e.g. J5 +-115 vs
        +-120); set_by: where each joint's come from (limits_set)."""
        return RobotModel(self.name, self.model, self.flange_frame,
                          tuple(lower_deg) if lower_deg is not None else self.lower_deg,
                          tuple(upper_deg) if upper_deg is not None else self.upper_deg,
                          self.joint_map,
                          tuple(set_by) if set_by is not None else self.limits_set)

    def limit_source(self, k: int) -> str:
        """Where joint k's limits come from, in words."""
        given = self.limits_set[k] if k < len(self.limits_set) else ""
        return given or f"the {self.name} model's own"

    def copy_model(self) -> pin.Model:
        return pin.Model(self.model)

    def base_M_flange(self, q_deg) -> pin.SE3:
        """Forward kinematics with Pinocchio (one configuration, commanded
        degrees; a deformed model's joint-space terms are applied)."""
        data = self.model.createData()
        q = np.asarray(q_deg, dtype=float) * DEG
        if self.joint_map is not None:
            q = self.joint_map.apply(q[None])[0]
        pin.framesForwardKinematics(self.model, data, q)
        return pin.SE3(data.oMf[self.flange_frame])


# The built-in ABB IRB 140. Joint origins in base coordinates at the zero pose,
# every joint frame parallel to the base frame there (so the thermal profile's
# per-joint displacements are in base axes). J3 is measured relative to the
# lower arm (no parallel-link coupling).
IRB140_ORIGINS = ((0, 0, 0), (70, 0, 352), (70, 0, 712), (70, 0, 712), (450, 0, 712),
                  (450, 0, 712))
IRB140_AXES = ("z", "y", "y", "x", "y", "x")
IRB140_FLANGE = (515, 0, 712)  # rotated +90 deg about y at the zero pose
IRB140_LOWER = (-180.0, -90.0, -230.0, -200.0, -115.0, -400.0)
IRB140_UPPER = (180.0, 110.0, 50.0, 200.0, 115.0, 400.0)
# Mass (kg) and centre of mass (base coordinates at the zero pose, mm) of the
# body each joint moves; used for the gravity-compliance effect (discover).
IRB140_BODIES = ((34.0, (30, 0, 250)), (16.0, (70, 0, 532)), (13.0, (150, 0, 712)),
                 (4.0, (330, 0, 712)), (1.5, (470, 0, 712)), (0.3, (505, 0, 712)))
GRAVITY_MM_S2 = 9810.0

_JOINT_TYPES = {"x": pin.JointModelRX, "y": pin.JointModelRY, "z": pin.JointModelRZ}


def _body_inertia(mass: float, com_local: np.ndarray) -> pin.Inertia:
    # Only mass and centre of mass matter for the gravity term; a small
    # sphere-like rotational inertia keeps the model physically valid.
    radius = 50.0
    return pin.Inertia(mass, com_local, np.eye(3) * 0.4 * mass * radius ** 2)


def irb140() -> RobotModel:
    model = pin.Model()
    model.name = "IRB140"
    model.gravity = pin.Motion(np.array([0.0, 0.0, -GRAVITY_MM_S2]), np.zeros(3))
    parent = 0
    prev = np.zeros(3)
    for i, (origin, axis) in enumerate(zip(IRB140_ORIGINS, IRB140_AXES)):
        origin = np.asarray(origin, dtype=float)
        placement = pin.SE3(np.eye(3), origin - prev)
        jid = model.addJoint(parent, _JOINT_TYPES[axis](), placement, f"J{i + 1}",
                             np.array([1e9]), np.array([1e9]),
                             np.array([IRB140_LOWER[i] * DEG]), np.array([IRB140_UPPER[i] * DEG]))
        mass, com = IRB140_BODIES[i]
        model.appendBodyToJoint(jid, _body_inertia(mass, np.asarray(com, float) - origin),
                                pin.SE3.Identity())
        model.addJointFrame(jid)
        parent = jid
        prev = origin
    flange = pin.SE3(rot_y(np.pi / 2), np.asarray(IRB140_FLANGE, float) - prev)
    fid = model.addFrame(pin.Frame(FLANGE_FRAME, parent, flange, pin.FrameType.OP_FRAME))
    return RobotModel("IRB140", model, fid, IRB140_LOWER, IRB140_UPPER)


# A link of a robot arm is shorter than this (m): a larger number is not one.
MAX_LINK_M = 100.0
_REVOLUTE = {"JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned"}


def _urdf_xml(path: Path) -> str:
    """The URDF's XML as text, in whatever encoding it declares (Pinocchio
    reads bytes as UTF-8: a Latin-1 name failed as Python decoded it); its
    XML errors with their line and column."""
    not_a_file(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputError(str(path), f"cannot load URDF: {exc.strerror or exc}") from None
    try:
        root = ET.fromstring(data)
    except ET.ParseError as exc:
        line, col = exc.position
        what = re.sub(r": line \d+, column \d+$", "", str(exc))
        raise InputError(str(path), f"not a URDF (XML: {what})", line, col + 1) from None
    if root.tag != "robot":
        raise InputError(str(path), f"not a URDF: expected a <robot> element, found <{root.tag}>",
                         1)
    return ET.tostring(root, encoding="unicode")


def _bad_joint(path: Path, joint: str, message: str) -> InputError:
    """Bad input at the URDF's element of `joint` (its line where found)."""
    return InputError(str(path), message, _element_line(path, joint))


def _element_line(path: Path, name: str, child: bool = False) -> int | None:
    """The line of the URDF's <joint name="name"> (child: of the joint
    whose <child link="name"/>; else of <link name="name"> where no joint
    has that name), None where it is not found."""
    try:
        text = path.read_bytes().decode("utf-8", "replace")
    except OSError:
        return None
    q = re.escape(name)
    pats = ([rf'<joint\b[^>]*[^/>]>(?:(?!</joint>|<joint\b).)*?'
             rf'<child\s+link\s*=\s*["\']{q}["\']']
            if child else [rf'<joint\s[^>]*\bname\s*=\s*["\']{q}["\']',
                           rf'<link\s[^>]*\bname\s*=\s*["\']{q}["\']'])
    for pat in pats:
        m = re.search(pat, text, re.S)
        if m is not None:
            return text.count("\n", 0, m.start()) + 1
    return None


def _heard(fn, *args) -> tuple:
    """(fn(*args) or the exception it raised, the errors urdfdom printed
    meanwhile): what the C++ parser prints on the process's stderr (each
    message with a line of its own source paths) is kept off the terminal
    and read, so that rapidcomp says what went wrong itself. urdfdom goes
    on past some errors (an inertial it cannot read: the link weighs
    nothing), so they are read where it succeeds too."""
    if sys.stderr is not None:
        sys.stderr.flush()
    # A process started without stderr (2>&-) gets one on /dev/null for
    # the call, closed again after: else the capture's own file would be
    # opened as fd 2 and closed under it.
    closed = _closed(2)
    if closed:
        fd = os.open(os.devnull, os.O_WRONLY)
        if fd != 2:
            os.dup2(fd, 2)
            os.close(fd)
    saved = os.dup(2)
    try:
        with tempfile.TemporaryFile() as heard:
            os.dup2(heard.fileno(), 2)
            try:
                out = fn(*args)
            except Exception as exc:  # pinocchio raises ValueError/RuntimeError variants
                out = exc
            finally:
                os.dup2(saved, 2)
            heard.seek(0)
            text = heard.read().decode("utf-8", "replace")
    finally:
        os.close(saved)
        if closed:
            os.close(2)
    errors = [line.split(":", 1)[1].strip() for line in text.splitlines()
              if line.startswith("Error:")]
    return out, errors


def _closed(fd: int) -> bool:
    try:
        os.fstat(fd)
    except OSError:
        return True
    return False


def load_urdf(path: str | Path, flange: str | None = None) -> RobotModel:
    """A 6-axis arm from URDF (metres), converted to millimetres here: a
    serial chain of 6 revolute joints whose numbers a robot arm can have
    (links within 100 m, no negative mass), else bad input (its limits are
    checked once --limit has had its say: checked_limits)."""
    path = Path(path)
    xml = _urdf_xml(path)
    model, errors = _heard(pin.buildModelFromXML, xml)
    if errors:
        raise InputError(str(path), "cannot load URDF: " + "; ".join(errors))
    if isinstance(model, Exception):
        raise InputError(str(path), f"cannot load URDF: {model}")
    if model.nq != 6 or model.njoints != 7 or any(j.nq != 1 for j in model.joints[1:]):
        raise InputError(str(path), f"expected a serial arm of 6 revolute joints, "
                                    f"found {model.njoints - 1} joints with nq={model.nq}")
    for i in range(1, model.njoints):
        name = model.names[i]
        kind = model.joints[i].shortname()
        if kind not in _REVOLUTE:
            what = ("prismatic" if "Prismatic" in kind or kind[-2:] in ("PX", "PY", "PZ")
                    else kind)
            raise _bad_joint(path, name, f"joint {name} is {what}: expected a serial arm of 6 "
                             "revolute joints")
        if model.parents[i] != i - 1:
            raise _bad_joint(path, name, f"joint {name} does not follow {model.names[i - 1]}: "
                             "expected a serial arm of 6 revolute joints")
        t = np.asarray(model.jointPlacements[i].translation, float)
        if not (np.isfinite(t).all() and np.abs(t).max() <= MAX_LINK_M):
            raise _bad_joint(path, name, f"joint {name}: its origin "
                             f"[{', '.join(f'{v:g}' for v in t)}] m is not within "
                             f"{MAX_LINK_M:g} m of the joint before it")
        mass = float(model.inertias[i].mass)
        if not (math.isfinite(mass) and mass >= 0):
            raise _bad_joint(path, name, f"joint {name}: its link's mass {mass:g} kg is not a "
                             "mass")
        inertia = np.asarray(model.inertias[i].inertia, float)
        com = np.asarray(model.inertias[i].lever, float)
        if not (np.isfinite(inertia).all() and np.isfinite(com).all()
                and np.abs(com).max() <= MAX_LINK_M):
            raise _bad_joint(path, name, f"joint {name}: its link's inertial is not a body's "
                             "(expected finite numbers and a centre of mass within "
                             f"{MAX_LINK_M:g} m)")
    for i in range(1, model.njoints):
        p = model.jointPlacements[i]
        model.jointPlacements[i] = pin.SE3(p.rotation, p.translation * MM_PER_M)
        inert = model.inertias[i]
        try:
            model.inertias[i] = pin.Inertia(inert.mass, inert.lever * MM_PER_M,
                                            inert.inertia * MM_PER_M ** 2)
        except RuntimeError:
            # (An inertia matrix Pinocchio finds not positive, CAD noise of
            # -1e-12: only the link's mass and centre of mass are used, for
            # gravity; its rotational inertia is taken as none.)
            model.inertias[i] = pin.Inertia(inert.mass, inert.lever * MM_PER_M,
                                            np.zeros((3, 3)))
    for f in model.frames:
        f.placement = pin.SE3(f.placement.rotation, f.placement.translation * MM_PER_M)
    model.gravity = pin.Motion(np.array([0.0, 0.0, -GRAVITY_MM_S2]), np.zeros(3))
    names = [flange] if flange else [FLANGE_FRAME, "flange", "tool_flange", "ee_link"]
    fid = next((model.getFrameId(n) for n in names if model.existFrame(n)), None)
    if fid is None:
        raise InputError(str(path), f"no flange frame: expected one named {', '.join(names)}")
    if model.frames[fid].parentJoint != model.njoints - 1:
        raise InputError(str(path), f"the flange frame {model.frames[fid].name} does not hang "
                                    f"on the last joint {model.names[model.njoints - 1]}")
    t = np.asarray(model.frames[fid].placement.translation, float) / MM_PER_M
    if not (np.isfinite(t).all() and np.abs(t).max() <= MAX_LINK_M):
        name = model.frames[fid].name
        raise InputError(str(path), f"the flange frame {name}: its origin "
                                    f"[{', '.join(f'{v:g}' for v in t)}] m is not within "
                                    f"{MAX_LINK_M:g} m of the last joint",
                         _element_line(path, name, True) or _element_line(path, name))
    lower = tuple(float(x) / DEG for x in model.lowerPositionLimit)
    upper = tuple(float(x) / DEG for x in model.upperPositionLimit)
    return RobotModel(model.name or path.stem, model, fid, lower, upper,
                      limits_set=(f"the <limit> of {path.name}",) * len(lower))


def checked_limits(robot: RobotModel, shown: str) -> RobotModel:
    """robot, each joint's lower limit below its upper one (a URDF joint
    without them has 0 and 0: --limit gives them), else bad input."""
    for name, lo, hi in zip(robot.joint_names, robot.lower_deg, robot.upper_deg):
        if not lo < hi:
            raise InputError(shown, f"joint {name}: its lower limit {lo:g} deg is not below its "
                             f"upper limit {hi:g} deg (give its range with --limit "
                             f"{name}=LOWER:UPPER)")
        # (As --limit takes them: two turns each way is every arm's most.)
        if not -720 <= lo < hi <= 720:
            raise InputError(shown, f"joint {name}: its limits {lo:g}..{hi:g} deg are not "
                             "within -720..720 deg (give its range with --limit "
                             f"{name}=LOWER:UPPER)")
    return robot


def override_limits(robot: RobotModel, specs) -> RobotModel:
    """Apply `--limit` options, each "J5=-120:120" (degrees)."""
    from ..errors import RapidcompError
    if not specs:
        return robot
    lower, upper = list(robot.lower_deg), list(robot.upper_deg)
    names = [n.lower() for n in robot.joint_names]
    given: dict[int, str] = {}
    for spec in specs:
        try:
            joint, rng = spec.split("=")
            lo, hi = (float(x) for x in rng.split(":"))
            k = names.index(joint.strip().lower())
        except ValueError:
            raise RapidcompError(f"--limit {spec}: expected JOINT=LOWER:UPPER in degrees with "
                                 f"JOINT one of {', '.join(robot.joint_names)}") from None
        if not (math.isfinite(lo) and math.isfinite(hi) and -720 <= lo < hi <= 720):
            raise RapidcompError(f"--limit {spec}: expected LOWER < UPPER, finite degrees "
                                 "within -720..720")
        if k in given:
            raise RapidcompError(f"--limit {spec}: {robot.joint_names[k]} is limited twice "
                                 f"(also --limit {given[k]})")
        given[k] = spec
        lower[k], upper[k] = lo, hi
    set_by = [f"set by --limit {given[k]}" if k in given else
              robot.limits_set[k] if k < len(robot.limits_set) else "" for k in range(len(lower))]
    return robot.with_limits(lower, upper, set_by)
