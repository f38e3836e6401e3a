"""What a program is: the modules of one RAPID task.

A controller runs tasks, not files: every module loaded into a task shares
one namespace (tool, work object and target data declared in a data or
system module are used by the motions of another). rapidcomp reads a task
from what people hand over:

* a module file (.mod, .modx, .sys, .prg): a task of that one module;
* a folder: every module file below it is one task;
* a program file (.pgf): the modules it lists;
* a controller backup (a folder holding RAPID/<TASK>/...): each motion task
  is its own program, named as in BACKINFO/backinfo.txt, its motion flag
  read from SYSPAR/SYS.cfg.

Only paths are found here; parsing is the caller's (job.py).
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, replace
from pathlib import Path, PurePath

from ..csvtable import number
from ..errors import InputError, RapidcompError
from ..kinematics.frames import MM_PER_M
from ..source import not_a_file

MODULE_SUFFIXES = (".mod", ".modx", ".sys", ".prg")
# A folder holding this many module files is not a task someone meant.
MAX_MODULES = 2000


@dataclass(frozen=True)
class TaskSource:
    """One task to compensate, as paths."""

    name: str                  # shown in reports: module file, folder, program or task name
    kind: str                  # "module", "folder", "pgf" or "backup"
    input: Path                # the path the user gave
    root: Path                 # module paths are relative to this folder
    modules: tuple[str, ...]   # relative POSIX paths of the task's modules
    task: str | None = None    # controller task name (backups)
    notes: tuple[str, ...] = ()
    # world_M_base of a backup's robot from SYSPAR/MOC.cfg: ((x, y, z) mm,
    # (q1, q2, q3, q4)), None when the backup does not set one.
    base: tuple | None = None
    # Why the backup cannot tell the base frame (several robots): an error
    # unless --base says it.
    base_problem: str | None = None
    # The mechanical unit that moves the robot's base (MOC.cfg ROBOT
    # -base_frame_coordinated or -base_frame_moved_by, a track): robtargets
    # need --track.
    base_moved_by: str | None = None
    # The robot a backup names for this task (MOC.cfg ROBOT -use_robot_type,
    # e.g. ROB1_140_0.81_6); a tuple of every type named where nothing
    # links the task to one robot; None when it names none.
    robot_type: str | tuple | None = None
    # The routines SYSPAR/SYS.cfg runs at events (CAB_EXEC_HOOKS, the
    # Controller topic's Event Routine: POWER_ON, START, STOP, RESTART...)
    # in this task, lower case.
    event_routines: tuple[str, ...] = ()
    # The routine the task's program starts at (SYS.cfg CAB_TASKS -Entry),
    # as written there.
    entry: str = "main"
    # A backup's module files of the task's folder that its backinfo.txt
    # does not list (a restore does not load them): not read.
    unlisted: tuple[str, ...] = ()

    @property
    def is_folder(self) -> bool:
        """Written as a folder (with the input's layout), not as one file."""
        return self.kind != "module"

    def shown(self, rel: str) -> str:
        """How a message names the task's module at rel: the path the user
        can open."""
        return str(self.root / rel) if self.is_folder else rel


def load_problem(source: TaskSource, files, rels: list[str] | None = None) -> InputError | None:
    """Why the controller would not load the task these parsed modules
    (files, ParsedFile) make, the first reason, or None: a module held
    twice (a copy of it in the task's folder), or a global name declared in
    two modules (data, routines; PERS of one type excepted: one shared
    object). rels: each file's path inside the task (default: its display
    path, as load_task names them). check and fix refuse such a task;
    inspect says so."""
    rels = rels if rels is not None else [pf.source.display_path for pf in files]

    def at(pf, rel: str, span, message: str) -> InputError:
        """The error at span of module pf (at rel in the task): file:line:col
        and its line, as a parse error names its place."""
        line, col = pf.source.position(span.start)
        return InputError(source.shown(rel), message, line, col, pf.source.line_text(line))
    modules: dict[str, str] = {}
    for pf, rel in zip(files, rels):
        for m in pf.modules:
            first = modules.setdefault(m.name.lower(), rel)
            if first != rel:
                # (A folder `fix` wrote inside the task: a .pgf's output is
                # PROGRAM_comp beside it.)
                output = next((part for path in (first, rel)
                               for part in PurePath(path).parts[:-1]
                               if part.lower().endswith("_comp")), None)
                advice = ("take the copy out of the backup, or list the task's modules in "
                          "its BACKINFO/backinfo.txt as the controller wrote it"
                          if source.kind == "backup" else
                          "give the program file (.pgf) or a folder without the copy")
                return at(pf, rel, m.node.name_span,
                          f"module {m.name} is also in {first}: a task holds each module once "
                          f"(the controller refuses to load it twice); {advice}"
                          + (f" ({output} is named as `rapidcomp fix` names its output: move it "
                             "out of the task's folder)" if output else ""))
    seen: dict[str, tuple] = {}
    for pf, rel in zip(files, rels):
        for m in pf.modules:
            found = [(r.node.name, "routine", None, r.node.span, r.node.scope)
                     for r in m.routines]
            found += [(d.name, d.storage, d.type, d.node.name_span, d.scope)
                      for d in m.declarations if d.routine is None]
            for name, kind, type_, span, scope in found:
                if (scope or "").upper() == "LOCAL":
                    continue
                first = seen.setdefault(name.lower(), (pf, kind, type_, span, m, rel))
                if first[4] is m:
                    continue            # (in one module: the parse said it)
                if kind == first[1] == "PERS" and type_ == first[2]:
                    continue
                other = f"{source.shown(first[5])}:{first[0].line(first[3])}"
                return at(pf, rel, span,
                          f"{name} is declared globally in two modules (also {other}): the "
                          "controller does not load the task (make one LOCAL, or give the "
                          "program file (.pgf) without the other)")
    return None


def is_module(path: Path) -> bool:
    return path.suffix.lower() in MODULE_SUFFIXES


def _modules_below(folder: Path, display: str) -> list[str]:
    found = []
    for p in folder.rglob("*"):
        if not is_module(p) or _hidden(p.relative_to(folder)):
            continue
        if p.is_symlink() and not p.exists():
            raise InputError(f"{display}/{p.relative_to(folder).as_posix()}",
                             "a link to a file that does not exist")
        if p.is_file():
            found.append(p.relative_to(folder).as_posix())
    found.sort()
    if len(found) > MAX_MODULES:
        raise RapidcompError(f"{display}: {len(found)} module files below it; a task holds "
                             f"at most {MAX_MODULES} (give the task's own folder)")
    return found


def _hidden(rel: Path) -> bool:
    return any(part.startswith(".") for part in rel.parts)


def tasks_of(path: str | Path, task_names: tuple[str, ...] = (),
             motion_only: bool = True) -> list[TaskSource]:
    """The tasks a command-line argument stands for (of a backup, its
    motion tasks; every task with motion_only=False)."""
    p = Path(path)
    shown = str(path)
    if not p.exists():
        raise RapidcompError(f"{shown}: no such file or folder")
    if p.is_dir():
        if (p / "RAPID").is_dir():
            return _backup(p, shown, task_names, motion_only)
        if task_names:
            raise RapidcompError(f"--task picks tasks of a controller backup; {shown} is a "
                                 "folder without RAPID/<TASK>/")
        mods = _modules_below(p, shown)
        if not mods:
            raise RapidcompError(f"{shown}: no module files (.mod, .modx, .sys, .prg) below it")
        return [TaskSource(p.name or shown, "folder", p, p, tuple(mods))]
    if task_names:
        raise RapidcompError(f"--task picks tasks of a controller backup; {shown} is a file")
    if p.suffix.lower() == ".pgf":
        return [_pgf(p, shown)]
    if not is_module(p):
        raise RapidcompError(f"{shown}: expected a module (.mod, .modx, .sys, .prg), a program "
                             "file (.pgf), a task folder or a controller backup")
    return [TaskSource(p.name, "module", p, p.parent, (p.name,))]


def _pgf(p: Path, shown: str) -> TaskSource:
    """<Program><Module>Name.mod</Module>...</Program>, module paths
    relative to the .pgf's folder."""
    not_a_file(p, shown)
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise InputError(shown, f"cannot read program file: {exc.strerror or exc}") from None
    try:
        root = ET.fromstring(data)
    except ET.ParseError as exc:
        line, col = exc.position
        what = re.sub(r": line \d+, column \d+$", "", str(exc))
        raise InputError(shown, f"not a program file (XML: {what})", line, col + 1) from None
    except (LookupError, ValueError) as exc:
        # (The XML declaration names an encoding Python does not know, or
        # one its bytes are not.)
        raise InputError(shown, f"not a program file (XML: {exc}); expected the encoding a "
                         "controller writes (UTF-8 or ISO-8859-1)", 1) from None
    if root.tag != "Program":
        raise InputError(shown, f"expected a <Program> element, found <{root.tag}>", 1)
    text = data.decode("utf-8", "replace")
    mods = []
    at = 0
    for el in root.iter("Module"):
        raw = (el.text or "").strip()
        rel = raw.replace("\\", "/")
        # (Its own element's line: a name such as "." is in the XML
        # declaration too.)
        m = re.compile(r"<Module>\s*" + re.escape(raw) + r"\s*</Module>").search(text, at)
        line = text.count("\n", 0, m.start()) + 1 if m else _line_of(text, rel)
        at = m.end() if m else at
        if not rel or Path(rel).is_absolute() or ".." in Path(rel).parts:
            raise InputError(shown, f"module path {rel!r}: expected a file name relative to "
                             "the program file", line)
        if not (p.parent / rel).is_file():
            raise InputError(shown, f"module {rel} listed here does not exist beside the "
                             "program file", line)
        if rel in mods:
            raise InputError(shown, f"module {rel} is listed twice", line)
        mods.append(rel)
    if not mods:
        raise InputError(shown, "the program file lists no <Module>", 1)
    return TaskSource(p.name, "pgf", p, p.parent, tuple(mods))


def _line_of(text: str, needle: str) -> int | None:
    i = text.find(needle) if needle else -1
    return text.count("\n", 0, i) + 1 if i >= 0 else None


# ------------------------------------------------------------------ backups

_TASK_LINE = re.compile(r"^>>(TASK\d+):\s*\(([^,)]*)", re.MULTILINE)


def _backup(root: Path, shown: str, wanted: tuple[str, ...],
            motion_only: bool = True) -> list[TaskSource]:
    folders = sorted(d for d in (root / "RAPID").iterdir() if d.is_dir())
    names, listed = _backinfo(root, shown)
    sys_cfg = _read_cfg(root / "SYSPAR" / "SYS.cfg", shown)
    motion = _motion_tasks(sys_cfg, shown)
    if motion and not names and not any(d.name.upper() in motion for d in folders):
        # The folders are TASK1, TASK2...; which is which task only
        # backinfo.txt says.
        why = ("is missing" if not (root / "BACKINFO" / "backinfo.txt").exists()
               else "names no task (no >>TASK1: line)")
        raise RapidcompError(
            f"{shown}: BACKINFO/backinfo.txt {why}, so the task folders "
            f"({', '.join(d.name for d in folders)}) cannot be matched to the motion "
            f"tasks SYSPAR/SYS.cfg names ({', '.join(sorted(motion))}); copy it from the backup")
    tasks, skipped, other = [], [], []
    for d in folders:
        name = names.get(d.name.upper(), d.name)
        mods = _modules_below(d, f"{shown}/RAPID/{d.name}")
        said, extra = [], []
        if d.name.upper() in listed:
            mods, said, extra = _as_listed(mods, listed[d.name.upper()], f"RAPID/{d.name}",
                                           name, shown)
        rel = [f"RAPID/{d.name}/{m}" for m in mods]
        if not rel:
            continue
        task = TaskSource(name, "backup", root, root, tuple(rel), name, notes=tuple(said),
                          unlisted=tuple(f"RAPID/{d.name}/{m}" for m in extra))
        if motion is not None and name.upper() not in motion:
            other.append(task)
            if motion_only:
                skipped.append(f"task {name} (RAPID/{d.name}) is not a motion task "
                               "(SYSPAR/SYS.cfg): not compensated")
                continue
        tasks.append(task)
    if wanted:
        chosen = []
        for w in wanted:
            hit = [t for t in tasks if w.upper() in (t.task.upper(),
                                                     t.modules[0].split("/")[1].upper())]
            if not hit:
                if any(w.upper() in (t.task.upper(), t.modules[0].split("/")[1].upper())
                       for t in other):
                    raise RapidcompError(f"--task {w}: {w} is not a motion task "
                                         "(SYSPAR/SYS.cfg); nothing to compensate there")
                have = ", ".join(t.task for t in tasks) or "none"
                raise RapidcompError(f"--task {w}: no motion task of that name in {shown} "
                                     f"(motion tasks: {have})")
            chosen += [t for t in hit if t not in chosen]
        tasks = chosen
    if motion is None and motion_only:
        skipped.append("SYSPAR/SYS.cfg says nothing of the tasks: every task holding modules "
                       "is treated as a motion task")
    if not tasks:
        raise RapidcompError(f"{shown}: a controller backup without a motion task holding "
                             "modules under RAPID/")
    groups = motion if motion is not None else {t.task.upper(): None for t in tasks}
    moc_cfg = _read_cfg(root / "SYSPAR" / "MOC.cfg", shown)
    frames = _base_frames(moc_cfg, shown, groups, _group_robots(sys_cfg, moc_cfg, shown))
    events = _cfg_instances(sys_cfg, "CAB_EXEC_HOOKS", f"{shown}/SYSPAR/SYS.cfg")
    entries = {(e.get("name") or "").upper(): e["entry"]
               for e in _cfg_instances(sys_cfg, "CAB_TASKS", f"{shown}/SYSPAR/SYS.cfg")
               if e.get("entry")}
    out = []
    for n, t in enumerate(tasks):
        frame, problem, mover, kind = frames.get(t.task.upper(), (None, None, None, None))
        # (An event routine without -Task, or with -AllTask or
        # -AllMotionTask, may be any motion task's: taken as this one's too.)
        mine = tuple(sorted({e["routine"].lower() for e in events if e.get("routine")
                             and (e.get("task") is None or "alltask" in e
                                  or "allmotiontask" in e
                                  or e["task"].upper() == t.task.upper())}))
        out.append(replace(t, notes=(tuple(skipped) if n == 0 else ()) + t.notes, base=frame,
                           base_problem=problem, base_moved_by=mover, event_routines=mine,
                           entry=entries.get(t.task.upper(), "main"), robot_type=kind))
    return out


def _read_bytes(path: Path, shown: str | None = None) -> bytes | None:
    """A backup file's bytes; None when it does not exist; a file that
    exists but cannot be read is bad input."""
    if not path.exists():
        return None
    not_a_file(path, _shown_cfg(path, shown))
    try:
        return path.read_bytes()
    except OSError as exc:
        raise InputError(_shown_cfg(path, shown), f"cannot read: {exc.strerror or exc}") from None


def _shown_cfg(path: Path, shown: str | None) -> str:
    return f"{shown}/{path.parent.name}/{path.name}" if shown else str(path)


_CFG_HEAD = re.compile(r"[A-Z_]+:CFG_")


def _read_cfg(path: Path, shown: str) -> str | None:
    """A controller configuration file's text (SYSPAR/*.cfg), None when it
    does not exist. It begins `TOPIC:CFG_...` (MOC:CFG_1.0:6:0::), in the
    controller's ASCII (one an editor saved as UTF-16, with its BOM, is
    read too); a file that does not is not one, and bad input: read as
    one, nothing in it would be found, and the backup's robot would be
    taken as standing at the world origin without a word."""
    raw = _read_bytes(path, shown)
    if raw is None:
        return None
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        text = raw.decode("utf-16").lstrip("\ufeff")
    else:
        # (Latin-1, as the controller writes it; an editor's UTF-8 BOM
        # left out, ASCII as it is.)
        text = raw.removeprefix(b"\xef\xbb\xbf").decode("latin-1")
    if not _CFG_HEAD.match(text.lstrip()):
        raise InputError(_shown_cfg(path, shown), "not a controller configuration file: "
                         f"expected a first line such as {path.stem.upper()}:CFG_1.0:6:0::", 1)
    return text


def _backinfo(root: Path, shown: str) -> tuple[dict[str, str], dict[str, list[str]]]:
    """From BACKINFO/backinfo.txt: TASKn folder -> task name (`>>TASK1:
    (T_ROB1,...)` lines), and TASKn folder -> the module files it lists for
    the task (below RAPID/TASKn, '/' between folders), the modules a
    restore loads into it: the lines after the task's up to the next `>>`,
    each `PROGMOD/Module1.mod @ ` (or with '\\'; attributes after the '@',
    or none); a task with no such line is not in the second."""
    raw = _read_bytes(root / "BACKINFO" / "backinfo.txt", shown) or b""
    # (As a module is read: UTF-8 where it is, else the controller's
    # Latin-1. A list of an accented module's name saved as UTF-8 names it
    # as its file system does.)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    names: dict = {}
    listed: dict = {}
    for m in _TASK_LINE.finditer(text):
        names[m.group(1).upper()] = m.group(2).strip() or m.group(1)
        start, end = text.find("\n", m.end()), text.find("\n>>", m.end())
        lines = (text[start + 1:end if end >= 0 else len(text)].splitlines() if start >= 0
                 else [])
        mods = [x for x in (line.split("@", 1)[0].strip().replace("\\", "/")
                            for line in lines) if x]
        if mods:
            listed[m.group(1).upper()] = mods
    return names, listed


def _as_listed(found: list[str], listed: list[str], folder: str, task: str,
               shown: str) -> tuple[list[str], list[str], list[str]]:
    """The module files of a backup's task folder a restore loads (those
    backinfo.txt lists, matched without regard to case as the controller's
    file system does), notes on those it lists but the backup does not
    hold and those it holds but does not list, and those. Where it holds
    none that are listed, the list is not this backup's: bad input."""
    want = {x.lower() for x in listed}
    have = {f.lower() for f in found}
    kept = [f for f in found if f.lower() in want]
    if found and not kept:
        raise RapidcompError(
            f"{shown}: BACKINFO/backinfo.txt lists {', '.join(listed)} as task {task}'s "
            f"modules, none of which {folder} holds (it holds {', '.join(found)}): the list is "
            "not this backup's, and a restore would load none of them; give the backinfo.txt "
            "the controller wrote with these modules")
    notes = []
    extra = [f for f in found if f.lower() not in want]
    if extra:
        notes.append(f"{', '.join(f'{folder}/{f}' for f in extra)} "
                     f"{'are' if len(extra) > 1 else 'is'} not among task {task}'s modules "
                     "that BACKINFO/backinfo.txt lists (a restore does not load "
                     f"{'them' if len(extra) > 1 else 'it'}): not read")
    missing = [x for x in listed if x.lower() not in have]
    if missing:
        notes.append(f"{', '.join(f'{folder}/{x}' for x in missing)}, which "
                     "BACKINFO/backinfo.txt lists among task "
                     f"{task}'s modules, {'are' if len(missing) > 1 else 'is'} not in the "
                     "backup: read without "
                     f"{'them' if len(missing) > 1 else 'it'}")
    return kept, notes, extra


def _cfg_instances(text: str | None, type_name: str,
                   where: str = "") -> list[dict[str, str | None]]:
    """The instances of one type of a controller configuration file
    (`TYPE:` then lines of `-attribute value`, continued with a backslash):
    lower-case attribute -> value (None for a flag without one). An
    attribute given twice in an instance, or two instances of one name, is
    bad input (in `where`): which one the controller took cannot be told."""
    if text is None:
        return []
    sections = []
    # (Every section of the type: a file merged from several may hold it
    # twice.)
    for start in re.finditer(rf"^{type_name}:", text, re.MULTILINE):
        section = text[start.end():]
        # The section ends at the next type line ("NAME:" at the start of a
        # line; UCCM0: has digits too).
        end = re.search(r"^[A-Z][A-Z0-9_]*:", section, re.MULTILINE)
        sections.append(section[:end.start()] if end else section)
    out = []
    for line in re.sub(r"\\[ \t]*\r?\n", " ", "\n".join(sections)).splitlines():
        if line.lstrip().startswith("#"):
            continue                  # (a comment: `# old: -name "ROB_OLD" ...`)
        pairs = re.findall(r'(?:^|\s)-(\w+)(?:[ \t]+("[^"]*"|[^\s"-]\S*|-[\d.]\S*))?', line)
        if not pairs:
            continue
        inst = {k.lower(): (v.strip('"') if v else None) for k, v in pairs}
        name = inst.get("name")
        if len(inst) < len(pairs):
            twice = next(k for k in inst if [p[0].lower() for p in pairs].count(k) > 1)
            raise InputError(where, f"{type_name} {name or ''}: -{twice} is given twice")
        if name is not None and any((o.get("name") or "").lower() == name.lower() for o in out):
            raise InputError(where, f"{type_name} {name} is defined twice")
        out.append(inst)
    return out


def _motion_tasks(text: str | None, shown: str) -> dict[str, str | None] | None:
    """Upper-case names of the motion tasks in SYSPAR/SYS.cfg (its text;
    CAB_TASKS instances with -MotionTask) -> their mechanical unit group
    (lower case, None when not given), or None when the file says nothing
    about tasks."""
    instances = _cfg_instances(text, "CAB_TASKS", f"{shown}/SYSPAR/SYS.cfg")
    if not instances:
        return None
    out = {}
    for inst in instances:
        name = inst.get("name")
        if name is None or "motiontask" not in inst:
            continue
        flag = inst["motiontask"]
        if flag is None or flag.upper() in ("YES", "TRUE"):
            group = inst.get("usemechanicalunitgroup")
            out[name.upper()] = group.lower() if group else None
    return out


_MOC_KEYS = ("base_frame_pos_x", "base_frame_pos_y", "base_frame_pos_z", "base_frame_orient_u0",
             "base_frame_orient_u1", "base_frame_orient_u2", "base_frame_orient_u3")
_IDENTITY = (0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)
MAX_BASE_M = 100.0


def _group_robots(sys_cfg: str | None, moc_cfg: str | None, shown: str) -> dict[str, str]:
    """Mechanical unit group -> its robot (lower case): MECHANICAL_UNIT_GROUP
    -Robot, a type of the controller's topic, SYSPAR/SYS.cfg (a RobotWare 6
    MultiMove backup has it there); one that MOC.cfg holds is read too."""
    out: dict[str, str] = {}
    for cfg, text in (("SYS.cfg", sys_cfg), ("MOC.cfg", moc_cfg)):
        for inst in _cfg_instances(text, "MECHANICAL_UNIT_GROUP", f"{shown}/SYSPAR/{cfg}"):
            if inst.get("name"):
                out.setdefault(inst["name"].lower(), (inst.get("robot") or "").lower())
    return out


def _base_frames(text: str | None, shown: str, groups_of: dict[str, str | None],
                 robot_of: dict[str, str]) -> dict:
    """Each motion task's robot base frame in the world from SYSPAR/MOC.cfg
    (its text):
    the task's mechanical unit group (SYS.cfg) names its ROBOT (robot_of:
    _group_robots), whose -base_frame_pos_x/y/z (metres) and
    -base_frame_orient_u0..u3 (quaternion w, x, y, z) place it. Task name
    (upper case) -> (frame: ((x, y, z) mm, (q1..q4)) or None for the world
    frame; the reason it cannot be told (several robots, no link to one) or
    None; the unit that moves the base or None; the robot's type,
    -use_robot_type, or None). Values no robot cell has are bad input."""
    robots = {}
    movers = {}
    kinds = {}
    where = f"{shown}/SYSPAR/MOC.cfg"
    for inst in _cfg_instances(text, "ROBOT", where):
        if inst.get("name") is None:
            continue
        vals = []
        for k, default in zip(_MOC_KEYS, _IDENTITY):
            try:
                v = number(inst[k] or "") if k in inst else default
            except ValueError:
                raise InputError(where, f"ROBOT {inst['name']}: -{k} "
                                 f"{inst.get(k) or '(no value)'} is not a number") from None
            if not (abs(v) <= MAX_BASE_M if k.startswith("base_frame_pos") else abs(v) <= 1.0):
                raise InputError(where, f"ROBOT {inst['name']}: -{k} {v:g} is not "
                                 + ("a position in metres within 100 m of the world origin"
                                    if k.startswith("base_frame_pos") else
                                    "a quaternion component (-1..1)"))
            vals.append(v)
        if abs(math.sqrt(sum(v * v for v in vals[3:])) - 1.0) > 1e-3:
            raise InputError(where, f"ROBOT {inst['name']}: -base_frame_orient_u0..u3 "
                             f"[{', '.join(f'{v:g}' for v in vals[3:])}] is not a unit "
                             "quaternion")
        robots[inst["name"].lower()] = None if tuple(vals) == _IDENTITY else (
            (vals[0] * MM_PER_M, vals[1] * MM_PER_M, vals[2] * MM_PER_M), tuple(vals[3:]))
        # The unit that moves its base (a track): -base_frame_coordinated,
        # as RobotWare 6 writes it, or -base_frame_moved_by, as older
        # systems do.
        movers[inst["name"].lower()] = (inst.get("base_frame_coordinated")
                                        or inst.get("base_frame_moved_by"))
        kinds[inst["name"].lower()] = inst.get("use_robot_type") or None
    out: dict = {}
    for task, group in groups_of.items():
        robot = robot_of.get(group or "")
        if robot not in robots and len(robots) == 1:
            robot = next(iter(robots))
        mover = movers.get(robot)
        # (Where nothing says which robot is the task's: every type named,
        # one or several.)
        kind = kinds.get(robot) if robot in robots else (
            tuple(sorted({k for k in kinds.values() if k})) or None)
        if type(kind) is tuple and len(kind) == 1:
            kind = kind[0]
        if robot in robots:
            out[task] = (robots[robot], None, mover, kind)
        elif len(set(robots.values())) <= 1:
            mover = next((m for m in movers.values() if m), None)
            out[task] = (next(iter(robots.values()), None), None, mover, kind)
        else:
            out[task] = (None, f"{where}: several robots with different base frames and nothing "
                               f"links task {task} to one (SYS.cfg CAB_TASKS "
                               "-UseMechanicalUnitGroup, MECHANICAL_UNIT_GROUP -Robot); say "
                               "where this task's "
                               "robot stands with --base X,Y,Z,Q1,Q2,Q3,Q4",
                         next((m for m in movers.values() if m), None), kind)
    return out
