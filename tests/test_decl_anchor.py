"""Where a new declaration goes when the line of the declaration it comes
from holds more (edit.Editor._anchor): after the line when the rest is
declarations and a comment (as for a line of one declaration); right
after the line's declarations when it goes on with a statement or a
routine (after the line, the new declaration would follow a statement or
lie in the routine). Oracle: the output parsed, and where each new
declaration is in it."""

import sys
from pathlib import Path

import pytest

from rapidcomp.compensate import fix as F
from rapidcomp.compensate.load import load_solver
from rapidcomp.compensate.plan import Task
from rapidcomp.rapid.parse import parse_text

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))
from fix import cam_module  # noqa: E402


@pytest.fixture(scope="module")
def solver():
    return load_solver(str(ROOT / "fixtures" / "warm.csv"), None, False)


def _lits(n):
    return [line.split(":=", 1)[1].rstrip(";")
            for line in cam_module(2 * n, 9).split("\n") if "CONST robtarget" in line]


HEAD = """MODULE M
  PERS tooldata tSpindle:=[TRUE,[[0,0,150],[1,0,0,0]],[2,[0,0,75],[1,0,0,0],0,0,0]];
  PERS wobjdata wPart:=[FALSE,TRUE,"",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];
  VAR num n:=1;
"""
MOVES = "    MoveL a1,v100,z1,tSpindle\\WObj:=wPart;\n    MoveL a2,v100,z1,tSpindle\\WObj:=wPart;\n"


def _out(solver, text):
    r = F.fix(Task("m.mod", (parse_text(text, "m.mod"),)), solver, "absj")
    assert r.failed == 0
    out = r.modules[0].text
    return out, parse_text(out, "out.mod").modules[0]


@pytest.mark.parametrize("tail", ["", " ! both", " VAR num k; ! both"])
def test_declarations_and_a_comment_on_the_line_new_ones_after_it(solver, tail):
    a1, a2 = _lits(2)
    line = f"  CONST robtarget a1:={a1}; CONST robtarget a2:={a2};{tail}\n"
    text = HEAD + line + "  PROC main()\n" + MOVES + "  ENDPROC\nENDMODULE\n"
    out, module = _out(solver, text)
    # The line as it was, the new declarations on the lines after it.
    assert line + "  LOCAL CONST jointtarget jt_a1:=" in out
    assert "\n  LOCAL CONST jointtarget jt_a2:=" in out
    assert {d.name for d in module.declarations if d.routine is None} >= {"jt_a1", "jt_a2"}


@pytest.mark.parametrize("tail", ["", " ! both"])
@pytest.mark.parametrize("transient", [False, True])
def test_a_declaration_of_the_line_going_on_onto_the_next(solver, tail, transient):
    """The line's last declaration goes on onto the next line: the new ones
    go after the line where it ends (not at the end of the first line,
    inside its literal: the output did not parse)."""
    a1, a2 = _lits(2)
    head, rest = a2.split("],", 1)
    line = (f"  CONST robtarget a1:={a1}; CONST robtarget a2:={head}],\n"
            f"    {rest};{tail}\n")
    text = HEAD + line + "  PROC main()\n" + MOVES + "  ENDPROC\nENDMODULE\n"
    if transient:
        from rapidcomp.compensate.load import load_state_solvers
        from rapidcomp.compensate.transient import Transient
        warm = str(ROOT / "fixtures" / "warm.csv")
        r = F.fix(Task("m.mod", (parse_text(text, "m.mod"),)), solver, "auto",
                  transient=(Transient(45.0, 45.0, 2.0), load_state_solvers(warm, None, False)))
        assert r.failed == 0
        out, kind = r.modules[0].text, "pose"
        names = ("a1_dq", "a2_dq")
    else:
        out, _ = _out(solver, text)
        kind, names = "jointtarget", ("jt_a1", "jt_a2")
    assert line + f"  LOCAL CONST {kind} {names[0]}:=" in out
    module = parse_text(out, "out.mod").modules[0]
    assert {d.name for d in module.declarations if d.routine is None} >= set(names)


def test_a_line_going_on_with_a_routine(solver):
    a1, a2 = _lits(2)
    text = (HEAD + f"  CONST robtarget a2:={a2};\n  LOCAL CONST robtarget a1:={a1}; PROC main()\n"
            + MOVES + "  ENDPROC\nENDMODULE\n")
    out, module = _out(solver, text)
    # Both new declarations at module level, before the routine.
    assert {d.name for d in module.declarations if d.routine is None} >= {"jt_a1", "jt_a2"}
    assert f"LOCAL CONST robtarget a1:={a1};\n  LOCAL CONST jointtarget jt_a1:=" in out
    assert out.index("jt_a1:=") < out.index("PROC main()")


def test_a_routine_line_going_on_with_a_statement(solver):
    a1, a2 = _lits(2)
    text = (HEAD + "  PROC main()\n"
            + f"    CONST robtarget a1:={a1}; CONST robtarget a2:={a2}; n:=2;\n"
            + MOVES + "  ENDPROC\nENDMODULE\n")
    out, module = _out(solver, text)
    # In the routine's declarations, before its first statement.
    assert {d.name for d in module.declarations if d.routine == "main"} >= {"jt_a1", "jt_a2"}
    assert f"CONST robtarget a2:={a2};\n    CONST jointtarget jt_a1:=" in out
    assert "\n    CONST jointtarget jt_a2:=" in out and out.count(" n:=2;") == 1


def test_a_move_naming_its_target_stays_a_robtarget_move(solver):
    # MoveAbsJ's target parameter is ToJointPos: `MoveL ToPoint:=a1,...`
    # made MoveAbsJ would not load. It keeps its kind, said in its row.
    a1, a2 = _lits(2)
    text = (HEAD + f"  CONST robtarget a1:={a1};\n  CONST robtarget a2:={a2};\n  PROC main()\n"
            + MOVES.replace("MoveL a1,", "MoveL ToPoint:=a1,") + "  ENDPROC\nENDMODULE\n")
    out, module = _out(solver, text)
    assert "MoveL ToPoint:=a1," in out and "MoveAbsJ jt_a2," in out
    r = F.fix(Task("m.mod", (parse_text(text, "m.mod"),)), solver, "absj")
    kept = [row for row in r.rows if row.target == "a1"]
    assert len(kept) == 1 and "kept as MoveL: its target is passed by name (ToPoint:=), which " \
        "rapidcomp does not rewrite as MoveAbsJ's ToJointPos:=" in kept[0].warnings
