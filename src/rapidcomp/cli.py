"""Command line. Parses options and maps domain errors to exit codes here,
in one place: 0 ok, 1 some targets not compensated, 2 bad input."""

from __future__ import annotations

import json
import math
import os
import re
import sys

import click

from .errors import Errors, InputError, RapidcompError

EXIT_OK = 0
EXIT_PARTIAL = 1
EXIT_BAD_INPUT = 2


def _fail(exc: RapidcompError) -> None:
    text = exc.format() if isinstance(exc, (InputError, Errors)) else f"rapidcomp: error: {exc}"
    click.echo(text, err=True)
    sys.exit(EXIT_BAD_INPUT)


def _write(files) -> None:
    """All files or none (atomic.py); an OS error names the path."""
    from pathlib import Path

    from .atomic import write_all
    try:
        write_all([(Path(p), data) for p, data in files])
    except OSError as exc:
        where = exc.filename or "output"
        why = exc.strerror or str(exc)
        # (A folder of the path that is a file: makedirs says "File exists".)
        blocking = next((str(p) for p in Path(str(where)).parents
                         if p.exists() and not p.is_dir()), None) if exc.filename else None
        if blocking is not None:
            why = f"{blocking} is a file, not a folder"
        _fail(RapidcompError(f"{where}: cannot write: {why}; nothing written"))


def _there(files) -> list[str]:
    """The paths of `files` where a file is already (the write replaces
    it: said, so that no earlier output or file of the user's goes without
    a word)."""
    return [str(p) for p, _ in files if os.path.lexists(p)]


def _replacing(shown: str, replaced: list[str]) -> str:
    """A path the "wrote" line shows, with what the write replaced: the
    file itself, or, for a folder (shown with its separator), how many of
    the files in it."""
    if not shown.endswith(os.sep):
        return shown + (" (replaced the file there)" if shown in replaced else "")
    n = sum(p.startswith(shown) for p in replaced)
    return shown + (f" (replaced {n} file{'s' if n > 1 else ''} there)" if n else "")


class _Group(click.Group):
    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except RecursionError:
            # Nesting deeper than job.MAX_FRAMES Python frames: generated
            # code of thousands of levels no controller runs either.
            _fail(RapidcompError("the program nests routine calls or blocks thousands of "
                                 "levels deep, more than rapidcomp follows; nothing written"))


class _Unheard:
    """stdout whose reader may go (`rapidcomp fix ... | head`): what is
    left to say then is dropped, and the command runs to its end, its
    files written and its exit code its own (click would end it at once
    with exit 1, which says some targets were not compensated)."""

    def __init__(self, stream):
        self._stream = stream
        self._gone = False

    def write(self, text):
        if not self._gone:
            try:
                return self._stream.write(text)
            except OSError as exc:
                self._went(exc)
        return len(text)

    def flush(self) -> None:
        if not self._gone:
            try:
                self._stream.flush()
            except OSError as exc:
                self._went(exc)

    def _went(self, exc: OSError) -> None:
        self._gone = True
        if not isinstance(exc, BrokenPipeError):
            # (stdout on a full disk: said once, on stderr.)
            sys.stderr.write(f"rapidcomp: stdout: cannot write: {exc.strerror or exc}; the "
                             "rest of the summary is not said\n")
        # (What the stream still holds, and Python's own flush at exit, go
        # to /dev/null: no "Exception ignored" on the terminal.)
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, self._stream.fileno())
        os.close(null)

    def __getattr__(self, name):
        return getattr(self._stream, name)


def run() -> None:
    """The `rapidcomp` command (and `python -m rapidcomp`): main() in a
    process of its own, set up for it (process.py: no cyclic collector, one
    malloc arena). The process ends as soon as the command has written its
    output and flushed its messages, without freeing its objects one by one
    (the system takes the memory back at once; 1e5 targets: ~0.5 s). Any
    other end than an exit (a crash), and any run under a debugger, profiler
    or coverage tool, ends the usual way."""
    from .process import own
    own()
    if sys.stdout is not None:
        sys.stdout = _Unheard(sys.stdout)
    try:
        main()
    except SystemExit as exc:
        if sys.gettrace() is not None or sys.getprofile() is not None:
            raise    # (a debugger, profiler or coverage tool writes its results at exit)
        code = exc.code
        if code is not None and not isinstance(code, int):
            raise    # (Python's exit prints the message; rapidcomp's codes are ints)
        try:
            for stream in (sys.stdout, sys.stderr):
                if stream is not None:     # (None: started with the descriptor closed)
                    stream.flush()
        except (OSError, ValueError):
            raise exc from None       # (a closed pipe: Python's own exit says so)
        os._exit(code or 0)


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="rapidcomp")
def main() -> None:
    """Thermal compensation of ABB RAPID programs (IRC5, IRB 140)."""
    from .compensate.job import allow_deep_nesting
    allow_deep_nesting()


def _floats(count: int, what: str, limits=None):
    """A click callback: "X,Y,Z" -> a tuple of `count` finite floats, each
    within limits[i] = (lo, hi) when given."""
    def parse(ctx, param, value):
        if value is None:
            return None
        try:
            vals = tuple(float(v) for v in value.split(","))
        except ValueError:
            vals = ()
        if len(vals) != count or not all(math.isfinite(v) for v in vals):
            raise click.BadParameter(f"expected {what} ({count} numbers separated by commas)")
        for v, (lo, hi) in zip(vals, limits or ()):
            if not lo <= v <= hi:
                raise click.BadParameter(f"{v:g} is out of range: expected {what}, each "
                                         f"within {lo:g}..{hi:g}")
        return vals
    return parse


# discover/noise.py's MIN_SIGMA_MM (the least noise a measurement of a
# robot's TCP has), written here so that the CLI starts without numpy.
MIN_SIGMA_MM = 1e-4


def _number(lo: float, hi: float, what: str, open_low: bool = False):
    """A click callback: one finite number in lo..hi (lo excluded when
    open_low)."""
    def parse(ctx, param, value):
        if value is None:
            return None
        ok = math.isfinite(value) and (lo < value if open_low else lo <= value) and value <= hi
        if not ok:
            low = f"> {lo:g}" if open_low else f">= {lo:g}"
            raise click.BadParameter(f"{value:g}: expected {what} {low} and <= {hi:g}")
        return value
    return parse


def _model_options(f):
    """The options that build the warm robot and name the task, shared by
    check and fix."""
    for option in reversed([
        click.option("--profile", required=True, type=click.Path(dir_okay=False),
                     help="Profile CSV: joint,dx_mm,dy_mm,dz_mm,rx_deg,ry_deg,rz_deg (or the "
                          "extended format discover writes)."),
        click.option("--with", "with_modules", multiple=True, type=click.Path(dir_okay=False),
                     help="Another module holding tool/work object/target data, read but not "
                          "written (repeatable)."),
        click.option("--task", "tasks", multiple=True, metavar="NAME",
                     help="Of a controller backup, only this motion task (repeatable; default: "
                          "every motion task)."),
        click.option("--robot", default=None, help="irb140 (default) or a URDF file."),
        click.option("--force", is_flag=True, help="Accept profile values beyond 5 mm / 1 deg, and a backup of another robot than the IRB 140 model."),
        click.option("--limit", "limits", multiple=True, metavar="JOINT=LO:HI",
                     help="Override a joint limit in degrees, e.g. J5=-120:120 (repeatable)."),
        click.option("--track", "track", multiple=True, metavar="AXIS:[-]x|y|z",
                     help="External axis eax_AXIS (a..f) carries the robot along that world "
                          "axis (-x: against it), in mm, e.g. a:x (repeatable). Default: "
                          "external axes do not move the robot's base."),
        click.option("--base", default=None, metavar="X,Y,Z,Q1,Q2,Q3,Q4",
                     callback=_floats(7, "X,Y,Z in mm and a unit quaternion Q1..Q4",
                                      [(-1e5, 1e5)] * 3 + [(-1.0, 1.0)] * 4),
                     help="The robot's base frame in the world (mm, quaternion w,x,y,z), as in "
                          "the controller's configuration. Default: a backup's SYSPAR/MOC.cfg, "
                          "else the world frame."),
        click.option("--start", default=None, metavar="J1,...,J6",
                     callback=_floats(6, "J1,...,J6 in degrees", [(-720.0, 720.0)] * 6),
                     help="Where the robot stands when the program starts (deg; main, or a "
                          "routine nothing given calls): its first move, if without "
                          "configuration supervision, takes the solution closest to it. "
                          "Default: its confdata, else the program's first jointtarget "
                          "(assumed)."),
    ]):
        f = option(f)
    return f


PROGRAM_HELP = ("PROGRAM is a module (.mod, .modx, .sys, .prg), a task folder (every module "
                "below it), a program file (.pgf) or a controller backup (RAPID/<TASK>/...).")


@main.command(epilog=PROGRAM_HELP)
@click.argument("program", type=click.Path())
@click.option("--json", "as_json", is_flag=True, help="Machine-readable output.")
def inspect(program: str, as_json: bool) -> None:
    """Show what the parser found in PROGRAM: counts, target data, motions
    (of each of a task's modules, in the order the task lists them)."""
    from .rapid.inspect import alone, modules_of, render_text, report
    problems: list = []
    unread: list = []
    notes: list = []
    try:
        reps = [report(pf) for pf in modules_of(program, problems, unread, notes)]
    except RapidcompError as exc:
        _fail(exc)
    # (One line each: the place and the message, without the source line
    # check's refusal shows under it.)
    said = [f"{p.format().splitlines()[0]}; check and fix refuse this task" for p in problems]
    said += [f"{p.format().splitlines()[0]}: not read; check and fix take it as a module not "
             "given" for p in unread]
    if as_json:
        # (A module alone: its report, as before tasks were taken.)
        doc = reps[0] if alone(program) else {"program": program, "modules": reps,
                                              "notes": notes, "problems": said}
        click.echo(json.dumps(doc, indent=2))
    else:
        click.echo("\n".join(render_text(r) for r in reps), nl=False)
        for line in notes + said:
            click.echo(f"note: {line}")


def _as_given(source, program: str) -> str:
    """An input as the user named it (two of one name in two folders told
    apart), a folder's with the program or task in it."""
    return str(source.input) if not source.is_folder else f"{source.input} ({program})"


@main.command(epilog=PROGRAM_HELP)
@click.argument("program", type=click.Path())
@_model_options
@click.option("--json", "as_json", is_flag=True, help="Machine-readable output.")
def check(program, profile, with_modules, tasks, robot, force, limits, track, base, start,
          as_json) -> None:
    """Predict each target's error on the warm robot; rewrite nothing.

    Exit code 1 when some targets could not be compensated.
    """
    from dataclasses import replace

    from .compensate.check import check as run_check
    from .compensate.check import render_text
    from .compensate.load import load_solver, load_task, robot_base, robot_of_backup
    from .compensate.targets import parse_track
    from .rapid.task import tasks_of
    try:
        sources = tasks_of(program, tuple(tasks))
        for m in with_modules:
            if not os.path.isfile(m):
                raise RapidcompError(f"{m}: no such file")
        solver = load_solver(profile, robot, force, limits)
        tracked = parse_track(track)
        said = [robot_of_backup(s, robot, force) for s in sources]
        results = [run_check(load_task(s, with_modules), solver, tracked, start,
                             robot_base(s, base)[0]) for s in sources]
        results = [replace(r, notes=s.notes + ((x,) if x else ()) + r.notes)
                   for r, s, x in zip(results, sources, said)]
    except RapidcompError as exc:
        _fail(exc)
    if as_json:
        docs = [{"program": r.program, "summary": r.summary(), "notes": list(r.notes),
                 "targets": [x.as_dict() for x in r.rows]} for r in results]
        doc = docs[0] if len(docs) == 1 else {"program": program, "tasks": docs}
        click.echo(json.dumps(doc, indent=2))
    else:
        # (As fix's first line names it; the JSON keeps the program's name:
        # no path of this machine.)
        click.echo("\n".join(render_text(replace(r, program=_as_given(s, r.program)))
                              for r, s in zip(results, sources)), nl=False)
    sys.exit(EXIT_PARTIAL if any(r.failed for r in results) else EXIT_OK)


@main.command(epilog=PROGRAM_HELP)
@click.argument("programs", nargs=-1, required=True, type=click.Path())
@_model_options
@click.option("-o", "--output", default=None, type=click.Path(),
              help="Output module (default PROGRAM_comp.mod beside the input) or, for a task "
                   "folder, program file or backup, the output folder (default PROGRAM_comp "
                   "beside it); a folder when several programs are given.")
@click.option("--emit", type=click.Choice(["auto", "absj", "robtarget"]), default="auto",
              show_default=True,
              help="auto: MoveJ becomes MoveAbsJ on a new jointtarget, MoveL and the rest keep "
                   "their kind (straight lines stay straight) with compensated robtargets; "
                   "absj: MoveL becomes MoveAbsJ too; robtarget: every instruction keeps its "
                   "kind.")
@click.option("--report", default=None, type=click.Path(dir_okay=False),
              help="Markdown review report (default: the output's name with .md).")
@click.option("--no-report", is_flag=True, help="Write no Markdown report.")
@click.option("--json", "json_path", default=None, type=click.Path(dir_okay=False),
              help="JSON report with the same content.")
@click.option("--allow-partial", is_flag=True,
              help="Write the output even when some targets cannot be compensated "
                   "(they stay as they were and are listed).")
@click.option("-q", "--quiet", is_flag=True, help="No summary on stdout.")
@click.option("--transient", is_flag=True,
              help="Compensate for the thermal state at run time (warm-up, pauses): each move "
                   "goes to rcTcJ(cold, dq) of a support module rcThermal.sys written next to "
                   "the output; needs --tau-heat, --temperature or a profile with tau_heat_min. "
                   "MoveJ becomes MoveAbsJ (rcTcJ), MoveL keeps its line (rcTcR) unless "
                   "--emit absj.")
@click.option("--tau-heat", type=float, default=None, metavar="MIN",
              help="--transient: warm-up time constant while the robot runs, minutes.")
@click.option("--tau-cool", type=float, default=None, metavar="MIN",
              help="--transient: cooling time constant while it stands, minutes "
                   "(default: --tau-heat).")
@click.option("--gap", type=float, default=None, metavar="MIN",
              help="--transient: a gap between compensated moves longer than this is a stop "
                   "(cooling); default 2 minutes.")
@click.option("--temperature", default=None, metavar="SIGNAL:T_COLD:T_WARM",
              help="--transient: the thermal state from an analog input instead of the clock, "
                   "s = (T - T_COLD) / (T_WARM - T_COLD) clipped to 0..1.")
def fix(programs, profile, output, emit, report, no_report, json_path, with_modules, tasks,
        robot, force, limits, track, base, start, allow_partial, quiet, transient, tau_heat,
        tau_cool, gap, temperature) -> None:
    """Write a compensated copy of each PROGRAM and a review report.

    Exit code 0: all statically known targets compensated; 1: some could not
    be (nothing is written unless --allow-partial); 2: bad input.
    """
    from .compensate.job import copies, run_all
    from .compensate.report import summary_lines
    try:
        specs = _fix_specs(programs, profile, output, emit, report, no_report, json_path,
                           with_modules, tasks, robot, force, limits, track, start, base,
                           _transient(transient, emit, tau_heat, tau_cool, gap, temperature,
                                      profile, robot, force))
        outcomes = run_all(specs)
        files = [(path, data) for o in outcomes for path, data in o.files]
        done = {path for path, _ in files}
        seen_inputs = set()
        for spec in specs:
            key = (str(spec.source.input), spec.output)
            if key not in seen_inputs:
                seen_inputs.add(key)
                files += copies(spec.source, spec.output, done)
    except RapidcompError as exc:
        _fail(exc)
    failed = any(o.result.failed for o in outcomes)
    for o in outcomes:
        r = o.result
        if not quiet:
            src = o.spec.source
            what = _as_given(src, r.program)
            # (Where nothing will be written, the first line says so too:
            # the reason follows on stderr.)
            held = "; not written" if failed and not allow_partial else ""
            click.echo(f"{what} -> {o.spec.output} ({r.mode}{held})")
            for line in summary_lines(r):
                click.echo(f"  {line}")
            for note in r.notes:
                click.echo(f"  note: {note}")
    if failed and not allow_partial:
        click.echo("rapidcomp: some targets cannot be compensated; nothing written "
                   "(--allow-partial writes the rest and lists these)", err=True)
        sys.exit(EXIT_PARTIAL)
    replaced = _there(files)
    _write(files)
    if not quiet:
        shown: list[str] = []
        for o in outcomes:
            if o.spec.source.is_folder and o.spec.output + os.sep not in shown:
                shown.append(o.spec.output + os.sep)
            shown += [p for p, _ in o.files if not o.spec.source.is_folder
                      or not p.startswith(o.spec.output + os.sep)]
        kept = [p for o in outcomes for p in o.kept if not o.spec.source.is_folder
                or not p.startswith(o.spec.output + os.sep)]
        # (Each once: programs into one folder share its support module.)
        shown, kept = list(dict.fromkeys(shown)), list(dict.fromkeys(kept))
        click.echo("wrote " + ", ".join(_replacing(p, replaced) for p in shown) + (
            f"; kept {', '.join(kept)} (the same support module was there)" if kept else ""))
    sys.exit(EXIT_PARTIAL if failed else EXIT_OK)


def _transient(on, emit, tau_heat, tau_cool, gap, temperature, profile=None, robot=None,
               force=False):
    """The Transient of --transient and its options, None without it; tau
    from the profile (`# tau_heat_min:`, written by discover) when
    --tau-heat is not given."""
    from .compensate.transient import make_transient
    given = [name for name, v in (("--tau-heat", tau_heat), ("--tau-cool", tau_cool),
                                  ("--gap", gap), ("--temperature", temperature))
             if v is not None]
    if not on:
        if given:
            raise RapidcompError(f"{given[0]} applies to --transient only")
        return None
    if emit == "robtarget":
        raise RapidcompError("--transient writes the targets the controller computes at run time "
                             "(rcTcJ for MoveAbsJ, rcTcR for robtarget moves) and chooses which "
                             "moves become MoveAbsJ as --emit auto or absj do; --emit robtarget "
                             "is not one of them")
    source = None
    if profile is not None and os.path.isfile(profile):
        from .compensate.load import load_robot
        from .kinematics.profile import read_profile
        prof = read_profile(profile, force=force, joint_names=load_robot(robot).joint_names)
        if prof.static_only:
            raise RapidcompError(f"{profile}: its effects are static (nothing changed over time "
                                 "in the warm-up campaign discover read): --transient would "
                                 "scale them with the thermal state; use fix without "
                                 "--transient")
        if tau_heat is None and temperature is None and prof.tau_heat_min is not None:
            tau_heat, source = prof.tau_heat_min, f"tau from {os.path.basename(profile)}"
            if tau_cool is None and prof.tau_cool_min is not None:
                tau_cool = prof.tau_cool_min
    return make_transient(tau_heat, tau_cool, gap, temperature, source)


def _fix_specs(programs, profile, output, emit, report, no_report, json_path, with_modules,
               tasks, robot, force, limits, track, start, base, transient=None):
    """One JobSpec per task, with output paths checked: never an input,
    never two jobs on one file, never inside an input folder."""
    from pathlib import Path

    from .compensate.job import JobSpec, default_output
    from .rapid.task import MODULE_SUFFIXES, is_module, tasks_of
    from .source import not_a_file
    several = len(programs) > 1
    if several and output is None:
        raise RapidcompError("several programs need -o DIR")
    if several and not os.path.isdir(output) and output.lower().endswith(MODULE_SUFFIXES):
        # (A folder named as a module file is not what was meant.)
        raise RapidcompError(f"-o {output}: several programs are written into a folder, each "
                             "under its own name; give a folder, not a module file name")
    for option, value in (("-o", output), ("--report", report), ("--json", json_path)):
        if value is not None and not value.strip():
            raise RapidcompError(f"{option}: an empty path; give a file name")
    if no_report and report:
        raise RapidcompError("--no-report and --report: give one of them")
    for p in [profile] + list(with_modules):
        # (Before any work: a pipe would be waited on, a missing file found
        # only when its job reads it.)
        not_a_file(p)
        if not os.path.exists(p):
            raise RapidcompError(f"{p}: no such file")
    groups = [(program, tasks_of(program, tuple(tasks))) for program in programs]
    n_tasks = sum(len(ts) for _, ts in groups)
    if n_tasks > 1 and (report or json_path):
        raise RapidcompError("--report/--json name one file; with several programs or tasks "
                             "each report is written next to its output")
    inputs = {os.path.realpath(p) for p in [profile] + list(with_modules)}
    folders = []
    for _, ts in groups:
        for t in ts:
            inputs.update(os.path.realpath(t.root / m) for m in t.modules)
            inputs.add(os.path.realpath(t.input))
            # A folder's or backup's output inside it would be read back as
            # part of the task next time; a program file names its modules.
            if t.kind in ("folder", "backup"):
                folders.append(os.path.realpath(t.root))
    specs = []
    # An output's real path -> (the input it is written for, what it is).
    seen: dict[str, tuple[str, str]] = {}
    for program, ts in groups:
        src = ts[0]
        name = Path(program.rstrip("/\\")).name
        if src.is_folder:
            stem = Path(name).stem if src.kind == "pgf" else name
            # (As a path says it once: -o out/ is the folder out, its report
            # out.md beside it, not out/.md in it.)
            out = str(Path(output) / stem) if several else (
                os.path.normpath(output) if output else default_output(
                    program.rstrip("/\\"), folder=True))
        elif several or (output is not None and (os.path.isdir(output) or output.endswith(
                ("/", os.sep)))):
            # (-o out/ names a folder, made if it is not there: not a file
            # named out.)
            named = output.rstrip("/" + os.sep) or output
            if os.path.exists(named) and not os.path.isdir(named):
                raise RapidcompError(f"-o {output}: {named} is a file, not a folder")
            out = str(Path(output) / name)
        else:
            out = output or default_output(program)
            if not is_module(Path(out)):
                # (A module file the controller loads has its suffix: `out`
                # is not a name a FlexPendant offers to load. Not guessed.)
                raise RapidcompError(
                    f"-o {output}: a module is written as a module file: give a name the "
                    f"controller loads ({', '.join(MODULE_SUFFIXES)}), or a folder "
                    f"(-o {output}/)")
        real_out = os.path.realpath(out)
        for f in folders:
            if real_out == f or real_out.startswith(f + os.sep):
                raise RapidcompError(f"{out}: is inside the input folder {program}; write the "
                                     "output beside it")
        if src.is_folder:
            _check_output_folder(out, src)
        for t in ts:
            if no_report:
                rep = None
            elif report:
                rep = report
            elif src.is_folder:
                rep = out + (f".{t.task}" if len(ts) > 1 else "") + ".md"
            else:
                rep = str(Path(out).with_suffix(".md"))
            # (The program's own file first: a clash names it, not its report.)
            paths = ([(str(Path(out) / m), "a module") for m in t.modules] if t.is_folder
                     else [(out, "the module")]) + [(rep, "the report"), (json_path, "the JSON")]
            for path, what in paths:
                if path is None:
                    continue
                real = os.path.realpath(path)
                if real in inputs:
                    raise RapidcompError(f"{path}: would overwrite an input")
                if real in seen:
                    first, first_what = seen[real]
                    raise RapidcompError(
                        f"{path}: would be both {first_what} of {first} and {what} of {program}"
                        + (": run them one at a time, each with its own -o"
                           if first != program else ": give it another name"))
                seen[real] = (program, what)
            # (A report too: a file in the input folder is read back as part
            # of the task, or copied with it, next time.)
            for path in (rep, json_path):
                real = os.path.realpath(path) if path is not None else None
                if real is not None and any(real.startswith(f + os.sep) for f in folders):
                    given = ", ".join(p for p, ts_ in groups
                                      if ts_[0].kind in ("folder", "backup"))
                    raise RapidcompError(f"{path}: is inside the input folder {given}; write "
                                         "the report beside it")
            specs.append(JobSpec(t, out, rep, json_path, profile, robot, tuple(with_modules),
                                 emit, force, tuple(limits), tuple(track), start, base,
                                 transient=transient))
    return specs


def _check_output_folder(out: str, src) -> None:
    """A task folder, program file or backup is written as a folder: not
    over a file, not into a folder that holds other things (a run into the
    output folder of an earlier run is fine: every file there is one it
    writes again)."""
    from pathlib import Path

    from .compensate.job import layout
    from .rapid.task import is_module
    p = Path(out)
    if is_module(p) or p.is_file():
        raise RapidcompError(f"-o {out}: {src.input} is written as a folder (its layout kept); "
                             "give a folder name")
    if p.is_dir():
        mine = set(layout(src))
        other = sorted(f.relative_to(p).as_posix() for f in p.rglob("*")
                       if f.is_file() and f.relative_to(p).as_posix() not in mine)
        if other:
            raise RapidcompError(f"-o {out}: the folder exists and holds files this run would "
                                 f"not write ({', '.join(other[:3])}"
                                 + (", ..." if len(other) > 3 else "") + "); give a new folder")


def _warmup_campaign(times, thermal_effects, tau_heat, sensors=(), tau_cool=None):
    """(times, thermal effect specs, tau, sensors) of simulate --times, or
    None."""
    import math
    if times is None:
        given = [o for o, v in (("--thermal-effect", thermal_effects), ("--tau-heat", tau_heat),
                                ("--sensor", sensors), ("--tau-cool", tau_cool)) if v]
        if given:
            raise RapidcompError(f"{given[0]} needs --times (a warm-up campaign)")
        return None
    # Minutes of running since the cold start; "+N" a stop of N minutes
    # after the previous round.
    ts, stands, pending = [], [], 0.0
    try:
        for x in times.split(","):
            x = x.strip()
            if x.startswith("+"):
                pending += float(x[1:])
            else:
                ts.append(float(x))
                stands.append(pending)
                pending = 0.0
    except ValueError:
        raise RapidcompError(f"--times {times}: expected minutes, e.g. 0,10,20,40 (+30: a "
                             "30 min stop after the round before it)") from None
    cumulative, total = [], 0.0
    for x in stands:
        total += x
        cumulative.append(total)
    keys = list(zip(ts, cumulative))
    if not ts or any(not math.isfinite(v) or v < 0 or v > 525_600 for v in ts + stands) or \
            len(set(keys)) != len(keys) or any(b < a for a, b in zip(ts, ts[1:])) or pending:
        raise RapidcompError(f"--times {times}: expected increasing minutes of running from 0 "
                             "to 525600, each stop (+N) followed by a round")
    if stands and stands[0] > 0:
        # (The robot starts cold: a stop before the first round cools
        # nothing, and its minutes would be a cooling discover cannot see.)
        raise RapidcompError(f"--times {times}: a stop (+N) follows a measurement round; the "
                             "first round is the cold start")
    if len(ts) < 3:
        raise RapidcompError(f"--times {times}: a warm-up campaign measures at 3 or more times "
                             "(two cannot tell a curve from a line)")
    if tau_heat is None or not (math.isfinite(tau_heat) and 0 < tau_heat <= 100_000):
        raise RapidcompError("--times needs --tau-heat MIN (the hidden warm-up time constant, "
                             "more than 0)")
    parsed = []
    for spec in sensors:
        parts = spec.split(":")
        try:
            cold, warm = float(parts[1]), float(parts[2])
            lag = float(parts[3]) if len(parts) == 4 else None
        except (ValueError, IndexError):
            cold = warm = lag = float("nan")
        if len(parts) not in (3, 4) or not parts[0].lower().startswith("temp_") or \
                not all(math.isfinite(v) and abs(v) <= 500 for v in (cold, warm)) or \
                (lag is not None and not (math.isfinite(lag) and 0 < lag <= 100_000)):
            raise RapidcompError(f"--sensor {spec}: expected temp_NAME:T_COLD:T_WARM[:TAU] "
                                 "(deg C, minutes)")
        # (A reading below absolute zero is no temperature.)
        if min(cold, warm) < -273.15:
            raise RapidcompError(f"--sensor {spec}: expected temperatures (deg C, above "
                                 "-273.15)")
        name = parts[0].lower()
        # (Its column's name: temp_ and a name; one column per sensor,
        # which discover reads back. A flat one, T_COLD = T_WARM, is a
        # sensor too: the room's.)
        if not re.fullmatch(r"temp_[a-z0-9_]+", name):
            raise RapidcompError(f"--sensor {spec}: expected temp_NAME (letters, digits, '_') "
                                 "as the column's name")
        if any(name == p[0] for p in parsed):
            raise RapidcompError(f"--sensor {spec}: {name} is given twice (one column per "
                                 "sensor)")
        parsed.append((name, cold, warm, lag))
    if tau_cool is not None and not (math.isfinite(tau_cool) and 0 < tau_cool <= 100_000):
        raise RapidcompError(f"--tau-cool {tau_cool:g}: minutes, more than 0")
    return ts, tuple(thermal_effects), tau_heat, tuple(parsed), stands, tau_cool


def _campaign_options(f):
    """The options that describe the measurement set-up, shared by discover
    and simulate."""
    for option in reversed([
        click.option("--profile", default=None, type=click.Path(dir_okay=False),
                     help="Profile CSV of the model (plain or extended); default: none."),
        click.option("--robot", default=None, help="irb140 (default) or a URDF file."),
        click.option("--tool", default="0,0,0",
                     callback=_floats(3, "X,Y,Z in mm", [(-2000.0, 2000.0)] * 3),
                     help="Measuring point in the flange frame, mm, each within +-2000 (default: "
                          "flange origin)."),
        click.option("--payload", default=None,
                     callback=_floats(4, "KG,CX,CY,CZ (kg, mm)",
                                      [(0.0, 1000.0)] + [(-2000.0, 2000.0)] * 3),
                     help="Load on the flange during the measurement: kg and centre of mass "
                          "in the flange frame, mm (gravity compliance)."),
        click.option("--force", is_flag=True, help="Accept profile values beyond the sanity "
                                                   "limits."),
    ]):
        f = option(f)
    return f


def _write_outcome(outcome, quiet: bool) -> None:
    replaced = _there(outcome.files)
    _write(outcome.files)
    if not quiet:
        for line in outcome.summary:
            click.echo(line)
        for note in outcome.notes:
            click.echo(f"note: {note}")
        if outcome.files:
            click.echo("wrote " + ", ".join(_replacing(p, replaced) for p, _ in outcome.files))


@main.command()
@click.argument("measured", type=click.Path(dir_okay=False))
@_campaign_options
@click.option("--sigma", type=float, default=None,
              callback=_number(MIN_SIGMA_MM, 10.0, "a standard deviation in mm"),
              help=f"Measurement noise, standard deviation per axis in mm, {MIN_SIGMA_MM:g} to "
                   "10 (default: estimated).")
@click.option("--report", "report_path", default=None, type=click.Path(dir_okay=False),
              help="Markdown report: residual analysis and one table per step.")
@click.option("--json", "json_path", default=None, type=click.Path(dir_okay=False),
              help="JSON result.")
@click.option("--plot", "plot_path", default=None, type=click.Path(dir_okay=False),
              help="PNG of residual vectors before/after (needs rapidcomp[plot]).")
@click.option("--out-profile", default=None, type=click.Path(dir_okay=False),
              help="Write the profile with the named effects added, for fix --profile.")
@click.option("--test", "test_path", default=None, type=click.Path(dir_okay=False),
              help="Poses measured but not fitted (same columns): the final model's error "
                   "there, next to the nominal model's.")
@click.option("--register", is_flag=True,
              help="The data are in the measuring system's own frame: move them rigidly onto "
                   "the nominal model first (base_frame then finds what is left).")
@click.option("-q", "--quiet", is_flag=True, help="No summary on stdout.")
def discover(measured, profile, robot, tool, payload, force, sigma, report_path, json_path,
             plot_path, out_profile, test_path, register, quiet) -> None:
    """Compare MEASURED positions with the model, name the effects it misses.

    MEASURED.csv has columns point,j1..j6,x,y,z: commanded joints (deg) and
    the measured position (mm, base frame) of the measuring point.
    """
    from .discover.job import run_discover
    try:
        outcome = run_discover(measured, profile, robot, tool, payload, sigma, report_path,
                               json_path, plot_path, out_profile, force, test_path,
                               register)
    except RapidcompError as exc:
        _fail(exc)
    _write_outcome(outcome, quiet)
    sys.exit(EXIT_OK)


@main.command()
@click.option("-o", "--output", required=True, type=click.Path(dir_okay=False),
              help="Measured-data CSV to write (point,j1..j6,x,y,z).")
@click.option("--points", default="cube", show_default=True,
              help="cube (the paper's 72 points), random:N, or a CSV of joints (point,j1..j6).")
@_campaign_options
@click.option("--effect", "effects", multiple=True, metavar="ID=V[,V...]",
              help="A catalogue effect and its values in its parameters' units, e.g. "
                   "joint_offset:J2=0.01 (repeatable).")
@click.option("--noise", type=float, default=0.005, show_default=True,
              callback=_number(0.0, 10.0, "a standard deviation in mm"),
              help="Gaussian noise, standard deviation per axis in mm, 0..10.")
@click.option("--seed", type=click.IntRange(0, 2 ** 32 - 1), default=0, show_default=True,
              help="Random seed (noise and random:N poses).")
@click.option("--table", "table_path", default=None, type=click.Path(dir_okay=False),
              help="Also write the detectability table as Markdown.")
@click.option("--times", default=None, metavar="T1,T2,...",
              help="A warm-up campaign: the points measured at each of these times, minutes "
                   "of running since a cold start (t_min column); +N: a stop of N minutes after "
                   "the round before it (stood_min column).")
@click.option("--thermal-effect", "thermal_effects", multiple=True, metavar="ID=V[,V...]",
              help="--times: an effect that grows with the thermal state, its steady-state "
                   "values (repeatable).")
@click.option("--tau-heat", type=float, default=None, metavar="MIN",
              help="--times: the warm-up time constant, minutes.")
@click.option("--tau-cool", type=float, default=None, metavar="MIN",
              help="--times: the cooling time constant during stops (+N in --times), minutes "
                   "(default: --tau-heat).")
@click.option("--sensor", "sensors", multiple=True, metavar="temp_NAME:T_COLD:T_WARM[:TAU]",
              help="--times: a temperature column rising from T_COLD to T_WARM deg C with the "
                   "warm-up (or its own time constant TAU, minutes), 0.05 deg C noise.")
@click.option("-q", "--quiet", is_flag=True, help="No summary on stdout.")
def simulate(output, points, profile, robot, tool, payload, force, effects, noise, seed,
             table_path, times, thermal_effects, tau_heat, tau_cool, sensors, quiet) -> None:
    """Make a measured-data file from a model, and say what it can detect."""
    from .discover.job import run_simulate
    try:
        campaign = _warmup_campaign(times, thermal_effects, tau_heat, sensors, tau_cool)
        outcome = run_simulate(output, points, profile, robot, tool, payload, effects, noise,
                               seed, table_path, force, campaign)
    except RapidcompError as exc:
        _fail(exc)
    _write_outcome(outcome, quiet)
    sys.exit(EXIT_OK)
