"""What a program is (rapid/task.py) and how `fix`/`check` take whole tasks
from the command line: folders, program files, backups, output layout."""

from __future__ import annotations

import json
import re
import shutil

import pytest
from click.testing import CliRunner

from rapidcomp.cli import main
from rapidcomp.errors import InputError, RapidcompError
from rapidcomp.kinematics.profile import parse_profile
from rapidcomp.rapid.task import tasks_of

from conftest import FIXTURES

TASKS = FIXTURES / "tasks"
WARM = str(FIXTURES / "warm.csv")


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def test_a_module_a_folder_a_program_file_and_a_backup():
    (m,) = tasks_of(FIXTURES / "cubes.mod")
    assert (m.kind, m.modules, m.is_folder) == ("module", ("cubes.mod",), False)
    (f,) = tasks_of(TASKS / "cell")
    assert (f.kind, f.name, f.modules) == ("folder", "cell", ("CellData.mod", "MainModule.mod"))
    (p,) = tasks_of(TASKS / "glue" / "Glue.pgf")
    assert (p.kind, p.modules) == ("pgf", ("GlueData.mod", "GlueMain.mod"))
    (b,) = tasks_of(TASKS / "backup_irbt")
    assert (b.kind, b.task) == ("backup", "T_ROB1")
    assert b.modules == ("RAPID/TASK1/PROGMOD/Track.mod", "RAPID/TASK1/SYSMOD/user.sys")
    assert b.notes == ("task T_COMM (RAPID/TASK2) is not a motion task (SYSPAR/SYS.cfg): not "
                       "compensated",)


def test_backup_without_sys_cfg_takes_every_task_and_names_them(tmp_path):
    bk = tmp_path / "bk"
    shutil.copytree(TASKS / "backup_irbt", bk)
    (bk / "SYSPAR" / "SYS.cfg").unlink()
    names = [t.task for t in tasks_of(bk)]
    assert names == ["T_ROB1", "T_COMM"]
    assert [t.task for t in tasks_of(bk, ("t_comm",))] == ["T_COMM"]
    (bk / "BACKINFO" / "backinfo.txt").unlink()
    assert [t.task for t in tasks_of(bk)] == ["TASK1", "TASK2"]


@pytest.mark.parametrize("setup, message", [
    (lambda d: d / "missing.mod", "no such file or folder"),
    (lambda d: (d / "x.txt").write_text("x") and d / "x.txt", "expected a module"),
    (lambda d: d, "no module files"),
])
def test_what_is_not_a_program(tmp_path, setup, message):
    with pytest.raises(RapidcompError, match=message):
        tasks_of(setup(tmp_path))


def test_bad_program_files_name_the_line(tmp_path):
    pgf = tmp_path / "P.pgf"
    pgf.write_text("<Program>\n  <Module>A.mod</Module>\n  <Module>B.mod</Module>\n</Program>\n")
    (tmp_path / "A.mod").write_text("MODULE A\nENDMODULE\n")
    with pytest.raises(InputError) as e:
        tasks_of(pgf)
    assert e.value.format() == f"{pgf}:3: module B.mod listed here does not exist beside the " \
                               "program file"
    pgf.write_text("<Program><Module>A.mod</Module>\n<Module>A.mod")
    with pytest.raises(InputError, match=r"P.pgf:2:\d+: not a program file"):
        tasks_of(pgf)
    with pytest.raises(RapidcompError, match="--task picks tasks of a controller backup"):
        tasks_of(TASKS / "cell", ("T_ROB1",))


def test_folder_output_has_the_input_layout_and_its_report_beside(tmp_path):
    r = run("fix", TASKS / "cell", "--profile", WARM, "-o", tmp_path / "out", "--emit",
            "robtarget", "-q")
    assert r.exit_code == 0, r.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "out.md"]
    report = (tmp_path / "out.md").read_text()
    assert "## CellData.mod" in report and "## MainModule.mod" in report
    assert str(tmp_path) not in report and str(FIXTURES) not in report


def test_default_output_is_beside_the_input_and_never_inside_it(tmp_path):
    cell = tmp_path / "cell"
    shutil.copytree(TASKS / "cell", cell)
    r = run("fix", cell, "--profile", WARM, "-q")
    assert r.exit_code == 0, r.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cell", "cell_comp", "cell_comp.md"]
    before = {p.name: p.read_bytes() for p in cell.iterdir()}
    r = run("fix", cell, "--profile", WARM, "-o", cell / "out")
    assert r.exit_code == 2 and "is inside the input folder" in r.output
    assert {p.name: p.read_bytes() for p in cell.iterdir()} == before
    # Nor its reports: a .mod report there was read back as a module of the
    # task next time (and refused: '#' is no RAPID).
    for option, name in (("--report", "r.mod"), ("--json", "r.json")):
        r = run("fix", cell, "--profile", WARM, "-o", tmp_path / "out", option, cell / name)
        assert r.exit_code == 2 and f"{name}: is inside the input folder" in r.output, r.output
        assert {p.name: p.read_bytes() for p in cell.iterdir()} == before
        assert not (tmp_path / "out").exists()


def test_several_tasks_use_a_folder_and_refuse_one_report_name(tmp_path):
    r = run("fix", TASKS / "cell", TASKS / "glue" / "Glue.pgf", "--profile", WARM,
            "-o", tmp_path / "o", "--report", tmp_path / "r.md")
    assert r.exit_code == 2 and "--report/--json name one file" in r.output
    r = run("fix", TASKS / "cell", TASKS / "glue" / "Glue.pgf", FIXTURES / "cubes.mod",
            "--profile", WARM, "--limit", "J5=-120:120", "-o", tmp_path / "o", "-q")
    assert r.exit_code == 0, r.output
    assert sorted(p.name for p in (tmp_path / "o").iterdir()) == [
        "Glue", "Glue.md", "cell", "cell.md", "cubes.md", "cubes.mod"]


def test_check_json_of_a_folder():
    r = run("check", TASKS / "cell", "--profile", WARM, "--json")
    assert r.exit_code == 0
    doc = json.loads(r.output)
    assert doc["program"] == "cell" and doc["summary"]["compensable"] == 29
    assert {t["file"] for t in doc["targets"]} == {"MainModule.mod"}
    assert all(t["rule"] for t in doc["targets"] if t["status"] == "compensable")


def test_urdf_arm_profile_rows_may_name_joints_j1_to_j6():
    names = ("shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3")
    text = "joint,dx_mm,dy_mm,dz_mm,rx_deg,ry_deg,rz_deg\nJ2,0.01,0,0,0,0.002,0\n" \
           "wrist_3,0,0,0.02,0,0,0\n"
    prof = parse_profile(text, "p.csv", joint_names=names)
    assert prof.get("shoulder_lift").d_mm == (0.01, 0.0, 0.0)
    assert prof.get("wrist_3").d_mm == (0.0, 0.0, 0.02)
    dup = text + "shoulder_lift,0,0,0,0,0,0\n"
    with pytest.raises(InputError, match="duplicate row for shoulder_lift .*name the same joints"):
        parse_profile(dup, "p.csv", joint_names=names)
    with pytest.raises(InputError, match="J1..J6"):
        parse_profile(text + "J7,0,0,0,0,0,0\n", "p.csv", joint_names=names)


def test_a_backup_robot_base_frame_and_other_tasks_writes(tmp_path):
    """SYSPAR/MOC.cfg's base frame is the robot's; a PERS target another
    task writes is a run-time value here too."""
    bk = tmp_path / "bk"
    shutil.copytree(TASKS / "backup_irbt", bk)
    (bk / "SYSPAR" / "MOC.cfg").write_text(
        "MOC:CFG_1.0:6:0::\n#\nROBOT:\n\n      -name \"ROB_1\" -use_robot_type \"ROB1_140\"\\\n"
        "      -base_frame_pos_x 0.1 -base_frame_pos_y -0.02 -base_frame_pos_z 0\\\n"
        "      -base_frame_orient_u0 1 -base_frame_orient_u1 0 -base_frame_orient_u2 0\\\n"
        "      -base_frame_orient_u3 0\n")
    (b,) = tasks_of(bk)
    assert b.base == ((100.0, -20.0, 0.0), (1.0, 0.0, 0.0, 0.0))
    r = run("check", bk, "--profile", WARM, "--track", "a:x", "--json")
    doc = json.loads(r.output)
    assert doc["summary"]["target_uses"] == 12
    # The other task writes the tool: every robtarget move is then untouched.
    comm = bk / "RAPID" / "TASK2" / "PROGMOD" / "Comm.mod"
    comm.write_text(comm.read_text().replace("Incr nTick;", "Incr nTick;\n"
                    "            tProbe.tframe.trans.z := 96;").replace(
                    "    VAR num nTick:=0;", "    VAR num nTick:=0;\n    PERS tooldata tProbe;"))
    r = run("check", bk, "--profile", WARM, "--track", "a:x", "--json")
    doc = json.loads(r.output)
    untouched = doc["summary"]["untouched"]
    assert list(untouched) == [
        "tProbe is assigned in another task at run time (RAPID/TASK2/PROGMOD/Comm.mod:8)"]


def test_output_folders_are_new_or_our_own(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    r = run("fix", TASKS / "cell", "--profile", WARM, "-o", out)
    assert r.exit_code == 2 and "holds files this run would not write (notes.txt)" in r.output
    r = run("fix", TASKS / "cell", "--profile", WARM, "-o", tmp_path / "o.mod")
    assert r.exit_code == 2 and "give a folder name" in r.output
    r = run("fix", TASKS / "cell", "--profile", WARM, "-o", tmp_path / "again", "-q")
    assert r.exit_code == 0
    r = run("fix", TASKS / "cell", "--profile", WARM, "-o", tmp_path / "again", "-q")
    assert r.exit_code == 0     # a run into its own earlier output folder


def test_with_a_module_of_the_task_is_read_once():
    r = run("check", TASKS / "cell", "--with", TASKS / "cell" / "CellData.mod", "--profile", WARM)
    assert r.exit_code == 0 and "more than once" not in r.output


@pytest.mark.parametrize("attribute", ["base_frame_coordinated", "base_frame_moved_by"])
def test_a_backup_whose_base_rides_on_a_track_needs_track(tmp_path, attribute):
    """MOC.cfg: ROB_1 -base_frame_coordinated "TRACK_1" (RobotWare 6; older
    systems: -base_frame_moved_by). Without --track the base position of a
    robtarget is not known: not compensated, naming the option (no
    positioner assumption, no MoveAbsJ frozen at the wrong place); with
    it, everything compensates."""
    bk = tmp_path / "bk"
    shutil.copytree(TASKS / "backup_irbt", bk)
    (bk / "SYSPAR" / "MOC.cfg").write_text(
        "MOC:CFG_1.0:6:0::\n#\nROBOT:\n\n      -name \"ROB_1\" -use_robot_type \"ROB1_140\"\\\n"
        f"      -{attribute} \"TRACK_1\" -base_mass 55.1\n")
    r = run("check", bk, "--profile", WARM, "--json")
    doc = json.loads(r.output)
    assert r.exit_code == 1
    assert any("TRACK_1 moves the robot's base" in n and "--track" in n for n in doc["notes"])
    rob = [t for t in doc["targets"] if t["instruction"] != "MoveAbsJ"]
    assert rob and all("--track AXIS:x|y|z" in t["reason"] for t in rob)
    assert doc["summary"]["compensable"] == 12 - len(rob)
    r = run("check", bk, "--profile", WARM, "--track", "a:x", "--json")
    assert r.exit_code == 0 and json.loads(r.output)["summary"]["compensable"] == 12


def test_moc_values_no_cell_has_are_bad_input(tmp_path):
    bk = tmp_path / "bk"
    shutil.copytree(TASKS / "backup_irbt", bk)
    for bad, says in (("-base_frame_pos_x abc", "-base_frame_pos_x abc is not a number"),
                      ("-base_frame_pos_x 1e300", "within 100 m"),
                      ("-base_frame_orient_u0 0.5", "is not a unit quaternion")):
        (bk / "SYSPAR" / "MOC.cfg").write_text(
            f"MOC:CFG_1.0:6:0::\n#\nROBOT:\n\n      -name \"ROB_1\" {bad}\n")
        r = run("check", bk, "--profile", WARM, "--track", "a:x")
        assert r.exit_code == 2 and "SYSPAR/MOC.cfg" in r.output and says in r.output, r.output


def test_a_moc_cfg_is_read_as_a_controller_writes_it_or_refused(tmp_path):
    """A comment line is no instance (`# old: -name "ROB_OLD" ...` made a
    second robot and the backup was refused); a file an editor saved as
    UTF-16 is the same file; one that is not a configuration file at all
    is bad input (read as one, the robot was taken at the world origin
    without a word)."""
    bk = tmp_path / "bk"
    shutil.copytree(TASKS / "backup_irbt", bk)
    moc = bk / "SYSPAR" / "MOC.cfg"
    text = ("MOC:CFG_1.0:6:0::\n#\nROBOT:\n\n      -name \"ROB_1\" -base_frame_pos_x 0.1\n"
            "# old: -name \"ROB_OLD\" -base_frame_pos_x 5\n")
    moc.write_text(text)
    (b,) = tasks_of(bk)
    assert b.base == ((100.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)) and b.base_problem is None
    for data in (text.encode("utf-16"), b"\xef\xbb\xbf" + text.encode()):   # (an editor's BOMs)
        moc.write_bytes(data)
        (b,) = tasks_of(bk)
        assert b.base == ((100.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0))
    # A type named with digits (UCCM0:) ends the section before it.
    moc.write_text(text + "#\nUCCM0:\n\n      -name \"ROB_1\" -base_frame_pos_x 0.3\n")
    (b,) = tasks_of(bk)
    assert b.base == ((100.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0))
    moc.write_bytes(bytes(range(256)) * 4)
    r = run("check", bk, "--profile", WARM, "--track", "a:x")
    assert r.exit_code == 2 and "MOC.cfg:1: not a controller configuration file" in r.output


@pytest.mark.parametrize("robot, says", [
    ('-name "ROB_1" -base_frame_pos_x 0.1 -base_frame_pos_x 0.2', "-base_frame_pos_x is given twice"),
    ('-name "ROB_1" -base_frame_pos_x 0.1\n\n      -name "ROB_1" -base_frame_pos_x 0.2',
     "ROBOT ROB_1 is defined twice"),
    ('-name "ROB_1" -base_frame_pos_x 1_0', "-base_frame_pos_x 1_0 is not a number"),
    ('-name "ROB_1" -base_frame_pos_x', "-base_frame_pos_x (no value) is not a number"),
])
def test_a_moc_value_a_controller_cannot_have_taken_is_bad_input(tmp_path, robot, says):
    """Which of two values the controller took cannot be told; 1_0 is ten
    to Python, no number to a controller; an attribute without its value
    was read as 0."""
    bk = tmp_path / "bk"
    shutil.copytree(TASKS / "backup_irbt", bk)
    (bk / "SYSPAR" / "MOC.cfg").write_text(f"MOC:CFG_1.0:6:0::\n#\nROBOT:\n\n      {robot}\n")
    r = run("check", bk, "--profile", WARM, "--track", "a:x")
    assert r.exit_code == 2 and "SYSPAR/MOC.cfg" in r.output and says in r.output, r.output


def test_a_backup_without_backinfo_says_so(tmp_path):
    """Without BACKINFO/backinfo.txt the folders TASK1, TASK2 cannot be
    matched to SYS.cfg's tasks: said (it said the backup has no motion
    task holding modules)."""
    bk = tmp_path / "bk"
    shutil.copytree(TASKS / "backup_irbt", bk)
    shutil.rmtree(bk / "BACKINFO")
    r = run("check", bk, "--profile", WARM, "--track", "a:x")
    assert r.exit_code == 2 and "BACKINFO/backinfo.txt is missing" in r.output, r.output
    assert "(TASK1, TASK2) cannot be matched to the motion tasks" in r.output
    (bk / "BACKINFO").mkdir()
    (bk / "BACKINFO" / "backinfo.txt").write_bytes(bytes(range(256)))
    r = run("check", bk, "--profile", WARM, "--track", "a:x")
    assert r.exit_code == 2 and "backinfo.txt names no task" in r.output, r.output


def test_a_program_file_error_names_its_modules_line(tmp_path):
    """A module named "." is on line 3 (the name is also in the XML
    declaration, on line 1)."""
    (tmp_path / "P.pgf").write_text('<?xml version="1.0" encoding="ISO-8859-1" ?>\n'
                                    "<Program>\n    <Module>.</Module>\n</Program>\n")
    r = run("check", tmp_path / "P.pgf", "--profile", WARM)
    assert r.exit_code == 2 and "P.pgf:3: module . listed here" in r.output, r.output


@pytest.mark.parametrize("declared, says", [
    ("ISO-2147483648-1", "P.pgf:1: not a program file (XML: unknown encoding: "
                         "ISO-2147483648-1); expected the encoding a controller writes"),
    ("utf-16", "P.pgf:1:31: not a program file (XML: encoding specified in XML declaration is "
               "incorrect)"),
])
def test_a_program_file_in_an_encoding_it_is_not_is_bad_input(tmp_path, declared, says):
    """An XML declaration naming an encoding Python does not know (a digit
    changed in ISO-8859-1), or one its bytes are not: exit 2 with the
    line, not the XML parser's traceback."""
    (tmp_path / "P.pgf").write_bytes(f'<?xml version="1.0" encoding="{declared}" ?>\n'
                                     "<Program>\n    <Module>A.mod</Module>\n</Program>\n"
                                     .encode())
    r = run("check", tmp_path / "P.pgf", "--profile", WARM)
    assert r.exit_code == 2 and says in r.output, r.output
    assert "Traceback" not in r.output


def test_a_compensated_program_is_recognised(tmp_path):
    """Compensating rapidcomp's own output adds the correction twice: the
    names it gives its values (jt_..., ..._c) are recognised and said."""
    out = tmp_path / "out"
    assert run("fix", TASKS / "cell", "--profile", WARM, "-o", out, "-q").exit_code == 0
    r = run("check", out, "--profile", WARM)
    assert "looks compensated already (jt_pGlue_1, jt_pPlace_offs are the names" in r.output
    assert "looks compensated" not in run("check", TASKS / "cell", "--profile", WARM).output


def test_a_compensated_program_with_inline_targets_only_is_recognised(tmp_path):
    """RoboDK writes every target inline: its compensated output gives no
    new name, only its file's (PROGRAM_comp.mod, the default output name)
    tells; the original's name does not."""
    shutil.copy(FIXTURES / "rapid" / "robodk.mod", tmp_path / "robodk.mod")
    first = run("fix", tmp_path / "robodk.mod", "--profile", WARM, "--allow-partial")
    assert first.exit_code == 1 and "looks compensated" not in first.output
    again = run("check", tmp_path / "robodk_comp.mod", "--profile", WARM)
    assert ("looks compensated already (robodk_comp.mod named as rapidcomp names its output)"
            in again.output), again.output
    # A task folder written by fix is named so too; so are a backup's
    # output folder and a program file's (found by a review: their task is
    # named otherwise).
    out = tmp_path / "cell_comp"
    assert run("fix", TASKS / "cell", "--profile", WARM, "-o", out, "-q").exit_code == 0
    assert "cell_comp named as rapidcomp names its output" in run(
        "check", out, "--profile", WARM).output
    shutil.copytree(TASKS / "backup_irbt", tmp_path / "backup_irbt")
    assert run("fix", tmp_path / "backup_irbt", "--profile", WARM, "--track", "a:x",
               "-q").exit_code == 0
    assert "backup_irbt_comp named as rapidcomp names its output" in run(
        "check", tmp_path / "backup_irbt_comp", "--profile", WARM, "--track", "a:x").output
    shutil.copytree(TASKS / "glue", tmp_path / "glue")
    assert run("fix", tmp_path / "glue" / "Glue.pgf", "--profile", WARM, "-q").exit_code == 0
    assert "Glue_comp named as rapidcomp names its output" in run(
        "check", tmp_path / "glue" / "Glue_comp" / "Glue.pgf", "--profile", WARM).output
    assert "looks compensated" not in run("check", tmp_path / "glue" / "Glue.pgf", "--profile",
                                          WARM).output


@pytest.mark.parametrize("elsewhere", [
    "PERS tooldata tG;",                                                    # takes B's value
    "PERS tooldata tG:=[TRUE,[[0,0,100],[1,0,0,0]],[1,[0,0,50],[1,0,0,0],0,0,0]];",  # the same
    "PERS tooldata tG:=[TRUE,[[0,0,120],[1,0,0,0]],[1,[0,0,50],[1,0,0,0],0,0,0]];",  # another
])
def test_a_pers_declared_without_a_value_takes_the_one_another_module_gives(tmp_path,
                                                                            elsewhere):
    """PERS of one name are one object: a declaration without a value
    takes the value another module declares it with, so the move is
    compensated exactly as with that module's declaration alone (the same
    error, the same written numbers); two different values are a load-order
    question and stay refused."""
    def task(folder, decl_a):
        folder.mkdir()
        (folder / "A.mod").write_text(
            f"MODULE A\n    {decl_a}\n"
            "    CONST robtarget p10:=[[522.217,0,335.289],[0,0,1,0],[0,0,0,0],"
            "[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
            "    PROC main()\n        MoveL p10, v100, fine, tG;\n    ENDPROC\nENDMODULE\n")
        (folder / "B.mod").write_text(
            "MODULE B\n    PERS tooldata tG:=[TRUE,[[0,0,100],[1,0,0,0]],[1,[0,0,50],"
            "[1,0,0,0],0,0,0]];\nENDMODULE\n")
        return folder
    alone = run("fix", task(tmp_path / "alone", "VAR num nOther;"), "--profile", WARM,
                "-o", tmp_path / "alone_out", "--json", tmp_path / "alone.json")
    got = run("fix", task(tmp_path / "two", elsewhere), "--profile", WARM,
              "-o", tmp_path / "two_out", "--json", tmp_path / "two.json")
    if "120" in elsewhere:
        assert got.exit_code == 1, got.output
        assert "tG is declared PERS with different values (A.mod:2, B.mod:2)" in got.output
        return
    assert alone.exit_code == got.exit_code == 0, got.output
    rows = [json.loads((tmp_path / f"{n}.json").read_text())["targets"] for n in ("alone", "two")]
    assert [r["error_um"] for r in rows[0]] == [r["error_um"] for r in rows[1]]
    out = [(tmp_path / f"{n}_out" / "A.mod").read_text().splitlines()[2:] for n in ("alone",
                                                                                "two")]
    assert out[0] == out[1] and out[0] != (tmp_path / "two" / "A.mod").read_text().splitlines()[2:]


@pytest.mark.parametrize("a, b, refused", [
    ("PROC Pick()\n    ENDPROC", "PROC Pick()\n    ENDPROC", True),
    ("VAR num n:=1;", "VAR num n:=2;", True),
    ("VAR num Pick:=1;", "PROC pick()\n    ENDPROC", True),
    ("PERS num n:=1;", "PERS string n:=\"\";", True),
    ("PERS num n:=1;", "PERS num n:=1;", False),
    ("LOCAL PROC Pick()\n    ENDPROC", "PROC Pick()\n    ENDPROC", False),
])
def test_a_global_name_in_two_modules_of_a_task_is_bad_input(tmp_path, a, b, refused):
    """The controller loads a task whose global names are each declared
    once (PERS of one type are one shared object; LOCAL ones are their
    module's): any other clash is bad input naming both places, nothing
    written."""
    task = tmp_path / "cell"
    task.mkdir()
    (task / "A.mod").write_text(f"MODULE A\n    {a}\n    PROC main()\n        MoveAbsJ "
                                "[[0,0,0,0,30,0],[9E9,9E9,9E9,9E9,9E9,9E9]],v100,fine,tool0;\n"
                                "    ENDPROC\nENDMODULE\n")
    (task / "B.mod").write_text(f"MODULE B\n    {b}\nENDMODULE\n")
    r = run("fix", task, "--profile", WARM, "-o", tmp_path / "out")
    if refused:
        assert r.exit_code == 2, r.output
        # (file:line:col of the second declaration, its line under it.)
        assert re.search(r"B\.mod:2:\d+: \S+ is declared globally in two modules \(also ",
                         r.output) and "A.mod:2)" in r.output, r.output
        assert r.output.splitlines()[1].strip() == b.splitlines()[0].strip(), r.output
        assert not (tmp_path / "out").exists()
    else:
        assert r.exit_code == 0, r.output


def test_two_modules_of_one_program_file_that_clash_are_refused_as_two_files_are(tmp_path):
    """An old .prg holds several modules: a global name in two of them is
    the same clash as in two files."""
    prg = tmp_path / "cell.prg"
    prg.write_text("MODULE A\n    VAR num n:=1;\n    PROC main()\n    ENDPROC\nENDMODULE\n"
                   "MODULE B\n    VAR num n:=2;\nENDMODULE\n")
    r = run("check", prg, "--profile", WARM)
    assert r.exit_code == 2 and "n is declared globally in two modules (also " in r.output, \
        r.output


def test_a_task_folder_holding_fix_output_says_so(tmp_path):
    """`fix` on a program file writes PROGRAM_comp beside it, inside the
    task's folder: `fix` on the folder then meets every module twice and
    refuses (the controller would), naming the output folder as what to
    move; a module copied twice elsewhere is refused without that hint."""
    glue = tmp_path / "glue"
    shutil.copytree(TASKS / "glue", glue)
    r = run("fix", glue / "Glue.pgf", "--profile", WARM, "--allow-partial")
    assert r.exit_code in (0, 1) and (glue / "Glue_comp").is_dir(), r.output
    r = run("check", glue, "--profile", WARM)
    assert r.exit_code == 2, r.output
    assert ("a task holds each module once (the controller refuses to load it twice); give "
            "the program file (.pgf) or a folder without the copy (Glue_comp is named as "
            "`rapidcomp fix` names its output: move it out of the task's folder)") in r.output
    shutil.rmtree(glue / "Glue_comp")
    (glue / "spare").mkdir()
    shutil.copy(glue / "GlueData.mod", glue / "spare" / "GlueData.mod")
    r = run("check", glue, "--profile", WARM)
    assert r.exit_code == 2 and "give the program file (.pgf) or a folder without the copy\n" \
        in r.output.replace("\r", ""), r.output


def test_a_target_local_to_another_module_is_said_so(tmp_path):
    """A move naming a target another module of the task declares LOCAL:
    the controller does not load such a task (its module does not see the
    name); said so, with where it is declared, not that a module is
    missing. 12 such moves: one line in the summary. A name no module
    declares still asks for the rest of the task."""
    target = ("[[400,300,250],[0.707107,0,0.707107,0],[0,0,-1,1],"
              "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]")
    folder = tmp_path / "cell"
    folder.mkdir()
    (folder / "Data.mod").write_text(
        "MODULE Data\n" + "".join(f"  LOCAL CONST robtarget p{k}:={target};\n" for k in range(12))
        + "ENDMODULE\n")
    (folder / "Main.mod").write_text(
        "MODULE Main\n  PROC main()\n" + "".join(f"    MoveL p{k},v100,fine,tool0;\n"
                                                 for k in range(12))
        + "    MoveL q9,v100,fine,tool0;\n  ENDPROC\nENDMODULE\n")
    r = CliRunner().invoke(main, ["fix", str(folder), "--profile", str(FIXTURES / "warm.csv"),
                                  "-o", str(tmp_path / "out")])
    assert r.exit_code == 1, r.output
    lines = [line.strip() for line in r.output.splitlines() if "not compensated" in line]
    assert lines[1] == (
        "not compensated (12 alike, each with target and numbers of its own; as Main.mod:3): "
        "p0 is declared LOCAL in another module (Data.mod:2), which alone sees it: the "
        "controller does not load this task (a reference error) [Main.mod lines 3-14]")
    assert lines[2] == ("not compensated: Main.mod:15 MoveL q9: q9 is not declared in the given "
                        "modules (give the whole task: its folder, program file or backup, or "
                        "the declaring module with --with)")
    assert not (tmp_path / "out").exists()


def test_an_encrypted_module_of_a_task_is_taken_as_not_given(tmp_path):
    """A task folder with an encrypted library (the controller loads it,
    rapidcomp cannot read it): not refused. Its module is taken as not
    given: a move whose tool only it can declare is left as written and
    says so, the flow is unknown after a call of its routine, the other
    moves are compensated, a note says what the unread module means, and
    the output holds it byte for byte. A module given alone that is
    encrypted stays bad input; inspect lists the folder's others."""
    cell = tmp_path / "cell"
    cell.mkdir()
    lib = (FIXTURES / "invalid" / "encrypted.mod").read_bytes()
    (cell / "Lib.mod").write_bytes(lib)
    (cell / "Main.mod").write_text(
        "MODULE Main\n"
        "  CONST robtarget pA:=[[500,0,400],[0,0,1,0],[0,-1,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
        "  CONST robtarget pB:=[[500,100,400],[0,0,1,0],[0,-1,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
        "  PROC main()\n"
        "    MoveL pA, v100, fine, tool0;\n"
        "    MoveL pB, v100, fine, tLib;\n"
        "    LibRoutine;\n"
        "    MoveL pA, v100, fine, tool0;\n"
        "  ENDPROC\n"
        "ENDMODULE\n")
    out = tmp_path / "out"
    r = run("fix", str(cell), "--profile", WARM, "-o", str(out))
    assert r.exit_code == 0, r.output
    assert "2 of 3 target uses compensated, 0 not compensated, 1 untouched" in r.output
    assert ("untouched (1): tool tLib is not declared in the modules rapidcomp can read (it may "
            "be in Lib.mod, which is encrypted); left as written [line 6]") in r.output
    assert "note: Lib.mod is encrypted: rapidcomp cannot read it and takes it as a module not " \
        "given" in r.output
    assert "LibRoutine (Main.mod:7)" in r.output
    assert (out / "Lib.mod").read_bytes() == lib
    assert "MoveL pB, v100, fine, tLib;" in (out / "Main.mod").read_text()
    r = run("fix", str(cell / "Lib.mod"), "--profile", WARM)
    assert r.exit_code == 2 and "binary or encrypted module" in r.output
    r = run("inspect", str(cell))
    assert r.exit_code == 0 and "MODULE Main" in r.output
    assert "Lib.mod:2:6: binary or encrypted module" in r.output
    assert "not read; check and fix take it as a module not given" in r.output
    # A MoveJ with a PERS tool the encrypted module may change stays a
    # robtarget move under --emit absj (which follows the change); one with
    # a CONST tool becomes MoveAbsJ.
    (cell / "Main.mod").write_text(
        "MODULE Main\n"
        "  PERS tooldata tGrip:=[TRUE,[[0,0,100],[1,0,0,0]],[1,[0,0,50],[1,0,0,0],0,0,0]];\n"
        "  CONST tooldata tFix:=[TRUE,[[0,0,100],[1,0,0,0]],[1,[0,0,50],[1,0,0,0],0,0,0]];\n"
        "  CONST robtarget pA:=[[500,0,400],[0,0,1,0],[0,-1,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
        "  CONST robtarget pB:=[[500,100,400],[0,0,1,0],[0,-1,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
        "  PROC main()\n    MoveJ pA, v100, fine, tGrip;\n    MoveJ pB, v100, fine, tFix;\n"
        "  ENDPROC\nENDMODULE\n")
    out2 = tmp_path / "out2"
    r = run("fix", str(cell), "--profile", WARM, "--emit", "absj", "-o", str(out2))
    assert r.exit_code == 0, r.output
    written = (out2 / "Main.mod").read_text()
    assert "    MoveJ pA, v100, fine, tGrip;" in written
    assert "    MoveAbsJ jt_pB, v100, fine, tFix;" in written
    assert ("kept as MoveJ: its tool tGrip is PERS data Lib.mod, which is encrypted, may change"
            in (tmp_path / "out2.md").read_text())
    # Every module encrypted: nothing to compensate, bad input.
    only = tmp_path / "only"
    only.mkdir()
    (only / "Lib.mod").write_bytes(lib)
    r = run("check", str(only), "--profile", WARM)
    assert r.exit_code == 2 and "every module of this task is encrypted" in r.output
    # A text module with a stray control byte is a text to mend, not an
    # encrypted one to pass over: bad input, as before.
    (cell / "Main.mod").write_text((cell / "Main.mod").read_text() + "\x1a")
    r = run("check", str(cell), "--profile", WARM)
    assert r.exit_code == 2 and "Main.mod:11:1: binary or encrypted module" in r.output


def test_a_backup_task_is_the_modules_backinfo_lists(tmp_path):
    """A restore loads the modules BACKINFO/backinfo.txt lists for a task
    (`PROGMOD\\Main.mod @ `, '\\' or '/', any case, attributes after '@'):
    a module file of the folder it does not list (a copy someone left
    there, declaring MODULE Track again: two modules of one name, refused,
    were it read) is not read, and one it lists that the backup lacks is
    read without; each said in a note. Without a list (a task line and no
    module lines) every module file is read."""
    bk = tmp_path / "bk"
    shutil.copytree(TASKS / "backup_irbt", bk)
    prog = bk / "RAPID" / "TASK1" / "PROGMOD"
    shutil.copy(prog / "Track.mod", prog / "Track_old.mod")
    info = bk / "BACKINFO" / "backinfo.txt"
    text = info.read_text()
    info.write_text(text.replace("SYSMOD/user.sys\nPROGMOD/Track.mod\n",
                                 "SYSMOD\\user.sys @ \nPROGMOD\\TRACK.MOD @ \n"
                                 "SYSMOD\\LINKEDM.sys @ HIDDEN\n"))
    (b,) = tasks_of(bk)
    assert b.modules == ("RAPID/TASK1/PROGMOD/Track.mod", "RAPID/TASK1/SYSMOD/user.sys")
    assert b.notes[1:] == (
        "RAPID/TASK1/PROGMOD/Track_old.mod is not among task T_ROB1's modules that "
        "BACKINFO/backinfo.txt lists (a restore does not load it): not read",
        "RAPID/TASK1/SYSMOD/LINKEDM.sys, which BACKINFO/backinfo.txt lists among task "
        "T_ROB1's modules, is not in the backup: read without it")
    r = run("check", bk, "--profile", WARM)
    assert r.exit_code in (0, 1) and "Track_old.mod is not among" in r.output, r.output
    # (inspect reads the task as check and fix do, and says so.)
    r = run("inspect", bk)
    assert r.exit_code == 0 and "MODULE Track\n" in r.output and r.output.count("MODULE ") == 3
    assert "note: RAPID/TASK1/PROGMOD/Track_old.mod is not among" in r.output
    assert "note: RAPID/TASK1/SYSMOD/LINKEDM.sys, which" in r.output
    # (Saved as UTF-8, a list naming an accented module names its file.)
    (prog / "Prüfung.mod").write_text("MODULE Pruefung\nENDMODULE\n")
    info.write_bytes(info.read_text().replace("PROGMOD\\TRACK.MOD @ \n",
                                              "PROGMOD\\TRACK.MOD @ \nPROGMOD\\Prüfung.mod @ \n")
                     .encode("utf-8"))
    (b,) = tasks_of(bk)
    assert "RAPID/TASK1/PROGMOD/Prüfung.mod" in b.modules
    info.write_text(text.replace("SYSMOD/user.sys\nPROGMOD/Track.mod\n", ""))
    r = run("check", bk, "--profile", WARM)
    assert r.exit_code == 2 and "module Track is also in" in r.output, r.output
    assert ("refuses to load it twice); take the copy out of the backup, or list the task's "
            "modules in its BACKINFO/backinfo.txt as the controller wrote it") in r.output


def test_a_backinfo_list_of_none_of_the_backups_modules_is_bad_input(tmp_path):
    """backinfo.txt lists modules of which the task's folder holds none (a
    list from another backup, a review's): a restore would load none; said,
    exit 2, not a task silently gone."""
    bk = tmp_path / "bk"
    shutil.copytree(TASKS / "backup_irbt", bk)
    info = bk / "BACKINFO" / "backinfo.txt"
    info.write_text(info.read_text().replace("SYSMOD/user.sys\nPROGMOD/Track.mod\n",
                                             "PROGMOD/Track_v2.mod @ \nSYSMOD/user_old.sys @\n"))
    r = run("check", bk, "--profile", WARM)
    assert r.exit_code == 2, r.output
    assert ("BACKINFO/backinfo.txt lists PROGMOD/Track_v2.mod, SYSMOD/user_old.sys as task "
            "T_ROB1's modules, none of which RAPID/TASK1 holds (it holds PROGMOD/Track.mod, "
            "SYSMOD/user.sys)") in r.output


def test_a_name_declared_only_in_an_unlisted_module_says_where_it_may_be(tmp_path):
    """The tool is declared in SYSMOD/user.sys, which backinfo.txt does not
    list (a new user's): not read, as a restore does not load it; the rows
    name it as where the tool may be, not 'give the whole task' (the
    backup was given whole)."""
    bk = tmp_path / "bk"
    shutil.copytree(TASKS / "backup_irbt", bk)
    info = bk / "BACKINFO" / "backinfo.txt"
    info.write_text(info.read_text().replace("SYSMOD/user.sys\n", ""))
    r = run("check", bk, "--profile", WARM, "--track", "a:x")
    assert r.exit_code == 1, r.output
    assert ("not compensable: tool tProbe is not declared in the modules the backup's "
            "BACKINFO/backinfo.txt lists (it may be in RAPID/TASK1/SYSMOD/user.sys, which it "
            "does not list, so a restore does not load it either") in r.output, r.output
    assert "give the whole task" not in r.output
