"""CAM-style RAPID module generator shared by the benchmarks.

Half the targets are declared (CONST robtarget pN:=[...]; MoveL pN,...),
half inline (MoveL [[...]],...), as post-processors write them.
"""

from __future__ import annotations

import random


def cam_module(n_targets: int, seed: int = 1, name: str = "CAM_Bench") -> str:
    rnd = random.Random(seed)
    declared = n_targets // 2
    inline = n_targets - declared
    q = "[0.707107,0,0.707107,0]"
    ext = "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]"

    def xyz():
        return (f"[{rnd.uniform(400, 700):.3f},{rnd.uniform(-300, 300):.3f},"
                f"{rnd.uniform(250, 550):.3f}]")

    lines = [f"MODULE {name}",
             "  PERS tooldata tSpindle:=[TRUE,[[0,0,150],[1,0,0,0]],[2,[0,0,75],[1,0,0,0],0,0,0]];",
             "  PERS wobjdata wPart:=[FALSE,TRUE,\"\",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];"]
    for i in range(declared):
        lines.append(f"  CONST robtarget p{i}:=[{xyz()},{q},[0,0,-1,0],{ext}];")
    lines.append("  PROC Path()")
    for i in range(declared):
        lines.append(f"    MoveL p{i},v100,z1,tSpindle\\WObj:=wPart;")
    for i in range(inline):
        lines.append(f"    MoveL [{xyz()},{q},[0,0,-1,0],{ext}],v100,z1,tSpindle\\WObj:=wPart;")
    lines += ["  ENDPROC", "ENDMODULE", ""]
    return "\n".join(lines)


def hand_module(n_targets: int, seed: int = 1, name: str = "Hand_Bench") -> str:
    """A module as people write one, n_targets move statements: declared targets
    with blanks after commas, speeds and zones that change from move to
    move, Offs and RelTool, MoveJ/MoveL/MoveC, inline targets, I/O and
    waits, IF blocks and FOR loops, comments; CRLF line breaks. Nothing
    runs of the same argument list the CAM path takes as one."""
    rnd = random.Random(seed)
    q = "[0.707107, 0, 0.707107, 0]"
    ext = "[9E+09, 9E+09, 9E+09, 9E+09, 9E+09, 9E+09]"
    n_decl = max(1, n_targets // 4)

    def xyz():
        return (f"[{rnd.uniform(400, 700):.2f}, {rnd.uniform(-300, 300):.2f}, "
                f"{rnd.uniform(250, 550):.2f}]")

    def tail():
        speed = rnd.choice(["v50", "v100", "v200", "v500", "v1000", "vmax"])
        zone = rnd.choice(["fine", "z1", "z5", "z10", "z50"])
        tool = rnd.choice(["tGripper", "tGlue"])
        wobj = rnd.choice(["", "\\WObj:=wTable", "\\WObj:=wFixture"])
        return f", {speed}, {zone}, {tool}{wobj};"

    lines = [f"MODULE {name}",
             "    ! Hand-written cell program (benchmark).",
             "    PERS tooldata tGripper := [TRUE, [[0, 0, 120], [1, 0, 0, 0]], "
             "[1.2, [0, 0, 60], [1, 0, 0, 0], 0, 0, 0]];",
             "    PERS tooldata tGlue := [TRUE, [[30, 0, 180], [0.965926, 0, 0.258819, 0]], "
             "[0.8, [10, 0, 90], [1, 0, 0, 0], 0, 0, 0]];",
             "    TASK PERS wobjdata wTable := [FALSE, TRUE, \"\", [[450, -300, 100], "
             "[1, 0, 0, 0]], [[0, 0, 0], [1, 0, 0, 0]]];",
             "    TASK PERS wobjdata wFixture := [FALSE, TRUE, \"\", [[500, 150, 200], "
             "[0.707107, 0, 0, 0.707107]], [[0, 0, 0], [1, 0, 0, 0]]];"]
    for i in range(n_decl):
        lines.append(f"    CONST robtarget p{i} := [{xyz()}, {q}, [0, 0, -1, 0], {ext}];")
    lines.append("    PROC main()")
    k = 0
    while k < n_targets:
        p = f"p{rnd.randrange(n_decl)}"
        r = rnd.random()
        if r < 0.35:
            lines.append(f"        MoveL {p}{tail()}")
        elif r < 0.5:
            lines.append(f"        MoveJ {p}{tail()}")
        elif r < 0.6:
            lines.append(f"        MoveL Offs({p}, 0, 0, {rnd.randint(5, 50)}){tail()}")
        elif r < 0.65:
            lines.append(f"        MoveL RelTool({p}, 0, 0, -10 \\Rz:={rnd.randint(-45, 45)})"
                         f"{tail()}")
        elif r < 0.75:
            lines.append(f"        MoveL [{xyz()}, {q}, [0, 0, -1, 0], {ext}]{tail()}")
        elif r < 0.8:
            lines.append(f"        MoveC {p}, p{rnd.randrange(n_decl)}{tail()}")
        elif r < 0.85:
            lines += ["        IF diPartPresent = 1 THEN", f"            MoveL {p}{tail()}",
                      "            SetDO doGripper, 1;", "            WaitTime 0.2;",
                      "        ENDIF"]
        elif r < 0.9:
            lines += [f"        ! approach {p}", f"        MoveL Offs({p}, 0, 0, 100){tail()}"]
        else:
            lines += ["        FOR i FROM 1 TO 2 DO", f"            MoveL {p}{tail()}",
                      "        ENDFOR"]
        k += 1
    lines += ["    ENDPROC", "ENDMODULE", ""]
    return "\r\n".join(lines)
