"""`rapidcomp inspect`: golden output per fixture (reviewed by eye) and JSON."""

import json

import pytest
from click.testing import CliRunner

from rapidcomp.cli import main

from conftest import FIXTURES, RAPID_FIXTURES
from regen_golden import GOLDEN, inspect_golden


@pytest.mark.parametrize("path", RAPID_FIXTURES, ids=lambda p: p.name)
def test_inspect_golden(path):
    expected = (GOLDEN / "inspect" / f"{path.name}.txt").read_text(encoding="utf-8")
    assert inspect_golden(path) == expected


def test_inspect_cli_json():
    result = CliRunner().invoke(main, ["inspect", str(FIXTURES / "rapid" / "robodk.mod"), "--json"])
    assert result.exit_code == 0
    rep = json.loads(result.stdout)
    m = rep["modules"][0]
    assert m["name"] == "MOD_Prog1"
    assert m["counts"]["motions"] == 5 and m["counts"]["inline_targets"] == 4
    first = m["motions"][0]
    assert first["instruction"] == "MoveAbsJ" and first["wobj"] == "rdkWObj"
    assert first["targets"][0]["robax"] == [41.85, 44.63, 25.88, 43.53, -75.61, -13.29]
    assert m["motions"][1]["targets"][0]["conf"] == [0, 0, -1, 0]


def test_inspect_cli_text_runs_on_every_fixture():
    for path in RAPID_FIXTURES:
        result = CliRunner().invoke(main, ["inspect", str(path)])
        assert result.exit_code == 0, result.output
        assert "MODULE" in result.stdout


@pytest.mark.parametrize("program,modules", [
    # (A program file: its modules in its order, not a stale copy beside.)
    ("glue/Glue.pgf", ["glue/GlueData.mod", "glue/GlueMain.mod"]),
    ("cell", ["cell/CellData.mod", "cell/MainModule.mod"]),
    # (A backup: every task's, motion or not.)
    ("backup_irbt", ["backup_irbt/RAPID/TASK1/PROGMOD/Track.mod",
                     "backup_irbt/RAPID/TASK1/SYSMOD/user.sys",
                     "backup_irbt/RAPID/TASK2/PROGMOD/Comm.mod"]),
])
def test_inspect_a_task_is_each_of_its_modules_inspected(program, modules):
    """`inspect` takes what `check` and `fix` take: a task folder, a program
    file or a backup is each of its modules as `inspect MODULE` shows it,
    one after the other (text), or listed (JSON)."""
    tasks = FIXTURES / "tasks"

    def run(*args):
        r = CliRunner().invoke(main, ["inspect", *args])
        assert r.exit_code == 0, r.output
        return r.stdout
    assert run(str(tasks / program)) == "\n".join(run(str(tasks / m)) for m in modules)
    doc = json.loads(run(str(tasks / program), "--json"))
    assert doc == {"program": str(tasks / program),
                   "modules": [json.loads(run(str(tasks / m), "--json")) for m in modules],
                   "notes": [], "problems": []}


def test_inspect_says_what_check_and_fix_refuse_in_a_task(tmp_path):
    """A folder with a stale copy of a module (or a global name declared in
    two modules) is listed as it is, exit 0, and a note says what check
    says of it, file:line, and that check and fix refuse it (a new user's
    inspect listed it without a word)."""
    tasks = FIXTURES / "tasks"
    r = CliRunner().invoke(main, ["inspect", str(tasks / "glue")])
    assert r.exit_code == 0, r.output
    c = CliRunner().invoke(main, ["check", str(tasks / "glue"), "--profile",
                                  str(FIXTURES / "warm.csv")])
    assert c.exit_code == 2
    refusal = c.output.strip().splitlines()[0]
    assert refusal.startswith(str(tasks / "glue" / "old" / "GlueMain.mod")
                              + ":1:8: module GlueMain")
    assert c.output.strip().splitlines()[1:] == ["    MODULE GlueMain", "           ^"]
    assert r.stdout.splitlines()[-1] == f"note: {refusal}; check and fix refuse this task"
    doc = json.loads(CliRunner().invoke(main, ["inspect", str(tasks / "glue"), "--json"]).stdout)
    assert doc["problems"] == [f"{refusal}; check and fix refuse this task"]
    assert len(doc["modules"]) == 3
    for name in ("A", "B"):
        (tmp_path / f"{name}.mod").write_text(
            f"MODULE {name}\n  CONST num nSpeed:=1;\nENDMODULE\n")
    r = CliRunner().invoke(main, ["inspect", str(tmp_path)])
    assert r.exit_code == 0 and r.stdout.splitlines()[-1] == (
        f"note: {tmp_path / 'B.mod'}:2:13: nSpeed is declared globally in two modules (also "
        f"{tmp_path / 'A.mod'}:2): the controller does not load the task (make one LOCAL, or "
        "give the program file (.pgf) without the other); check and fix refuse this task")
