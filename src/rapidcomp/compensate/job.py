"""One `rapidcomp fix` job per task: load (load.py), compensate, render
outputs in memory. Files are written by the caller, all at once
(atomic.py), and only when every job succeeded: bad input anywhere means no
output anywhere.

Several tasks run in a process pool of two workers where the process may use
two CPUs (cpus.py), else one after the other.
"""

from __future__ import annotations

import os
import re
import sys

from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field, replace
from pathlib import Path

from .. import side
from ..atomic import utf8
from ..collector import paused
from ..cpus import side_by_side
from ..errors import Errors, InputError, RapidcompError
from ..process import let_go
from ..progress import Progress
from ..rapid.task import TaskSource
from . import report
from .fix import FixResult, fix
from .load import load_solver, load_state_solvers, load_task, robot_base, robot_of_backup


@dataclass(frozen=True)
class JobSpec:
    source: TaskSource
    output: str                      # module file, or the output folder of a task folder
    report: str | None
    json: str | None
    profile: str
    robot: str | None
    with_modules: tuple[str, ...]
    mode: str
    force: bool
    limits: tuple[str, ...] = ()
    track: tuple[str, ...] = ()
    start: tuple[float, ...] | None = None
    base: tuple[float, ...] | None = None       # --base X,Y,Z,Q1..Q4
    progress: bool | None = None
    transient: object | None = None               # transient.Transient

    @property
    def program(self) -> str:
        return str(self.source.input)


@dataclass(frozen=True)
class Report:
    """A report file, rendered as it is written: a CAM program's report is
    ~75 MB of text (JSON: ~150 MB), not held whole as text and again as
    bytes (1e5 targets with --json peaked at 1.9 GB so)."""

    kind: str                        # "markdown" | "json"
    result: FixResult
    meta: dict
    # The job's progress line, shown again while the report is written.
    progress: Progress | None = field(default=None, compare=False)

    def chunks(self) -> Iterator[bytes]:
        # (Millions of objects made and dropped: the collector paused, as
        # for the job itself.)
        if self.progress is not None:
            self.progress.stage("writing the JSON report" if self.kind == "json"
                                else "writing the report")
        try:
            with paused():
                render = report.markdown if self.kind == "markdown" else report.as_json
                for piece in render(self.result, self.meta, pieces=True):
                    yield utf8(piece)
        finally:
            # (Cleared also when the write fails: the error's message
            # starts a line of its own.)
            if self.progress is not None:
                self.progress.done()

    def render(self) -> bytes:
        return b"".join(self.chunks())


@dataclass(frozen=True)
class JobOutcome:
    spec: JobSpec
    result: FixResult
    # (path, bytes or a Report) to write: atomic.write_all takes both.
    files: tuple[tuple[str, bytes | Report], ...]
    # Files of the output that were there already as they would be written
    # (a transient support module another program of the folder wrote).
    kept: tuple[str, ...] = ()


def default_output(path: str, folder: bool = False) -> str:
    p = Path(path)
    if folder:
        base = p.parent / p.stem if p.suffix.lower() == ".pgf" else p
        return str(base.with_name(base.name + "_comp"))
    return str(p.with_name(p.stem + "_comp" + p.suffix))


def output_path(spec: JobSpec, rel: str) -> Path:
    if not spec.source.is_folder:
        return Path(spec.output)
    return Path(spec.output) / rel


# Python frames the analyses may use: a routine call chain or a nesting of
# IF/WHILE blocks takes a few each (real programs: tens of levels).
MAX_FRAMES = 20_000


def allow_deep_nesting() -> None:
    """Programs nested hundreds of levels deep (generated code) are
    followed, not a RecursionError (Python 3.11 calls between Python
    functions need no C stack)."""
    if sys.getrecursionlimit() < MAX_FRAMES:
        sys.setrecursionlimit(MAX_FRAMES)


def run(spec: JobSpec) -> JobOutcome:
    # Loading and encoding the output make millions of objects too (fix
    # and parse pause the collector for their own part, a Report its
    # rendering).
    with paused():
        return _run(spec)


def _run(spec: JobSpec) -> JobOutcome:
    allow_deep_nesting()
    # (What the job before kept goes now: process.py.)
    let_go(None)
    src = spec.source
    progress = Progress(src.name, spec.progress)
    # A big task's job hands work to a second process (side.py), forked
    # here while this one is small; it is reaped when the result is made.
    with side.helping(_size(src)):
        return _run_helped(spec, src, progress)


def _size(src: TaskSource) -> int:
    """Bytes of the task's modules (0 for one that cannot be read: the
    parse says why)."""
    total = 0
    for rel in src.modules:
        try:
            total += (src.root / rel).stat().st_size
        except (OSError, ValueError):
            pass
    return total


def _run_helped(spec: JobSpec, src: TaskSource, progress: Progress) -> JobOutcome:
    from .targets import parse_track
    progress.stage("parsing")
    task = load_task(src, spec.with_modules)
    robot_note = robot_of_backup(src, spec.robot, spec.force)
    solver = load_solver(spec.profile, spec.robot, spec.force, spec.limits)
    progress.stage("compensating")
    names = {} if src.is_folder else {src.modules[0]: Path(spec.output).name}
    base, base_text = robot_base(src, spec.base)
    transient = support = None
    kept: list[str] = []
    if spec.transient is not None:
        from .transient import check_names
        check_names(task, spec.transient)
        # (The support module, and whether one of another program is where
        # it goes, known before the work: not refused after it.)
        support = _support_files(spec, task, kept)
        transient = (spec.transient, load_state_solvers(spec.profile, spec.robot, spec.force,
                                                        spec.limits))
    result = fix(task, solver, spec.mode, track=parse_track(spec.track), output_names=names,
                 start=spec.start, base=base, transient=transient, json=bool(spec.json))
    if src.notes or robot_note:
        result = replace(result, notes=src.notes + ((robot_note,) if robot_note else ())
                         + result.notes)
    progress.stage("writing")
    meta = {
        "output": Path(spec.output).name + ("/" if src.is_folder else ""),
        "mode": spec.mode,
        "profile": Path(spec.profile).name,
        "robot": Path(spec.robot).name if spec.robot else "irb140",
        "with": ", ".join(Path(m).name for m in spec.with_modules) or "-",
        "joint limits": ", ".join(spec.limits) or "robot defaults",
    }
    meta["robot base"] = base_text
    if spec.track:
        meta["track"] = ", ".join(spec.track)
    if spec.start:
        meta["start"] = ", ".join(f"{v:g}" for v in spec.start)
    if spec.transient is not None:
        meta["transient"] = spec.transient.law
    if src.is_folder:
        meta = {"input": f"{src.kind} {src.input.name}" + (f", task {src.task}" if src.task
                                                           else ""),
                "modules": len(src.modules), **meta}
    # Past the result the parsed task is not needed, but for each module's
    # encoding (1e5 targets: ~300 MB; in the command's own process kept to
    # its end instead of freed object by object, process.py).
    sources = [pf.source for pf in task.files]
    let_go(task)
    task = None
    out = []
    for source, m in zip(sources, result.modules):
        out.append((str(output_path(spec, m.path)), source.encode(m.text)))
    if support is not None:
        out += support
    if spec.report:
        out.append((spec.report, Report("markdown", result, meta, progress)))
    if spec.json:
        out.append((spec.json, Report("json", result, meta, progress)))
    progress.done()
    return JobOutcome(spec, result, tuple(out), tuple(kept))


def _support_files(spec: JobSpec, task, kept: list[str]) -> list[tuple[str, bytes]]:
    """The transient support module, where the task loads it: next to the
    output module; in a folder next to the task's first module (a backup:
    its task's SYSMOD folder, whose modules a restore loads); a program
    file (.pgf) lists it after its last module. Where the same module is
    there already, its path goes to `kept`, not to the files."""
    from .transient import MODULE_FILE, differs, support_module
    src = spec.source
    first = task.files[0].source
    nl = "\r\n" if "\r\n" in first.text else "\n"
    text = support_module(spec.transient, nl).encode("ascii")
    if not src.is_folder:
        out = [(str(Path(spec.output).parent / MODULE_FILE), text)]
    else:
        rel = Path(src.modules[0]).parent
        if src.kind == "backup" and rel.name.upper() == "PROGMOD":
            rel = rel.parent / "SYSMOD"
        out = [(str(Path(spec.output) / rel / MODULE_FILE), text)]
    path = Path(out[0][0])
    if path.exists():
        try:
            existing = path.read_bytes()
        except OSError:
            existing = None
        if existing is None or existing.replace(b"\r\n", b"\n") != text.replace(b"\r\n", b"\n"):
            where, what = differs(existing, text)
            raise RapidcompError(f"{path}{where}: exists and is not this support module"
                                 f"{': ' + what if what else ''} (another program's, with other "
                                 "settings, or a file of yours); write the output to another "
                                 "folder or remove it")
        # The same module (another program of the folder wrote it, in its
        # own line breaks): kept as it is.
        out = []
        kept.append(str(path))
    if not src.is_folder:
        return out
    # A program file lists the support module too: the one given, or each
    # of a task folder's (copied with it; a program loads only what it
    # lists).
    if src.kind == "pgf":
        pgfs = [src.input]
    elif src.kind == "folder":
        pgfs = sorted(p for p in src.root.rglob("*.pgf") if p.is_file())
    else:
        pgfs = []
    for p in pgfs:
        try:
            raw = p.read_bytes()
        except OSError as exc:
            raise InputError(str(p), f"cannot read file: {exc.strerror or exc}") from None
        where = p.parent.relative_to(src.root) if src.kind == "folder" else Path(".")
        entry = Path(os.path.relpath(rel / MODULE_FILE, where)).as_posix()
        listed = _listing(raw, entry)
        if listed is None:
            raise InputError(str(p), "lists no <Module>: cannot add the transient support "
                             f"module {MODULE_FILE}")
        dest = Path(spec.output) / (p.name if src.kind == "pgf" else p.relative_to(src.root))
        out.append((str(dest), listed))
    return out


def _listing(raw: bytes, entry: str) -> bytes | None:
    """A program file's bytes with `<Module>entry</Module>` on a line of its
    own after its last module (not one commented out), in its own line
    breaks, indentation and encoding, every other byte as it was; None
    where it lists no module. (Read as text, its CRLF became LF: its bytes
    are taken as they are; ASCII is the same in every encoding but
    UTF-16's, which keeps its BOM.)"""
    codec = ("utf-16-le" if raw.startswith(b"\xff\xfe") else
             "utf-16-be" if raw.startswith(b"\xfe\xff") else "latin-1")
    pgf = raw.decode(codec)
    end = _last_module_end(pgf)
    if end < 0:
        return None
    line = pgf[max(pgf.rfind("\n", 0, end), pgf.rfind("\r", 0, end)) + 1:end]
    indent = line[:len(line) - len(line.lstrip(" \t"))]
    cut = end + len("</Module>")
    nl = "\r\n" if "\r\n" in pgf else "\r" if "\r" in pgf and "\n" not in pgf else "\n"
    return (pgf[:cut] + nl + indent + f"<Module>{entry}</Module>" + pgf[cut:]).encode(codec)


def _last_module_end(pgf: str) -> int:
    """Where the last `</Module>` of a program file's text begins that is
    not inside an XML comment (a module listed and commented out is not
    one the controller loads; -1: none)."""
    comments = [(m.start(), m.end()) for m in re.finditer(r"<!--.*?-->", pgf, re.DOTALL)]
    at = len(pgf)
    while True:
        at = pgf.rfind("</Module>", 0, at)
        if at < 0 or not any(a <= at < b for a, b in comments):
            return at


def run_all(specs: list[JobSpec], workers: int | None = None) -> list[JobOutcome]:
    """Run jobs (in parallel when there are several, on `workers`
    processes, default two where this process may use two CPUs); after all
    ended, the bad inputs of every job are raised together."""
    if workers is None:
        workers = side_by_side()
    if len(specs) == 1:
        return [run(specs[0])]
    errors: list[RapidcompError] = []
    outcomes = []
    if workers <= 1:
        for spec in specs:
            try:
                outcomes.append(run(spec))
            except RapidcompError as exc:
                errors.append(exc)
    else:
        try:
            with ProcessPoolExecutor(max_workers=min(workers, len(specs))) as pool:
                futures = [pool.submit(_run_rendered, s) for s in specs]
                for spec, f in zip(specs, futures):
                    try:
                        outcomes.append(f.result())
                    except RapidcompError as exc:
                        errors.append(exc)
                    except BrokenProcessPool:
                        errors.append(RapidcompError(
                            f"{spec.source.input}: the worker process compensating it died "
                            "(out of memory?); nothing written"))
        except BrokenProcessPool:  # raised again when the pool shuts down
            pass
    if errors:
        raise errors[0] if len(errors) == 1 else Errors(errors)
    return outcomes


def _run_rendered(spec: JobSpec) -> JobOutcome:
    """run() in a worker process: its reports rendered there, in parallel
    with the other worker's, and returned as bytes. (The workers keep both
    cores busy: a module's literals are decoded in the worker itself, not
    by a process of its own, rapid/predecode.py.)"""
    from ..rapid import predecode
    predecode.enabled = side.enabled = False
    out = run(spec)
    # (The parsed program goes before the reports are rendered here: a
    # worker goes on to its next module, and ends without os._exit.)
    let_go(None)
    return replace(out, files=tuple((path, data.render() if isinstance(data, Report) else data)
                                    for path, data in out.files))


def layout(source: TaskSource) -> list[str]:
    """Relative paths of everything written for a folder input: its tasks'
    modules and the files copied so the output has the input's layout (a
    backup whole, so it restores; a program file's .pgf; a task folder's
    .pgf files)."""
    if not source.is_folder:
        return []
    root = source.root
    if source.kind == "backup":
        paths = [p for p in root.rglob("*") if p.is_file()]
    elif source.kind == "pgf":
        paths = [source.input]
    else:
        paths = [p for p in root.rglob("*.pgf") if p.is_file()]
    rels = {p.relative_to(root).as_posix() for p in paths} | set(source.modules)
    return sorted(rels)


def copies(source: TaskSource, output: str, written: set[str]) -> list[tuple[str, bytes]]:
    """The files of layout() that no job writes, copied byte for byte; a
    backup's BACKINFO/backinfo.txt, which lists each task's modules for a
    restore, also lists a transient support module written into a task."""
    from .transient import MODULE_FILE
    out = []
    for rel in layout(source):
        dest = str(Path(output) / rel)
        if dest in written:
            continue
        p = source.root / rel
        try:
            data = p.read_bytes()
        except OSError as exc:
            raise InputError(str(p), f"cannot read file: {exc.strerror or exc}") from None
        if source.kind == "backup" and rel.lower() == "backinfo/backinfo.txt":
            tasks = sorted({Path(w).parent.parent.name for w in written
                            if Path(w).name == MODULE_FILE
                            and Path(w).parent.name.upper() == "SYSMOD"
                            and Path(w).is_relative_to(Path(output))})
            data = _list_support(data, tasks, MODULE_FILE)
        out.append((dest, data))
    return out


def _list_support(data: bytes, tasks: list[str], module: str) -> bytes:
    """backinfo.txt with `SYSMOD/<module>` listed under each task's
    `>>TASK1: (...)` section (after its last module line)."""
    if not tasks:
        return data
    text = data.decode("latin-1")
    nl = "\r\n" if "\r\n" in text else "\n"
    lines = text.split(nl)
    out, section = [], None
    for i, line in enumerate(lines):
        if line.startswith(">>"):
            section = line[2:].split(":", 1)[0].strip()
        out.append(line)
        nxt = lines[i + 1] if i + 1 < len(lines) else ">>"
        last_of_section = line.strip() and (nxt.startswith(">>") or not nxt.strip())
        if section in tasks and not line.startswith(">>") and last_of_section:
            out.append(f"SYSMOD/{module}")
            tasks = [t for t in tasks if t != section]
    return nl.join(out).encode("latin-1")
