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

import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

from ..errors import InputError, RapidcompError

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

    @property
    def is_folder(self) -> bool:
        """Written as a folder (with the input's layout), not as one file."""
        return self.kind != "module"


def is_module(path: Path) -> bool:
    return path.suffix.lower() in MODULE_SUFFIXES


def _modules_below(folder: Path, display: str) -> list[str]:
    found = sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*")
                   if p.is_file() and is_module(p) and not _hidden(p.relative_to(folder)))
    if len(found) > MAX_MODULES:
        raise RapidcompError(f"{display}: {len(found)} module files below it; a task holds "
                             f"at most {MAX_MODULES} (give the task's own folder)")
    return found


def _hidden(rel: Path) -> bool:
    return any(part.startswith(".") for part in rel.parts)


def tasks_of(path: str | Path, task_names: tuple[str, ...] = ()) -> list[TaskSource]:
    """The tasks a command-line argument stands for."""
    p = Path(path)
    shown = str(path)
    if not p.exists():
        raise RapidcompError(f"{shown}: no such file or folder")
    if p.is_dir():
        if (p / "RAPID").is_dir():
            return _backup(p, shown, task_names)
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
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise InputError(shown, f"cannot read program file: {exc.strerror or exc}") from None
    try:
        root = ET.fromstring(data)
    except ET.ParseError as exc:
        line, col = exc.position
        raise InputError(shown, f"not a program file: {exc.msg if hasattr(exc, 'msg') else exc}",
                         line, col + 1) from None
    if root.tag != "Program":
        raise InputError(shown, f"expected a <Program> element, found <{root.tag}>", 1)
    text = data.decode("utf-8", "replace")
    mods = []
    for el in root.iter("Module"):
        rel = (el.text or "").strip().replace("\\", "/")
        line = _line_of(text, rel)
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


def _backup(root: Path, shown: str, wanted: tuple[str, ...]) -> list[TaskSource]:
    folders = sorted(d for d in (root / "RAPID").iterdir() if d.is_dir())
    names = _backinfo_names(root)
    motion = _motion_tasks(root)
    tasks, skipped = [], []
    for d in folders:
        name = names.get(d.name.upper(), d.name)
        mods = _modules_below(d, f"{shown}/RAPID/{d.name}")
        rel = [f"RAPID/{d.name}/{m}" for m in mods]
        if not rel:
            continue
        if motion is not None and name.upper() not in motion:
            skipped.append(f"task {name} (RAPID/{d.name}) is not a motion task "
                           "(SYSPAR/SYS.cfg): not compensated")
            continue
        tasks.append(TaskSource(name, "backup", root, root, tuple(rel), name))
    if wanted:
        chosen = []
        for w in wanted:
            hit = [t for t in tasks if w.upper() in (t.task.upper(),
                                                     t.modules[0].split("/")[1].upper())]
            if not hit:
                have = ", ".join(t.task for t in tasks) or "none"
                raise RapidcompError(f"--task {w}: no motion task of that name in {shown} "
                                     f"(motion tasks: {have})")
            chosen += [t for t in hit if t not in chosen]
        tasks = chosen
    if not tasks:
        raise RapidcompError(f"{shown}: a controller backup without a motion task holding "
                             "modules under RAPID/")
    if skipped:
        tasks[0] = TaskSource(tasks[0].name, tasks[0].kind, tasks[0].input, tasks[0].root,
                              tasks[0].modules, tasks[0].task, tuple(skipped))
    return tasks


def _read_text(path: Path) -> str | None:
    try:
        return path.read_bytes().decode("latin-1")
    except OSError:
        return None


def _backinfo_names(root: Path) -> dict[str, str]:
    """TASKn folder -> task name, from `>>TASK1: (T_ROB1,...)` lines."""
    text = _read_text(root / "BACKINFO" / "backinfo.txt") or ""
    return {m.group(1).upper(): m.group(2).strip() or m.group(1)
            for m in _TASK_LINE.finditer(text)}


def _motion_tasks(root: Path) -> set[str] | None:
    """Upper-case names of the motion tasks in SYSPAR/SYS.cfg (CAB_TASKS
    instances with -MotionTask), or None when the file says nothing about
    tasks."""
    text = _read_text(root / "SYSPAR" / "SYS.cfg")
    if text is None or "CAB_TASKS:" not in text:
        return None
    section = text.split("CAB_TASKS:", 1)[1]
    # The section ends at the next type line ("NAME:" at the start of a line).
    end = re.search(r"^[A-Z_]+:", section, re.MULTILINE)
    if end:
        section = section[:end.start()]
    out = set()
    for line in re.sub(r"\\[ \t]*\r?\n", " ", section).splitlines():
        name = re.search(r'-Name\s+"([^"]+)"', line)
        flag = re.search(r'-MotionTask(?:\s+"?(\w+)"?)?', line)
        if name and flag and (flag.group(1) is None or flag.group(1).upper() in ("YES", "TRUE")):
            out.add(name.group(1).upper())
    return out
