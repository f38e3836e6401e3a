"""`rapidcomp fix` from the command line gives the same bytes with every
CAM-scale shortcut (issue #14) taken as with every one that can be switched
off switched off, on every fixture, golden case and task folder, in every
--emit mode (and --transient, --transient --emit absj on a few).

The shortcuts are forced on where the inputs are small: the job's helper
(side.py) and the parse's child (rapid/predecode.py) run for any size, and
the test asserts they did. The general side has neither, lexes one token
at a time, resolves and chooses by the general rules, and verifies on the
output parsed again instead of the edited numbers read back.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from rapidcomp import side
from rapidcomp.cli import main
from rapidcomp.compensate import fix as F
from rapidcomp.rapid import predecode as PD

from test_cam_paths import _slow

ROOT = Path(__file__).resolve().parents[1]
FIXTURES = ROOT / "fixtures"
PROFILE = FIXTURES / "warm.csv"
# Every program the repository holds as a fixture or golden case (a golden
# case that copies a fixture is that fixture), with the options it needs.
PROGRAMS = {
    "cubes.mod": (FIXTURES / "cubes.mod", ("--limit", "J5=-120:120")),
    "paper_front.mod": (FIXTURES / "paper_front.mod", ()),
    **{f"rapid/{p.name}": (p, ()) for p in sorted((FIXTURES / "rapid").iterdir())},
    "golden refusals": (ROOT / "tests" / "golden" / "fix" / "refusals" / "before.mod", ()),
    "task cell": (FIXTURES / "tasks" / "cell", ()),
    "task glue.pgf": (FIXTURES / "tasks" / "glue" / "Glue.pgf", ()),
    "backup irbt": (FIXTURES / "tasks" / "backup_irbt", ()),
    "backup irbt on a track": (FIXTURES / "tasks" / "backup_irbt", ("--track", "a:x")),
}
MODES = {
    "auto": ("--emit", "auto"),
    "absj": ("--emit", "absj"),
    "robtarget": ("--emit", "robtarget"),
    "transient": ("--transient", "--tau-heat", "30"),
    "transient absj": ("--transient", "--tau-heat", "30", "--emit", "absj"),
}
TRANSIENT_ON = {"cubes.mod", "rapid/robodk.mod", "task cell"}


def _fix(program: Path, options: tuple, where: Path) -> tuple:
    """(exit code, output printed, {relative path: bytes} of what was
    written) of `rapidcomp fix` on a copy of program in `where`."""
    where.mkdir()
    copy = where / program.name
    (shutil.copytree if program.is_dir() else shutil.copy)(program, copy)
    if program.suffix == ".pgf":            # (a program file: its modules beside it)
        for p in program.parent.iterdir():
            if p != program and p.is_file():
                shutil.copy(p, where / p.name)
    before = {p for p in where.rglob("*") if p.is_file()}
    r = CliRunner().invoke(main, ["fix", str(copy), "--profile", str(PROFILE), "--allow-partial",
                                  "--json", str(where / "report.json"), *options])
    written = {p.relative_to(where).as_posix(): p.read_bytes() for p in sorted(where.rglob("*"))
               if p.is_file() and p not in before}
    return r.exit_code, r.output.replace(str(where), "<here>"), written


def _count(monkeypatch, module, name: str, seen: list) -> None:
    real = getattr(module, name)

    def counted(*args, **kwargs):
        seen.append(name)
        return real(*args, **kwargs)
    monkeypatch.setattr(module, name, counted)


CASES = [(p, m) for p in PROGRAMS for m in MODES
         if not m.startswith("transient") or p in TRANSIENT_ON]


@pytest.mark.parametrize("program,mode", CASES)
def test_fix_with_every_shortcut_gives_what_the_general_paths_give(program, mode, tmp_path,
                                                                   monkeypatch):
    path, options = PROGRAMS[program]
    options = (*options, *MODES[mode])
    # Every shortcut, forced on for any size, and seen to run.
    for module in (side, PD):
        monkeypatch.setattr(module, "enabled", True)
        monkeypatch.setattr(module, "side_by_side", lambda: 2)
    monkeypatch.setattr(side, "HELP_FROM", 0)
    monkeypatch.setattr(PD, "PREDECODE_FROM", 0)
    handed: list = []
    _count(monkeypatch, side.Helper, "call", handed)
    decoded: list = []
    _count(monkeypatch, PD.Ahead, "result", decoded)
    fast = _fix(path, options, tmp_path / "fast")
    assert handed and decoded, "the helper and the parse's child must have run"
    monkeypatch.undo()
    # The general ways.
    _slow(monkeypatch)
    monkeypatch.setattr(side, "enabled", False)
    monkeypatch.setattr(PD, "enabled", False)
    for name in ("relex", "relex_absj", "relex_copies", "relex_transient"):
        monkeypatch.setattr(F, name, lambda *args: None)
    reparsed: list = []
    _count(monkeypatch, F, "reparse", reparsed)
    slow = _fix(path, options, tmp_path / "slow")
    monkeypatch.undo()
    assert fast[0] == slow[0] and fast[0] in (0, 1), fast[1]
    assert fast[1] == slow[1]
    assert fast[2].keys() == slow[2].keys()
    for name in fast[2]:
        assert fast[2][name] == slow[2][name], name
    # Something was written and verified: a compensated output.
    assert any(name.endswith(".md") for name in fast[2]) and reparsed
