"""Real-shaped programs (issue #10), compensated from the command line and
re-evaluated by an independent model of the controller (controller.py).

For every arm move of the input program the model computes the joints the
controller commands and the pose they reach on the ideal robot (the pose
the program asks for). It then runs the compensated output the same way
and puts its joints through Pinocchio FK of the deformed robot: each move
must land on the pose the input asks for within 1 um and 1e-4 deg, on the
same configuration (no joint moves more than 1 deg). Exceptions, each with
its own bound: moves under program displacement (compensated for the
undisplaced pose: the error the report states per mm of displacement),
MoveAbsJ at the wrist singularity (orientation left over, reported).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from controller import Controller, fk
from rapidcomp.kinematics.profile import deform, read_profile
from rapidcomp.kinematics.robot import irb140
from rapidcomp.rapid.parse import parse_file

from conftest import FIXTURES, ROOT

NOMINAL = irb140()
WARM = deform(NOMINAL, read_profile(FIXTURES / "warm.csv"))
TASKS = FIXTURES / "tasks"
JOINTS = json.loads((TASKS / "JOINTS.json").read_text())


def rapidcomp(*args, check=True):
    r = subprocess.run([sys.executable, "-m", "rapidcomp", *map(str, args)], cwd=ROOT,
                       capture_output=True, text=True)
    if check:
        assert r.returncode == 0, r.stdout + r.stderr
    return r


def parsed(folder: Path, names) -> list:
    return [parse_file(folder / n, n) for n in names]


def evaluate(inp, out, track=None, displaced_um=1.0, **controller):
    """Run input and output on the controller model; returns the rows
    (executed input, executed output, position error um, orientation error
    deg) and checks the bounds."""
    entry = controller.pop("entry", "main")
    a = Controller(inp, NOMINAL, track, **controller).run(entry)
    b = Controller(out, NOMINAL, track, **controller).run(entry)
    assert [x.kind == "ext" for x in a] == [x.kind == "ext" for x in b]
    assert len(a) == len(b) > 0
    rows = []
    for x, y in zip(a, b):
        if x.kind == "ext":
            continue
        want = x.pose if x.pose is not None else fk(NOMINAL, x.q_deg)
        got = fk(WARM, y.q_deg)
        # (At the move's tool centre point: at J5 = 0 only one point's
        # position can be held exact, and it is that one.)
        tcp = np.zeros(3) if x.tcp is None else x.tcp
        err_um = np.linalg.norm(got.act(tcp) - want.act(tcp)) * 1000
        err_deg = np.degrees(np.linalg.norm(pin.log3(want.rotation.T @ got.rotation)))
        assert np.max(np.abs(y.q_deg - x.q_deg)) < 1.0, (x.line, x.q_deg, y.q_deg)
        singular = x.kind == "joint" and abs(x.q_deg[4]) < 1.0
        assert err_um <= (displaced_um if x.displaced else 1.0), (x.file, x.line, err_um)
        assert err_deg <= (0.02 if singular else 1e-4), (x.file, x.line, err_deg)
        rows.append((x, y, err_um, err_deg))
    return rows


# ---------------------------------------------------------------- the cell task folder

CELL = ["CellData.mod", "MainModule.mod"]


@pytest.fixture(scope="module", params=["auto", "absj", "robtarget"])
def cell(request, tmp_path_factory):
    out = tmp_path_factory.mktemp(request.param) / "cell_comp"
    r = rapidcomp("fix", TASKS / "cell", "--profile", FIXTURES / "warm.csv", "-o", out,
                  "--emit", request.param, "--json", out.with_suffix(".json"))
    return request.param, out, r.stdout, json.loads(out.with_suffix(".json").read_text())


def test_cell_task_lands_every_move_on_its_pose(cell):
    mode, out, _, doc = cell
    assert doc["summary"]["compensated"] == 29 and doc["summary"]["not_compensated"] == 0
    rows = evaluate(parsed(TASKS / "cell", CELL), parsed(out, CELL), displaced_um=1.5)
    assert len(rows) == 29
    instructions = [y.instruction for _, y, _, _ in rows]
    if mode == "absj":
        # Displaced moves stay robtarget moves (MoveAbsJ is not displaced).
        assert [y.instruction for x, y, _, _ in rows if x.displaced] == ["MoveJ", "MoveL", "MoveL"]
        assert instructions.count("MoveAbsJ") == 29 - 3
    elif mode == "auto":
        # MoveJ becomes MoveAbsJ (not the displaced one); every MoveL stays.
        assert [(x.instruction, y.instruction) for x, y, _, _ in rows
                if x.instruction != y.instruction] == [("MoveJ", "MoveAbsJ")] * 6
    else:
        assert "MoveAbsJ" not in [y.instruction for x, y, _, _ in rows if x.kind == "rob"]
    # The displaced pick: the error of the undisplaced correction stays
    # within what the report states per mm of displacement (|d| = 2.8 mm).
    disp = [r for r in doc["targets"] if any("program displacement" in w for w in r["warnings"])]
    assert len(disp) == 3
    per_mm = max(float(w.split("adds up to ")[1].split(" um")[0])
                 for r in disp for w in r["warnings"] if "adds up to" in w)
    worst = max(e for x, _, e, _ in rows if x.displaced)
    assert worst <= per_mm * np.hypot(2.5, 1.25) + 0.05


def test_cell_home_at_the_wrist_singularity_is_compensated_in_position(cell):
    _, _, _, doc = cell
    homes = [r for r in doc["targets"] if r["target"] in ("jHome", "jPark")]
    assert [r["status"] for r in homes] == ["compensated"] * 3
    for r in homes:
        assert r["residual_um"] <= 1.0
        assert 0 < r["residual_deg"] < 0.02
        assert any("deg left over" in w for w in r["warnings"])
        assert max(abs(d) for d in r["delta_deg"]) <= 1.0  # J4/J6 within the bound


def test_cell_spare_slot_blocks_nothing(cell):
    mode, out, stdout, doc = cell
    data = (out / "CellData.mod").read_text()
    if mode == "absj":
        # The new jointtarget arrays keep a valid value in the spare slot.
        assert "jt_pPlace{6}:=[" in data
        block = data.split("jt_pPlace{6}:=[")[1].split("];")[0]
        assert block.strip().splitlines()[-1].strip().startswith("[[0,0,0,0,0,0],[9E+09")
        assert any(n.startswith("jt_pPlace: elements no executed move reaches (pPlace{6}) hold "
                                "[0,0,0,0,0,0], the calibration position") for n in doc["notes"])
    # The spare slot itself is left as written.
    assert "[[0,0,0],[0,0,0,0],[0,0,0,0],[9E+09" in data


def test_cell_extax_assumption_is_stated_and_moveextj_untouched(cell):
    _, _, stdout, doc = cell
    assert any("assumed not to move the robot's base" in n for n in doc["notes"])
    ext = [r for r in doc["targets"] if r["instruction"] == "MoveExtJ"]
    assert len(ext) == 1 and ext[0]["status"] == "untouched"
    assert "moves only external axes" in ext[0]["reason"]


def test_cell_boundary_targets_keep_their_confdata_in_robtarget_mode():
    """pPlace{5} was taught at J1 = J4 = J6 = 0 and written with 3
    decimals: with a zero profile nothing changes; with the warm profile
    the written cf values stay as taught where the compensated joint is
    within 0.01 deg of the quadrant."""
    from rapidcomp.compensate.fix import fix
    from rapidcomp.compensate.plan import Task
    from rapidcomp.kinematics.ik import Solver
    files = tuple(parsed(TASKS / "cell", CELL))
    zero = Solver(NOMINAL, NOMINAL)
    result = fix(Task("cell", files), zero, "robtarget")
    assert result.edits == () and result.failed == 0


def test_module_alone_names_the_missing_tool_and_the_folder_compensates(tmp_path):
    r = rapidcomp("fix", TASKS / "cell" / "MainModule.mod", "--profile", FIXTURES / "warm.csv",
                  "-o", tmp_path / "m.mod", check=False)
    assert r.returncode == 1
    assert "tool tGripper" in r.stdout and "--with" in r.stdout
    assert "nothing written" in r.stderr and list(tmp_path.iterdir()) == []
    r = rapidcomp("fix", TASKS / "cell" / "MainModule.mod", "--with",
                  TASKS / "cell" / "CellData.mod", "--profile", FIXTURES / "warm.csv",
                  "-o", tmp_path / "m.mod")
    # --with modules are read, never written: targets declared there get new
    # declarations in the module that uses them.
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.md", "m.mod"]
    text = (tmp_path / "m.mod").read_text()
    assert "LOCAL CONST jointtarget jt_pPlace_offs{6}" in text   # MoveJ -> MoveAbsJ
    assert "LOCAL CONST robtarget pPlace_c{6}" in text           # MoveL stays straight
    parse_file(tmp_path / "m.mod")


# ---------------------------------------------------------------- CAM, supervision off

@pytest.mark.parametrize("mode", ["absj", "robtarget"])
def test_cam_supervision_off_placeholder_confdata(mode, tmp_path):
    src = FIXTURES / "rapid" / "cam_confoff.mod"
    out = tmp_path / "cam.mod"
    r = rapidcomp("fix", src, "--profile", FIXTURES / "warm.csv", "-o", out, "--emit", mode)
    assert "182 of 182 target uses compensated" in r.stdout
    rows = evaluate([parse_file(src)], [parse_file(out)])
    # The controller model found the joints the path was made from.
    path = np.array(JOINTS["cam_confoff"]["PATH"])
    got = np.array([x.q_deg for x, _, _, _ in rows if x.kind == "rob"])
    assert np.max(np.abs(got - path)) < 0.01
    if mode == "robtarget":
        # Supervision is off: the controller does not read confdata, so the
        # placeholder stays as written; only numbers of poses change.
        before, after = src.read_text().splitlines(), out.read_text().splitlines()
        assert len(before) == len(after)
        moves = [b for b in after if b.startswith("MoveL")]
        assert all(",[0,-1,-1,0]," in b for b in moves)


def test_cam_first_move_needs_a_known_position(tmp_path):
    """Without any jointtarget and with placeholder confdata, the first
    move's solution cannot be known: refused with the reason and a way out."""
    text = (FIXTURES / "rapid" / "cam_confoff.mod").read_text()
    lines = [ln for ln in text.splitlines() if not ln.startswith("MoveAbsJ")]
    prog = tmp_path / "nohome.mod"
    prog.write_text("\n".join(lines) + "\n")
    r = rapidcomp("fix", prog, "--profile", FIXTURES / "warm.csv", "-o", tmp_path / "o.mod",
                  check=False)
    assert r.returncode == 1
    assert "the program has no jointtarget to start from" in r.stdout


def test_cam_without_home_compensates_from_start(tmp_path):
    """cam_inline.mod: a routine no given module calls, ConfL\\Off, placeholder
    confdata, no jointtarget: with --start (where the robot stands when the
    routine runs) every move compensates; the controller model, started
    there with ConfJ off, lands them all."""
    src = FIXTURES / "rapid" / "cam_inline.mod"
    out = tmp_path / "cam.mod"
    r = rapidcomp("fix", src, "--profile", FIXTURES / "warm.csv", "-o", out, "--emit",
                  "robtarget", "--start", "0,0,0,0,30,0")
    assert "313 of 313 target uses compensated" in r.stdout
    rows = evaluate([parse_file(src)], [parse_file(out)], entry="Contour",
                    start_deg=[0, 0, 0, 0, 30, 0], confj=False)
    assert len(rows) == 313


# ---------------------------------------------------------------- program file

def test_program_file_is_the_task_and_the_folder_with_a_stale_copy_is_refused(tmp_path):
    out = tmp_path / "glue"
    rapidcomp("fix", TASKS / "glue" / "Glue.pgf", "--profile", FIXTURES / "warm.csv",
              "-o", out)
    assert sorted(p.name for p in out.iterdir()) == ["Glue.pgf", "GlueData.mod", "GlueMain.mod"]
    assert (out / "Glue.pgf").read_bytes() == (TASKS / "glue" / "Glue.pgf").read_bytes()
    names = ["GlueData.mod", "GlueMain.mod"]
    rows = evaluate(parsed(TASKS / "glue", names), parsed(out, names))
    assert len(rows) == 14  # 2 MoveAbsJ, the 12 bead points (two are circle points)
    r = rapidcomp("fix", TASKS / "glue", "--profile", FIXTURES / "warm.csv", "-o",
                  tmp_path / "g2", check=False)
    assert r.returncode == 2
    assert "old/GlueMain.mod:1:" in r.stderr and "module GlueMain is also in" in r.stderr
    assert not (tmp_path / "g2").exists()


def test_a_robot_base_away_from_the_world_frame(tmp_path):
    """--base: robtargets are world coordinates, the arm solves them from
    its base frame; the controller model with the same base lands them."""
    out = tmp_path / "glue"
    base = (10.0, -5.0, 3.0, 0.999848, 0.0, 0.0, 0.017452)   # 2 deg about z
    r = rapidcomp("fix", TASKS / "glue" / "Glue.pgf", "--profile", FIXTURES / "warm.csv",
                  "-o", out, "--base", ",".join(map(str, base)), "--json", tmp_path / "g.json")
    assert "14 of 14 target uses compensated" in r.stdout
    doc = json.loads((tmp_path / "g.json").read_text())
    assert doc["robot base"].startswith("--base 10,-5,3,")
    names = ["GlueData.mod", "GlueMain.mod"]
    from controller import se3
    base_se3 = pin.SE3(se3(base[:3], base[3:]).rotation, np.array(base[:3]))
    rows = evaluate(parsed(TASKS / "glue", names), parsed(out, names), base=base_se3)
    assert len(rows) == 14


# ---------------------------------------------------------------- backup, robot on a track

def test_backup_with_a_track(tmp_path):
    out = tmp_path / "bk"
    r = rapidcomp("fix", TASKS / "backup_irbt", "--profile", FIXTURES / "warm.csv", "-o", out,
                  check=False)
    assert r.returncode == 1 and "--track" in r.stdout   # out of reach as a positioner
    assert not out.exists()
    r = rapidcomp("fix", TASKS / "backup_irbt", "--profile", FIXTURES / "warm.csv", "-o", out,
                  "--track", "a:x")
    assert "(T_ROB1)" in r.stdout and "12 of 12 target uses compensated" in r.stdout
    assert "T_COMM" in r.stdout and "not a motion task" in r.stdout
    src_files = sorted(p.relative_to(TASKS / "backup_irbt") for p in
                       (TASKS / "backup_irbt").rglob("*") if p.is_file())
    out_files = sorted(p.relative_to(out) for p in out.rglob("*") if p.is_file())
    assert src_files == out_files
    changed = [p for p in src_files
               if (out / p).read_bytes() != (TASKS / "backup_irbt" / p).read_bytes()]
    assert [str(p) for p in changed] == ["RAPID/TASK1/PROGMOD/Track.mod"]
    names = ["RAPID/TASK1/SYSMOD/user.sys", "RAPID/TASK1/PROGMOD/Track.mod"]
    rows = evaluate(parsed(TASKS / "backup_irbt", names), parsed(out, names),
                    track={0: (1.0, 0.0, 0.0)})
    assert len(rows) == 12  # 10 stations, MoveAbsJ jStart twice
    # MoveAbsJ keeps the track value of the robtarget it replaces.
    text = (out / "RAPID/TASK1/PROGMOD/Track.mod").read_text()
    assert "jt_pSt5_1:=[[" in text and "],[1600,9E+09" in text


def test_backup_task_selection(tmp_path):
    r = rapidcomp("check", TASKS / "backup_irbt", "--profile", FIXTURES / "warm.csv",
                  "--task", "T_ROB9", check=False)
    assert r.returncode == 2 and "--task T_ROB9" in r.stderr and "T_ROB1" in r.stderr
    r = rapidcomp("check", TASKS / "backup_irbt", "--profile", FIXTURES / "warm.csv",
                  "--task", "TASK1", "--track", "a:x")
    # (The backup as given, and the task chosen in it.)
    assert r.stdout.startswith(f"{TASKS / 'backup_irbt'} (T_ROB1): predicted error")


def test_a_backup_of_another_robot_is_not_taken_as_an_irb_140(tmp_path):
    """A backup whose MOC.cfg names its robot (-use_robot_type): an IRB 140
    (ROB1_140_0.81_6) is the built-in model's; an IRB 1200 is refused
    (exit 2, nothing written: its program compensated with the IRB 140's
    kinematics would move the robot by the difference) unless --force, and
    a URDF given is taken as that robot, each said in a note."""
    import shutil
    backup = tmp_path / "backup_irbt"
    shutil.copytree(TASKS / "backup_irbt", backup)
    moc = backup / "SYSPAR" / "MOC.cfg"
    base = moc.read_text()

    def robot(kind):
        moc.write_text(base + f'\nROBOT:\n\n      -name "ROB_1" -use_robot_type "{kind}"\n')
    common = ["--profile", FIXTURES / "warm.csv", "--track", "a:x"]
    robot("ROB1_140_0.81_6")
    r = rapidcomp("check", backup, *common)
    assert "-use_robot_type" not in r.stdout
    robot("ROB1_1200_0.9_5_TypeB")
    out = tmp_path / "out"
    r = rapidcomp("fix", backup, *common, "-o", out, check=False)
    assert r.returncode == 2, r.stdout + r.stderr
    # (Named as the input was given, at the line naming the robot, as a
    # module's error names its place.)
    line = next(n for n, text in enumerate(moc.read_text().splitlines(), 1) if "1200" in text)
    assert (f"{moc}:{line}: it names the robot ROB1_1200_0.9_5_TypeB "
            "(-use_robot_type), not an IRB 140") in r.stderr
    assert '\n          -name "ROB_1" -use_robot_type "ROB1_1200_0.9_5_TypeB"\n' in r.stderr
    assert not out.exists()
    r = rapidcomp("check", backup, *common, check=False)
    assert r.returncode == 2 and "--robot ARM.urdf" in r.stderr
    r = rapidcomp("check", backup, *common, "--force", check=False)
    assert ("note: backup_irbt/SYSPAR/MOC.cfg names the robot ROB1_1200_0.9_5_TypeB "
            "(-use_robot_type), not an IRB 140: taken as an IRB 140 (--force)") in r.stdout
    r = rapidcomp("check", backup, *common, "--robot", FIXTURES / "robots" / "irb140.urdf",
                  check=False)
    assert ("note: backup_irbt/SYSPAR/MOC.cfg names the robot ROB1_1200_0.9_5_TypeB "
            "(-use_robot_type): --robot irb140.urdf is taken as its model") in r.stdout
    # Two robots, nothing linking the task to one: an IRB 140 and an IRB
    # 1200 are refused, two IRB 140 variants are not.
    moc.write_text(base + '\nROBOT:\n\n      -name "ROB_1" -use_robot_type "ROB1_140_0.81_6"\n'
                   '\n      -name "ROB_2" -use_robot_type "ROB2_1200_0.9_5"\n')
    r = rapidcomp("check", backup, *common, check=False)
    assert r.returncode == 2 and ("the robots ROB1_140_0.81_6, ROB2_1200_0.9_5 (-use_robot_type) "
                                  "and nothing links task T_ROB1 to one of them") in r.stderr
    moc.write_text(base + '\nROBOT:\n\n      -name "ROB_1" -use_robot_type "ROB1_140_0.81_6"\n'
                   '\n      -name "ROB_2" -use_robot_type "ROB2_140T_0.81_6"\n')
    assert rapidcomp("check", backup, *common).returncode == 0


@pytest.mark.parametrize("kind, irb140", [
    ("ROB1_140_0.81_6", True), ("ROB1_140T_0.81_6", True), ("ROB2_140F_0.81_6", True),
    ("IRB 140CW", True), ("ROB1_1400_1.44_5", False), ("ROB1_1410_1.44_5", False),
    ("ROB1_6700_2.6_140", False), ("ROB_R_14000_05_05_TYPEA", False), ("GantryXYZ", False)])
def test_the_irb_140s_robot_types(kind, irb140):
    """Its model field, not a 140 elsewhere in the type (a payload)."""
    from rapidcomp.compensate.load import is_irb140
    assert is_irb140(kind) is irb140


def test_the_readme_task_commands_run_as_written(tmp_path):
    """The three commands of the README's 'Whole tasks' section, on a copy
    of fixtures/ (default outputs beside the inputs)."""
    import shutil
    shutil.copytree(FIXTURES, tmp_path / "fixtures")
    readme = (ROOT / "README.md").read_text()
    section = readme.split("## Whole tasks")[1].split("```sh")[1].split("```")[0]
    commands = [line.split("#")[0].split() for line in section.strip().splitlines()]
    assert len(commands) == 3
    for cmd in commands:
        assert cmd[0] == "rapidcomp"
        r = subprocess.run([sys.executable, "-m", "rapidcomp", *cmd[1:]], cwd=tmp_path,
                           capture_output=True, text=True)
        assert r.returncode == 0, (cmd, r.stdout, r.stderr)
    t = tmp_path / "fixtures" / "tasks"
    assert (t / "cell_comp" / "MainModule.mod").is_file() and (t / "cell_comp.md").is_file()
    assert (t / "glue" / "Glue_comp" / "Glue.pgf").is_file()
    assert (t / "backup_irbt_comp" / "SYSPAR" / "SYS.cfg").is_file()


@pytest.mark.parametrize("decimals", [6, 9])
def test_robtargets_taught_with_a_straight_wrist_keep_their_orientation(tmp_path, decimals):
    """Robtargets taught at J5 = 0 (J4 = J6 = 0, J1 turned), their quaternion
    written with 6 or 9 decimals (so J5 comes out a few 1e-4 deg off 0 with
    an arbitrary J4/J6 split), a 150 mm tool: MoveJ becomes MoveAbsJ whose
    joints, on the warm robot (Pinocchio FK, independent of the solver),
    put the TCP on the programmed point and the tool within the thermal
    tilt (< 0.05 deg) of the programmed orientation."""
    taught = [[-10, 5, 10, 0, 0, 0], [45, 0, 30, 0, 0, 0], [20, 0, 0, 0, 0, 0],
              [30, -10, 40, 0, 0, 0]]
    tool = pin.SE3(np.eye(3), np.array([0.0, 0.0, 150.0]))
    decls, moves = [], []
    for n, q in enumerate(taught):
        M = fk(NOMINAL, q) * tool
        quat = pin.Quaternion(M.rotation)
        wxyz = [quat.w, quat.x, quat.y, quat.z]
        cf1 = int(np.floor(q[0] / 90.0))
        decls.append(f"    CONST robtarget p{n}:=[[{','.join(f'{v:.3f}' for v in M.translation)}],"
                     f"[{','.join(f'{v:.{decimals}f}' for v in wxyz)}],[{cf1},0,0,0],"
                     "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];")
        moves.append(f"        MoveJ p{n}, v100, fine, tProbe;")
    src = tmp_path / "wrist.mod"
    src.write_text("MODULE Wrist\n    PERS tooldata tProbe:=[TRUE,[[0,0,150],[1,0,0,0]],"
                   "[1,[0,0,50],[1,0,0,0],0,0,0]];\n" + "\n".join(decls)
                   + "\n    PROC main()\n" + "\n".join(moves) + "\n    ENDPROC\nENDMODULE\n")
    out = tmp_path / "wrist_comp.mod"
    r = subprocess.run([sys.executable, "-m", "rapidcomp", "fix", str(src), "--profile",
                        str(FIXTURES / "warm.csv"), "-o", str(out), "--json",
                        str(tmp_path / "r.json")], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    written = parse_file(out)
    joints = {d.name: d.value for m in written.modules for d in m.declarations
              if d.type == "jointtarget"}
    assert len(joints) == len(taught)
    for n, q in enumerate(taught):
        want = fk(NOMINAL, q) * tool
        jt = joints[f"jt_p{n}"]
        got = fk(WARM, np.asarray(jt.values[:6], float)) * tool
        assert np.linalg.norm(got.translation - want.translation) * 1000 < 1.0, n
        tilt = np.degrees(np.linalg.norm(pin.log3(want.rotation.T @ got.rotation)))
        assert tilt < 0.05, (n, tilt)
