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
