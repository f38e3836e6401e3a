"""Edges of the flow analysis and of what counts as a run-time value: error
handlers and what they switch, labels, functions in expressions, TRAPs
calling what is not known, the external axis offset, FOR indices behind a
condition, --start only where the program starts, PERS shared with other
tasks, base frames of several robots. Each case is a small program whose
controller behaviour is stated in its test."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from rapidcomp.compensate.fix import fix
from rapidcomp.compensate.flow import PROGRAM_START, RESUME
from rapidcomp.compensate.plan import Plan, Task
from rapidcomp.rapid.parse import parse_text
from rapidcomp.rapid.task import tasks_of

from test_flow import EXT, P1, P1_BAD, SOLVER, rows_of, states, task
from test_tasks import TASKS, WARM, run

ON, OFF, BOTH = {"on"}, {"off"}, {"on", "off"}


def test_an_error_in_a_callee_reaches_the_callers_handler_with_the_callees_state():
    """Sub switches ConfL off and may fail (no handler of its own): main's
    handler then runs with ConfL off, though main itself never switches."""
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    PROC main()
        Sub;
        ConfL\\On;
        MoveL p1, v100, fine, tool0;
    ERROR
        MoveL p1, v100, fine, tool0;
    ENDPROC
    PROC Sub()
        ConfL\\Off;
        WaitTime 1;
    ENDPROC
ENDMODULE""")
    plan, st = states(t)
    assert st[(8, "to")].confl == BOTH
    assert st[(8, "to")].last == {RESUME}    # wherever the error stopped the robot


def test_retry_brings_what_the_handler_switches_into_every_statement():
    """The handler switches ConfL off and retries: the failed statement may
    be any of the body's, so every move may run with ConfL off; a handler
    that switches nothing changes nothing."""
    body = """    PROC main()
        MoveL p1, v100, fine, tool0;
        WaitDI di1, 1;
        MoveL p1, v100, fine, tool0;
    ERROR
        {handler}
        RETRY;
    ENDPROC"""
    for handler, want in (("ConfL\\Off;", BOTH), ("TPWrite \"again\";", ON)):
        t = task(f"""MODULE A
    CONST robtarget p1:={P1};
{body.format(handler=handler)}
ENDMODULE""")
        plan, st = states(t)
        assert st[(4, "to")].confl == want and st[(6, "to")].confl == want, handler
        # The robot resumes where it stopped: the moves keep their order.
        assert {plan.by_key[k].line for k in st[(6, "to")].last} == {4}
    # A switch later in the body does not reach back: the first move can
    # only be retried in the state it runs in (EXIT: no second cycle).
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    PROC main()
        MoveL p1, v100, fine, tool0;
        WaitDI di1, 1;
        ConfL\\Off;
        MoveL p1, v100, fine, tool0;
        EXIT;
    ERROR
        RETRY;
    ENDPROC
ENDMODULE""")
    plan, st = states(t)
    assert st[(4, "to")].confl == ON and st[(7, "to")].confl == OFF


def test_a_label_after_an_unconditional_goto_is_reached():
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    PROC main()
        GOTO later;
        MoveL p1, v100, fine, tool0;
        later:
        MoveL p1, v100, fine, tool0;
    ENDPROC
ENDMODULE""")
    plan, st = states(t)
    assert (5, "to") not in {(plan.by_key[k].line, k[2]) for k in plan.flow.before}
    # The label holds what the GOTO brings: supervision as at the start.
    assert st[(7, "to")].confl == ON and st[(7, "to")].pdisp == OFF


def test_a_goto_back_to_a_label_brings_its_state_around():
    """ConfL is on the first time round, off after the GOTO back: both at
    the label's move; nothing in the task switches displacement on, so the
    label invents none."""
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    VAR num n:=0;
    PROC main()
      again:
        MoveL p1, v100, fine, tool0;
        ConfL\\Off;
        IF n > 0 GOTO again;
        MoveL p1, v100, fine, tool0;
        EXIT;
    ENDPROC
ENDMODULE""")
    plan, st = states(t)
    assert st[(6, "to")].confl == BOTH and st[(6, "to")].pdisp == OFF
    assert {plan.by_key[k].line for k in st[(6, "to")].last if k != PROGRAM_START} == {6}
    assert st[(9, "to")].confl == OFF


def test_functions_called_in_expressions_are_followed():
    """A FUNC of the module that switches ConfL off, called in an IF
    condition: the move after it runs with ConfL off; a function no given
    module declares may do anything."""
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    PROC main()
        IF Ready() THEN
            MoveL p1, v100, fine, tool0;
        ENDIF
        IF VendorCheck(1) MoveL p1, v100, fine, tool0;
    ENDPROC
    FUNC bool Ready()
        ConfL\\Off;
        RETURN TRUE;
    ENDFUNC
ENDMODULE""")
    plan, st = states(t)
    assert st[(5, "to")].confl == OFF
    assert st[(7, "to")].confl == BOTH and st[(7, "to")].pdisp == BOTH
    assert "VendorCheck" in " ".join(plan.notes())


def test_a_trap_calling_an_unknown_routine_makes_everything_unknown():
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    VAR intnum ir;
    PROC main()
        CONNECT ir WITH tr;
        MoveL p1, v100, fine, tool0;
    ENDPROC
    TRAP tr
        VendorRecover;
    ENDTRAP
ENDMODULE""")
    plan, st = states(t)
    s = st[(6, "to")]
    assert s.confl == BOTH and s.confj == BOTH and s.pdisp == BOTH
    assert any("TRAP" in n for n in plan.notes())


def test_pdispoff_does_not_end_an_external_axis_offset_on_a_track():
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    PROC main()
        EOffsSet [100,0,0,0,0,0];
        PDispOff;
        MoveL p1, v100, fine, tool0;
        EOffsOff;
        MoveL p1, v100, fine, tool0;
    ENDPROC
ENDMODULE""")
    plan = Plan(t, track=((0, np.array([1.0, 0, 0])),))
    by_line = {u.line: u for u in plan.uses}
    assert plan.may_be_displaced(by_line[6]) and not plan.may_be_displaced(by_line[8])
    # Without a track the offset moves other axes: no displacement.
    plan = Plan(t)
    assert not plan.may_be_displaced(by_line[6])


def test_a_for_index_out_of_range_behind_a_condition_is_not_bad_input():
    """The condition keeps the move from ever reading p{4}: the program runs
    on the controller, so it is not refused; that use is untouched and the
    others are compensated. Without the condition the controller stops with
    ERR_INDEX: bad input (tested in test_real_programs)."""
    t = task(f"""MODULE A
    CONST robtarget p{{3}}:=[{P1},{P1},{P1}];
    CONST num N:=4;
    PROC main()
        FOR i FROM 1 TO N DO
            IF i <= 3 THEN
                MoveL p{{i}}, v100, fine, tool0;
            ENDIF
        ENDFOR
    ENDPROC
ENDMODULE""")
    rows = fix(t, SOLVER, "auto").rows
    status = sorted(r.status for r in rows)
    assert status == ["compensated"] * 3 + ["untouched"]
    (u,) = [r for r in rows if r.status == "untouched"]
    assert "index 4 of p is outside 1..3" in u.reason and "ERR_INDEX" in u.reason


def test_a_for_bound_may_be_a_const_of_the_routine():
    t = task(f"""MODULE A
    CONST robtarget p{{2}}:=[{P1},{P1}];
    PROC main()
        CONST num N:=2;
        FOR i FROM 1 TO N DO
            MoveL p{{i}}, v100, fine, tool0;
        ENDFOR
    ENDPROC
ENDMODULE""")
    plan = Plan(t)
    assert sorted(u.label for u in plan.uses) == ["p{i} [i=1]", "p{i} [i=2]"]
    assert all(u.reason is None for u in plan.uses)


def test_start_is_where_the_program_starts_not_after_an_unknown_call():
    """ConfL off, placeholder confdata, no jointtarget: the first move takes
    the solution closest to --start; a move after a call the flow cannot
    follow has no known position, and --start says nothing about it. (EXIT:
    the program ends, main does not start again from line 7.)"""
    t = task(f"""MODULE A
    PROC main()
        ConfL\\Off;
        MoveL {P1_BAD}, v100, fine, tool0;
        VendorProc;
        ConfL\\Off;
        MoveL {P1_BAD}, v100, fine, tool0;
        EXIT;
    ENDPROC
ENDMODULE""")
    rows = {r.line: r for r in fix(t, SOLVER, "auto", start=[40, 40, 25, 40, -70, -10]).rows}
    assert rows[4].status == "compensated" and rows[4].rule == "closest to --start (ConfL\\Off)"
    assert rows[7].status == "not compensated"
    assert "position before it is unknown" in rows[7].reason


def test_main_restarts_from_where_its_cycle_ends():
    """Continuous run: main's first move also runs after its last one."""
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    CONST robtarget p2:={P1};
    PROC main()
        MoveL p1, v100, fine, tool0;
        MoveL p2, v100, fine, tool0;
    ENDPROC
ENDMODULE""")
    plan, st = states(t)
    lines = {plan.by_key[k].line if k != PROGRAM_START else "start" for k in st[(5, "to")].last}
    assert lines == {"start", 6}


def test_a_use_the_flow_never_reaches_is_in_the_entry_state():
    """After RETURN: never runs. Nothing in the task switches displacement
    on, so it is not assumed to be displaced."""
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    PROC main()
        RETURN;
        MoveL p1, v100, fine, tool0;
    ENDPROC
ENDMODULE""")
    plan, st = states(t)
    assert st[(5, "to")].pdisp == OFF and st[(5, "to")].confl == BOTH


def test_function_arguments_may_be_written():
    """StrToVal fills its second argument; a FUNC with an INOUT parameter
    may change what it is given; a function no given module declares may
    too. A function's IN argument is not written."""
    t = task(f"""MODULE A
    VAR robtarget pA:={P1};
    VAR robtarget pB:={P1};
    VAR robtarget pC:={P1};
    VAR robtarget pD:={P1};
    VAR bool ok;
    PROC main()
        ok := StrToVal("[[0,0,0],[1,0,0,0],[0,0,0,0],{EXT}]", pA);
        ok := Nudge(pB);
        ok := VendorFn(pC);
        ok := Look(pD);
        MoveL pA, v100, fine, tool0;
        MoveL pB, v100, fine, tool0;
        MoveL pC, v100, fine, tool0;
        MoveL pD, v100, fine, tool0;
    ENDPROC
    FUNC bool Nudge(INOUT robtarget p)
        p.trans.x := p.trans.x + 1;
        RETURN TRUE;
    ENDFUNC
    FUNC bool Look(robtarget p)
        RETURN p.trans.x > 0;
    ENDFUNC
ENDMODULE""")
    rows = rows_of(t, "auto")
    assert rows[12].reason == "pA is filled by StrToVal at run time (M0.mod:8)"
    assert rows[13].reason == "pB is passed to Nudge, which may change it at run time (M0.mod:9)"
    assert rows[14].reason.startswith("pC is passed to function VendorFn, which no given module "
                                      "declares (it may change it)")
    assert rows[15].reason is None and rows[15].status == "compensated"


def test_a_pers_target_another_task_reads_is_not_edited_in_place(tmp_path):
    """PERS data are one object for all tasks: editing the declaration would
    change what the other task reads; the compensated value goes into a new
    declaration instead."""
    bk = tmp_path / "bk"
    shutil.copytree(TASKS / "backup_irbt", bk)
    track = bk / "RAPID" / "TASK1" / "PROGMOD" / "Track.mod"
    text = track.read_text().replace("CONST robtarget pSt1_2", "PERS robtarget pSt1_2")
    track.write_text(text)
    decl = next(line for line in text.splitlines() if "PERS robtarget pSt1_2" in line)
    comm = bk / "RAPID" / "TASK2" / "PROGMOD" / "Comm.mod"
    comm.write_text(comm.read_text().replace(
        "    VAR num nTick:=0;", f"    VAR num nTick:=0;\n{decl}\n    VAR num nX;").replace(
        "Incr nTick;", "Incr nTick;\n            nX := pSt1_2.trans.x;"))
    out = tmp_path / "out"
    r = run("fix", bk, "--profile", WARM, "--track", "a:x", "-o", out, "--emit", "robtarget")
    assert r.exit_code == 0, r.output
    written = (out / track.relative_to(bk)).read_text()
    assert decl in written                    # the shared declaration is as it was
    assert "MoveL pSt1_2_c," in written
    # Unshared, it is edited in place.
    comm.write_text(comm.read_text().replace("pSt1_2.trans.x", "0").replace(decl, ""))
    r = run("fix", bk, "--profile", WARM, "--track", "a:x", "-o", tmp_path / "o2", "--emit",
            "robtarget")
    written = (tmp_path / "o2" / track.relative_to(bk)).read_text()
    assert decl not in written and "MoveL pSt1_2," in written


# The task's group and the group's robot, as a RobotWare 6 MultiMove backup
# writes them: both in SYS.cfg (the controller's topic).
_GROUPS = ('#\nMECHANICAL_UNIT_GROUP:\n\n      -Name "rob1" -Robot "ROB_1" -MechanicalUnit_1 '
           '"TRACK_1"\\\n      -UseMotionPlanner "motion_planner_1"\n\n'
           '      -Name "rob2" -Robot "ROB_2" -UseMotionPlanner "motion_planner_2"\n')


@pytest.mark.parametrize("groups_in", ["SYS.cfg", "MOC.cfg"])
def test_backup_base_frame_follows_task_group_robot(tmp_path, groups_in):
    """Two robots with different base frames: each task's comes from its
    mechanical unit group's robot (the groups in SYS.cfg, as a controller
    writes them; in MOC.cfg read too); the identity is a real value too."""
    bk = tmp_path / "bk"
    shutil.copytree(TASKS / "backup_irbt", bk)
    sys_cfg = bk / "SYSPAR" / "SYS.cfg"
    sys_cfg.write_text(sys_cfg.read_text().replace('-UseMechanicalUnitGroup "rob1"',
                                                   '-UseMechanicalUnitGroup "rob2"')
                       + (_GROUPS if groups_in == "SYS.cfg" else ""))
    moc = ("MOC:CFG_1.0:6:0::\n" + (_GROUPS if groups_in == "MOC.cfg" else "") + "#\n"
           "ROBOT:\n\n      -name \"ROB_1\" -use_robot_type \"ROB1_140\" -base_frame_pos_x 1.5\n\n"
           "      -name \"ROB_2\" -use_robot_type \"ROB2_140\"\\\n"
           "      -base_frame_pos_x -0.25 -base_frame_orient_u0 0.707107"
           " -base_frame_orient_u3 0.707107\n")
    (bk / "SYSPAR" / "MOC.cfg").write_text(moc)
    (b,) = tasks_of(bk)
    assert b.base == ((-250.0, 0.0, 0.0), (0.707107, 0.0, 0.0, 0.707107))
    (bk / "SYSPAR" / "MOC.cfg").write_text(moc.replace(
        " -base_frame_pos_x -0.25 -base_frame_orient_u0 0.707107 -base_frame_orient_u3 0.707107",
        ""))
    (b,) = tasks_of(bk)
    assert b.base is None and b.base_problem is None      # ROB_2 sits at the world origin
    # Nothing links the task to a robot: refused unless --base says it.
    sys_cfg.write_text(sys_cfg.read_text().replace(' -UseMechanicalUnitGroup "rob2"', ""))
    (bk / "SYSPAR" / "MOC.cfg").write_text(moc)
    (b,) = tasks_of(bk)
    assert b.base_problem is not None and "--base" in b.base_problem
    r = run("check", bk, "--profile", WARM, "--track", "a:x")
    assert r.exit_code == 2 and "several robots with different base frames" in r.output
    r = run("check", bk, "--profile", WARM, "--track", "a:x", "--base", "0,0,0,1,0,0,0")
    assert r.exit_code == 0, r.output


def test_an_array_slot_no_move_reaches_may_hold_an_unusable_value():
    """p{3} is never used and holds a zero quaternion: its MoveAbsJ slot gets
    the calibration position instead of refusing the program."""
    zero = f"[[400,300,250],[0,0,0,0],[0,0,-1,1],{EXT}]"
    t = Task("t", (parse_text(f"""MODULE A
    CONST robtarget p{{3}}:=[{P1},{P1},{zero}];
    PROC main()
        FOR i FROM 1 TO 2 DO
            MoveJ p{{i}}, v100, fine, tool0;
        ENDFOR
    ENDPROC
ENDMODULE""", "M0.mod"),))
    res = fix(t, SOLVER, "auto")
    assert [r.status for r in res.rows] == ["compensated"] * 2
    text = res.modules[0].text
    assert "[[0,0,0,0,0,0]," in text.replace(" ", "")


def test_a_tool_the_routine_assigns_is_the_value_assigned_last_before_the_move():
    """RoboDK declares a default rdkTool and assigns the real tool (or its
    declared value again) at the top of its routine, before the moves, and
    again at a tool change. Each move is solved with the value its routine
    assigned last before it: the very output of the program that declares
    that value (the oracle), and the report says where. A move before the
    first assignment, one in another routine, and any move of data also
    assigned in a block run with a value not known here: left as written."""
    decl = "[TRUE,[[0,0,150],[1,0,0,0]],[2,[0,0,75],[1,0,0,0],0,0,0.005]]"
    same = "[TRUE,[[0.000,0.000,150.000],[1.0000,0,0,0]],[2.000,[0,0,75],[1,0,0,0],0,0,0.005]]"
    other = "[TRUE,[[0,0,120],[1,0,0,0]],[2,[0,0,75],[1,0,0,0],0,0,0.005]]"

    def run(body: str, tool: str = decl) -> tuple:
        result = fix(task(f"""MODULE A
    PERS tooldata rdkTool:={tool};
    PROC main()
{body}    ENDPROC
    PROC Other()
        MoveL {P2}, v100, fine, rdkTool;
    ENDPROC
ENDMODULE"""), SOLVER, "auto")
        lines = result.modules[0].text.splitlines()
        return ({r.line: (r.status, r.reason) for r in result.rows},
                [ln for ln in lines if "MoveL" in ln], result.notes)

    rows, moves, notes = run(f"""        MoveL {P1}, v100, fine, rdkTool;
        rdkTool := {same};
        MoveL {P1}, v100, fine, rdkTool;
        rdkTool := {other};
        MoveL {P1}, v100, fine, rdkTool;
        Other;
""")
    assert rows[4][0] == "untouched" and "rdkTool is assigned at run time (M0.mod:" in rows[4][1]
    assert rows[6] == rows[8] == ("compensated", None)
    assert rows[12][0] == "untouched"                     # (Other: not known here)
    assert ("assigned by the routine that moves with them: rdkTool (M0.mod lines 5, 7); each "
            "move there is solved with the value assigned last before it") in " ".join(notes)
    # The oracle: each value declared, nothing assigned.
    _, with_150, _ = run(f"        MoveL {P1}, v100, fine, rdkTool;\n")
    _, with_120, _ = run(f"        MoveL {P1}, v100, fine, rdkTool;\n", other)
    assert moves[1] == with_150[0] and moves[2] == with_120[0] and moves[1] != moves[2]
    # Also assigned in a block: which value a move runs with is not known.
    rows, _, _ = run(f"""        rdkTool := {other};
        MoveL {P1}, v100, fine, rdkTool;
        IF di1 = 1 THEN
            rdkTool := {same};
        ENDIF
""")
    assert rows[5][0] == "untouched" and "rdkTool is assigned at run time" in rows[5][1]
    # A GOTO may run the body out of order: not known either.
    rows, _, _ = run(f"""        rdkTool := {other};
    again:
        MoveL {P1}, v100, fine, rdkTool;
        rdkTool := {same};
        GOTO again;
""")
    assert rows[6][0] == "untouched" and "rdkTool is assigned at run time" in rows[6][1]
    # An error handler runs after an error anywhere, before an assignment too.
    rows, _, _ = run(f"""        rdkTool := {other};
        MoveL {P1}, v100, fine, rdkTool;
    ERROR
        MoveL {P1}, v100, fine, rdkTool;
        RETRY;
""")
    assert rows[5][0] == "compensated" and rows[7][0] == "untouched"
    # A call that may run the routine again (itself; a routine no given
    # module declares, which may call anything) may leave the other value:
    # the moves after it, up to the next assignment, are not known; after
    # that one they are. A routine an interrupt may run: none is known.
    rows, _, _ = run(f"""        rdkTool := {other};
        MoveL {P1}, v100, fine, rdkTool;
        IF nDepth < 1 THEN
            Incr nDepth;
            main;
        ENDIF
        MoveL {P1}, v100, fine, rdkTool;
        VendorProc;
        rdkTool := {same};
        MoveL {P1}, v100, fine, rdkTool;
        VendorProc;
        MoveL {P1}, v100, fine, rdkTool;
""")
    assert [rows[k][0] for k in (5, 10, 13, 15)] == ["compensated", "untouched", "compensated",
                                                      "untouched"]
    rows, _, _ = run(f"""        CONNECT irT WITH tr;
        ITimer 1, irT;
        rdkTool := {other};
        MoveL {P1}, v100, fine, rdkTool;
    ENDPROC
    TRAP tr
        main;
    ENDTRAP
    PROC Unused()
""")
    assert rows[7][0] == "untouched"


def test_a_move_after_one_not_compensated_says_so():
    """ConfL\\Off, no jointtarget, every confdata naming no solution: the
    first move cannot start (say --start); each one after it cannot follow
    the move before, which is not compensated: said so (it said "after a
    call, search or error", of a program with none)."""
    bad = "[[60.1,556,162.5],[0,0,1,0],[0,-1,-1,0],[9E9,9E9,9E9,9E9,9E9,9E9]]"
    t = task(f"""MODULE A
  PROC main()
    ConfL \\Off;
    MoveL {bad},v150,z20,tool0;
    MoveL {bad},v150,z20,tool0;
  ENDPROC
ENDMODULE
""")
    rows = rows_of(t, "robtarget")
    assert [r.status for r in rows.values()] == ["not compensated"] * 2
    assert rows[4].reason.endswith("(say where the robot starts with --start)")
    assert rows[5].reason.endswith("(the move before it, line 4, is not compensated: where the "
                                   "robot is after it is not known)")
    # The move before untouched (a VAR without a value): said so too.
    t = task(f"""MODULE A
  VAR robtarget pv;
  PROC main()
    ConfL \\Off;
    MoveL pv,v150,z20,tool0;
    MoveL {bad},v150,z20,tool0;
  ENDPROC
ENDMODULE
""")
    rows = rows_of(t, "robtarget")
    assert rows[6].reason.endswith("(the move before it, line 5, is untouched (its target is not "
                                   "known statically): where the robot is after it is not known)")


def test_a_circle_point_after_an_unknown_position_names_no_supervision():
    """A MoveC after a move that is not compensated, supervision never
    switched off: its circle point's rule and caution say circle point, not
    ConfL\\Off (which the program never wrote)."""
    t = task(f"""MODULE Circ
    CONST jointtarget jHome:=[[0,0,0,0,30,0],{EXT}];
    CONST robtarget pBad:=[[528.052,330.107,394.049],[0.109616,0.097797,0.948198,0.281675],[0,0,-1,1],{EXT}];
    CONST robtarget pCir:=[[501.340,363.638,388.294],[0.103144,0.074606,0.957319,0.259490],[0,0,0,0],{EXT}];
    CONST robtarget pEnd:=[[481.415,405.857,367.621],[0.063427,0.044437,0.972710,0.218716],[0,0,0,0],{EXT}];
    PROC main()
        MoveAbsJ jHome,v500,fine,tool0;
        MoveL pBad,v100,fine,tool0;
        MoveC pCir,pEnd,v50,z1,tool0;
    ENDPROC
ENDMODULE
""")
    cir = next(r for r in fix(t, SOLVER, "robtarget").rows if r.target == "pCir")
    assert cir.rule == "confdata; position before unknown (circle point)"
    assert not any("Off" in w for w in cir.warnings), cir.warnings


# ---------------------------------------------------------------- displacement set at run time

P2 = f"[[400,150,250],[0.707107,0,0.707107,0],[0,0,-1,1],{EXT}]"


def _statuses(body: str, decls: str = "") -> dict:
    """line -> (status, reason) of fix on a module with p1, p2 and body."""
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    CONST robtarget p2:={P2};
    CONST jointtarget jHome:=[[0,0,0,0,30,0],{EXT}];
{decls}    PROC main()
{body}    ENDPROC
ENDMODULE""")
    return {r.line: (r.status, r.reason) for r in fix(t, SOLVER, "auto").rows}


def test_a_displacement_read_where_the_robot_is_keeps_that_move_as_written():
    """PDispOn without \\ExeP takes the displacement from where the robot
    is: the move that put it there, compensated, would shift the
    displacement by its correction, so it is left as written; the
    displacement is then its programmed position's, as in the program, and
    the displaced move and a MoveAbsJ (never displaced) are compensated."""
    rows = _statuses("""        MoveJ p1, v500, fine, tool0;
        PDispOn p1, tool0;
        MoveL p2, v500, fine, tool0;
        MoveAbsJ jHome, v500, fine, tool0;
        PDispOff;
        MoveL p2, v500, fine, tool0;
""")
    assert rows[6][0] == "untouched" and rows[6][1].startswith(
        "a program displacement set at run time (M0.mod:7) may read where this move leaves "
        "the robot")
    assert rows[8][0] == rows[9][0] == rows[11][0] == "compensated"


def test_crobt_and_a_search_read_what_the_robot_measured():
    """\\ExeP:=CRobT() reads where the robot is, as a variable CRobT()
    filled does: the move before is left as written, and so is the move
    displaced. A fixed PDispOn after a measured one adds to it (PDispOn
    displacements add up): still measured. After a search, where the robot
    is comes from the search, not from a move the flow follows: the search's
    own target is compensated."""
    rows = _statuses("""        MoveAbsJ jHome, v500, fine, tool0;
        PDispOn \\ExeP:=CRobT(\\Tool:=tool0), p1, tool0;
        MoveL p2, v200, fine, tool0;
        PDispOff;
        MoveJ p1, v500, fine, tool0;
        pHere := CRobT(\\Tool:=tool0);
        PDispOn \\ExeP:=pHere, p1, tool0;
        MoveL p2, v200, fine, tool0;
        PDispOff;
""", "    VAR robtarget pHere;\n")
    assert [rows[k][0] for k in (7, 9, 11, 14)] == ["untouched"] * 4
    assert "(M0.mod:8: its \\ExeP CRobT(\\Tool:=tool0) is not a value" in rows[9][1]
    stacked = _statuses("""        MoveL p1, v500, fine, tool0;
        SearchL \\Stop, di1, pFound, p2, v50, tool0;
        PDispOn \\ExeP:=pFound, p2, tool0;
        PDispOn \\ExeP:=p2, p1, tool0;
        MoveL p1, v200, fine, tool0;
        PDispOff;
""", "    VAR robtarget pFound;\n")
    assert [stacked[k][0] for k in (7, 8, 11)] == ["compensated", "compensated", "untouched"]


def test_a_displacement_read_in_a_handler_may_read_any_move():
    """An error handler (or a TRAP) runs where an error (an interrupt)
    stopped the robot: a PDispOn without \\ExeP there may read where any
    move left it, so none is compensated. A TRAP that only switches
    displacement off leaves the others as they are."""
    rows = _statuses("""        MoveAbsJ jHome, v500, fine, tool0;
        nX := 1 / nZero;
        MoveL p2, v500, fine, tool0;
    ERROR
        PDispOn p1, tool0;
        MoveL p2, v500, fine, tool0;
        PDispOff;
        TRYNEXT;
""", "    VAR num nZero:=0;\n    VAR num nX;\n")
    assert {status for status, _ in rows.values()} == {"untouched"}
    assert "(M0.mod:12, in an interrupt routine or an error handler)" in rows[8][1]
    off = task(f"""MODULE A
    CONST robtarget p1:={P1};
    CONST robtarget p2:={P2};
    VAR robtarget pFound;
    VAR intnum ir1;
    PROC main()
        CONNECT ir1 WITH tReset;
        ISignalDI di1, 1, ir1;
        MoveL p1, v500, fine, tool0;
        SearchL \\Stop, di2, pFound, p2, v50, tool0;
        PDispOn \\ExeP:=pFound, p2, tool0;
        MoveL p1, v200, fine, tool0;
        PDispOff;
    ENDPROC
    TRAP tReset
        PDispOff;
    ENDTRAP
ENDMODULE""")
    got = {r.line: r.status for r in fix(off, SOLVER, "auto").rows}
    assert got == {9: "compensated", 10: "compensated", 12: "untouched"}


def test_a_frame_written_with_variables_is_set_at_run_time():
    rows = _statuses("""        MoveL p1, v500, fine, tool0;
        SearchL \\Stop, di1, pFound, p2, v50, tool0;
        dx := pFound.trans.x - p2.trans.x;
        PDispSet [[dx,0,0],[1,0,0,0]];
        MoveL p2, v200, fine, tool0;
        PDispOff;
        PDispSet [[0,0,5],[1,0,0,0]];
        MoveL p2, v200, fine, tool0;
        PDispOff;
""", "    VAR robtarget pFound;\n    VAR num dx;\n")
    assert rows[12][0] == "untouched" and "(M0.mod:11: PDispSet's frame is not a value" in \
        rows[12][1]
    assert rows[15][0] == "compensated"


def test_a_searched_exep_sets_the_displacement_at_run_time():
    """\\ExeP:= a search's result: the warm robot found the part with its
    own error, so the displaced move is left as written; the search's own
    targets and the moves outside the displacement are compensated. With
    \\ExeP and ProgPoint both fixed by the program (CONST, a PERS nothing
    assigns), the displacement is the program's: compensated, as before."""
    searched = _statuses("""        MoveL p1, v500, fine, tool0;
        SearchL \\Stop, di1, pFound, p2, v50, tool0;
        PDispOn \\ExeP:=pFound, p1, tool0;
        MoveL p2, v200, fine, tool0;
        PDispOff;
        MoveL p1, v500, fine, tool0;
""", "    VAR robtarget pFound;\n")
    assert searched[10][0] == "untouched"
    assert "(M0.mod:9: its \\ExeP pFound is not a value the program fixes)" in searched[10][1]
    assert [searched[k][0] for k in (7, 8, 12)] == ["compensated"] * 3
    fixed = _statuses("""        MoveL p1, v500, fine, tool0;
        PDispOn \\ExeP:=pTaught, p1, tool0;
        MoveL p2, v200, fine, tool0;
        PDispOff;
""", f"    PERS robtarget pTaught:={P2};\n")
    assert {k: s for k, (s, _) in fixed.items()} == {7: "compensated", 9: "compensated"}


def test_a_frame_or_exep_not_made_where_the_robot_is_reads_no_move():
    """A PDispSet frame (here from an analog input) or an \\ExeP from a
    search reads no move's position: the move just before it is compensated
    (only the displaced moves stay as written). Where the task calls
    CRobT() anywhere, the frame may have been made with it: that move is
    left as written, and the reason says so."""
    body = """        MoveL p1, v500, fine, tool0;
        SearchL \\Stop, di1, pFound, p2, v50, tool0;
        MoveL p1, v500, fine, tool0;
        PDispOn \\ExeP:=pFound, p2, tool0;
        MoveL p2, v200, fine, tool0;
        PDispOff;
        MoveL p2, v500, fine, tool0;
        fr.trans.x := AInput(aiCamX);
        PDispSet fr;
        MoveL p1, v200, fine, tool0;
        PDispOff;
"""
    decls = "    VAR robtarget pFound;\n    VAR pose fr;\n"
    rows = _statuses(body, decls)
    assert {k: s for k, (s, _) in rows.items()} == {
        8: "compensated", 9: "compensated", 10: "compensated", 12: "untouched",
        14: "compensated", 17: "untouched"}, rows
    crobt = _statuses(body + "        pHere := CRobT();\n",
                      decls + "    VAR robtarget pHere;\n")
    for line, at in ((11, "M0.mod:12"), (15, "M0.mod:17")):
        assert crobt[line][0] == "untouched", crobt
        assert crobt[line][1].startswith(
            f"a program displacement set at run time ({at}) may read where this move leaves "
            "the robot (PDispOn without \\ExeP does; a frame or \\ExeP made with CRobT(), "
            "CPos() or CJointT(), which a task calls, may)"), crobt[line][1]


def test_the_moves_a_position_read_measures_are_the_ones_before_it():
    """Where the task sets a displacement at run time from what CRobT()
    read, the move before the CRobT() is the one it measured (not only the
    move before the PDispSet): both are left as written, the first with
    where CRobT() reads. A CRobT() in a comment or a string reads nothing;
    another task's CRobT() (\\TaskName: it may read this robot) counts."""
    body = """        MoveL p1, v500, fine, tool0;
        pHere := CRobT();
        MoveL p2, v500, fine, tool0;
        fr := [pHere.trans, [1,0,0,0]];
        PDispSet fr;
        MoveL p2, v200, fine, tool0;
        PDispOff;
"""
    decls = "    VAR robtarget pHere;\n    VAR pose fr;\n"
    rows = _statuses(body, decls)
    assert {k: s for k, (s, _) in rows.items()} == {
        8: "untouched", 10: "untouched", 13: "untouched"}, rows
    assert rows[8][1].startswith("a program displacement set at run time (M0.mod:9, where "
                                 "CRobT() reads it) may read where this move leaves the robot")
    # (Read inside a move's own arguments: the same, though the move calls
    # no function but built-in ones.)
    inside = _statuses(body.replace("pHere := CRobT();",
                                    "MoveL Offs(CRobT(), 0, 0, 10), v500, fine, tool0;"), decls)
    assert inside[8][0] == "untouched" and inside[8][1].startswith(
        "a program displacement set at run time (M0.mod:9, where CRobT() reads it)"), inside
    quiet = body.replace("pHere := CRobT();", "pHere := pHere; ! not CRobT() any more")
    rows = _statuses(quiet.replace("tool0;\n        fr", "tool0;\n        TPWrite \"CRobT()\";"
                                   "\n        fr"), decls)
    assert {k: s for k, (s, _) in rows.items()} == {
        8: "compensated", 10: "compensated", 14: "untouched"}, rows
    # A PDispOn without \\ExeP reads where the robot is itself: a CRobT()
    # elsewhere is not what it reads (the move before it is compensated).
    itself = _statuses("""        MoveL p1, v500, fine, tool0;
        pHere := CRobT();
        MoveL p2, v500, fine, tool0;
        PDispOn p2, tool0;
        MoveL p1, v200, fine, tool0;
        PDispOff;
""", "    VAR robtarget pHere;\n")
    assert {k: s for k, (s, _) in itself.items()} == {
        7: "compensated", 9: "untouched", 11: "compensated"}, itself
    # A CRobT() in a TRAP may run after any move: no move is followed.
    trapped = _statuses("""        MoveL p1, v500, fine, tool0;
        MoveL p2, v500, fine, tool0;
        fr := [pHere.trans, [1,0,0,0]];
        PDispSet fr;
        MoveL p2, v200, fine, tool0;
        PDispOff;
""", decls + "    TRAP tHit\n        pHere := CRobT();\n    ENDTRAP\n")
    assert {k: s for k, (s, _) in trapped.items()} == {
        11: "untouched", 12: "untouched", 15: "untouched"}, trapped
    assert "(M0.mod:8, its CRobT() in an interrupt routine or an error handler) may read " \
        "where any move leaves the robot" in trapped[11][1]
    other = parse_text("MODULE T2\n    PERS robtarget pShared;\n    PROC main()\n        "
                       "pShared := CRobT(\\TaskName:=\"T_ROB1\");\n    ENDPROC\nENDMODULE\n",
                       "T2.mod")
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    CONST robtarget p2:={P2};
    PERS robtarget pShared;
    VAR pose fr;
    PROC main()
        MoveL p1, v500, fine, tool0;
        fr := [pShared.trans, [1,0,0,0]];
        PDispSet fr;
        MoveL p2, v200, fine, tool0;
        PDispOff;
    ENDPROC
ENDMODULE""")
    alone = {r.line: r.status for r in fix(t, SOLVER, "auto").rows}
    t = Task(t.name, t.files, observers=(other,))
    shared = {r.line: r.status for r in fix(t, SOLVER, "auto").rows}
    assert alone == {7: "compensated", 10: "untouched"}
    assert shared == {7: "untouched", 10: "untouched"}


def test_a_frame_set_at_run_time_reaches_the_routines_it_displaces():
    """PDispSet of a pose the program computes (DefFrame of points, here a
    variable assigned by a function no given module declares) may be
    measured: Work's move, reached both with and without it, is left as
    written; PDispSet of a CONST frame displaces by a known amount."""
    rows = _statuses("""        fr := MeasureTray();
        PDispSet fr;
        Work;
        PDispOff;
        Work;
        PDispSet frFixed;
        MoveL p1, v200, fine, tool0;
        PDispOff;
    ENDPROC
    PROC Work()
        MoveL p2, v200, fine, tool0;
""", "    VAR pose fr;\n    CONST pose frFixed:=[[0,0,5],[1,0,0,0]];\n")
    assert rows[18][0] == "untouched" and "PDispSet's frame is not a value" in rows[18][1]
    assert rows[14][0] == "compensated"


def test_ufmec_moves_only_a_movable_user_frame():
    """wobjdata's ufmec names the unit a movable user frame (ufprog FALSE)
    moves with; with ufprog TRUE the frame is fixed and ufmec unused: the
    move is compensated. ufprog FALSE: coordinated, left as written."""
    def status(ufprog: str) -> str:
        frame = "[[100,-500,200],[0.965925826,0,0,0.258819045]],[[0,0,0],[1,0,0,0]]"
        target = ("[[18.30127,-68.30127,100],[0.683012702,0.183012702,0.683012702,"
                  f"-0.183012702],[-2,0,2,0],{EXT}]")
        rows = _statuses("        MoveL pW, v200, fine, tProbe\\WObj:=wFix;\n",
                         f'    TASK PERS wobjdata wFix:=[FALSE,{ufprog},"STN1",{frame}];\n'
                         "    PERS tooldata tProbe:=[TRUE,[[0,0,150],[1,0,0,0]],[0.5,[0,0,60],"
                         "[1,0,0,0],0,0,0]];\n"
                         f"    CONST robtarget pW:={target};\n")
        (status, reason), = rows.values()
        return status if reason is None else f"{status}: {reason}"
    assert status("TRUE") == "compensated"
    assert status("FALSE") == "untouched: work object wFix is coordinated with a mechanical unit"


def test_a_target_in_a_record_is_left_as_written_not_refused():
    """A robtarget component of a record of the program's own type is a
    target the controller moves to: listed as untouched (exit 0), not
    refused; data of a type that is no target at all is refused."""
    record = ("    RECORD station\n        robtarget app;\n        num speed;\n    ENDRECORD\n"
              f"    CONST station st1:=[{P1},100];\n")
    rows = _statuses("        MoveJ st1.app, v500, fine, tool0;\n        MoveL p2, v500, fine, tool0;\n",
                     record)
    assert list(rows.values()) == [
        ("untouched", "the target is a component of st1, a station: rapidcomp compensates "
                      "robtarget and jointtarget data, not components of other data; left as "
                      "written"), ("compensated", None)]
    rows = _statuses("        MoveJ nSpeed, v500, fine, tool0;\n        MoveJ st1.speed, v500, fine, "
                     "tool0;\n", record + "    CONST num nSpeed:=1;\n")
    assert list(rows.values()) == [("not compensated", "nSpeed is a num, not a target"),
                                   ("not compensated", "st1.speed is a num, not a target")]


def test_a_target_in_an_array_of_records_is_left_as_written_not_refused():
    """As a record's: an element of an array of records (`sts{2}.app`, a
    public RobotStudio program's `Welds1{1}.position`), left as written;
    a component that is no target is still refused."""
    record = ("    RECORD station\n        robtarget app;\n        num speed;\n    ENDRECORD\n"
              f"    CONST station sts{{2}}:=[[{P1},100],[{P1},50]];\n")
    rows = _statuses("        MoveJ sts{2}.app, v500, fine, tool0;\n"
                     "        MoveJ sts{1}.speed, v500, fine, tool0;\n", record)
    assert list(rows.values()) == [
        ("untouched", "the target is a component of sts, a station: rapidcomp compensates "
                      "robtarget and jointtarget data, not components of other data; left as "
                      "written"), ("not compensated", "sts{1}.speed is a num, not a target")]


def test_the_displacement_warning_names_the_offset_where_a_track_carries_the_robot():
    """With a track, EOffsSet displaces the robot too: the row's warning
    names both kinds of displacement; without one, program displacement."""
    from rapidcomp.compensate.rows import displacement_warning
    on_track = P1.replace(EXT, "[0,9E+09,9E+09,9E+09,9E+09,9E+09]")
    t = task(f"""MODULE A
    CONST robtarget p1:={on_track};
    PROC main()
        EOffsSet [100,0,0,0,0,0];
        MoveL p1, v100, fine, tool0;
        EOffsOff;
    ENDPROC
ENDMODULE""")
    (row,) = fix(t, SOLVER, "auto", track=((0, np.array([1.0, 0, 0])),)).rows
    (said,) = [w for w in row.warnings if w.startswith("may run under")]
    assert said.startswith("may run under program displacement (PDispOn/PDispSet) or an "
                           "external axis offset (EOffsOn/EOffsSet): compensated for the "
                           "undisplaced pose")
    assert displacement_warning(0.31).startswith(
        "may run under program displacement (PDispOn/PDispSet): compensated")


def test_long_lists_of_lines_are_cut_with_the_count_left():
    from rapidcomp.compensate.plan import line_ranges
    assert line_ranges([1, 2, 3, 5, 7, 8]) == "1-3, 5, 7-8"
    # Eleven ranges are named whole; from twelve on, ten and the lines left.
    eleven = [10 * k for k in range(1, 12)]
    assert line_ranges(eleven) == ", ".join(str(x) for x in eleven)
    many = [10 * k for k in range(1, 12)] + [200, 201, 202]
    assert line_ranges(many) == ("10, 20, 30, 40, 50, 60, 70, 80, 90, 100 and 4 more lines")


def test_a_for_loop_to_dim_of_a_declared_array_walks_it():
    """Dim(pts, 1) of a declared array is its size, fixed where it is
    declared: the loop walks every element (the controller does the same);
    Dim of a routine's open-array parameter is the caller's: untouched."""
    rows = _statuses("""        FOR i FROM 1 TO Dim(pts, 1) DO
            MoveL pts{i}, v100, fine, tool0;
        ENDFOR
        Walk pts;
    ENDPROC
    PROC Walk(robtarget ps{*})
        FOR i FROM 1 TO Dim(ps, 1) DO
            MoveL ps{i}, v100, fine, tool0;
        ENDFOR
""", f"    CONST robtarget pts{{3}}:=[{P1},{P2},{P1}];\n")
    assert [status for status, _ in rows.values()] == ["compensated", "untouched"]
    plan = Plan(task(f"""MODULE A
    CONST robtarget pts{{3}}:=[{P1},{P2},{P1}];
    PROC Walk(robtarget ps{{*}})
        FOR i FROM 1 TO Dim(ps, 1) DO
            MoveL ps{{i}}, v100, fine, tool0;
        ENDFOR
    ENDPROC
ENDMODULE"""))
    (loop,) = plan.uses[0].motion.loops
    module = plan.task.files[0].modules[0]
    assert plan.resolver.loop_range(loop, module, "Walk") is None     # (the caller's size)
    fixed = fix(task(f"""MODULE A
    CONST robtarget pts{{3}}:=[{P1},{P2},{P1}];
    PROC main()
        FOR i FROM 1 TO Dim(pts, 1) DO
            MoveL pts{{i}}, v100, fine, tool0;
        ENDFOR
    ENDPROC
ENDMODULE"""), SOLVER, "auto")
    assert sorted(r.target for r in fixed.rows) == ["pts{i} [i=1]", "pts{i} [i=2]", "pts{i} [i=3]"]
    assert fixed.summary()["compensated"] == 3


def test_a_trap_that_stores_and_restores_the_path_switches_nothing():
    """RestoPath moves the robot back onto the interrupted path: a built-in
    the flow knows, not a call that may switch supervision or displacement.
    main's MoveJ is turned into MoveAbsJ, and no note says the TRAP
    switches anything."""
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    CONST robtarget pSafe:={P2};
    VAR intnum irStop;
    PROC main()
        CONNECT irStop WITH tStop;
        ISignalDI di1, 1, irStop;
        MoveJ p1, v500, fine, tool0;
    ENDPROC
    TRAP tStop
        StopMove;
        StorePath;
        MoveJ pSafe, v500, fine, tool0;
        RestoPath;
        StartMove;
    ENDTRAP
ENDMODULE""")
    result = fix(t, SOLVER, "auto")
    assert "MoveAbsJ jt_p1," in result.modules[0].text
    assert not any("(TRAP) switches" in n for n in result.notes)
    assert not any(w.startswith("may run under") for r in result.rows for w in r.warnings)


def test_the_absj_note_names_each_tool_once_and_a_local_variable_keeps_its_reason():
    """RAPID's names are one whatever their case: tGrip and TGRIP are one
    tool in the MoveAbsJ note; tool0 and wobj0 cannot change. A routine's
    own variable without a value says so, not that another routine's
    variable of its name is assigned."""
    t = task(f"""MODULE A
    CONST robtarget p1:={P1};
    CONST robtarget p2:={P2};
    PERS tooldata tGrip:=[TRUE,[[0,0,10],[1,0,0,0]],[0.5,[0,0,6],[1,0,0,0],0,0,0]];
    PROC main()
        MoveJ p1, v500, fine, tGrip;
        MoveJ p2, v500, fine, TGRIP;
        MoveJ p1, v500, fine, TOOL0 \\WObj:=WOBJ0;
    ENDPROC
ENDMODULE""")
    (note,) = [n for n in fix(t, SOLVER, "auto").notes if "turned into MoveAbsJ go to" in n]
    assert note.startswith("the moves turned into MoveAbsJ go to joints computed with tGrip as "
                           "the modules declare them")
    rows = _statuses("""        VAR robtarget pt;
        MoveL pt, v100, fine, tool0;
        Other;
    ENDPROC
    PROC Other()
        VAR robtarget pt;
        pt := CRobT();
""")
    assert list(rows.values()) == [("untouched", "pt has no literal value (declared without a "
                                                 "value)")]


def test_a_tool_the_routine_assigns_is_resolved_once_per_name(monkeypatch):
    """A RoboDK program's moves all name the tool its routine assigns: the
    assigned value is decoded once per assignment and name, not once per
    move (issue #14: 1e5 moves took 2.3 times as long, 1.6 times the
    memory)."""
    from rapidcomp.compensate import targets as T
    calls = []
    real = T.Resolver._tool

    def counted(self, *args, **kwargs):
        calls.append(args[0].name)
        return real(self, *args, **kwargs)
    monkeypatch.setattr(T.Resolver, "_tool", counted)
    tool = "[TRUE,[[0,0,150],[1,0,0,0]],[2,[0,0,75],[1,0,0,0],0,0,0]]"
    moves = "\n".join(f"        MoveL {P1}, v100, fine, rdkTool;" for _ in range(40))
    text = (f"MODULE M\n    PERS tooldata rdkTool:={tool};\n    PROC main()\n"
            f"        rdkTool := {tool};\n{moves}\n    ENDPROC\nENDMODULE\n")
    result = fix(Task("m.mod", (parse_text(text, "m.mod"),)), SOLVER, "auto")
    assert result.failed == 0 and len(result.rows) == 40
    # (Once by the plan's resolver, once by the verifying one.)
    assert 1 <= len(calls) <= 2, calls


def test_what_resolving_an_assigned_tool_noted_is_said_for_every_move():
    """A tool its routine assigns, resolved once (above), still gives each
    move's row what its resolution noted (a quaternion normalised): found
    by a review, only the first move's row said it."""
    tool = "[TRUE,[[0,0,150],[0.9,0,0,0]],[2,[0,0,75],[1,0,0,0],0,0,0]]"
    moves = "\n".join(f"        MoveL {P1}, v100, fine, rdkTool;" for _ in range(3))
    text = (f"MODULE M\n    PERS tooldata rdkTool:={tool};\n    PROC main()\n"
            f"        rdkTool := {tool};\n{moves}\n    ENDPROC\nENDMODULE\n")
    rows = fix(Task("m.mod", (parse_text(text, "m.mod"),)), SOLVER, "auto").rows
    assert [r.line for r in rows] == [5, 6, 7]
    assert all(any("quaternion norm 0.9" in w for w in r.warnings) for r in rows), [
        r.warnings for r in rows]


def test_data_assigned_at_run_time_names_each_assignment():
    """A work object whose frame the routine assigns a value known at run
    time only before each of three moves (a public example's
    `box.oframe := my_pose`): each move's reason names every assignment by
    its line, in text order, not one of them (which was the last, after the
    first two moves)."""
    rows = _statuses("""        wBox.oframe := myPose;
        MoveJ p1, v500, fine, tool0\\WObj:=wBox;
        wBox.oframe := myPose;
        MoveJ p1, v500, fine, tool0\\WObj:=wBox;
        wBox.oframe := myPose;
        MoveJ p1, v500, fine, tool0\\WObj:=wBox;
""", "    PERS wobjdata wBox:=[FALSE,TRUE,\"\",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\n"
         "    VAR pose myPose;\n")
    reasons = {line: why for line, (status, why) in rows.items() if status == "untouched"}
    assert sorted(reasons) == [9, 11, 13], rows
    assert all("wBox is assigned at run time (" in why and ":8, 10, 12)" in why
               for why in reasons.values()), reasons
