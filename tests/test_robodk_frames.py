"""Programs as RoboDK's ABB post writes them: the tool's and the work
object's frames assigned in the program before the moves that use them
(`rdkTool.tframe := [...]; rdkWObj.uframe := [...];`), their declared
values zero. Each move is compensated with the frames assigned last before
it, and the compensated program, run by the independent controller model
(controller.py) on the warm robot, lands every move where the input sends
the ideal one; where the frame a move uses is not known, the move is left
as written and the report says why."""

from __future__ import annotations

import re

import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner

from controller import fk
from rapidcomp.cli import main
from rapidcomp.kinematics.chain import Chain
from rapidcomp.kinematics.conf import confdata
from rapidcomp.kinematics.frames import DEG, matrix_to_quat_wxyz
from rapidcomp.kinematics.ik import Solver
from rapidcomp.rapid.parse import parse_file

from conftest import ROOT
from test_real_programs import NOMINAL, evaluate
from test_real_programs import rapidcomp as own_process


class _Run:
    def __init__(self, result):
        self.returncode = result.exit_code
        self.stdout = result.stdout
        self.stderr = result.stderr


def rapidcomp(*args, check=True):
    """The command line, run in this process (a few dozen runs: no Python
    started for each); the profile's path from the repository's root."""
    args = [str(ROOT / a) if a == "fixtures/warm.csv" else str(a) for a in args]
    r = _Run(CliRunner().invoke(main, args, catch_exceptions=False))
    if check:
        assert r.returncode == 0, r.stdout + r.stderr
    return r

EXT = "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]"
# Joints of the moves (deg): front workspace, away from the wrist singularity.
Q = np.array([[10, 20, 10, 30, -60, 20], [25, 30, 5, -20, -45, 40], [-15, 15, 20, 40, -70, -30],
              [5, 35, -10, 10, -50, 60], [-30, 25, 15, -35, -80, 10], [20, 10, 25, 15, -40, -50],
              [0, 30, 0, 25, -55, 35]], float)
TOOLS = {"T1": pin.SE3(pin.utils.rotate("y", 0.3), np.array([10.0, -5.0, 150.0])),
         "T2": pin.SE3(pin.utils.rotate("x", -0.2), np.array([0.0, 20.0, 180.0]))}
FRAMES = {"U1": pin.SE3(pin.utils.rotate("z", 0.5), np.array([300.0, -100.0, 50.0])),
          "U2": pin.SE3(pin.utils.rotate("z", -0.25), np.array([350.0, 80.0, 120.0]))}


def pose_text(M: pin.SE3) -> str:
    """A pose as the post writes one: [[x, y, z],[q1, q2, q3, q4]]."""
    w, x, y, z = matrix_to_quat_wxyz(M.rotation)
    t = M.translation
    return f"[[{t[0]:.3f}, {t[1]:.3f}, {t[2]:.3f}],[{w:.8f}, {x:.8f}, {y:.8f}, {z:.8f}]]"


def target(i: int, tool: str, frame: str) -> str:
    """The robtarget that puts the flange at the joints Q[i] with that tool
    in that user frame (wobj_M_target = uframe^-1 . base_M_flange . tframe),
    its confdata that of Q[i]."""
    q = Q[i] * DEG
    M = FRAMES[frame].inverse() * fk(NOMINAL, Q[i]) * TOOLS[tool]
    _, frames = Chain.from_robot(NOMINAL).joint_frames(q[None])
    conf = confdata(q[None], frames[:, 4], Solver(NOMINAL).geometry.phi)[0]
    return f"[{pose_text(M)[1:-1]},[{','.join(str(int(c)) for c in conf)}],{EXT}]"


def move(kind: str, i: int, tool: str, frame: str) -> str:
    return f"    {kind} {target(i, tool, frame)},rdkSpeed,z1,rdkTool,\\WObj:=rdkWObj;"


def program(body: list[str]) -> str:
    return "\n".join([
        "%%%", "  VERSION:1", "  LANGUAGE:ENGLISH", "%%%", "", "MODULE MOD_Prog1", "",
        "  LOCAL PERS tooldata rdkTool := [TRUE,[[0,0,0],[1,0,0,0]],[2,[0,0,15],[1,0,0,0],0,0,"
        "0.005]];",
        "  LOCAL PERS wobjdata rdkWObj := [FALSE, TRUE, \"\", [[0,0,0],[1,0,0,0]],"
        "[[0,0,0],[1,0,0,0]]];",
        "  VAR speeddata rdkSpeed := [250,500,5000,1000]; ! set default speed", "",
        "  PROC Prog1()", "    ConfJ \\On;", "    ConfL \\Off;", *body, "  ENDPROC",
        "ENDMODULE", ""])


def tframe(tool: str) -> str:
    return f"    rdkTool.tframe := {pose_text(TOOLS[tool])};"


def uframe(frame: str) -> str:
    return f"    rdkWObj.uframe := {pose_text(FRAMES[frame])};"


BODY = [tframe("T1"), uframe("U1"), "    rdkSpeed := [500.00,500,5000,1000];",
        f"    MoveAbsJ [[{','.join(f'{a:.6f}' for a in Q[0])}],{EXT}],rdkSpeed,z1,rdkTool,"
        "\\WObj:=rdkWObj;",
        move("MoveJ", 1, "T1", "U1"), move("MoveL", 2, "T1", "U1"),
        uframe("U2"), move("MoveL", 3, "T1", "U2"), move("MoveL", 4, "T1", "U2"),
        tframe("T2"), move("MoveL", 5, "T2", "U2"), move("MoveJ", 6, "T2", "U2"),
        "    WaitTime 1.000;"]
FIRST_LINE = 15            # (of the routine's body, in program())


@pytest.mark.parametrize("mode", ["auto", "robtarget"])
def test_frames_assigned_before_the_moves_are_the_ones_each_move_is_compensated_with(
        mode, tmp_path):
    src = tmp_path / "MOD_Prog1.mod"
    src.write_text(program(BODY))
    out = tmp_path / "out.mod"
    r = rapidcomp("fix", src, "--profile", "fixtures/warm.csv", "-o", out, "--emit", mode)
    assert "7 of 7 target uses compensated" in r.stdout, r.stdout
    lines = [FIRST_LINE + k for k, b in enumerate(BODY) if "frame :=" in b]
    assert ("assigned by the routine that moves with them: rdkTool.tframe (MOD_Prog1.mod lines "
            f"{lines[0]}, {lines[3]}); rdkWObj.uframe (MOD_Prog1.mod lines {lines[1]}, "
            f"{lines[2]})") in r.stdout, r.stdout
    inp = [parse_file(src, src.name)]
    rows = evaluate(inp, [parse_file(out, src.name)], entry="Prog1")
    assert len(rows) == 7
    # The input asks for the flange where the joints Q put it: through the
    # frames assigned before each move, not the declared ones.
    for (x, _, _, _), q in zip(rows, Q):
        want = fk(NOMINAL, q)
        got = x.pose if x.pose is not None else fk(NOMINAL, x.q_deg)
        assert np.linalg.norm(got.translation - want.translation) < 1e-2
    if mode == "robtarget":
        # (Nothing but the moves' numbers changed: the assignments as they
        # were.)
        before, after = src.read_text().splitlines(), out.read_text().splitlines()
        assert [a for a, b in zip(before, after) if a != b] == [
            line for line in before if line.lstrip().startswith(("MoveAbsJ", "MoveJ", "MoveL"))]


WHOLE_T1 = f"    rdkTool := [TRUE,{pose_text(TOOLS['T1'])},[2,[0,0,15],[1,0,0,0],0,0,0.005]];"


@pytest.mark.parametrize("case", ["before the first", "after a whole value later",
                                  "in a block",
                                  "a call between the frame's assignments",
                                  "a call later in the move's loop",
                                  "a call in the error handler"])
def test_a_move_whose_frame_is_not_known_is_left_as_written(case, tmp_path):
    body = {
        # (Run again, the routine starts with the frames of its last run.)
        "before the first": ([move("MoveL", 1, "T1", "U1"), tframe("T1"), uframe("U1"),
                              move("MoveL", 2, "T1", "U1")]),
        # (The whole value assigned after the first move: on a second run it
        # is the one that move starts with; the second move takes it.)
        "after a whole value later": ([tframe("T1"), uframe("U1"), move("MoveL", 1, "T1", "U1"),
                                       WHOLE_T1, move("MoveL", 2, "T1", "U1")]),
        "in a block": (["    IF TRUE THEN", tframe("T1"), "    ENDIF", uframe("U1"),
                        move("MoveL", 1, "T1", "U1"), move("MoveL", 2, "T1", "U1")]),
        # A call that may run the routine again (no given module declares
        # UserProc) after the first assignment the frame is made of: between
        # two of them; later in the loop, before the move's next round; in
        # the error handler, before RETRY runs the move again.
        "a call between the frame's assignments": (
            [uframe("U1"), "    UserProc;", "    rdkWObj.oframe := [[0, 0, 0],[1, 0, 0, 0]];",
             tframe("T1"), move("MoveL", 1, "T1", "U1"), move("MoveL", 2, "T1", "U1")]),
        "a call later in the move's loop": (
            [tframe("T1"), uframe("U1"), "    FOR i FROM 1 TO 2 DO",
             move("MoveL", 1, "T1", "U1"), "      UserProc;", "    ENDFOR",
             move("MoveL", 2, "T1", "U1")]),
        "a call in the error handler": (
            [tframe("T1"), uframe("U1"), move("MoveL", 1, "T1", "U1"),
             move("MoveL", 2, "T1", "U1"), "  ERROR", "    UserRecover;", "    RETRY;"]),
    }[case]
    src = tmp_path / "MOD_Prog1.mod"
    src.write_text(program(body))
    out = tmp_path / "out.mod"
    r = rapidcomp("fix", src, "--profile", "fixtures/warm.csv", "-o", out, "--emit", "robtarget",
                  "--allow-partial", check=False)
    assert r.returncode == 0, r.stdout + r.stderr
    before, after = src.read_text().splitlines(), out.read_text().splitlines()
    moved = [a for a, b in zip(before, after) if a != b]
    if case in ("before the first", "after a whole value later"):
        assert "1 untouched" in r.stdout and moved == [body[-1]], r.stdout
    else:
        assert "2 untouched" in r.stdout and moved == [], r.stdout
    # (Said with assignments of the data not known, by line: the tool's,
    # or where only the work object's frame is not, its.)
    name = "rdkWObj" if case == "a call between the frame's assignments" else "rdkTool"
    writes = [FIRST_LINE + k for k, b in enumerate(body) if b.lstrip().startswith(name)]
    m = re.search(rf"{name} is assigned at run time \(MOD_Prog1.mod:([\d, ]+)\)", r.stdout)
    assert m is not None, r.stdout
    named = [int(x) for x in m.group(1).split(", ")]
    assert named and set(named) <= set(writes), r.stdout


def test_a_component_of_the_load_is_no_frame(tmp_path):
    """rdkTool.tload.mass assigned between the frames and the moves (was:
    not followed, both moves left as written): a tool's load is no frame,
    the moves are compensated with the frames assigned before them (the
    output's poses those the joints Q give through them)."""
    body = [tframe("T1"), uframe("U1"), "    rdkTool.tload.mass := 3;",
            move("MoveL", 1, "T1", "U1"), move("MoveL", 2, "T1", "U1")]
    src = tmp_path / "MOD_Prog1.mod"
    src.write_text(program(body))
    out = tmp_path / "out.mod"
    r = rapidcomp("fix", src, "--profile", "fixtures/warm.csv", "-o", out, "--emit", "robtarget")
    assert "2 of 2 target uses compensated" in r.stdout, r.stdout
    before, after = src.read_text().splitlines(), out.read_text().splitlines()
    assert [a for a, b in zip(before, after) if a != b] == body[-2:]
    rows = evaluate([parse_file(src, src.name)], [parse_file(out, src.name)], entry="Prog1")
    for (x, _, _, _), q in zip(rows, Q[1:3]):
        want = fk(NOMINAL, q)
        got = x.pose if x.pose is not None else fk(NOMINAL, x.q_deg)
        assert np.linalg.norm(got.translation - want.translation) < 1e-2


def test_a_declared_frame_is_said_where_it_is_declared(tmp_path):
    """The routine assigns the user frame; the object frame is the
    declared one, in the task's data module: a message about it names that
    module and line, not the assignment's."""
    task = tmp_path / "cell"
    task.mkdir()
    (task / "Data.mod").write_text("\n".join([
        "MODULE Data", "  PERS tooldata rdkTool := [TRUE,[[0,0,0],[1,0,0,0]],[2,[0,0,15],"
        "[1,0,0,0],0,0,0.005]];",
        "  PERS wobjdata rdkWObj := [FALSE, TRUE, \"\", [[0,0,0],[1,0,0,0]],"
        "[[0,0,200000],[1,0,0,0]]];", "ENDMODULE", ""]))
    (task / "Main.mod").write_text("\n".join([
        "MODULE Main", "  VAR speeddata rdkSpeed := [250,500,5000,1000];", "  PROC main()",
        tframe("T1"), uframe("U1"), move("MoveL", 1, "T1", "U1"), "  ENDPROC", "ENDMODULE",
        ""]))
    r = rapidcomp("fix", task, "--profile", "fixtures/warm.csv", "-o", tmp_path / "out",
                  check=False)
    assert r.returncode == 2, r.stdout + r.stderr
    assert "Data.mod:3:" in r.stderr and "200000" in r.stderr, r.stderr


# ---------------------------------------------------------------- several programs

def module(name: str, routines: dict[str, list[str]], data: bool = True) -> str:
    """A module as the post writes a main program and the programs it
    calls: each PROC its own frames' assignments before its moves."""
    lines = ["MODULE " + name, ""]
    if data:
        lines += [
            "  PERS tooldata rdkTool := [TRUE,[[0,0,0],[1,0,0,0]],[2,[0,0,15],[1,0,0,0],0,0,"
            "0.005]];",
            "  PERS wobjdata rdkWObj := [FALSE, TRUE, \"\", [[0,0,0],[1,0,0,0]],"
            "[[0,0,0],[1,0,0,0]]];",
            "  VAR speeddata rdkSpeed := [250,500,5000,1000];", ""]
    for routine, body in routines.items():
        lines += [f"  PROC {routine}()", *body, "  ENDPROC", ""]
    return "\n".join(lines + ["ENDMODULE", ""])


def whole_tool(tool: str) -> str:
    return f"    rdkTool := [TRUE,{pose_text(TOOLS[tool])},[2,[0,0,15],[1,0,0,0],0,0,0.005]];"


def whole_wobj(frame: str) -> str:
    return f"    rdkWObj := [FALSE, TRUE, \"\", {pose_text(FRAMES[frame])},[[0,0,0],[1,0,0,0]]];"


# RoboDK's main program and the programs it calls, each assigning its frames
# before its moves; main's move after the calls is left as written (the
# fixture rapid/robodk_programs.mod, and its golden case).
PROGRAMS = {
    "Main": [tframe("T1"), uframe("U1"), move("MoveL", 0, "T1", "U1"),
             move("MoveJ", 1, "T1", "U1"), "    Prog2;", "    Prog3;",
             move("MoveL", 2, "T1", "U1")],
    "Prog2": [tframe("T2"), uframe("U2"), move("MoveL", 3, "T2", "U2"),
              move("MoveL", 4, "T2", "U2")],
    "Prog3": [tframe("T1"), uframe("U2"), move("MoveJ", 5, "T1", "U2"),
              move("MoveL", 6, "T1", "U2")]}


def fixed_and_run(tmp_path, routines: dict, entry: str, n: int, *options) -> tuple:
    """The module of these routines fixed: every one of its n target uses
    compensated, and both run on the controller model from entry (the
    stdout, the rows evaluate() checked)."""
    src = tmp_path / "MOD_Main.mod"
    src.write_text(module("MOD_Main", routines))
    out = tmp_path / "out.mod"
    r = rapidcomp("fix", src, "--profile", "fixtures/warm.csv", "-o", out, *options)
    assert f"{n} of {n} target uses compensated" in r.stdout, r.stdout
    rows = evaluate([parse_file(src, src.name)], [parse_file(out, src.name)], entry=entry)
    assert len(rows) == n
    return r.stdout, rows


@pytest.mark.parametrize("mode", ["auto", "robtarget"])
@pytest.mark.parametrize("style", ["frames", "whole values"])
def test_each_program_is_compensated_with_the_frames_it_assigns_itself(mode, style, tmp_path):
    """RoboDK's main program and the programs it calls each assign rdkTool
    and rdkWObj before their own moves (their frames, or whole values): each
    move is compensated with its own routine's, checked on the controller
    model running the whole program."""
    tool, wobj = (tframe, uframe) if style == "frames" else (whole_tool, whole_wobj)
    stdout, rows = fixed_and_run(tmp_path, {
        "Main": [tool("T1"), wobj("U1"), move("MoveL", 0, "T1", "U1"),
                 move("MoveJ", 1, "T1", "U1"), "    Prog2;", "    Prog3;"],
        "Prog2": [tool("T2"), wobj("U2"), move("MoveL", 3, "T2", "U2"),
                  move("MoveL", 4, "T2", "U2")],
        "Prog3": [tool("T1"), wobj("U2"), move("MoveJ", 5, "T1", "U2"),
                  move("MoveL", 6, "T1", "U2")]}, "Main", 6, "--emit", mode)
    assert "assigned by the routines: " in stdout, stdout
    for (x, _, _, _), q in zip(rows, np.delete(Q, 2, axis=0)):
        want = fk(NOMINAL, q)
        got = x.pose if x.pose is not None else fk(NOMINAL, x.q_deg)
        assert np.linalg.norm(got.translation - want.translation) < 1e-2


TRAP = "  VAR intnum irq;\n  TRAP OnSignal\n    Prog2;\n  ENDTRAP\n\n  PROC Main()"
# case -> (routines, text replaced in the module, Main's moves (Q rows) left
# as written, how many moves are, what the report says of them).
CROSS = {
    # (Outer runs Prog2, which assigns them: Main's moves after either call
    # take Prog2's frames.)
    "a call of a program that calls one that assigns them": (
        {"Main": [tframe("T1"), uframe("U1"), move("MoveL", 0, "T1", "U1"), "    Outer;",
                  move("MoveL", 1, "T1", "U1"), "    Prog2;", move("MoveL", 2, "T1", "U1")],
         "Outer": ["    WaitTime 0.1;", "    Prog2;"],
         "Prog2": [tframe("T2"), uframe("U2"), move("MoveL", 3, "T2", "U2")]},
        None, (1, 2), 2, "the call at line 11 may assign it again before this move"),
    "an interrupt routine that calls one": (
        {"Main": ["    CONNECT irq WITH OnSignal;", tframe("T1"), uframe("U1"),
                  move("MoveL", 0, "T1", "U1")],
         "Prog2": [tframe("T2"), uframe("U2"), move("MoveL", 3, "T2", "U2")]},
        ("  PROC Main()", TRAP), (0,), 2, "by a routine an interrupt may run"),
    # (Its arguments are evaluated before the move moves: Zn's tool.)
    "a function in the move's own arguments": (
        {"Main": [tframe("T1"), uframe("U1"), move("MoveL", 0, "T1", "U1"),
                  move("MoveL", 1, "T1", "U1").replace(",z1,", ",Zn(),")],
         "Prog2": [tframe("T2"), uframe("U2"), move("MoveL", 3, "T2", "U2")]},
        ("  PROC Prog2()", "  FUNC zonedata Zn()\n    Prog2;\n    RETURN z1;\n  ENDFUNC\n\n"
         "  PROC Prog2()"), (1,), 1, "the call at line 11 may assign it again before this move"),
    # (Prog2 moves the object frame; Main assigns the user frame only: the
    # object frame is Prog2's where it ran before, else the declared one.)
    "another routine assigns a frame this one does not": (
        {"Main": ["    Prog2;", tframe("T1"), uframe("U1"), move("MoveL", 0, "T1", "U1")],
         "Prog2": [tframe("T2"), uframe("U2"), "    rdkWObj.oframe := [[0,0,37],[1,0,0,0]];",
                   move("MoveL", 3, "T2", "U2")]},
        None, (0,), 1, "another routine assigns rdkWObj.oframe (MOD_Main.mod:17)"),
    # (Nothing calls SetT2 and it moves with nothing: run from the
    # FlexPendant, or as an event routine, while the program is stopped.)
    "a service routine that assigns them": (
        {"Main": [tframe("T1"), uframe("U1"), move("MoveL", 0, "T1", "U1")],
         "SetT2": [tframe("T2")]},
        None, (0,), 1, "by SetT2 (MOD_Main.mod:14), which no given routine calls"),
    # (Something calls SetT2, but only ToolChange, which main does not run.)
    "a routine only a service routine runs": (
        {"Main": [tframe("T1"), uframe("U1"), move("MoveL", 0, "T1", "U1")],
         "ToolChange": ["    SetT2;"], "SetT2": [tframe("T2")]},
        None, (0,), 1, "by SetT2 (MOD_Main.mod:18), which ToolChange (MOD_Main.mod:13) runs"),
    # (Main runs SetT2 too, after its own move; ToolChange may run it at
    # any stop.)
    "a routine main runs that a service routine runs too": (
        {"Main": [tframe("T1"), uframe("U1"), move("MoveL", 0, "T1", "U1"), "    SetT2;"],
         "ToolChange": ["    SetT2;"], "SetT2": [tframe("T2")]},
        None, (0,), 1, "by SetT2 (MOD_Main.mod:19), which ToolChange (MOD_Main.mod:14) runs"),
    # (ToolChange calls itself: it is entered from outside all the same.)
    "a service routine that calls itself": (
        {"Main": [tframe("T1"), uframe("U1"), move("MoveL", 0, "T1", "U1")],
         "ToolChange": [tframe("T2"), "    IF FALSE ToolChange;"]},
        None, (0,), 1, "by ToolChange (MOD_Main.mod:14), which no given routine calls"),
    # (One routine assigns them, twice; TestProg runs it, at a stop it may
    # leave T2 for the move after the first assignment.)
    "one routine that assigns them twice, which a service routine runs": (
        {"Main": ["    Prog1;"],
         "Prog1": [tframe("T1"), uframe("U1"), move("MoveL", 0, "T1", "U1"), tframe("T2"),
                   move("MoveL", 3, "T2", "U1")],
         "TestProg": ["    Prog1;"]},
        None, (0,), 2, "by Prog1 (MOD_Main.mod:15), which TestProg (MOD_Main.mod:19) runs"),
    # (Svc may run any routine: Prog2 too.)
    "a service routine that makes a late-bound call": (
        {"Main": [tframe("T1"), uframe("U1"), move("MoveL", 0, "T1", "U1"), "    Prog2;"],
         "Prog2": [tframe("T2"), uframe("U2"), move("MoveL", 3, "T2", "U2")],
         "Svc": ['    CallByVar "Prog", 2;']},
        None, (0,), 2, "may run any routine (a late-bound call"),
    # (No main: the program is Prog1, the routine nothing calls that moves
    # with them; ToolChange moves with tool0 only, and may run at any stop.)
    "without a main, a routine that moves with another tool only": (
        {"Prog1": [tframe("T1"), uframe("U1"), move("MoveL", 0, "T1", "U1")],
         "ToolChange": [f"    MoveAbsJ [[0,0,0,0,30,0],{EXT}],v100,fine,tool0;", tframe("T2")]},
        None, (0,), 1, "by ToolChange (MOD_Main.mod:15), which no given routine calls"),
    # (A MoveLSync runs the procedure it names at its point: the moves after
    # it take Prog2's frames; so may the MoveLSync's own, zone or not.)
    "a procedure a MoveLSync runs": (
        {"Main": [tframe("T1"), uframe("U1"), move("MoveL", 0, "T1", "U1"),
                  move("MoveLSync", 1, "T1", "U1")[:-1] + ",\"Prog2\";",
                  move("MoveL", 2, "T1", "U1")],
         "Prog2": [tframe("T2"), uframe("U2"), move("MoveL", 3, "T2", "U2")]},
        None, (2,), 2, "the call at line 11 may assign it again before this move"),
}


@pytest.mark.parametrize("case", list(CROSS))
def test_a_move_whose_frames_another_routine_may_change_is_left_as_written(case, tmp_path):
    """Between a routine's assignments and its move, a call that may run
    another routine assigning the same data (through others, in the move's
    own arguments too) changes the value; an interrupt may run one
    anywhere, and so may a routine nothing calls that moves with none of it
    (a service or event routine): then no move of the data is followed;
    another routine that assigns a frame this one does not leaves that
    frame unknown. The report says which of these it is."""
    routines, replaced, kept, n, said = CROSS[case]
    text = module("MOD_Main", routines)
    if replaced is not None:
        text = text.replace(*replaced)
    src = tmp_path / "MOD_Main.mod"
    src.write_text(text)
    r = rapidcomp("fix", src, "--profile", "fixtures/warm.csv", "-o", tmp_path / "out.mod",
                  "--allow-partial", check=False)
    assert r.returncode == 0, r.stdout + r.stderr
    assert f"{n} untouched" in r.stdout and said in r.stdout, r.stdout
    after = (tmp_path / "out.mod").read_text()
    lines = [b for body in routines.values() for b in body if b.lstrip().startswith("Move")]
    for k in kept:
        line = next(b for b in lines if b == move("MoveL", k, "T1", "U1")
                    or b == move("MoveL", k, "T1", "U1").replace(",z1,", ",Zn(),"))
        assert line in after


def test_a_tool_load_another_routine_assigns_changes_no_target(tmp_path):
    """Another routine assigns the tool's load only (rdkTool.tload): the
    moves of a routine that assigns its frame are followed all the same."""
    fixed_and_run(tmp_path, {
        "Main": ["    Prog2;", tframe("T1"), uframe("U1"), move("MoveL", 0, "T1", "U1")],
        "Prog2": ["    rdkTool.tload := [3,[0,0,20],[1,0,0,0],0,0,0];", tframe("T2"),
                  uframe("U2"), move("MoveL", 3, "T2", "U2")]}, "Main", 2)


def test_routines_of_two_modules_keep_their_own_values(tmp_path):
    """Two modules of a task, alike to the character up to their routines'
    assignments (at the same offsets), assign different tools there and
    move to one declared target: each move with its own routine's tool."""
    task = tmp_path / "cell"
    task.mkdir()
    # (The flange at the joints Q[2] through the tool T1; through T2 close by.)
    q = Q[2] * DEG
    _, frames = Chain.from_robot(NOMINAL).joint_frames(q[None])
    conf = confdata(q[None], frames[:, 4], Solver(NOMINAL).geometry.phi)[0]
    pose = pose_text(fk(NOMINAL, Q[2]) * TOOLS["T1"])
    (task / "Data.mod").write_text("\n".join([
        "MODULE Data",
        "  PERS tooldata rdkTool := [TRUE,[[0,0,0],[1,0,0,0]],[2,[0,0,15],[1,0,0,0],0,0,"
        "0.005]];",
        "  PERS wobjdata rdkWObj := [FALSE, TRUE, \"\", [[0,0,0],[1,0,0,0]],"
        "[[0,0,0],[1,0,0,0]]];",
        "  VAR speeddata rdkSpeed := [250,500,5000,1000];",
        f"  CONST robtarget pShared := [{pose[1:-1]},[{','.join(str(int(c)) for c in conf)}],"
        f"{EXT}];",
        "  PROC main()", "    ProgA;", "    ProgB;", "  ENDPROC", "ENDMODULE", ""]))
    for name, tool in (("A", "T1"), ("B", "T2")):
        (task / f"Mod{name}.mod").write_text(module(f"Mod{name}", {f"Prog{name}": [
            tframe(tool),
            "    MoveL pShared,rdkSpeed,z1,rdkTool,\\WObj:=rdkWObj;"]}, data=False))
    out = tmp_path / "out"
    r = rapidcomp("fix", task, "--profile", "fixtures/warm.csv", "-o", out, "--emit",
                  "robtarget")
    assert "2 of 2 target uses compensated" in r.stdout, r.stdout
    names = ["Data.mod", "ModA.mod", "ModB.mod"]
    inp = [parse_file(task / n, n) for n in names]
    rows = evaluate(inp, [parse_file(out / n, n) for n in names])
    assert len(rows) == 2


@pytest.mark.parametrize("other", ["writes nothing of it", "assigns its frame"])
def test_another_task_of_a_backup_only_changes_what_it_writes(other, tmp_path):
    """A backup's other task that never writes rdkTool leaves each program's
    frames followed; one that assigns its frame (PERS data are shared
    between tasks) may change it at any moment: its moves are left as
    written."""
    root = tmp_path / "backup"
    for path, text in {
        "BACKINFO/backinfo.txt": ">>SYSTEM_ID:\nCELL\n\n>>TASK1: (T_ROB1,,)\n"
                                 "PROGMOD/MOD_Main.mod\n\n>>TASK2: (T_COMM,,)\n"
                                 "PROGMOD/Comm.mod\n\n>>EOF:\n",
        "SYSPAR/SYS.cfg": "SYS:CFG_1.0:6:0::\n#\nCAB_TASKS:\n\n      -Name \"T_ROB1\" -Type "
                          "\"NORMAL\" -MotionTask\n\n      -Name \"T_COMM\" -Type \"SEMISTATIC\"\n",
        "RAPID/TASK1/PROGMOD/MOD_Main.mod": module("MOD_Main", {
            "main": [tframe("T1"), uframe("U1"), move("MoveL", 0, "T1", "U1"), "    Prog2;"],
            "Prog2": [tframe("T2"), uframe("U2"), move("MoveL", 3, "T2", "U2")]}),
        "RAPID/TASK2/PROGMOD/Comm.mod": module("Comm", {"main": (
            ["    WaitTime 1;"] if other == "writes nothing of it" else [tframe("T2")])}),
    }.items():
        (root / path).parent.mkdir(parents=True, exist_ok=True)
        (root / path).write_text(text)
    r = rapidcomp("fix", root, "--profile", "fixtures/warm.csv", "-o", tmp_path / "out",
                  "--allow-partial", check=False)
    assert r.returncode == 0, r.stdout + r.stderr
    assert ("2 of 2 target uses compensated" if other == "writes nothing of it"
            else "0 of 2 target uses compensated") in r.stdout, r.stdout
    if other != "writes nothing of it":
        # (Said by the other task's write, not this task's own.)
        assert "in another task at run time (RAPID/TASK2/PROGMOD/Comm.mod:" in r.stdout, \
            r.stdout


def test_local_data_of_one_name_in_two_modules_is_followed_apart(tmp_path):
    """Each program's module declares its own LOCAL PERS rdkTool (as
    RoboDK's post does); one program assigns it whole, the other only its
    frame: two data, each followed on its own (not one name whose whole
    value another routine assigns), checked on the controller model, which
    keeps a module's LOCAL data apart."""
    task = tmp_path / "cell"
    task.mkdir()
    local = ("  LOCAL PERS tooldata rdkTool := [TRUE,[[0,0,0],[1,0,0,0]],[2,[0,0,15],"
             "[1,0,0,0],0,0,0.005]];\n  LOCAL PERS wobjdata rdkWObj := [FALSE, TRUE, \"\", "
             "[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\n  VAR speeddata rdkSpeed := "
             "[250,500,5000,1000];\n")
    (task / "Main.mod").write_text(module("Main", {"main": ["    ProgA;", "    ProgB;"]},
                                          data=False))
    (task / "ModA.mod").write_text(module("ModA", {"ProgA": [
        whole_tool("T1"), whole_wobj("U1"), move("MoveL", 0, "T1", "U1")]},
        data=False).replace("MODULE ModA\n", "MODULE ModA\n" + local))
    (task / "ModB.mod").write_text(module("ModB", {"ProgB": [
        tframe("T2"), uframe("U2"), move("MoveL", 3, "T2", "U2")]},
        data=False).replace("MODULE ModB\n", "MODULE ModB\n" + local.replace(
            "VAR speeddata rdkSpeed", "LOCAL VAR speeddata rdkSpeed")))
    out = tmp_path / "out"
    r = rapidcomp("fix", task, "--profile", "fixtures/warm.csv", "-o", out)
    assert "2 of 2 target uses compensated" in r.stdout, r.stdout
    names = ["Main.mod", "ModA.mod", "ModB.mod"]
    rows = evaluate([parse_file(task / n, n) for n in names],
                    [parse_file(out / n, n) for n in names])
    assert len(rows) == 2


def test_without_a_main_a_routine_that_runs_the_programs_is_their_entry(tmp_path):
    """No main: Run, which nothing calls and which moves with nothing
    itself, runs the programs that do; each assigns its own frames: all
    followed (Run is the program's entry, not a service routine)."""
    fixed_and_run(tmp_path, {
        "Run": ["    Prog1;", "    Prog2;"],
        "Prog1": [tframe("T1"), uframe("U1"), move("MoveL", 0, "T1", "U1")],
        "Prog2": [tframe("T2"), uframe("U2"), move("MoveL", 3, "T2", "U2")]}, "Run", 2)


def test_a_local_routine_of_one_name_in_two_modules_is_called_or_not_on_its_own(tmp_path):
    """ModA's main calls ModA's LOCAL Setup; ModB's LOCAL Setup, which
    assigns the tool, nothing calls (a call resolves to the calling
    module's own routine first): a service routine, so no move of the tool
    is followed."""
    task = tmp_path / "cell"
    task.mkdir()
    (task / "ModA.mod").write_text(module("ModA", {
        "main": ["    Setup;", tframe("T1"), uframe("U1"), move("MoveL", 0, "T1", "U1")]}
    ).replace("  PROC main()", "  LOCAL PROC Setup()\n    WaitTime 0.1;\n  ENDPROC\n\n"
              "  PROC main()"))
    (task / "ModB.mod").write_text(module("ModB", {"Setup": [tframe("T2")]}, data=False)
                                   .replace("  PROC Setup()", "  LOCAL PROC Setup()"))
    r = rapidcomp("fix", task, "--profile", "fixtures/warm.csv", "-o", tmp_path / "out",
                  "--allow-partial", check=False)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "1 untouched" in r.stdout and "by Setup (ModB.mod:4)" in r.stdout, r.stdout


def test_a_routine_run_at_a_stop_that_can_only_assign_the_same_value_changes_nothing(
        tmp_path):
    """TestProg runs Prog1 too, but every assignment of the frames gives the
    same value: run at a stop, it assigns it again. The moves are followed
    (left as written, had it assigned another)."""
    fixed_and_run(tmp_path, {
        "Main": ["    Prog1;"],
        "Prog1": [tframe("T1"), uframe("U1"), move("MoveL", 0, "T1", "U1"),
                  move("MoveJ", 1, "T1", "U1")],
        "TestProg": ["    Prog1;"]}, "Main", 2)


def test_the_reason_names_the_first_service_routine_in_the_text(tmp_path):
    """Several routines nothing calls assign the tool: the reason names the
    first of them as the text has them, the same on every run."""
    src = tmp_path / "MOD_Main.mod"
    src.write_text(module("MOD_Main", {
        "Main": [tframe("T1"), uframe("U1"), move("MoveL", 0, "T1", "U1")],
        **{f"Svc{k}": [tframe("T2")] for k in (3, 1, 2)}}))
    # (Each run a process of its own: the order of a set of ids is not the
    # same from one process to the next.)
    # (Each into a folder of its own: a run's output is not the last's.)
    outs = {own_process("fix", src, "--profile", "fixtures/warm.csv", "-o",
                        tmp_path / f"{k}" / "o.mod", "--allow-partial").stdout.replace(
                            str(tmp_path / f"{k}"), "") for k in range(3)}
    (out,) = outs
    assert "by Svc3 (MOD_Main.mod:14), which no given routine calls" in out, out


def backup(tmp_path, sys_cfg: str, routines: dict[str, list[str]]):
    """A controller backup of one motion task, T_ROB1, holding one module
    of these routines, with this SYSPAR/SYS.cfg."""
    root = tmp_path / "backup"
    for path, text in {
        "BACKINFO/backinfo.txt": ">>SYSTEM_ID:\nCELL\n\n>>TASK1: (T_ROB1,,)\n"
                                 "PROGMOD/MOD_Main.mod\n\n>>EOF:\n",
        "SYSPAR/SYS.cfg": sys_cfg,
        "RAPID/TASK1/PROGMOD/MOD_Main.mod": module("MOD_Main", routines),
    }.items():
        (root / path).parent.mkdir(parents=True, exist_ok=True)
        (root / path).write_text(text)
    return root


# How a backup's SYSPAR/SYS.cfg names an event routine (the Controller
# topic's Event Routine type, CAB_EXEC_HOOKS), and whether it is this task's.
EVENTS = {
    "none": ("", False),
    "this task": ('-Routine "ResetTool" -Shelf "RESTART" -Task "T_ROB1"', True),
    "all tasks": ('-Routine "ResetTool" -Shelf "POWER_ON" -Task "T_ROB2" -AllTask', True),
    "all motion tasks": ('-Routine "ResetTool" -Shelf "START" -Task "T_ROB2" -AllMotionTask', True),
    "continued line": ('-Routine "ResetTool" -Shelf "STOP" \\\n          -Task "T_ROB1"', True),
    "another task": ('-Routine "ResetTool" -Shelf "RESTART" -Task "T_ROB2"', False),
}


@pytest.mark.parametrize("event", EVENTS)
def test_an_event_routine_of_sys_cfg_that_assigns_the_tool(event, tmp_path):
    """main calls ResetTool, which assigns the tool, then assigns its own
    and moves: followed, unless SYSPAR/SYS.cfg also runs ResetTool at an
    event of this task (CAB_EXEC_HOOKS, e.g. RESTART): then it may run
    between any two statements, and the moves are left as written with that
    reason. The section may come twice (a file merged from several): the
    hook is in the second."""
    hook, counts = EVENTS[event]
    cfg = ("SYS:CFG_1.0:6:0::\n#\nCAB_EXEC_HOOKS:\n\n      -Routine \"Other\" -Shelf "
           "\"POWER_ON\" -Task \"T_ROB1\"\n#\nCAB_TASKS:\n\n      -Name \"T_ROB1\" -Type "
           "\"NORMAL\" -MotionTask\n")
    if hook:
        cfg += f"#\nCAB_EXEC_HOOKS:\n\n      {hook}\n"
    root = backup(tmp_path, cfg, {
        "main": ["    ResetTool;", tframe("T1"), uframe("U1"), move("MoveL", 0, "T1", "U1")],
        "ResetTool": [tframe("T2")]})
    r = rapidcomp("fix", root, "--profile", "fixtures/warm.csv", "-o", tmp_path / "out",
                  "--allow-partial")
    if counts:
        assert "1 untouched" in r.stdout and "which is an event routine" in r.stdout, r.stdout
    else:
        assert "1 of 1 target uses compensated" in r.stdout, r.stdout


@pytest.mark.parametrize("entry", [None, "Start"])
def test_the_entry_routine_a_backup_names(entry, tmp_path):
    """SYS.cfg's CAB_TASKS -Entry names the routine the program starts at.
    Start is it: walked from the program's start (no "entered from
    outside" note for it), and Prog2, which nothing calls and which assigns
    another tool, is then a routine an operator may run at a stop: no move
    with the tool is followed. Without -Entry there is no main: Start and
    Prog2 are each a program of their own, each move compensated with its
    own routine's tool."""
    cfg = ("SYS:CFG_1.0:6:0::\n#\nCAB_TASKS:\n\n      -Name \"T_ROB1\" -Type \"NORMAL\" "
           "-MotionTask" + (f' -Entry "{entry}"' if entry else "") + "\n")
    root = backup(tmp_path, cfg, {
        "Start": [tframe("T1"), uframe("U1"), move("MoveL", 0, "T1", "U1")],
        "Prog2": [tframe("T2"), uframe("U1"), move("MoveL", 1, "T2", "U1")]})
    r = rapidcomp("fix", root, "--profile", "fixtures/warm.csv", "-o", tmp_path / "out",
                  "--allow-partial")
    outside = "entered from outside what was given"
    if entry:
        assert "0 of 2 target uses compensated" in r.stdout, r.stdout
        assert "by Prog2 (RAPID/TASK1/PROGMOD/MOD_Main.mod:" in r.stdout, r.stdout
        assert "(Start, or where" in r.stdout, r.stdout
        note = next(line for line in r.stdout.splitlines() if outside in line)
        assert note.rstrip().endswith(": Prog2") or "Prog2;" in note, note
        assert "Start" not in note.split(outside)[1].split(";")[0], note
    else:
        assert "2 of 2 target uses compensated" in r.stdout, r.stdout
        assert "Prog2, Start" in r.stdout or "Start, Prog2" in r.stdout, r.stdout


def test_local_mains_that_move_with_nothing_are_still_the_entries(tmp_path):
    """Two LOCAL mains, neither moving with the tool: they are the entries
    all the same (not the routines nothing calls that do move with it,
    which is the rule without any main), so Prog2, which nothing calls
    and which assigns another tool, may run at a stop: nothing followed."""
    task = tmp_path / "cell"
    task.mkdir()
    (task / "ModA.mod").write_text(module("ModA", {
        "main": ['    TPWrite "A";'],
        "Prog1": [tframe("T1"), uframe("U1"), move("MoveL", 0, "T1", "U1")],
        "Prog2": [tframe("T2"), uframe("U2"), move("MoveL", 3, "T2", "U2")]}
    ).replace("  PROC main()", "  LOCAL PROC main()"))
    (task / "ModB.mod").write_text(module("ModB", {"main": ['    TPWrite "B";']}, data=False)
                                   .replace("  PROC main()", "  LOCAL PROC main()"))
    r = rapidcomp("fix", task, "--profile", "fixtures/warm.csv", "-o", tmp_path / "out",
                  "--allow-partial")
    assert "0 of 2 target uses compensated" in r.stdout, r.stdout
    assert "which no given routine calls" in r.stdout, r.stdout


class _Forget(dict):
    """A memo that keeps nothing: each lookup made afresh."""

    def get(self, key, default=None):
        return default

    def __setitem__(self, key, value):
        pass


def _plain(v):
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, tuple):
        return (type(v).__name__,) + tuple(_plain(x) for x in v)
    return v


def test_the_frames_each_move_takes_remembered_by_where_it_lies_are_those_found_for_it():
    """A RoboDK program's 1e5 moves take the tool and work object a few
    assignments before them make: remembered per move line's tail by where
    the move lies among its routine's assignments and the calls that may
    run it again (Resolver._tool_wobj, _site_chain), they are what the
    resolver finds for each move alone, with nothing remembered: before the
    first assignment, between and after them, after a whole value, after a
    call that may assign them again, in a loop and in an error handler, in
    two routines."""
    from rapidcomp.compensate.plan import Plan, Task
    from rapidcomp.rapid import ast as A
    from rapidcomp.rapid.parse import parse_text
    m = [move("MoveL", i % 7, "T1", "U1") for i in range(8)]
    body = [m[0], tframe("T1"), m[1], uframe("U1"), m[2], m[3], uframe("U2"), m[4],
            WHOLE_T1, m[5], "    UserProc;", m[6], tframe("T2"), "    FOR i FROM 1 TO 2 DO",
            m[7], "      UserProc;", "    ENDFOR", m[1], "  ERROR", m[2], "    RETRY;"]
    other = ["  PROC Prog2()", tframe("T2"), uframe("U1"), m[3], m[4], "    Prog1;", m[5],
             "  ENDPROC"]
    texts = [program(body).replace("ENDMODULE", "\n".join(other) + "\nENDMODULE"),
             # (Two moves alike but for the loop the second is in, whose
             # call may assign the frames again before its next round.)
             program([tframe("T1"), uframe("U2"), m[6], "    FOR i FROM 1 TO 2 DO", m[6],
                      "      UserProc;", "    ENDFOR"]),
             # (A routine's own rdkTool, and the module's in the routine
             # after it: the data each name means, found per routine.)
             program([tframe("T1"), uframe("U1"), m[0], m[1]]).replace("ENDMODULE", "\n".join([
                 "  PROC Prog2()",
                 "    VAR tooldata rdkTool := [TRUE,[[0,0,0],[1,0,0,0]],[2,[0,0,15],[1,0,0,0],0,0,"
                 "0.005]];", tframe("T2"), m[2], m[3], "  ENDPROC", "ENDMODULE"]))]
    tails = 0
    got, want, ends = [], [], []
    for text in texts:
        task = Task("MOD_Prog1.mod", (parse_text(text, "MOD_Prog1.mod"),))
        fast, slow = Plan(task), Plan(task)
        r = slow.resolver
        r._chains = r._tail_sites = r._tails = r._pairs = r._data_ids = _Forget()
        module = task.files[0].modules[0]
        for motion in module.motions:
            if not motion.spec.moves_arm or motion.spec.joint_space:
                continue
            tails += type(motion.args) is A.TailArgs
            got.append(_plain(fast.resolver._tool_wobj(motion, module)))
            want.append(_plain(r._tool_wobj_of(motion, module)))
        ends.append(len(got))
    assert got == want
    assert tails >= 10
    # (Known and not known both, the loop's move too: the test covers each.)
    assert {t[0] for _, t, _ in got} >= {"tuple", "Unresolved"}
    assert [t[0] for _, t, _ in got[ends[1] - 2:ends[1]]] == ["tuple", "Unresolved"]
    # (The routine's own tool, and the module's: both known, not the same.)
    assert got[ends[2] - 1][1][0] == "tuple" and got[ends[2] - 1][1] != got[ends[1] + 1][1]
