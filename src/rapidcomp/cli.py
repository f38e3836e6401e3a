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
