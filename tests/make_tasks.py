"""Write the real-shaped task fixtures under fixtures/tasks/ and the CAM
module fixtures/rapid/cam_confoff.mod.

Run from the repository root: python tests/make_tasks.py

Every robtarget is made from joint angles chosen here: Pinocchio FK of the
nominal IRB 140, expressed in the work object and tool of its move, written
as the tool that made it writes numbers (RobotStudio: 3 decimals in mm,
quaternions to 6 decimals, true confdata; a CAM post: placeholder confdata
and configuration supervision off). The joints are kept in JOINTS.json
beside each fixture: the independent controller model of the tests
(controller.py) must reproduce them from the text.

Shapes (issue #10):
  tasks/cell/        task folder: a user module and a data module (tools, work
                     objects and targets live in the data module); home at J5 = 0,
                     a park position near it; a PDispSet block; MoveExtJ of a
                     positioner; targets with J1/J4/J6 = 0 written with 3 decimals;
                     a robtarget array with a spare slot the program never reaches;
                     glue targets carrying a positioner angle (eax_a).
  tasks/glue/        a program file (Glue.pgf) listing two modules; the folder also
                     holds a stale copy of the main module (same module name), so
                     the folder as a task is refused and the .pgf is the program.
  tasks/backup_irbt/ a controller backup: T_ROB1 on a track (eax_a along world x),
                     its tool in a system module; T_COMM, a background task.
  rapid/cam_confoff.mod  a CAM post's output: ConfJ\\Off, ConfL\\Off, placeholder
                     confdata [0,-1,-1,0], a MoveAbsJ home, 180 MoveL along a path on
                     which J1, J4 and J6 cross quadrant boundaries.
  rapid/robodk_frames.mod  RoboDK's ABB post's output: rdkTool and rdkWObj declared
                     zero, their frames assigned in the routine before the moves
                     (rdkTool.tframe := [...]), a work object and a tool change
                     between moves (test_robodk_frames.py: the joints Q there).
  rapid/grasshopper_robots.mod  the Grasshopper plugin Robots' output: inline
                     targets whose external axes are the data extj
                     (test_grasshopper.py).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pinocchio as pin

from rapidcomp.kinematics.robot import irb140

ROOT = Path(__file__).resolve().parents[1]
TASKS = ROOT / "fixtures" / "tasks"
ROBOT = irb140()
EXT_NONE = "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]"


def se3(pos, quat_wxyz) -> pin.SE3:
    w, x, y, z = quat_wxyz
    q = pin.Quaternion(w, x, y, z)
    q.normalize()
    return pin.SE3(q.matrix(), np.asarray(pos, float))


def flange(q_deg) -> pin.SE3:
    data = ROBOT.model.createData()
    pin.framesForwardKinematics(ROBOT.model, data, np.radians(q_deg))
    return pin.SE3(data.oMf[ROBOT.flange_frame])


def conf_of(q_deg) -> tuple[int, int, int, int]:
    data = ROBOT.model.createData()
    pin.forwardKinematics(ROBOT.model, data, np.radians(q_deg))
    w = data.oMi[5].translation
    q1 = math.radians(q_deg[0])
    behind = math.cos(q1) * w[0] + math.sin(q1) * w[1] < 0
    cfx = 4 * behind + 2 * (q_deg[2] < -90) + (q_deg[4] < 0)
    return (math.floor(q_deg[0] / 90), math.floor(q_deg[3] / 90), math.floor(q_deg[5] / 90),
            cfx)


def num(x: float, decimals: int) -> str:
    text = f"{x:.{decimals}f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def quat_text(R) -> list[str]:
    q = pin.Quaternion(np.asarray(R))
    wxyz = np.array([q.w, q.x, q.y, q.z])
    if wxyz[0] < 0:
        wxyz = -wxyz
    return [num(v, 6) for v in wxyz]


def robtarget(q_deg, wobj: pin.SE3, tool: pin.SE3, conf=None, ext=EXT_NONE,
              base: pin.SE3 | None = None) -> str:
    """The robtarget (3 decimals, quaternion to 6) whose flange pose is the
    nominal FK of q_deg: wobj_M_target = wobj^-1 . world_M_base . flange . tool."""
    world_M_base = base if base is not None else pin.SE3.Identity()
    t = wobj.inverse() * world_M_base * flange(q_deg) * tool
    c = conf if conf is not None else conf_of(q_deg)
    return (f"[[{','.join(num(v, 3) for v in t.translation)}],[{','.join(quat_text(t.rotation))}],"
            f"[{','.join(map(str, c))}],{ext}]")


def jointtarget(q_deg, ext=EXT_NONE) -> str:
    return f"[[{','.join(num(v, 6) for v in q_deg)}],{ext}]"


def write(path: Path, text: str, newline: str = "\n") -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(text.replace("\n", newline).encode("ascii"))


# ------------------------------------------------------------------ cell

T_GRIPPER = ("[TRUE,[[0,0,120],[1,0,0,0]],[1.2,[0,0,60],[1,0,0,0],0,0,0]]",
             se3([0, 0, 120], [1, 0, 0, 0]))
T_GLUE = ("[TRUE,[[30,0,180],[0.965926,0,0.258819,0]],[0.8,[10,0,90],[1,0,0,0],0,0,0]]",
          se3([30, 0, 180], [0.965926, 0, 0.258819, 0]))
W_TABLE = ("[FALSE,TRUE,\"\",[[450,-300,100],[1,0,0,0]],[[0,0,0],[1,0,0,0]]]",
           se3([450, -300, 100], [1, 0, 0, 0]))
W_FIXTURE = ("[FALSE,TRUE,\"\",[[500,150,200],[0.707107,0,0,0.707107]],[[0,0,0],[1,0,0,0]]]",
             se3([500, 150, 200], [0.707107, 0, 0, 0.707107]))

# The pick runs displaced by the camera's measurement: away from quadrant
# boundaries (a displacement of a few mm turns J1/J4/J6 by ~0.1 deg).
PICK_APP = [8.0, 15.0, 5.0, 12.0, 70.0, -14.0]
PICK = [8.0, 25.0, 10.0, 12.0, 55.0, -14.0]
# Taught with J4, J6 (and for the fifth nest J1) at exactly 0 (the wrist
# unturned): written with 3 decimals they solve a few 1e-5 deg either side.
PLACE = [[-50.0 + 10 * k, 28.0, 2.0, 0.0, 60.0, 0.0] for k in range(1, 6)]
GLUE = [[30.0 + 3 * k, 35.0, -5.0 + k, -20.0 + 5 * k, 50.0, 10.0 - 4 * k] for k in range(8)]
HOME = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
PARK = [-90.0, -30.0, 30.0, 0.0, 0.2, 0.0]


def cell() -> None:
    folder = TASKS / "cell"
    tg, tgl, wt, wf = T_GRIPPER[1], T_GLUE[1], W_TABLE[1], W_FIXTURE[1]
    spare = "[[0,0,0],[0,0,0,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
    places = ",\n        ".join([robtarget(q, wt, tg) for q in PLACE] + [spare])
    glue_ext = "[45,9E+09,9E+09,9E+09,9E+09,9E+09]"
    glues = ",\n        ".join(robtarget(q, wf, tgl, ext=glue_ext) for q in GLUE)
    data = f"""MODULE CellData
    ! Cell data: tools, work objects and taught positions (saved by RobotStudio).
    PERS tooldata tGripper:={T_GRIPPER[0]};
    PERS tooldata tGlue:={T_GLUE[0]};
    TASK PERS wobjdata wTable:={W_TABLE[0]};
    TASK PERS wobjdata wFixture:={W_FIXTURE[0]};
    ! Tray offset measured by the camera before each pick.
    PERS pose pdTray:=[[2.5,-1.25,0],[1,0,0,0]];
    ! Home and park: the wrist straight (J5 = 0 and 0.2 deg).
    CONST jointtarget jHome:={jointtarget(HOME)};
    CONST jointtarget jPark:={jointtarget(PARK)};
    ! Positioner (eax_a) turned to 90 deg; the robot does not move.
    CONST jointtarget jTurn:=[[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09],[90,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pPickApp:={robtarget(PICK_APP, wt, tg)};
    CONST robtarget pPick:={robtarget(PICK, wt, tg)};
    ! Five nests; the sixth slot is a spare, not used yet.
    CONST robtarget pPlace{{6}}:=[
        {places}];
    ! Glue bead on the fixture, positioner at 45 deg.
    CONST robtarget pGlue{{8}}:=[
        {glues}];
ENDMODULE
"""
    main = """MODULE MainModule
    ! Pick from the camera-located tray, place into five nests, glue the fixture.
    PROC main()
        ConfJ\\On;
        ConfL\\On;
        MoveAbsJ jHome\\NoEOffs, v1000, z50, tGripper;
        Pick;
        FOR i FROM 1 TO 5 DO
            MoveJ Offs(pPlace{i},0,0,60), v1000, z20, tGripper\\WObj:=wTable;
            MoveL pPlace{i}, v200, fine, tGripper\\WObj:=wTable;
            MoveL Offs(pPlace{i},0,0,60), v1000, z20, tGripper\\WObj:=wTable;
        ENDFOR
        MoveExtJ jTurn, vrot50, fine;
        Glue;
        MoveAbsJ jPark, v1000, z50, tGripper;
        MoveAbsJ jHome, v1000, fine, tGripper;
    ENDPROC

    PROC Pick()
        ! The camera measured the tray: shift the program by pdTray.
        PDispSet pdTray;
        MoveJ pPickApp, v1000, z50, tGripper\\WObj:=wTable;
        MoveL pPick, v200, fine, tGripper\\WObj:=wTable;
        MoveL pPickApp, v500, z50, tGripper\\WObj:=wTable;
        PDispOff;
    ENDPROC

    PROC Glue()
        MoveJ pGlue{1}, v500, z10, tGlue\\WObj:=wFixture;
        FOR k FROM 2 TO 8 DO
            MoveL pGlue{k}, v100, z1, tGlue\\WObj:=wFixture;
        ENDFOR
    ENDPROC
ENDMODULE
"""
    write(folder / "CellData.mod", data, "\r\n")
    write(folder / "MainModule.mod", main, "\r\n")


# ------------------------------------------------------------------ glue (.pgf)

T_NOZZLE = ("[TRUE,[[0,40,160],[0.984808,0.173648,0,0]],[0.6,[0,10,70],[1,0,0,0],0,0,0]]",
            se3([0, 40, 160], [0.984808, 0.173648, 0, 0]))
W_PART = ("[FALSE,TRUE,\"\",[[420,-80,260],[0.996195,0,0,-0.087156]],[[0,0,0],[1,0,0,0]]]",
          se3([420, -80, 260], [0.996195, 0, 0, -0.087156]))
# A bead around a rectangle: four sides (MoveL) and four rounded corners (MoveC).
BEAD = [[-10.0 + 2 * k, 40.0 + (k % 3), 15.0 - (k % 2), -35.0 + 4 * k, 40.0 + k, 60.0 - 6 * k]
        for k in range(12)]


def glue() -> None:
    folder = TASKS / "glue"
    tn, wp = T_NOZZLE[1], W_PART[1]
    pts = "\n".join(f"    CONST robtarget pBead{k + 1}:={robtarget(q, wp, tn)};"
                    for k, q in enumerate(BEAD))
    data = f"""MODULE GlueData
    PERS tooldata tNozzle:={T_NOZZLE[0]};
    PERS wobjdata wPart:={W_PART[0]};
{pts}
    CONST jointtarget jSafe:={jointtarget([0, -10, 10, 0, 45, 0])};
ENDMODULE
"""
    lines = ["        MoveJ pBead1, v500, z10, tNozzle\\WObj:=wPart;"]
    k = 2
    while k <= 12:
        if k % 3 == 0 and k < 12:
            lines.append(f"        MoveC pBead{k}, pBead{k + 1}, v80, z1, tNozzle\\WObj:=wPart;")
            k += 2
        else:
            lines.append(f"        MoveL pBead{k}, v80, z1, tNozzle\\WObj:=wPart;")
            k += 1
    body = "\n".join(lines)
    main = f"""MODULE GlueMain
    PROC main()
        MoveAbsJ jSafe, v1000, z50, tNozzle;
        Bead;
        MoveAbsJ jSafe, v1000, fine, tNozzle;
    ENDPROC

    PROC Bead()
{body}
    ENDPROC
ENDMODULE
"""
    old = main.replace("    PROC Bead()", "    ! Superseded by GlueMain.mod; kept for reference.\n"
                                          "    PROC Bead()")
    pgf = """<?xml version="1.0" encoding="ISO-8859-1" ?>
<Program>
    <Module>GlueData.mod</Module>
    <Module>GlueMain.mod</Module>
</Program>
"""
    write(folder / "GlueData.mod", data)
    write(folder / "GlueMain.mod", main)
    write(folder / "old" / "GlueMain.mod", old)
    write(folder / "Glue.pgf", pgf, "\r\n")


# ------------------------------------------------------------------ backup, robot on a track

T_PROBE = ("[TRUE,[[0,0,95],[1,0,0,0]],[0.4,[0,0,40],[1,0,0,0],0,0,0]]",
           se3([0, 0, 95], [1, 0, 0, 0]))
TRACK = [0.0, 400.0, 800.0, 1200.0, 1600.0]
STATIONS = [[10.0, 30.0, 15.0, 5.0, 40.0, -10.0], [-15.0, 35.0, 10.0, -5.0, 45.0, 20.0]]


def backup() -> None:
    root = TASKS / "backup_irbt"
    tp = T_PROBE[1]
    decls = []
    seq = []
    for i, e in enumerate(TRACK):
        base = pin.SE3(np.eye(3), np.array([e, 0.0, 0.0]))
        for j, q in enumerate(STATIONS):
            name = f"pSt{i + 1}_{j + 1}"
            ext = f"[{num(e, 1)},9E+09,9E+09,9E+09,9E+09,9E+09]"
            decls.append(f"    CONST robtarget {name}:="
                         f"{robtarget(q, pin.SE3.Identity(), tp, ext=ext, base=base)};")
            seq.append(f"        MoveJ {name}, v1000, fine, tProbe;" if j == 0 else
                       f"        MoveL {name}, v200, fine, tProbe;")
    track = "\n".join(decls)
    body = "\n".join(seq)
    prog = f"""MODULE Track
    ! Probing stations along the track (eax_a, mm along world x).
{track}
    CONST jointtarget jStart:=[[0,-10,10,0,50,0],[0,9E+09,9E+09,9E+09,9E+09,9E+09]];

    PROC main()
        MoveAbsJ jStart, v1000, fine, tProbe;
{body}
        MoveAbsJ jStart, v1000, fine, tProbe;
    ENDPROC
ENDMODULE
"""
    user = f"""MODULE user(SYSMODULE)
    ! User system data
    PERS tooldata tProbe:={T_PROBE[0]};
    VAR num reg1:=0;
ENDMODULE
"""
    comm = """MODULE Comm
    ! Background task: cell communication, no motion.
    VAR num nTick:=0;
    PROC main()
        WHILE TRUE DO
            Incr nTick;
            WaitTime 1;
        ENDWHILE
    ENDPROC
ENDMODULE
"""
    backinfo = """>>SYSTEM_ID:
IRBT_CELL

>>PRODUCTS_ID:
RobotWare Version: 6.15.03.00

>>TASK1: (T_ROB1,,)
SYSMOD/user.sys
PROGMOD/Track.mod

>>TASK2: (T_COMM,,)
PROGMOD/Comm.mod

>>EOF:
"""
    sys_cfg = """SYS:CFG_1.0:6:0::
#
CAB_TASKS:

      -Name "T_ROB1" -Type "NORMAL" -MotionTask -UseMechanicalUnitGroup "rob1"

      -Name "T_COMM" -Type "SEMISTATIC"
"""
    moc = """MOC:CFG_1.0:6:0::
#
SINGLE:

      -name "TRACK_1" -use_single_type "TRACK_1" -use_joint "TRACK_1"
"""
    write(root / "BACKINFO" / "backinfo.txt", backinfo, "\r\n")
    write(root / "SYSPAR" / "SYS.cfg", sys_cfg, "\r\n")
    write(root / "SYSPAR" / "MOC.cfg", moc, "\r\n")
    write(root / "RAPID" / "TASK1" / "PROGMOD" / "Track.mod", prog, "\r\n")
    write(root / "RAPID" / "TASK1" / "SYSMOD" / "user.sys", user, "\r\n")
    write(root / "RAPID" / "TASK2" / "PROGMOD" / "Comm.mod", comm, "\r\n")


# ------------------------------------------------------------------ CAM, supervision off

T_SPINDLE = ("[TRUE,[[0,0,185],[1,0,0,0]],[3.5,[0,0,90],[1,0,0,0],0,0,0]]",
             se3([0, 0, 185], [1, 0, 0, 0]))
CAM_HOME = [0.0, 0.0, 0.0, 0.0, 60.0, 0.0]


def cam_path(n: int = 180) -> list[list[float]]:
    """A smooth joint path: J1 swings through 0, J4 through 0, J6 turns
    through -90, 0, 90 and 180 (quadrant boundaries all along)."""
    out = []
    for k in range(n):
        t = k / (n - 1)
        out.append([-25.0 + 50.0 * t, 35.0 + 8.0 * math.sin(3 * t), 5.0 + 6.0 * math.cos(2 * t),
                    -30.0 + 60.0 * t, 50.0 + 10.0 * math.sin(5 * t), -120.0 + 310.0 * t])
    return out


def cam() -> None:
    ts = T_SPINDLE[1]
    placeholder = (0, -1, -1, 0)
    path = cam_path()
    moves = "\n".join(f"MoveL {robtarget(q, pin.SE3.Identity(), ts, conf=placeholder)},"
                      f"v50,z1,tSpindle\\WObj:=wobj0;" for q in path[1:])
    text = f"""MODULE CAM_Pocket
! Post-processed toolpath (configuration supervision off, placeholder confdata)
PERS tooldata tSpindle:={T_SPINDLE[0]};
PROC main()
ConfJ\\Off;
ConfL\\Off;
MoveAbsJ {jointtarget(CAM_HOME)},v200,fine,tSpindle;
MoveJ {robtarget(path[0], pin.SE3.Identity(), ts, conf=placeholder)},v200,z5,tSpindle\\WObj:=wobj0;
{moves}
MoveAbsJ {jointtarget(CAM_HOME)},v200,fine,tSpindle;
ENDPROC
ENDMODULE
"""
    write(ROOT / "fixtures" / "rapid" / "cam_confoff.mod", text)


def robodk() -> None:
    from test_robodk_frames import BODY, PROGRAMS, module, program
    write(ROOT / "fixtures" / "rapid" / "robodk_frames.mod", program(BODY))
    write(ROOT / "fixtures" / "rapid" / "robodk_programs.mod", module("MOD_Main", PROGRAMS))


def grasshopper() -> None:
    from test_grasshopper import MOVES, program
    write(ROOT / "fixtures" / "rapid" / "grasshopper_robots.mod", program(MOVES))


def main() -> None:
    cell()
    glue()
    backup()
    cam()
    robodk()
    grasshopper()
    joints = {"cell": {"PICK_APP": PICK_APP, "PICK": PICK, "PLACE": PLACE, "GLUE": GLUE,
                       "HOME": HOME, "PARK": PARK},
              "glue": {"BEAD": BEAD},
              "backup_irbt": {"TRACK": TRACK, "STATIONS": STATIONS},
              "cam_confoff": {"HOME": CAM_HOME, "PATH": cam_path()}}
    (TASKS / "JOINTS.json").write_text(json.dumps(joints, indent=1) + "\n")


if __name__ == "__main__":
    main()
