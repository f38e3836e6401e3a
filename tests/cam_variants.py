"""CAM-like RAPID modules whose runs of moves are broken in every way a
real program breaks them, for the tests of the CAM-scale paths (issue #14):
each path must give what the general one gives on these.

Targets are reachable by construction: random joints of the nominal IRB 140
put through its forward kinematics and a 150 mm tool, written with the
confdata of those joints (in a few number spellings).
"""

from __future__ import annotations

import random

import numpy as np

from rapidcomp.kinematics.chain import Chain
from rapidcomp.kinematics.conf import confdata
from rapidcomp.kinematics.frames import DEG, matrix_to_quat_wxyz
from rapidcomp.kinematics.ik import Solver
from rapidcomp.kinematics.robot import irb140

HEAD = ["  PERS tooldata tSpindle:=[TRUE,[[0,0,150],[1,0,0,0]],[2,[0,0,75],[1,0,0,0],0,0,0]];",
        "  PERS wobjdata wPart:=[FALSE,TRUE,\"\",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];"]
TAIL = ",v100,z1,tSpindle\\WObj:=wPart;"
EXT = "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]"


def targets(n: int, seed: int) -> list[tuple]:
    """(tcp position, quaternion w,x,y,z, confdata, joints deg) of n targets."""
    robot = irb140()
    chain = Chain.from_robot(robot)
    rng = np.random.default_rng(seed)
    sign = rng.choice([-1.0, 1.0], size=(n, 3))
    q = np.stack([sign[:, 0] * rng.uniform(5, 40, n), rng.uniform(0, 45, n),
                  rng.uniform(-20, 35, n), sign[:, 1] * rng.uniform(5, 60, n),
                  rng.uniform(-100, -25, n), sign[:, 2] * rng.uniform(5, 85, n)], axis=1)
    R, p = chain.fk(q * DEG)
    _, frames = chain.joint_frames(q * DEG)
    conf = confdata(q * DEG, frames[:, 4], Solver(robot).geometry.phi)
    tcp = p + R[:, :, 2] * 150.0
    return [(tcp[i], matrix_to_quat_wxyz(R[i]), conf[i], q[i]) for i in range(n)]


def robtarget(t, style: int = 0) -> str:
    p, qw, c, _ = t
    cs = ",".join(str(int(x)) for x in c)
    if style == 1:        # blanks after the commas (RobotStudio)
        return (f"[[{p[0]:.3f}, {p[1]:.3f}, {p[2]:.3f}], [{qw[0]:.6f}, {qw[1]:.6f}, "
                f"{qw[2]:.6f}, {qw[3]:.6f}], [{cs.replace(',', ', ')}], "
                f"{EXT.replace(',', ', ')}]")
    if style == 2:        # fewer decimals, lower-case exponents
        return (f"[[{p[0]:.2f},{p[1]:.2f},{p[2]:.2f}],[{qw[0]:.5f},{qw[1]:.5f},{qw[2]:.5f},"
                f"{qw[3]:.5f}],[{cs}],[9e9,9e9,9e9,9e9,9e9,9e9]]")
    return (f"[[{p[0]:.3f},{p[1]:.3f},{p[2]:.3f}],[{qw[0]:.6f},{qw[1]:.6f},{qw[2]:.6f},"
            f"{qw[3]:.6f}],[{cs}],{EXT}]")


def jointtarget(t) -> str:
    return "[[" + ",".join(f"{v:.4f}" for v in t[3]) + "]," + EXT + "]"


def broken_runs(seed: int) -> str:
    """Declared and inline moves in runs broken by comments, blank lines,
    other arguments, supervision switched, a wait, an IF, a label, two
    moves on a line, letter case, \\Conc; a LOCAL target; entered from main."""
    T = targets(260, seed)
    rnd = random.Random(seed)
    lines = [f"MODULE Runs{seed}"] + HEAD
    for i in range(100):
        lines.append(f"  CONST robtarget p{i}:={robtarget(T[i], rnd.choice([0, 0, 0, 1, 2]))};")
        if i % 37 == 5:
            lines.append("  ! a comment between declarations")
        if i % 41 == 7:
            lines.append("")
    lines += ["  LOCAL CONST robtarget pl:=" + robtarget(T[100]) + ";",
              "  PROC main()", "    Path;", "  ENDPROC", "  PROC Path()",
              "    MoveAbsJ " + jointtarget(T[101]) + "\\NoEOffs,v1000,fine,tSpindle;"]
    tails = [",v200,z1,tSpindle\\WObj:=wPart;", ",v100,fine,tSpindle\\WObj:=wPart;",
             ",v100,z1,tSpindle;", " ,v100,z1,tSpindle\\WObj:=wPart;",
             ",v100,z1,tSpindle\\WObj:=wPart; ! c", "\\Conc,v100,z1,tSpindle\\WObj:=wPart;"]
    for i in range(100):
        r = rnd.random()
        if r < 0.03:
            lines.append("    ! comment")
        elif r < 0.05:
            lines.append("")
        elif r < 0.07:
            lines.append("    WaitTime 0.1;")
        elif r < 0.08:
            lines.append("    ConfL\\Off;")
        elif r < 0.09:
            lines.append("    ConfL\\On;")
        tail = TAIL if rnd.random() < 0.85 else rnd.choice(tails)
        move = rnd.choice(["MoveL"] * 8 + ["MoveJ", "movel", "MOVEL"])
        target = f"p{i}" if rnd.random() < 0.5 else robtarget(T[120 + i], rnd.choice([0, 0, 1, 2]))
        lines.append(f"    {move} {target}{tail}")
        if i == 40:
            lines += ["    IF TRUE THEN", f"      MoveL p{i}{TAIL}",
                      f"      MoveL {robtarget(T[250])}{TAIL}", "    ENDIF"]
        if i == 60:
            lines.append("    lbl:")
        if i == 80:
            lines.append(f"    MoveL pl{TAIL} MoveL pl{TAIL}")
    lines += ["  ENDPROC", "ENDMODULE", ""]
    return "\n".join(lines)


def other_shapes(seed: int) -> str:
    """CRLF lines; an array walked by FOR, Offs, MoveC, runs of MoveAbsJ on
    declared and inline jointtargets, PERS targets, a routine's own target,
    a TRAP's move."""
    T = targets(240, seed)
    lines = [f"MODULE Shapes{seed}"] + HEAD
    lines.append("  CONST robtarget arr{4}:=[" + ",".join(robtarget(T[i]) for i in range(4)) + "];")
    lines += [f"  PERS robtarget q{i}:={robtarget(T[10 + i])};" for i in range(30)]
    lines += [f"  CONST jointtarget j{i}:={jointtarget(T[50 + i])};" for i in range(20)]
    lines += ["  PROC main()", f"    CONST robtarget loc:={robtarget(T[80])};", "    ConfL\\On;"]
    lines += [f"    MoveAbsJ j{i}{TAIL}" for i in range(20)]
    lines += [f"    MoveAbsJ {jointtarget(T[90 + i])}{TAIL}" for i in range(20)]
    lines += ["    FOR i FROM 1 TO 4 DO", f"      MoveL arr{{i}}{TAIL}", "    ENDFOR"]
    lines += [f"    MoveL q{i}{TAIL}" for i in range(30)]
    lines += [f"    MoveL loc{TAIL}", f"    MoveL Offs(loc,1,2,3){TAIL}",
              f"    MoveC {robtarget(T[120])},{robtarget(T[121])}{TAIL}"]
    lines += [f"    MoveJ {robtarget(T[130 + i])}{TAIL}" for i in range(40)]
    lines += ["  ENDPROC", "  TRAP tr", f"    MoveL {robtarget(T[200])}{TAIL}", "  ENDTRAP",
              "ENDMODULE", ""]
    return "\r\n".join(lines)


def not_called(seed: int) -> str:
    """Routines nothing calls (supervision not known); a target used twice
    and from two routines; a named ToPoint; a search; ConfL\\Off."""
    T = targets(160, seed)
    lines = [f"MODULE Loose{seed}"] + HEAD
    lines += [f"  CONST robtarget p{i}:={robtarget(T[i])};" for i in range(50)]
    lines += ["  VAR robtarget ps;", "  PROC A()"]
    lines += [f"    MoveL p{i}{TAIL}" for i in range(50)]
    lines += [f"    MoveL p{i}{TAIL}" for i in range(15)]
    lines += [f"    MoveL ToPoint:=p3{TAIL}", f"    SearchL\\Stop,diSensor,ps,p4,v100,tSpindle\\WObj:=wPart;"]
    lines += [f"    MoveL {robtarget(T[100 + i])}{TAIL}" for i in range(40)]
    lines += ["  ENDPROC", "  PROC B()", "    ConfL\\Off;"]
    lines += [f"    MoveL p{i}{TAIL}" for i in range(20, 40)]
    lines += ["  ENDPROC", "ENDMODULE", ""]
    return "\n".join(lines)


def bench_module(n: int, seed: int, confl: str) -> str:
    """bench/fix.py's CAM module (random reachable targets with their
    confdata), under ConfL as given ('' = not known: entered from outside)."""
    import sys
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))
    from fix import cam_module
    return cam_module(n, seed).replace("  PROC Path()\n", f"  PROC Path()\n{confl}")


VARIANTS = {"broken_runs": broken_runs, "other_shapes": other_shapes, "not_called": not_called}
