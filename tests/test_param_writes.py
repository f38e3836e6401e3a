"""Data passed to an INOUT/VAR/PERS parameter of a given routine is changed
at run time only where the routine may write that parameter: it assigns it
(whole or a component), fills it (a search's result, a built-in that fills
an argument), or passes it on to a parameter that may be written, a
routine no given module declares or a late-bound call; SetDataVal with a
name computed at run time may write any. A tool passed to a helper's PERS
tooldata parameter for its moves (common ABB style; a public socket
server's `PROC jump(..., PERS tooldata tool, ...)` left 74 of 96 moves
untouched) changes nothing: the moves with it are compensated. Expected
verdicts read off each routine's text by hand."""

import pytest

from rapidcomp.compensate.fix import fix
from rapidcomp.compensate.plan import Task
from rapidcomp.kinematics.ik import Solver
from rapidcomp.kinematics.profile import deform, read_profile
from rapidcomp.kinematics.robot import irb140
from rapidcomp.rapid.parse import parse_text

from conftest import FIXTURES

ROBOT = irb140()
SOLVER = Solver(ROBOT, deform(ROBOT, read_profile(FIXTURES / "warm.csv")))
EXT = "[9E9,9E9,9E9,9E9,9E9,9E9]"


def _reason(helpers: str, call: str = "Go p1, tPen;", storage: str = "CONST") -> str | None:
    """The row of `MoveL p1, ..., tPen;` (before the call) in a module
    whose main calls `call` and declares `helpers`: its reason, None where
    compensated."""
    text = f"""MODULE M0
    PERS tooldata tPen:=[TRUE,[[0,0,100],[1,0,0,0]],[0.5,[0,0,50],[1,0,0,0],0,0,0]];
    {storage} robtarget p1:=[[400,0,400],[0,0,1,0],[0,0,0,0],{EXT}];
    VAR num n:=0;
    PROC main()
        MoveL p1, v100, fine, tPen;
        {call}
    ENDPROC
{helpers}
ENDMODULE"""
    rows = fix(Task("t", (parse_text(text, "M0.mod"),)), SOLVER, "robtarget").rows
    row = next(r for r in rows if r.line == 6)
    return None if row.status == "compensated" else row.reason


READS = """    PROC Go(robtarget pt, PERS tooldata tl)
        VAR robtarget here;
        here := CRobT(\\Tool:=tl);
        MoveL Offs(pt,0,0,20), v100, fine, tl;
    ENDPROC"""


def test_a_tool_only_read_by_the_routine_is_static():
    assert _reason(READS) is None


@pytest.mark.parametrize("body", [
    "tl.tframe.trans.z := 5;",                         # (a component)
    "tl := [TRUE,[[0,0,90],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];",
    "GetSysData tl;",                                  # (a built-in fills it)
    "RMQGetMsgData msg, tl;",                          # (another task's message fills it)
    "SiGetCyclic dev, tl, 64;",                        # (a subscription updates it)
    "Vendor tl;",                                      # (a routine not given)
    "%\"Dyn\"% tl;",                                   # (a late-bound call)
    "SetDataVal \"x\"+\"y\", n;",                      # (any data, by a computed name)
    "Pass tl;",                                        # (passed on to one that writes it)
])
def test_a_routine_that_may_write_it_changes_it(body):
    helpers = f"""    PROC Go(robtarget pt, PERS tooldata tl)
        VAR rmqmessage msg;
        {body}
        MoveL pt, v100, fine, tl;
    ENDPROC
    PROC Pass(PERS tooldata t)
        t.tframe.trans.z := 1;
    ENDPROC"""
    reason = _reason(helpers)
    assert reason is not None and reason.startswith("tPen is passed to Go, which may change it "
                                                    "at run time (M0.mod:7)")


def test_passed_on_to_a_parameter_not_written_changes_nothing():
    """Pass reads its parameter; Go calls itself with it too (recursion: no
    path writes it); an optional argument to a parameter written elsewhere
    (\\T), not the one passed (\\U)."""
    helpers = """    PROC Go(robtarget pt, PERS tooldata tl)
        Pass tl;
        Opt \\U:=tl;
        IF n > 3 Go pt, tl;
        MoveL pt, v100, fine, tl;
    ENDPROC
    PROC Pass(PERS tooldata t)
        MoveL Offs(CRobT(\\Tool:=t), 0, 0, 10), v100, fine, t;
    ENDPROC
    PROC Opt(\\PERS tooldata T | PERS tooldata U)
        IF Present(T) T.tframe.trans.z := 1;
    ENDPROC"""
    assert _reason(helpers) is None


def test_a_written_parameter_passed_by_name_is_written():
    helpers = """    PROC Go(robtarget pt, PERS tooldata tl)
        Opt \\T:=tl;
    ENDPROC
    PROC Opt(\\PERS tooldata T | PERS tooldata U)
        IF Present(T) T.tframe.trans.z := 1;
    ENDPROC"""
    assert _reason(helpers).startswith("tPen is passed to Go, which may change it")


def test_a_search_result_parameter_is_written():
    """SearchL's search point is its result: passed to a routine whose
    INOUT parameter a search fills, the target (a PERS: a CONST is not
    passed to an INOUT parameter) is changed."""
    helpers = """    PROC Find(INOUT robtarget found)
        SearchL \\Stop, di1, found, Offs(p1,0,0,-50), v50, tPen;
    ENDPROC"""
    assert _reason(helpers, "Find p1;", "PERS").startswith("p1 is passed to Find, which may change it")


def test_a_named_required_argument_holds_its_place():
    """`Recal pt:=p1, tPen;`: pt is named, tPen the second required
    argument, which Recal writes (named, pt used to shift the positions: tPen
    was read as pt's, the robot then 150 mm off)."""
    helpers = """    PROC Recal(robtarget pt, PERS tooldata tl)
        tl.tframe.trans.z := 250;
    ENDPROC"""
    assert _reason(helpers, "Recal pt:=p1, tPen;").startswith(
        "tPen is passed to Recal, which may change it")


@pytest.mark.parametrize("stmt, changed", [
    ("tPen.tload.mass := 2;", False),
    ("tPen.tload := [2,[0,0,50],[1,0,0,0],0,0,0];", False),
    ("TPReadNum tPen.tload.mass, \"mass?\";", False),
    ("Go p1, tPen;", False),                    # (Go sets its parameter's load)
    ("tPen.tframe.trans.z := 120;", True),
    ("tPen.robhold := FALSE;", True),           # (a stationary tool then)
    ("TPReadNum tPen.tframe.trans.z, \"z?\";", True),
])
def test_a_tools_load_written_changes_no_pose(stmt, changed):
    """A program that sets its tool's load (after a grip: tool.tload.mass
    := ...; in public tool changers and servers) changes none of the frames
    the compensation reads: the tool's moves are compensated; its frame or
    robhold written, they are not."""
    helpers = """    PROC Go(robtarget pt, PERS tooldata tl)
        tl.tload.mass := 1;
        TPReadNum tl.tload.cog.z, "cog?";
    ENDPROC"""
    reason = _reason(helpers, stmt)
    assert (reason is not None) == changed, reason
    if changed:
        assert reason.startswith("tPen is ")
