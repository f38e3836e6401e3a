"""Command line. Parses options and maps domain errors to exit codes here,
in one place: 0 ok, 1 some targets not compensated, 2 bad input."""

from __future__ import annotations

import json
import sys

import click

from .errors import InputError, RapidcompError

EXIT_OK = 0
EXIT_PARTIAL = 1
EXIT_BAD_INPUT = 2


def _fail(exc: RapidcompError) -> None:
    click.echo(f"rapidcomp: error: {exc}" if not isinstance(exc, InputError) else exc.format(),
               err=True)
    sys.exit(EXIT_BAD_INPUT)


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="rapidcomp")
def main() -> None:
    """Thermal compensation of ABB RAPID programs (IRC5, IRB 140)."""


def _model_options(f):
    """The options that build the warm robot, shared by check and fix."""
    for option in reversed([
        click.option("--profile", required=True, type=click.Path(dir_okay=False),
                     help="Profile CSV: joint,dx_mm,dy_mm,dz_mm,rx_deg,ry_deg,rz_deg (or the extended format discover writes)."),
        click.option("--with", "with_modules", multiple=True, type=click.Path(dir_okay=False),
                     help="Other modules holding tool/work object/target data (repeatable)."),
        click.option("--robot", default=None, help="irb140 (default) or a URDF file."),
        click.option("--force", is_flag=True, help="Accept profile values beyond 5 mm / 1 deg."),
        click.option("--limit", "limits", multiple=True, metavar="JOINT=LO:HI",
                     help="Override a joint limit in degrees, e.g. J5=-120:120 (repeatable)."),
    ]):
        f = option(f)
    return f


@main.command()
@click.argument("program", type=click.Path(dir_okay=False))
@click.option("--json", "as_json", is_flag=True, help="Machine-readable output.")
def inspect(program: str, as_json: bool) -> None:
    """Show what the parser found in PROGRAM: counts, target data, motions."""
    from .rapid.inspect import render_text, report
    from .rapid.parse import parse_file
    try:
        pf = parse_file(program)
    except RapidcompError as exc:
        _fail(exc)
    rep = report(pf)
    if as_json:
        click.echo(json.dumps(rep, indent=2))
    else:
        click.echo(render_text(rep), nl=False)


@main.command()
@click.argument("program", type=click.Path(dir_okay=False))
@_model_options
@click.option("--json", "as_json", is_flag=True, help="Machine-readable output.")
def check(program, profile, with_modules, robot, force, limits, as_json) -> None:
    """Predict each target's error on the warm robot; rewrite nothing.

    Exit code 1 when some targets could not be compensated.
    """
    from dataclasses import asdict

    from .compensate.check import check as run_check
    from .compensate.check import render_text, summary
    from .compensate.job import load_solver
    from .rapid.parse import parse_file
    try:
        files = [parse_file(program)] + [parse_file(m) for m in with_modules]
        solver = load_solver(profile, robot, force, limits)
    except RapidcompError as exc:
        _fail(exc)
    rows = run_check(files, solver)
    summ = summary(rows)
    if as_json:
        click.echo(json.dumps({"program": program, "summary": summ,
                               "targets": [asdict(r) for r in rows]}, indent=2))
    else:
        click.echo(render_text(rows, summ, program), nl=False)
    sys.exit(EXIT_PARTIAL if summ["not_compensable"] else EXIT_OK)


@main.command()
@click.argument("programs", nargs=-1, required=True, type=click.Path(dir_okay=False))
@_model_options
@click.option("-o", "--output", default=None, type=click.Path(),
              help="Output module (default PROGRAM_comp.mod beside the input); a directory "
                   "when several programs are given.")
@click.option("--emit", type=click.Choice(["absj", "robtarget"]), default="absj",
              show_default=True,
              help="absj: MoveJ/MoveL become MoveAbsJ on new jointtargets; robtarget: every "
                   "instruction keeps its kind, robtarget values are rewritten.")
@click.option("--report", default=None, type=click.Path(dir_okay=False),
              help="Markdown review report (default: the output's name with .md).")
@click.option("--no-report", is_flag=True, help="Write no Markdown report.")
@click.option("--json", "json_path", default=None, type=click.Path(dir_okay=False),
              help="JSON report with the same content.")
@click.option("--allow-partial", is_flag=True,
              help="Write the output even when some targets cannot be compensated "
                   "(they stay as they were and are listed).")
@click.option("-q", "--quiet", is_flag=True, help="No summary on stdout.")
def fix(programs, profile, output, emit, report, no_report, json_path, with_modules, robot,
        force, limits, allow_partial, quiet) -> None:
    """Write a compensated copy of each PROGRAM and a review report.

    Exit code 0: all statically known targets compensated; 1: some could not
    be (nothing is written unless --allow-partial); 2: bad input.
    """
    from pathlib import Path

    from .atomic import write_all
    from .compensate.job import run_all
    from .compensate.report import summary_lines
    try:
        specs = _fix_specs(programs, profile, output, emit, report, no_report, json_path,
                           with_modules, robot, force, limits)
        outcomes = run_all(specs)
    except RapidcompError as exc:
        _fail(exc)
    failed = any(o.result.failed for o in outcomes)
    for o in outcomes:
        r = o.result
        if not quiet:
            click.echo(f"{r.program} -> {r.output} ({r.mode})")
            for line in summary_lines(r):
                click.echo(f"  {line}")
            for note in r.notes:
                click.echo(f"  note: {note}")
    if failed and not allow_partial:
        click.echo("rapidcomp: some targets cannot be compensated; nothing written "
                   "(--allow-partial writes the rest and lists these)", err=True)
        sys.exit(EXIT_PARTIAL)
    write_all([(Path(path), data) for o in outcomes for path, data in o.files])
    if not quiet:
        for o in outcomes:
            click.echo("wrote " + ", ".join(path for path, _ in o.files))
    sys.exit(EXIT_PARTIAL if failed else EXIT_OK)


def _fix_specs(programs, profile, output, emit, report, no_report, json_path, with_modules,
               robot, force, limits):
    """One JobSpec per program, with output paths checked: never the input
    itself, never two jobs on one file."""
    import os
    from pathlib import Path

    from .compensate.job import JobSpec, default_output
    several = len(programs) > 1
    if several and (report or json_path):
        raise RapidcompError("--report/--json name one file; with several programs each "
                             "report is written next to its output")
    if several and output is None:
        raise RapidcompError("several programs need -o DIR")
    for p in list(programs) + [profile] + list(with_modules):
        if not os.path.isfile(p):
            raise RapidcompError(f"{p}: no such file")
    specs = []
    seen: set[str] = set()
    for program in programs:
        if several or (output is not None and os.path.isdir(output)):
            out = str(Path(output) / Path(program).name)
        else:
            out = output or default_output(program)
        rep = None if no_report else (report or str(Path(out).with_suffix(".md")))
        paths = [out] + [x for x in (rep, json_path) if x]
        for path in paths:
            real = os.path.realpath(path)
            if real in seen or any(os.path.realpath(i) == real
                                   for i in list(programs) + list(with_modules) + [profile]):
                raise RapidcompError(f"{path}: would overwrite an input or another output")
            seen.add(real)
        specs.append(JobSpec(program, out, rep, json_path, profile, robot, tuple(with_modules),
                             emit, force, tuple(limits)))
    return specs


def _floats(count: int, what: str):
    """A click callback: "X,Y,Z" -> a tuple of `count` floats."""
    def parse(ctx, param, value):
        if value is None:
            return None
        try:
            vals = tuple(float(v) for v in value.split(","))
        except ValueError:
            vals = ()
        if len(vals) != count or not all(v == v and abs(v) != float("inf") for v in vals):
            raise click.BadParameter(f"expected {what} ({count} numbers separated by commas)")
        return vals
    return parse


def _campaign_options(f):
    """The options that describe the measurement set-up, shared by discover
    and simulate."""
    for option in reversed([
        click.option("--profile", default=None, type=click.Path(dir_okay=False),
                     help="Profile CSV of the model (plain or extended); default: none."),
        click.option("--robot", default=None, help="irb140 (default) or a URDF file."),
        click.option("--tool", default="0,0,0", callback=_floats(3, "X,Y,Z in mm"),
                     help="Measuring point in the flange frame, mm (default: flange origin)."),
        click.option("--payload", default=None, callback=_floats(4, "KG,CX,CY,CZ"),
                     help="Load on the flange during the measurement: kg and centre of mass "
                          "in the flange frame, mm (gravity compliance)."),
        click.option("--force", is_flag=True, help="Accept profile values beyond the sanity "
                                                   "limits."),
    ]):
        f = option(f)
    return f


def _write_outcome(outcome, quiet: bool) -> None:
    from pathlib import Path

    from .atomic import write_all
    write_all([(Path(p), data) for p, data in outcome.files])
    if not quiet:
        for line in outcome.summary:
            click.echo(line)
        for note in outcome.notes:
            click.echo(f"note: {note}")
        if outcome.files:
            click.echo("wrote " + ", ".join(p for p, _ in outcome.files))


@main.command()
@click.argument("measured", type=click.Path(dir_okay=False))
@_campaign_options
@click.option("--sigma", type=float, default=None,
              help="Measurement noise, standard deviation per axis in mm (default: estimated).")
@click.option("--report", "report_path", default=None, type=click.Path(dir_okay=False),
              help="Markdown report: residual analysis and one table per step.")
@click.option("--json", "json_path", default=None, type=click.Path(dir_okay=False),
              help="JSON result.")
@click.option("--plot", "plot_path", default=None, type=click.Path(dir_okay=False),
              help="PNG of residual vectors before/after (needs rapidcomp[plot]).")
@click.option("--out-profile", default=None, type=click.Path(dir_okay=False),
              help="Write the profile with the named effects added, for fix --profile.")
@click.option("-q", "--quiet", is_flag=True, help="No summary on stdout.")
def discover(measured, profile, robot, tool, payload, force, sigma, report_path, json_path,
             plot_path, out_profile, quiet) -> None:
    """Compare MEASURED positions with the model, name the effects it misses.

    MEASURED.csv has columns point,j1..j6,x,y,z: commanded joints (deg) and
    the measured position (mm, base frame) of the measuring point.
    """
    from .discover.job import run_discover
    try:
        outcome = run_discover(measured, profile, robot, tool, payload, sigma, report_path,
                               json_path, plot_path, out_profile, force)
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
              help="Gaussian noise, standard deviation per axis in mm.")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Random seed (noise and random:N poses).")
@click.option("--table", "table_path", default=None, type=click.Path(dir_okay=False),
              help="Also write the detectability table as Markdown.")
@click.option("-q", "--quiet", is_flag=True, help="No summary on stdout.")
def simulate(output, points, profile, robot, tool, payload, force, effects, noise, seed,
             table_path, quiet) -> None:
    """Make a measured-data file from a model, and say what it can detect."""
    from .discover.job import run_simulate
    try:
        outcome = run_simulate(output, points, profile, robot, tool, payload, effects, noise,
                               seed, table_path, force)
    except RapidcompError as exc:
        _fail(exc)
    _write_outcome(outcome, quiet)
    sys.exit(EXIT_OK)
