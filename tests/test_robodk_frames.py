"""Programs as RoboDK's ABB post writes them: the tool's and the work
object's frames assigned in the program before the moves that use them
(`rdkTool.tframe := [...]; rdkWObj.uframe := [...];`), their declared
values zero. Each move is compensated with the frames assigned last before
it, and the compensated program, run by the independent controller model
(controller.py) on the warm robot, lands every move where the input sends
the ideal one; where the frame a move uses is not known, the move is left
as written and the report says why."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from controller import fk
from rapidcomp.kinematics.chain import Chain
from rapidcomp.kinematics.conf import confdata
from rapidcomp.kinematics.frames import DEG, matrix_to_quat_wxyz
from rapidcomp.kinematics.ik import Solver
from rapidcomp.rapid.parse import parse_file

from test_real_programs import NOMINAL, evaluate, rapidcomp

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
                                  "in a block", "a component of the load",
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
        # (A component of the load, assigned by a nested name: not followed.)
        "a component of the load": ([tframe("T1"), uframe("U1"), "    rdkTool.tload.mass := 3;",
                                     move("MoveL", 1, "T1", "U1"),
                                     move("MoveL", 2, "T1", "U1")]),
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
    # (Said with one of the assignments of the data not known: the tool's,
    # or where only the work object's frame is not, its.)
    name = "rdkWObj" if case == "a call between the frame's assignments" else "rdkTool"
    writes = [FIRST_LINE + k for k, b in enumerate(body) if b.lstrip().startswith(name)]
    assert any(f"{name} is assigned at run time (MOD_Prog1.mod:{n})" in r.stdout
               for n in writes), r.stdout


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
