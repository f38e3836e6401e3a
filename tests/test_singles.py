"""Inline literals of numbers each read by one use alone are held as
Singles, not a Group each (issue #14: no Group per target), and `fix`
writes with them what it writes with a Group each: the same output, edits,
diffs, rows, notes and reports, in every --emit mode, where uses fail their
solve, the wrist singularity or their verification (each such one then a
Group of its own, which says why). Oracle: fix with a Group for every use
(grouping(singles=False), the grouping `check` makes)."""

from pathlib import Path

import pytest

from cam_variants import EXT, VARIANTS, bench_module
from test_takeback import _same, missing
from rapidcomp.compensate import fix as F
from rapidcomp.compensate import place as P
from rapidcomp.compensate.load import load_solver
from rapidcomp.compensate.plan import Task
from rapidcomp.rapid.parse import parse_text

ROOT = Path(__file__).resolve().parents[1]

# Inline targets a Single cannot keep: RobotStudio's home at J5 = 0 (its
# robtarget needs a J4/J6 split: not compensated as a MoveL kept one; a
# MoveAbsJ can), one out of reach, one in Offs (a Group of its own whatever
# it does), around plain ones.
FAILING = f"""MODULE Odd
  PROC main()
    MoveL [[600,100,500],[0,0,1,0],[0,0,0,0],{EXT}],v100,z1,tool0;
    MoveL [[515,0,712],[0.707107,0,0.707107,0],[0,0,0,0],{EXT}],v100,fine,tool0;
    MoveL [[600,-100,500],[0,0,1,0],[-1,0,-1,0],{EXT}],v100,z1,tool0;
    MoveL [[2600,0,500],[0,0,1,0],[0,0,0,0],{EXT}],v100,z1,tool0;
    MoveL Offs([[600,0,450],[0,0,1,0],[0,0,0,0],{EXT}],0,0,10),v100,z1,tool0;
    MoveJ [[550,50,550],[0,0,1,0],[0,0,0,0],{EXT}],v100,z1,tool0;
  ENDPROC
ENDMODULE
"""

PROGRAMS = {
    **{name: make(3) for name, make in VARIANTS.items()},
    "cam": bench_module(300, 6, ""),
    "cam_confoff": bench_module(300, 6, "    ConfL\\Off;\n"),
    "failing": FAILING,
}


@pytest.fixture(scope="module")
def solver():
    return load_solver(str(ROOT / "fixtures" / "warm.csv"), None, False, ("J5=-120:120",))


def _fix(text: str, name: str, solver, mode: str, monkeypatch, singles: bool,
         miss_every: int = 0):
    """(fix's result, [(Groups, Singles' elements) settle left, per round]);
    miss_every: every such use made to miss by 5 um (test_takeback.missing)."""
    left: list = []
    real_settle = P.settle

    def settle(gs, *args):
        real_settle(gs, *args)
        left.append((sum(type(g) is P.Group for g in gs),
                     sum(len(g.uses) for g in gs if type(g) is P.Singles)))
    monkeypatch.setattr(P, "settle", settle)
    if not singles:
        real = P.grouping
        monkeypatch.setattr(P, "grouping", lambda *a, **k: real(*a, **{**k, "singles": False}))
    if miss_every:
        missing(monkeypatch, miss_every)
    result = F.fix(Task(name, (parse_text(text, name + ".mod"),)), solver, mode)
    monkeypatch.undo()
    return result, left


@pytest.mark.parametrize("miss_every", [0, 7])
@pytest.mark.parametrize("mode", ["auto", "absj", "robtarget"])
@pytest.mark.parametrize("name", sorted(PROGRAMS))
def test_singles_write_what_a_group_each_writes(name, mode, miss_every, solver, monkeypatch):
    text = PROGRAMS[name]
    got, left = _fix(text, name, solver, mode, monkeypatch, True, miss_every)
    want, whole = _fix(text, name, solver, mode, monkeypatch, False, miss_every)
    _same(got, want, mode)
    # The inline uses were Singles, not a Group each (the oracle's were).
    assert whole[0][1] == 0
    singles = left[0][1]
    assert singles >= (3 if name == "failing" else 40)
    assert left[0][0] + singles == whole[0][0]
    if miss_every:
        # Some missed and were taken back or placed again as Groups.
        assert "would miss by 5.000 um" in "".join(r.reason or "" for r in got.rows)


def test_a_single_that_fails_is_a_group_of_its_own_that_says_why(solver, monkeypatch):
    got, left = _fix(FAILING, "failing", solver, "auto", monkeypatch, True)
    rows = got.rows
    assert [r.status for r in rows] == ["compensated", "not compensated", "compensated",
                                        "not compensated", "compensated", "compensated"]
    assert "J4/J6 split a robtarget cannot carry" in rows[1].reason
    assert rows[1].reason.endswith(": a MoveAbsJ can (--emit absj for a MoveL)")
    assert "out of reach" in rows[3].reason
    assert [r.action for r in rows[::2]] == ["inline robtarget rewritten"] * 3
    assert rows[5].action == "MoveJ -> MoveAbsJ, inline jointtarget"
    # The two plain MoveL targets and the MoveJ were Singles; the two
    # that fail and the Offs one, Groups.
    assert left == [(3, 3)]
    text = got.modules[0].text
    assert "[[515,0,712],[0.707107,0,0.707107,0]" in text and "[[2600,0,500]" in text
