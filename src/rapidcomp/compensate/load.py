"""Loading what a job works on: the robot (built-in or URDF, joint limits),
the warm robot's solver (profile), a task's modules (and the modules of the
controller's other tasks, whose PERS writes count), the robot's base frame.
Shared by `check` and `fix`; errors are InputError/RapidcompError."""

from __future__ import annotations

import os
from pathlib import PurePath

from ..errors import InputError, RapidcompError
from ..rapid.task import TaskSource, tasks_of
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
    the --with modules; a module name twice in a task is refused, as the
    controller refuses to load it."""
    from ..rapid.parse import parse_file, with_task_aliases
    files = [_parse(source, rel) for rel in source.modules]
    seen: dict[str, str] = {}
    for pf in files:
        for m in pf.modules:
            first = seen.setdefault(m.name.lower(), pf.source.display_path)
            if first != pf.source.display_path:
                # (A folder `fix` wrote inside the task: a .pgf's output is
                # PROGRAM_comp beside it.)
                output = next((part for path in (first, pf.source.display_path)
                               for part in PurePath(path).parts[:-1]
                               if part.lower().endswith("_comp")), None)
                raise InputError(_shown(source, pf.source.display_path),
                                 f"module {m.name} is also in {first}: a task holds each module "
                                 "once (the controller refuses to load it twice); give the "
                                 "program file (.pgf) or a folder without the copy"
                                 + (f" ({output} is named as `rapidcomp fix` names its output: "
                                    "move it out of the task's folder)" if output else ""),
                                 pf.line(m.node.name_span))
    _one_global_each(source, files)
    mine = {os.path.realpath(source.root / rel) for rel in source.modules}
    context = [parse_file(m) for m in with_modules if os.path.realpath(m) not in mine]
    # (An ALIAS of one module types the data of every other.)
    both = with_task_aliases(files + context)
    files, context = both[:len(files)], both[len(files):]
    observers = []
    if source.kind == "backup":
        # PERS data are shared between tasks: the other tasks' writes count.
        for other in tasks_of(source.input, motion_only=False):
            if other.task != source.task:
                observers += [_parse(other, rel) for rel in other.modules]
    origin = source.input.parent.name if source.kind == "pgf" else source.input.name
    return Task(source.task or source.name, tuple(files), tuple(context), tuple(observers),
                source.base_moved_by, origin, source.event_routines, source.entry)


def _one_global_each(source: TaskSource, files) -> None:
    """A global name declared in two modules of a task (data, routines;
    PERS of one type excepted: one shared object) is refused, as the
    controller refuses to load the task."""
    seen: dict[str, tuple] = {}
    for pf in files:
        for m in pf.modules:
            found = [(r.node.name, "routine", None, r.node.span, r.node.scope)
                     for r in m.routines]
            found += [(d.name, d.storage, d.type, d.node.name_span, d.scope)
                      for d in m.declarations if d.routine is None]
            for name, kind, type_, span, scope in found:
                if (scope or "").upper() == "LOCAL":
                    continue
                first = seen.setdefault(name.lower(), (pf, kind, type_, span, m))
                if first[4] is m:
                    continue            # (in one module: the parse said it)
                if kind == first[1] == "PERS" and type_ == first[2]:
                    continue
                other = f"{_shown(source, first[0].source.display_path)}:{first[0].line(first[3])}"
                raise InputError(_shown(source, pf.source.display_path),
                                 f"{name} is declared globally in two modules (also {other}): "
                                 "the controller does not load the task (make one LOCAL, or "
                                 "give the program file (.pgf) without the other)",
                                 pf.line(span))


def _parse(source: TaskSource, rel: str):
    """A module of a task, named by its path inside the task (reports
    carry no absolute paths); a bad module is reported by the path the
    user can open."""
    from ..rapid.parse import parse_file
    try:
        return parse_file(source.root / rel, rel)
    except InputError as exc:
        if not source.is_folder:
            raise
        raise InputError(_shown(source, rel), exc.message, exc.line, exc.col,
                         exc.source_line) from None


def _shown(source: TaskSource, rel: str) -> str:
    return str(source.root / rel) if source.is_folder else rel


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
