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


def _load_robot(robot: str | None):
    from .kinematics.robot import irb140, load_urdf
    if robot is None or robot.lower() == "irb140":
        return irb140()
    return load_urdf(robot)


@main.command()
@click.argument("program", type=click.Path(dir_okay=False))
@click.option("--profile", required=True, type=click.Path(dir_okay=False),
              help="Thermal profile CSV (joint,dx_mm,dy_mm,dz_mm,rx_deg,ry_deg,rz_deg).")
@click.option("--with", "with_modules", multiple=True, type=click.Path(dir_okay=False),
              help="Other modules holding tool/work object/target data (repeatable).")
@click.option("--robot", default=None, help="irb140 (default) or a URDF file.")
@click.option("--force", is_flag=True, help="Accept profile values beyond 5 mm / 1 deg.")
@click.option("--json", "as_json", is_flag=True, help="Machine-readable output.")
def check(program, profile, with_modules, robot, force, as_json) -> None:
    """Predict each target's error on the warm robot; rewrite nothing.

    Exit code 1 when some targets could not be compensated.
    """
    from dataclasses import asdict

    from .compensate.check import check as run_check
    from .compensate.check import render_text, summary
    from .kinematics.analytic import UnsupportedGeometry
    from .kinematics.ik import Solver
    from .kinematics.profile import deform, read_profile
    from .rapid.parse import parse_file
    try:
        files = [parse_file(program)] + [parse_file(m) for m in with_modules]
        nominal = _load_robot(robot)
        prof = read_profile(profile, force=force, joint_names=nominal.joint_names)
        solver = Solver(nominal, deform(nominal, prof))
    except RapidcompError as exc:
        _fail(exc)
    except UnsupportedGeometry as exc:
        _fail(RapidcompError(f"{robot}: {exc}"))
    rows = run_check(files, solver)
    summ = summary(rows)
    if as_json:
        click.echo(json.dumps({"program": program, "summary": summ,
                               "targets": [asdict(r) for r in rows]}, indent=2))
    else:
        click.echo(render_text(rows, summ, program), nl=False)
    sys.exit(EXIT_PARTIAL if summ["not_compensable"] else EXIT_OK)
