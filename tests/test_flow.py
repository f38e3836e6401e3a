"""The motion state the controller runs each move in (flow.py), the rule
that chooses its solution (solve.py) and how a task's names resolve
(targets.py), on small hand-written tasks. Expected states are read off
the RAPID semantics by hand (ConfJ/ConfL and program displacement persist
across routine calls; supervision is on at program start)."""

from __future__ import annotations

import re

import numpy as np
import pinocchio as pin
import pytest

from rapidcomp.compensate.check import check
from rapidcomp.compensate.flow import PROGRAM_START
from rapidcomp.compensate.fix import fix
from rapidcomp.compensate.plan import Plan, Task
from rapidcomp.kinematics.ik import Solver
from rapidcomp.kinematics.profile import deform, read_profile
from rapidcomp.kinematics.robot import irb140
from rapidcomp.rapid.parse import parse_text

from conftest import FIXTURES

ROBOT = irb140()
SOLVER = Solver(ROBOT, deform(ROBOT, read_profile(FIXTURES / "warm.csv")))
EXT = "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]"
# The paper's P1 (front cube, Table 5 row 1) and P4, flange Ry(90).
P1 = f"[[400,300,250],[0.707107,0,0.707107,0],[0,0,-1,1],{EXT}]"
P4 = f"[[400,-150,250],[0.707107,0,0.707107,0],[-1,-1,0,1],{EXT}]"
P1_BAD = f"[[400,300,250],[0.707107,0,0.707107,0],[0,-1,-1,0],{EXT}]"   # placeholder
# P4 on the other wrist branch (J4 + 180, -J5, J6 + 180): valid, but not the
# solution closest to P1's.
P4_FLIP = f"[[400,-150,250],[0.707107,0,0.707107,0],[-1,1,2,0],{EXT}]"


def task(*modules: str) -> Task:
    files = tuple(parse_text(text, f"M{i}.mod") for i, text in enumerate(modules))
    return Task("t", files)


def states(t: Task):
    plan = Plan(t)
    return plan, {(u.line, u.role): plan.state(u) for u in plan.uses}


def test_supervision_persists_into_called_routines_and_starts_on():
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    PROC main()
        MoveL p1, v100, fine, tool0;
        ConfL\\Off;
        Sub;
        ConfL\\On;
        Sub;
    ENDPROC
    PROC Sub()
        MoveL p1, v100, fine, tool0;
        MoveJ p1, v100, fine, tool0;
    ENDPROC
ENDMODULE""")
    plan, st = states(t)
    assert st[(4, "to")].confl == {"on"}
    # Sub is called with ConfL off and with it on: both.
    assert st[(11, "to")].confl == {"on", "off"}
    assert st[(12, "to")].confj == {"on"}
    # The previous move of Sub's first move: main's MoveL (first call) and
    # Sub's own MoveJ (second call).
    assert {plan.by_key[k].line for k in st[(11, "to")].last} == {4, 12}


def test_branches_join_and_loops_chain_their_moves():
    t = task(f"""MODULE A
    CONST robtarget p{{3}}:=[{P1},{P1},{P1}];
    VAR num n:=0;
    PROC main()
        IF n > 1 THEN
            ConfJ\\Off;
        ENDIF
        MoveJ p{{1}}, v100, fine, tool0;
        FOR i FROM 1 TO 3 DO
            MoveL p{{i}}, v100, fine, tool0;
        ENDFOR
        WHILE n < 3 DO
            MoveL p{{2}}, v100, fine, tool0;
            MoveL p{{3}}, v100, fine, tool0;
        ENDWHILE
    ENDPROC
ENDMODULE""")
    plan, st = states(t)
    assert st[(8, "to")].confj == {"on", "off"}
    loop = {k[3]: s for k, s in plan.flow.before.items() if plan.by_key[k].line == 10}
    line = {u.key: u.line for u in plan.uses}
    assert {line[k] for k in loop[(("i", 1),)].last} == {8}
    prev2 = list(loop[(("i", 2),)].last)[0]
    assert line[prev2] == 10 and prev2[3] == (("i", 1),)
    # The WHILE body's first move follows the loop before it, or its own last move.
    assert {line[k] for k in st[(13, "to")].last} == {10, 14}


def test_program_displacement_from_a_caller_and_unknown_calls():
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    PERS pose pd:=[[1,0,0],[1,0,0,0]];
    PROC main()
        PDispSet pd;
        Work;
        PDispOff;
        Work;
        VendorProc;
        MoveL p1, v100, fine, tool0;
    ENDPROC
    PROC Work()
        MoveL p1, v100, fine, tool0;
    ENDPROC
ENDMODULE""")
    plan, st = states(t)
    assert st[(13, "to")].pdisp == {"on", "off"}
    after = st[(10, "to")]
    assert after.last is None and after.confl == {"on", "off"} and after.pdisp == {"on", "off"}
    assert any("VendorProc (M0.mod:9)" in n for n in plan.notes())


def test_routines_nobody_calls_are_entries_with_unknown_state():
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    PROC main()
        MoveL p1, v100, fine, tool0;
    ENDPROC
    PROC Service()
        MoveL p1, v100, fine, tool0;
    ENDPROC
ENDMODULE""")
    plan, st = states(t)
    assert st[(7, "to")].confl == {"on", "off"} and st[(7, "to")].last == {PROGRAM_START}
    assert st[(7, "to")].pdisp == {"off"}   # nothing given switches it on
    assert any("Service" in n and "not called" in n for n in plan.notes())


def rows_of(t: Task, mode="absj"):
    return {r.line: r for r in fix(t, SOLVER, mode).rows}


def test_supervision_off_follows_the_previous_move_and_ignores_confdata():
    t = task(f"""MODULE A
    CONST jointtarget jStart:=[[35,40,25,40,-70,-10],{EXT}];
    PROC main()
        ConfL\\Off;
        MoveAbsJ jStart, v100, fine, tool0;
        MoveL {P1_BAD}, v100, fine, tool0;
    ENDPROC
ENDMODULE""")
    rows = rows_of(t)
    r = rows[6]
    assert r.status == "compensated" and r.rule == "closest to line 5 (ConfL\\Off)"
    # The solution is the paper's (Table 5 row 1, truncated to 2 decimals).
    assert np.allclose(r.nominal_deg, [41.85, 44.63, 25.88, 43.53, -75.61, -13.29], atol=0.01)
    # With supervision on, the same placeholder has no solution.
    t_on = task(f"""MODULE A
    PROC main()
        MoveL {P1_BAD}, v100, fine, tool0;
    ENDPROC
ENDMODULE""")
    r = rows_of(t_on)[3]
    assert r.status == "not compensated" and "J4 quadrant no solution has" in r.reason


def test_unknown_supervision_valid_confdata_other_closest_stays_a_robtarget_move():
    """Service is entered from outside the given modules: ConfL may be on or
    off. Its confdata is valid but from P1 the closest solution of P4 is
    another: compensated on the confdata's solution, kept as MoveL (the
    controller keeps choosing), and the report says what was assumed. The
    first move: where the robot stands when Service starts is not known, so
    with ConfL off the controller might choose another solution: kept a
    robtarget move too, with a caution."""
    t = task(f"""MODULE A
    PROC Service()
        MoveL {P1}, v100, fine, tool0;
        MoveL {P4_FLIP}, v100, fine, tool0;
    ENDPROC
ENDMODULE""")
    rows = rows_of(t)
    assert rows[3].rule == "confdata (ConfL on or off: the same solution)"
    assert rows[3].action == "inline robtarget rewritten"
    assert any("where the robot stands is not known" in w for w in rows[3].warnings)
    r = rows[4]
    assert r.status == "compensated" and r.rule == "confdata (ConfL may be on or off here)"
    assert r.action == "inline robtarget rewritten"
    assert any("may be on or off here" in w and "closest" in w for w in r.warnings)


def test_unknown_supervision_invalid_confdata_means_off():
    t = task(f"""MODULE A
    CONST jointtarget jStart:=[[35,40,25,40,-70,-10],{EXT}];
    PROC Service()
        MoveAbsJ jStart, v100, fine, tool0;
        MoveL {P1_BAD}, v100, fine, tool0;
    ENDPROC
ENDMODULE""")
    r = rows_of(t)[5]
    assert r.status == "compensated"
    assert r.rule.endswith("its confdata names no solution, so ConfL is off here")


def test_previous_moves_that_disagree_are_refused():
    """Supervision off after an IF whose branches leave the wrist on either
    side: the controller's choice depends on the branch taken."""
    t = task(f"""MODULE A
    CONST jointtarget jA:=[[41.85,44.63,25.88,43.53,-75.61,-13.29],{EXT}];
    CONST jointtarget jB:=[[41.85,44.63,25.88,-136.47,75.61,166.71],{EXT}];
    VAR num n:=0;
    PROC main()
        ConfL\\Off;
        IF n > 0 THEN
            MoveAbsJ jA, v100, fine, tool0;
        ELSE
            MoveAbsJ jB, v100, fine, tool0;
        ENDIF
        MoveL {P1_BAD}, v100, fine, tool0;
    ENDPROC
ENDMODULE""")
    r = rows_of(t)[12]
    assert r.status == "not compensated"
    assert "depends on which move ran before it, or on the solution it took (lines 8, 10)" in r.reason


# A path nothing calls (configuration supervision not known) ending in a
# MoveC whose circle point follows a move that may stand on either of two
# solutions (from a CAM trial).
ARC = """MODULE Arc
  PERS tooldata tSpindle:=[TRUE,[[0,0,150],[1,0,0,0]],[2,[0,0,75],[1,0,0,0],0,0,0]];
  PERS wobjdata wPart:=[FALSE,TRUE,"",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];
  PROC Path()
    MoveL [[664.341,-22.091,198.394],[0.480747,0.154977,0.835020,0.218189],[-1,-1,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],v100,z1,tSpindle\\WObj:=wPart;
    MoveL [[582.152,-315.711,529.647],[0.588877,0.216899,0.673159,-0.391197],[-1,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],v100,z1,tSpindle\\WObj:=wPart;
    MoveL [[592.351,-419.782,351.690],[0.718510,0.432001,0.530041,-0.127181],[-1,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],v100,z1,tSpindle\\WObj:=wPart;
    MoveC [[719.333,270.783,530.856],[0.553563,0.163580,0.568579,0.586112],[0,-1,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],[[717.333,268.783,530.856],[0.553563,0.163580,0.568579,0.586112],[0,-1,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],v100,z1,tSpindle\\WObj:=wPart;
  ENDPROC
ENDMODULE
"""


def test_a_circle_point_after_a_move_on_either_solution_says_so():
    """The circle point is passed on the solution closest to where the
    robot is whatever the supervision: refused because the move before it
    may stand on either of two solutions, said so (it said ConfL\\Off,
    which the program never switches)."""
    cir, = (r for r in fix(task(ARC), SOLVER, "auto").rows if r.status == "not compensated")
    assert cir.line == 8 and cir.instruction == "MoveC"
    assert cir.reason == ("the circle point is passed on the solution closest to where the robot "
                          "is, and that depends on which move ran before it, or on the solution "
                          "it took (line 7)")


def test_scopes_local_data_parameters_and_ambiguous_globals():
    t = task(f"""MODULE A
    LOCAL CONST robtarget p:={P1};
    CONST robtarget q:={P1};
    PROC main()
        MoveL p, v100, fine, tool0;
        B_Go;
    ENDPROC
    PROC Go(robtarget t)
        MoveL t, v100, fine, tool0;
    ENDPROC
ENDMODULE""", f"""MODULE B
    LOCAL CONST robtarget p:={P4};
    CONST robtarget q:={P4};
    PROC B_Go()
        MoveL p, v100, fine, tool0;
        MoveL q, v100, fine, tGun;
    ENDPROC
ENDMODULE""")
    plan = Plan(t)
    by = {(u.file.source.display_path, u.line): u for u in plan.uses}
    assert by[("M0.mod", 5)].p[1] == pytest.approx(300 - 0, abs=200)  # A's own p (y = 300)
    assert by[("M0.mod", 5)].source.record.xyz[1] == 300
    assert by[("M1.mod", 5)].source.record.xyz[1] == -150      # B's LOCAL p shadows A's
    assert "parameter of routine Go" in by[("M0.mod", 9)].reason
    assert not by[("M0.mod", 9)].blocked
    u = by[("M1.mod", 6)]
    assert u.blocked and "declared globally more than once (M0.mod:3, M1.mod:3)" in u.reason


def test_a_missing_tool_is_named_with_its_missing_work_object():
    """Both named at once (as a missing target is with them), so that the
    declaring modules are given at once, not found one run at a time; a
    work object that is declared (wobj0 here) is not named."""
    t = task(f"""MODULE A
    PROC main()
        MoveL {P1}, v100, fine, tGun\\WObj:=wTable;
        MoveL {P1}, v100, fine, tGun;
    ENDPROC
ENDMODULE""")
    rows = rows_of(t)
    both, alone = rows[3], rows[4]
    assert both.status == alone.status == "not compensated"
    assert both.reason.startswith("tool tGun and work object wTable are not declared in the "
                                  "given modules (give the whole task")
    assert alone.reason.startswith("tool tGun is not declared in the given modules (give the "
                                   "whole task")


def test_an_element_reached_on_two_configurations_gets_two_values():
    """p{1} named by a literal index after two different wrist positions
    (ConfJ off): two solutions, so two jointtargets."""
    t = task(f"""MODULE A
    CONST robtarget p{{2}}:=[{P1_BAD},{P4}];
    CONST jointtarget jA:=[[41.85,44.63,25.88,43.53,-75.61,-13.29],{EXT}];
    CONST jointtarget jB:=[[41.85,44.63,25.88,-136.47,75.61,166.71],{EXT}];
    PROC main()
        ConfJ\\Off;
        MoveAbsJ jA, v100, fine, tool0;
        MoveJ p{{1}}, v100, fine, tool0;
        MoveAbsJ jB, v100, fine, tool0;
        MoveJ p{{1}}, v100, fine, tool0;
    ENDPROC
ENDMODULE""")
    rows = rows_of(t)
    assert rows[8].status == rows[10].status == "compensated"
    assert rows[8].action == "MoveJ -> MoveAbsJ jt_p_1" and rows[10].action == "MoveJ -> MoveAbsJ jt_p_1_2"
    assert abs(rows[8].nominal_deg[3] - rows[10].nominal_deg[3]) == pytest.approx(180, abs=0.1)


def test_a_walked_array_element_on_two_configurations_is_one_failure_not_a_wrong_value():
    """The same FOR loop walks p after two different wrist positions: one
    jointtarget array cannot hold both solutions of its first element."""
    t = task(f"""MODULE A
    CONST robtarget p{{2}}:=[{P1_BAD},{P1_BAD}];
    CONST jointtarget jA:=[[41.85,44.63,25.88,43.53,-75.61,-13.29],{EXT}];
    CONST jointtarget jB:=[[41.85,44.63,25.88,-136.47,75.61,166.71],{EXT}];
    PROC main()
        ConfJ\\Off;
        MoveAbsJ jA, v100, fine, tool0;
        Walk;
        MoveAbsJ jB, v100, fine, tool0;
        Walk;
    ENDPROC
    PROC Walk()
        FOR i FROM 1 TO 2 DO
            MoveJ p{{i}}, v100, fine, tool0;
        ENDFOR
    ENDPROC
ENDMODULE""")
    rows = [r for r in fix(t, SOLVER, "absj").rows if r.instruction == "MoveJ"]
    assert {r.status for r in rows} == {"not compensated"}
    assert "different configurations" in rows[0].reason or "depends on which move" in rows[0].reason


def test_check_is_fixs_plan():
    """check and fix share the plan and the solve: the same joints, rules
    and errors for every use (fix's residual is of the written values)."""
    from rapidcomp.rapid.parse import parse_file
    names = ["CellData.mod", "MainModule.mod"]
    t = Task("cell", tuple(parse_file(FIXTURES / "tasks" / "cell" / n, n) for n in names))
    c = check(t, SOLVER)
    f = fix(t, SOLVER, "robtarget")
    assert len(c.rows) == len(f.rows) == 30
    for a, b in zip(c.rows, f.rows):
        assert (a.line, a.target, a.rule, a.nominal_deg, a.compensated_deg, a.error_um) == (
            b.line, b.target, b.rule, b.nominal_deg, b.compensated_deg, b.error_um)
        assert (a.status, b.status) in {("compensable", "compensated"), ("untouched", "untouched")}


# ---------------------------------------------------------------- what else changes the state

def test_callbyvar_and_unknown_procedures_make_everything_unknown():
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    VAR num n:=1;
    PROC main()
        CallByVar "Mode", n;
        MoveL p1, v100, fine, tool0;
    ENDPROC
    PROC Mode1()
        ConfL\\Off;
    ENDPROC
ENDMODULE""")
    plan, st = states(t)
    s = st[(6, "to")]
    assert s.confl == {"on", "off"} and s.pdisp == {"on", "off"} and s.last is None
    assert any("CallByVar" in n for n in plan.notes())


def test_main_restarts_from_where_its_cycle_ends():
    """Continuous run: main starts again without resetting supervision or
    displacement, so its first move may run displaced."""
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    PROC main()
        MoveJ p1, v100, fine, tool0;
        PDispSet [[0,0,20],[1,0,0,0]];
        MoveL p1, v100, fine, tool0;
    ENDPROC
ENDMODULE""")
    plan, st = states(t)
    assert st[(4, "to")].pdisp == {"on", "off"}
    rows = rows_of(t)
    assert rows[4].action == "robtarget p1 rewritten in place"    # never a MoveAbsJ


def test_exitcycle_ends_the_cycle():
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    VAR num n:=0;
    PROC main()
        MoveJ p1, v100, fine, tool0;
        IF n > 0 THEN
            MoveL p1, v100, fine, tool0;
            ConfJ\\Off;
            ExitCycle;
        ENDIF
        MoveJ p1, v100, fine, tool0;
    ENDPROC
ENDMODULE""")
    plan, st = states(t)
    line = {u.key: u.line for u in plan.uses}
    assert {line[k] for k in st[(11, "to")].last} == {5}   # ExitCycle does not fall through
    assert st[(5, "to")].confj == {"on", "off"}             # ... main starts again after it


def test_recursion_records_its_moves_as_unknown():
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    VAR num n:=0;
    PROC main()
        Cycle;
    ENDPROC
    PROC Cycle()
        MoveL p1, v100, fine, tool0;
        ConfL\\Off;
        PDispSet [[10,0,0],[1,0,0,0]];
        IF n < 3 Cycle;
    ENDPROC
ENDMODULE""")
    plan, st = states(t)
    s = st[(8, "to")]
    assert s.confl == {"on", "off"} and s.pdisp == {"on", "off"}
    assert any("call themselves: Cycle" in n for n in plan.notes())


def test_an_error_handler_that_switches_supervision_is_followed():
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    PROC main()
        Probe;
        MoveL p1, v100, fine, tool0;
    ENDPROC
    PROC Probe()
        MoveL p1, v100, fine, tool0;
    ERROR
        ConfL\\Off;
        RETURN;
    ENDPROC
ENDMODULE""")
    _, st = states(t)
    assert st[(5, "to")].confl == {"on", "off"}


def test_retry_resumes_the_body_with_what_the_handler_switched():
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    PROC main()
        MoveL p1, v100, fine, tool0;
        MoveL p1, v100, fine, tool0;
    ERROR
        PDispSet [[5,0,0],[1,0,0,0]];
        RETRY;
    ENDPROC
ENDMODULE""")
    _, st = states(t)
    assert st[(4, "to")].pdisp == {"on", "off"}


def test_a_trap_that_switches_supervision_makes_it_unknown_everywhere():
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    VAR intnum iStop;
    PROC main()
        CONNECT iStop WITH trStop;
        MoveL p1, v100, fine, tool0;
    ENDPROC
    TRAP trStop
        ConfL\\Off;
    ENDTRAP
ENDMODULE""")
    plan, st = states(t)
    assert st[(6, "to")].confl == {"on", "off"}
    assert any("TRAP" in n for n in plan.notes())


def test_goto_labels_and_test_cases():
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    VAR num n:=0;
    PROC main()
        TEST n
        CASE 1:
            ConfL\\Off;
        DEFAULT:
            ConfL\\On;
        ENDTEST
        MoveL p1, v100, fine, tool0;
        again:
        MoveL p1, v100, fine, tool0;
        IF n < 2 GOTO again;
    ENDPROC
ENDMODULE""")
    plan, st = states(t)
    assert st[(11, "to")].confl == {"on", "off"}
    # The label: after line 11, or after itself (the GOTO back).
    assert {plan.by_key[k].line for k in st[(13, "to")].last} == {11, 13}


def test_data_changed_by_calls_is_a_run_time_value():
    """Writes that are not assignments: an INOUT parameter of a given
    routine, a procedure no given module declares, GetDataVal and
    SetDataVal (with a literal name; with a computed one, any data)."""
    t = task(f"""MODULE A
    PERS robtarget pA:={P1};
    PERS robtarget pB:={P1};
    PERS robtarget pC:={P1};
    PERS robtarget pD:={P1};
    CONST robtarget pE:={P1};
    PROC main()
        Shift pA, 50;
        VisionUpdate pB;
        GetDataVal "x", pC;
        SetDataVal "pD", pA;
        MoveL pA, v100, fine, tool0;
        MoveL pB, v100, fine, tool0;
        MoveL pC, v100, fine, tool0;
        MoveL pD, v100, fine, tool0;
        MoveL pE, v100, fine, tool0;
    ENDPROC
    PROC Shift(INOUT robtarget p, num dz)
        p.trans.z := p.trans.z + dz;
    ENDPROC
ENDMODULE""")
    rows = rows_of(t)
    assert "pA is passed to Shift, which may change it at run time (M0.mod:8)" == rows[12].reason
    assert "passed to VisionUpdate, which no given module declares" in rows[13].reason
    assert "pC is filled by GetDataVal at run time" in rows[14].reason
    assert "pD is set by SetDataVal at run time" in rows[15].reason
    assert rows[16].status == "compensated"                   # CONST: never written
    assert {rows[k].status for k in (12, 13, 14, 15)} == {"untouched"}


def test_a_loop_variable_hides_a_constant_of_the_same_name():
    t = task(f"""MODULE A
    CONST num i:=3;
    CONST robtarget p{{3}}:=[{P1},{P1},{P1}];
    PROC main()
        FOR i FROM 1 TO 2 DO
            MoveL p{{i}}, v100, fine, tool0;
        ENDFOR
    ENDPROC
ENDMODULE""")
    plan = Plan(t)
    assert sorted(u.label for u in plan.uses) == ["p{i} [i=1]", "p{i} [i=2]"]
    assert sorted(u.source.element for u in plan.uses) == [0, 1]


def test_pers_with_different_values_in_two_modules_is_not_guessed():
    t = task(f"""MODULE A
    PERS robtarget pT:={P1};
    PROC main()
        MoveL pT, v100, fine, tool0;
    ENDPROC
ENDMODULE""", f"""MODULE B
    PERS robtarget pT:={P4};
ENDMODULE""")
    r = rows_of(t)[4]
    assert r.status == "not compensated" and "declared PERS with different values" in r.reason


def test_pers_targets_stay_robtarget_moves_and_copies_say_so():
    t = task(f"""MODULE A
    PERS robtarget pT:={P1};
    PROC main()
        MoveJ pT, v100, fine, tool0;
        MoveJ Offs(pT,0,0,50), v100, fine, tool0;
    ENDPROC
ENDMODULE""")
    rows = rows_of(t)
    assert rows[4].action == "robtarget pT rewritten in place"
    assert rows[5].action == "new robtarget pT_offs_c"
    assert any("pT is PERS" in w for w in rows[5].warnings)


def test_a_robtarget_at_the_wrist_singularity_is_refused_with_the_reason_not_a_crash():
    """RobotStudio's home robtarget [515,0,712] is exactly at J5 = 0: its
    compensation needs a J4/J6 split no robtarget carries. As MoveJ in the
    default mode it becomes a MoveAbsJ, which can."""
    home = f"[[515,0,712],[0.707107,0,0.707107,0],[0,0,0,0],{EXT}]"
    t = task(f"""MODULE A
    CONST robtarget pHome:={home};
    PROC main()
        MoveL pHome, v100, fine, tool0;
        MoveJ pHome, v100, fine, tool0;
    ENDPROC
ENDMODULE""")
    rows = rows_of(t, "auto")
    assert rows[4].status == "not compensated" and "J4/J6 split" in rows[4].reason
    assert rows[5].status == "compensated" and rows[5].action.startswith("MoveJ -> MoveAbsJ")


def test_near_but_past_the_wrist_singularity_a_robtarget_carries_the_split():
    """J5 at 1.22 deg (a public IRB 140 program's MoveL): within the wrist
    fallback's 5 deg (J4/J6 swing 0.9 deg, the orientation partly left
    over) but past the 0.5 deg singularity margin, where the written pose
    decides the split (its IK gives the compensated joints back): the
    robtarget is rewritten, not refused as one at J5 = 0 is. Oracle: the
    written pose is Pinocchio's FK of the row's compensated joints on the
    nominal model (within the written digits); J4 and J6 moved apart."""
    t = task(f"""MODULE A
    CONST robtarget pA:=[[167.304,-324.006,124.992],[0,0,1,0],[-1,0,-1,0],{EXT}];
    CONST jointtarget jStart:=[[-62,50,30,0,10,-62],{EXT}];
    PROC main()
        ConfL\\On;
        MoveAbsJ jStart,v100,fine,tool0;
        MoveL pA,v100,fine,tool0;
    ENDPROC
ENDMODULE""")
    result = fix(t, SOLVER, "robtarget")
    row = next(r for r in result.rows if r.instruction == "MoveL")
    assert row.status == "compensated", row.reason
    assert abs(row.nominal_deg[4] - 1.22) < 0.01
    q = np.asarray(row.compensated_deg)
    assert q[3] < -0.5 and q[5] - row.nominal_deg[5] > 0.5       # (the split)
    assert any("0.0085 deg left over" in w for w in row.warnings)
    written = re.search(r"pA:=\[\[([^\]]*)\],\[([^\]]*)\]", result.modules[0].text)
    pos = np.array(written.group(1).split(","), float)
    quat = np.array(written.group(2).split(","), float)
    data = ROBOT.model.createData()
    pin.framesForwardKinematics(ROBOT.model, data, q * np.pi / 180)
    M = data.oMf[ROBOT.flange_frame]
    assert np.abs(M.translation - pos).max() < 1e-3   # (mm)
    w = pin.Quaternion(M.rotation)
    assert min(np.abs(quat - [w.w, w.x, w.y, w.z]).max(),
               np.abs(quat + [w.w, w.x, w.y, w.z]).max()) < 1e-6


def test_a_jointtargets_row_says_nothing_of_a_cfx_change():
    """A MoveAbsJ to J5 ~ 0 (a public cell's home, its joints as written):
    the compensation turns J5 past 0, which a robtarget's cfx would say; a
    jointtarget has no confdata, so its row does not warn of one."""
    t = task(f"""MODULE A
    PROC main()
        MoveAbsJ [[6.47345E-07,-0.00132846,-0.000315338,-0.000474194,-0.00141919,0.00235598],
                  {EXT}], v100, fine, tool0;
        MoveAbsJ [[30,20,10,0,-0.0014,0],{EXT}], v100, fine, tool0;
    ENDPROC
ENDMODULE""")
    rows = fix(t, SOLVER, "auto").rows
    assert [r.status for r in rows] == ["compensated"] * 2
    assert not [w for r in rows for w in r.warnings if "cfx" in w]
    # A robtarget there (a review's): turned into MoveAbsJ (a MoveJ in
    # either mode), no confdata is written, and no cfx said.
    home = "[[501.0038,289.2547,467.7907],[0.482973133,-0.224142287,0.836510403,0.129412261]"
    t = task(f"""MODULE A
    CONST robtarget pH:={home},[0,-1,-1,1],{EXT}];
    PROC main()
        ConfJ\\On;
        MoveJ pH, v100, fine, tool0;
    ENDPROC
ENDMODULE""")
    for mode in ("absj", "auto"):
        (row,) = fix(t, SOLVER, mode).rows
        assert row.status == "compensated" and row.action.startswith("MoveJ -> MoveAbsJ")
        assert not [w for w in row.warnings if "cfx" in w], (mode, row.warnings)


def test_a_wrist_singular_move_kept_a_robtarget_move_says_why_not_which_option():
    """The refusal at the wrist names what keeps the move from MoveAbsJ,
    which would carry the split: the mode only where nothing else does
    (auto, a MoveL: --emit absj); where supervision is off from an unknown
    start or program displacement may be on, that, and no --emit hint
    (--emit absj was given)."""
    home = f"[[515,0,712],[0.707107,0,0.707107,0],[0,0,0,0],{EXT}]"

    def reason(before: str, mode: str) -> str:
        t = task(f"""MODULE A
    CONST robtarget pHome:={home};
    PROC main()
{before}        MoveL pHome, v100, fine, tool0;
    ENDPROC
ENDMODULE""")
        rows = [r for r in fix(t, SOLVER, mode).rows if r.instruction == "MoveL"]
        assert len(rows) == 1 and rows[0].status == "not compensated"
        assert "J4/J6 split a robtarget cannot carry" in rows[0].reason
        return rows[0].reason.split("itself)", 1)[1]
    assert reason("", "auto") == ": a MoveAbsJ can (--emit absj for a MoveL)"
    assert reason("", "robtarget") == ": a MoveAbsJ can (--emit absj)"
    off = reason("        ConfL\\Off;\n", "absj")
    # (main runs again: the move follows itself, from an unknown start.)
    assert off == (": a MoveAbsJ can, but not here: follows itself (its run before), whose "
                   "configuration is assumed: kept a robtarget move")
    disp = reason("        PDispOn \\ExeP:=pHome, pHome, tool0;\n", "absj")
    assert disp == (": a MoveAbsJ can, but not here: program displacement may be active here "
                    "(a MoveAbsJ would ignore it): kept a robtarget move")


def test_a_wrist_refusal_shared_by_moves_says_per_line_what_keeps_each():
    """One value read by moves kept robtarget moves for different reasons
    (one displaced, one not; a MoveC beside a MoveL): the refusal each row
    carries names the lines and what keeps each, and says nothing of
    MoveAbsJ for the MoveC."""
    home = f"[[515,0,712],[0.707107,0,0.707107,0],[0,0,0,0],{EXT}]"
    mid = f"[[515,60,700],[0.707107,0,0.707107,0],[0,0,0,0],{EXT}]"

    def reasons(body: str) -> dict:
        t = task(f"""MODULE A
    CONST robtarget pHome:={home};
    CONST robtarget pMid:={mid};
    PROC main()
{body}    ENDPROC
ENDMODULE""")
        return {r.line: r.reason.split("itself)", 1)[1] for r in fix(t, SOLVER, "auto").rows
                if r.target == "pHome" and r.status == "not compensated"}
    got = reasons("        MoveL pHome, v100, fine, tool0;\n        PDispOn \\ExeP:=pHome, "
                  "pHome, tool0;\n        MoveL pHome, v100, fine, tool0;\n"
                  "        PDispOff;\n")
    want = (": line 5: a MoveAbsJ can (--emit absj for a MoveL); line 7: a MoveAbsJ can, but "
            "not here: program displacement may be active here (a MoveAbsJ would ignore it): "
            "kept a robtarget move")
    assert got == {5: want, 7: want}
    got = reasons("        MoveC pMid, pHome, v100, fine, tool0;\n"
                  "        MoveL pHome, v100, fine, tool0;\n")
    assert got == {5: ": line 6: a MoveAbsJ can (--emit absj for a MoveL)",
                   6: ": line 6: a MoveAbsJ can (--emit absj for a MoveL)"}


def test_join_of_states_is_their_flags_and_last_moves_united():
    """State.join unites each flag set and the moves that may have run
    last (None: unknown wins); an equal state joins to the state itself."""
    import itertools
    from rapidcomp.compensate.flow import BOTH, OFF, ON, State
    flags = [frozenset((ON,)), frozenset((OFF,)), BOTH]
    lasts = [None, frozenset(), frozenset({(0, 1, "target", ())}),
             frozenset({(0, 1, "target", ()), (0, 2, "target", ())})]
    states = [State(a, b, c, d, e) for a, b, c, d, e in itertools.product(
        flags, flags[:2], flags[1:], flags[1:2], lasts)]
    for a, b in itertools.product(states, repeat=2):
        got = a.join(b)
        last = None if a.last is None or b.last is None else a.last | b.last
        assert got == State(a.confj | b.confj, a.confl | b.confl, a.pdisp | b.pdisp,
                            a.eoffs | b.eoffs, last)
        # An equal state, made anew: the state itself.
        twin = State(*(None if v is None else frozenset(v) for v in
                       (b.confj, b.confl, b.pdisp, b.eoffs, b.last)))
        assert b.join(twin) is b


def test_a_backward_handler_runs_under_a_displacement_only_where_one_may_be_on():
    """Stepping backwards may come at any point of the program: a BACKWARD
    handler's move runs with supervision and the position unknown, and
    under program displacement only where something may switch one on (a
    PDispOn, or a call not known statically); where nothing can, none is
    assumed there either, as the entry's note says. Its singular robtarget
    is then refused for what does keep it from MoveAbsJ (the position
    before it), not for a displacement no module can set."""
    home = f"[[515,0,712],[0.707107,0,0.707107,0],[0,0,0,0],{EXT}]"

    def reason(extra: str) -> str:
        t = task(f"""MODULE A
    CONST robtarget pHome:={home};
    PROC main()
        MoveJ pHome, v100, fine, tool0;
        routine1;{extra}
    ENDPROC
    PROC routine1()
        MoveAbsJ [[0,0,0,0,30,0],{EXT}], v100, fine, tool0;
    BACKWARD
        MoveL pHome, v100, fine, tool0;
    ENDPROC
ENDMODULE""")
        rows = [r for r in fix(t, SOLVER, "absj").rows if r.instruction == "MoveL"]
        assert len(rows) == 1 and rows[0].status == "not compensated"
        assert "J4/J6 split a robtarget cannot carry" in rows[0].reason
        return rows[0].reason.split("itself)", 1)[1]
    displaced = (": a MoveAbsJ can, but not here: program displacement may be active here (a "
                 "MoveAbsJ would ignore it): kept a robtarget move")
    none = reason("")
    assert "displacement" not in none
    assert none.startswith(": a MoveAbsJ can, but not here: ConfL\\Off and the robot's "
                           "position before this move is not known here")
    assert reason("\n        PDispOn \\ExeP:=pHome, pHome, tool0;\n        PDispOff;") == displaced
    assert reason("\n        %\"rout\" + \"ine2\"%;") == displaced


def test_of_as_many_uses_the_plain_one_keeps_the_declaration():
    """A target read plainly by one move and in Offs by another: two values
    of as many uses. The declaration is edited in place for the plain use
    (its name keeps the value it is read for) and the Offs use reads a copy
    named for the call, in whichever order the moves come."""
    for first, second in ((0, 1), (1, 0)):
        moves = ["MoveL p1, v100, fine, tool0;", "MoveL Offs(p1, 0, 0, 20), v100, fine, tool0;"]
        t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    PROC main()
        {moves[first]}
        {moves[second]}
    ENDPROC
ENDMODULE""")
        rows = rows_of(t, "robtarget")
        plain, offs = (rows[4], rows[5]) if first == 0 else (rows[5], rows[4])
        assert plain.action == "robtarget p1 rewritten in place"
        assert offs.action == "new robtarget p1_offs_c"
