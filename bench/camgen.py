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
