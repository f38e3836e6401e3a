"""Loading what a job works on: the robot (built-in or URDF, joint limits),
the warm robot's solver (profile), a task's modules (and the modules of the
controller's other tasks, whose PERS writes count), the robot's base frame.
Shared by `check` and `fix`; errors are InputError/RapidcompError."""

from __future__ import annotations

import os
import re

from ..errors import InputError, RapidcompError
from ..rapid.task import TaskSource, load_problem, tasks_of
from ..source import EncryptedModule
from .plan import Task


def load_robot(robot: str | None, limits=()):
    from ..kinematics.analytic import ArmGeometry, UnsupportedGeometry
    from ..kinematics.chain import Chain
    from ..kinematics.robot import checked_limits, irb140, load_urdf, override_limits
    if robot is None or robot.lower() == "irb140":
        return override_limits(irb140(), limits)
    if not os.path.exists(robot):
        raise RapidcompError(f"--robot {robot}: not a built-in robot (irb140) and no such URDF "
                             "file")
    model = load_urdf(robot)
    # Every command solves the arm in closed form (fix, check) or places
    # points by it (simulate): one it cannot is refused here, for all.
    try:
        ArmGeometry.from_chain(Chain.from_robot(model))
    except UnsupportedGeometry as exc:
        raise InputError(robot, str(exc)) from None
    return checked_limits(override_limits(model, limits), robot)


def load_solver(profile: str, robot: str | None, force: bool, limits=()):
    from ..kinematics.analytic import UnsupportedGeometry
    from ..kinematics.ik import Solver
    from ..kinematics.profile import deform, read_profile
    nominal = load_robot(robot, limits)
    prof = read_profile(profile, force=force, joint_names=nominal.joint_names)
    try:
        return Solver(nominal, deform(nominal, prof))
    except UnsupportedGeometry as exc:
        raise RapidcompError(f"{robot}: {exc}") from exc


def load_state_solvers(profile: str, robot: str | None, force: bool, limits=()) -> dict:
    """Transient: {s: Solver of the robot deformed by s . profile} for the
    thermal states the written program is verified at."""
    from ..kinematics.ik import Solver
    from ..kinematics.profile import deform, read_profile, scaled
    from .transient import STATES
    nominal = load_robot(robot, limits)
    prof = read_profile(profile, force=force, joint_names=nominal.joint_names)
    return {s: Solver(nominal, deform(nominal, scaled(prof, s))) for s in STATES}


def load_task(source: TaskSource, with_modules=()) -> Task:
    """Parse the task's modules (named by their path inside the task) and
    the --with modules; a task the controller would not load (a module
    twice, a global name declared twice: load_problem) is refused."""
    from ..rapid.parse import parse_file, with_task_aliases
    # (An encrypted module of a task, which the controller loads and no
    # one reads, is taken as a module not given: its data, routines and
    # writes unknown; the output holds it as it is.)
    unreadable: list[str] = []
    files = [f for f in (_parse(source, rel, unreadable) for rel in source.modules)
             if f is not None]
    if not files:
        raise InputError(str(source.input), "every module of this task is encrypted (or "
                         "binary): nothing rapidcomp can read to compensate")
    problem = load_problem(source, files)
    if problem is not None:
        raise problem
    mine = {os.path.realpath(source.root / rel) for rel in source.modules}
    context = [parse_file(m) for m in with_modules if os.path.realpath(m) not in mine]
    # (An ALIAS of one module types the data of every other.)
    both = with_task_aliases(files + context)
    files, context = both[:len(files)], both[len(files):]
    observers = []
    others: list[str] = []
    if source.kind == "backup":
        # PERS data are shared between tasks: the other tasks' writes count.
        for other in tasks_of(source.input, motion_only=False):
            if other.task != source.task:
                # (Another task's encrypted module declares nothing this
                # task sees; its writes to shared PERS data are unknown.)
                observers += [f for f in (_parse(other, rel, others) for rel in other.modules)
                              if f is not None]
    origin = source.input.parent.name if source.kind == "pgf" else source.input.name
    return Task(source.task or source.name, tuple(files), tuple(context), tuple(observers),
                source.base_moved_by, origin, source.event_routines, source.entry,
                tuple(unreadable), tuple(others), source.unlisted)


def _parse(source: TaskSource, rel: str, unreadable: list | None = None):
    """A module of a task, named by its path inside the task (reports
    carry no absolute paths); a bad module is reported by the path the
    user can open. An encrypted module of a folder, program or backup is
    None, its path added to `unreadable`."""
    from ..rapid.parse import parse_file
    try:
        return parse_file(source.root / rel, rel)
    except EncryptedModule:
        if not source.is_folder or unreadable is None:
            raise
        # (Its path inside the task, a backup's from the backup's folder.)
        unreadable.append(rel)
        return None
    except InputError as exc:
        if not source.is_folder:
            raise
        raise InputError(source.shown(rel), exc.message, exc.line, exc.col,
                         exc.source_line) from None


# The model field of a backup's robot type (MOC.cfg -use_robot_type):
# ROB1_140_0.81_6, ROB2_1200_0.9_5_TypeB, ROB_R_14000_05_05_TYPEA; or an
# IRB number in another spelling.
_MODEL = re.compile(r"ROB\w*?_(\d+[A-Z]*)(?:_|$)", re.IGNORECASE)
_IRB = re.compile(r"IRB[\s_]*(\d+[A-Z]*)", re.IGNORECASE)
# The IRB 140 and its variants (140T, 140F foundry, 140CW, 140W).
_IRB140 = re.compile(r"140[A-Z]*", re.IGNORECASE)


def is_irb140(kind: str) -> bool:
    """Whether a robot type names the IRB 140 (its model field, not a
    number elsewhere in it: ROB1_6700_2.6_140 is an IRB 6700)."""
    m = _MODEL.match(kind) or _IRB.search(kind)
    return m is not None and _IRB140.fullmatch(m.group(1)) is not None


def robot_of_backup(source: TaskSource, robot: str | None, force: bool) -> str | None:
    """A backup names its robot (MOC.cfg ROBOT -use_robot_type). The
    built-in model is the IRB 140: a backup of another robot is refused,
    its program compensated with another arm's kinematics would move the
    robot by the difference, unless --force (then a note says so); so is
    one of several robots of which nothing says which is the task's,
    unless each is an IRB 140. A URDF (--robot) is taken as the robot
    named, which a note says. None where nothing is to be said."""
    kind = source.robot_type
    if kind is None:
        return None
    kinds = kind if type(kind) is tuple else (kind,)
    # (The backup by its name: the note goes into the report.)
    where = f"{source.input.name}/SYSPAR/MOC.cfg"
    which = (f"the robot {kinds[0]} (-use_robot_type)" if len(kinds) == 1 else
             f"the robots {', '.join(kinds)} (-use_robot_type) and nothing links task "
             f"{source.task} to one of them (SYS.cfg -UseMechanicalUnitGroup)")
    if robot is not None and robot.lower() != "irb140":
        return f"{where} names {which}: --robot {os.path.basename(robot)} is taken as its model"
    if all(is_irb140(k) for k in kinds):
        return None
    what = "not an IRB 140" if len(kinds) == 1 else "not every one an IRB 140"
    if not force:
        # (The error names the file as the input was given and the line of
        # the first robot type that is not an IRB 140's, as a module's
        # error names its place.)
        cfg = source.input / "SYSPAR" / "MOC.cfg"
        line, text = _line_naming(cfg, next(k for k in kinds if not is_irb140(k)))
        raise InputError(str(cfg), f"it names {which}, {what}, rapidcomp's built-in model: give "
                         "this robot's model with --robot ARM.urdf; --force takes it as an "
                         "IRB 140", line, None, text)
    return f"{where} names {which}, {what}: taken as an IRB 140 (--force)"


def _line_naming(path, kind: str) -> tuple:
    """(line number, its text) of the first line of a configuration file
    that gives `kind` as a -use_robot_type (not a comment), or (None,
    None)."""
    try:
        with open(path, encoding="latin-1") as f:
            for n, line in enumerate(f, 1):
                if (not line.lstrip().startswith("#") and "-use_robot_type" in line
                        and kind in line.split("-use_robot_type", 1)[1]):
                    return n, line
    except OSError:
        pass
    return None, None


def robot_base(source: TaskSource, given) -> tuple:
    """(world_M_base as (R, p) or None, what the report says of it): --base,
    else a backup's SYSPAR/MOC.cfg, else the world frame."""
    from .targets import parse_base
    if given is not None:
        return parse_base(given), "--base " + ",".join(f"{v:g}" for v in given)
    if source.base_problem is not None:
        raise RapidcompError(source.base_problem)
    if source.base is not None:
        (x, y, z), q = source.base
        return (parse_base((x, y, z, *q)),
                f"({x:g}, {y:g}, {z:g}) mm, [{', '.join(f'{v:g}' for v in q)}] (SYSPAR/MOC.cfg)")
    return None, "the world frame (assumed; --base sets another)"
