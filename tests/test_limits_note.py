"""A program that goes beyond the joint limits as written: a program the
controller runs is within its own limits, so the limits rapidcomp used are
not the controller's. fix and check say which joint, by how much, what the
limits were and where they came from (the user's --limit or the model's
own), and how to give the controller's. The amounts are the jointtargets'
own numbers less the limits, worked out by hand here."""

from __future__ import annotations

from click.testing import CliRunner

from rapidcomp.cli import main

from conftest import FIXTURES

WARM = str(FIXTURES / "warm.csv")
# MoveAbsJ to J1 = 30 deg and J5 = 118 deg as written; a MoveL within every
# limit. (J1 -10..10 by --limit: 20 deg beyond; the IRB 140 model's J5
# -115..115: 3 deg beyond.)
PROGRAM = """MODULE Lim
  CONST jointtarget jFar:=[[30,0,0,0,45,0],[9E9,9E9,9E9,9E9,9E9,9E9]];
  CONST jointtarget jBent:=[[0,10,10,0,118,0],[9E9,9E9,9E9,9E9,9E9,9E9]];
  CONST jointtarget jNear:=[[0,0,0,0,45,0],[9E9,9E9,9E9,9E9,9E9,9E9]];
  PROC main()
    MoveAbsJ jFar, v100, fine, tool0;
    MoveAbsJ jBent, v100, fine, tool0;
    MoveAbsJ jNear, v100, fine, tool0;
  ENDPROC
ENDMODULE
"""


def _note(output: str) -> list[str]:
    return [line for line in output.splitlines() if "goes beyond the joint limits" in line]


def _run(tmp_path, command: str, *args: str, program: str = PROGRAM):
    """`rapidcomp COMMAND program ARGS` (fix: -o out.mod) and the output's path."""
    src = tmp_path / "lim.mod"
    src.write_text(program)
    out = tmp_path / "out.mod"
    more = ["-o", str(out)] if command == "fix" else []
    return CliRunner().invoke(main, [command, str(src), "--profile", WARM, *args, *more]), out


def test_fix_names_the_joint_the_amount_and_the_limit_option(tmp_path):
    r, out = _run(tmp_path, "fix", "--limit", "J1=-10:10")
    assert r.exit_code == 1, r.output
    assert not out.exists()
    note, = _note(r.output)
    assert "J1 at 1 target, by up to 20 deg (its limits -10..10 deg, set by --limit J1=-10:10)" \
        in note
    assert "J5 at 1 target, by up to 3 deg (its limits -115..115 deg, the IRB140 model's own)" \
        in note
    assert ("if this one runs, --limit J1=-10:10 is narrower than the controller's: give the "
            "controller's own limits with --limit JOINT=LOWER:UPPER") in note


def test_check_says_the_same(tmp_path):
    r, _ = _run(tmp_path, "check", "--limit", "J1=-10:10", "--limit", "J5=-120:120")
    note, = _note(r.output)
    assert "J1 at 1 target, by up to 20 deg (its limits -10..10 deg, set by --limit " \
        "J1=-10:10)" in note
    assert "J5" not in note.split(". The controller")[0]


def test_no_note_within_the_limits(tmp_path):
    r, out = _run(tmp_path, "fix", "--limit", "J5=-120:120")
    assert r.exit_code == 0, r.output
    assert _note(r.output) == []
    assert _note(out.with_suffix(".md").read_text()) == []


def test_a_target_beyond_two_limits_names_both(tmp_path):
    """J1 = 30 (20 deg beyond --limit J1=-10:10) and J5 = 118 (3 deg beyond
    the model's 115) in one jointtarget: its row and the note name both,
    the worse first, each with its amount and its limits' source."""
    r, _ = _run(tmp_path, "check", "--limit", "J1=-10:10",
                program=PROGRAM.replace("[[30,0,0,0,45,0]", "[[30,0,0,0,118,0]"))
    assert "MoveAbsJ jFar: nominal: J1 beyond its limit by 20.0000 deg, J5 by 3.0000 deg" \
        in r.output, r.output
    note, = _note(r.output)
    assert "J1 at 1 target, by up to 20 deg" in note
    # (jFar and jBent both beyond J5.)
    assert "J5 at 2 targets, by up to 3 deg (its limits -115..115 deg, the IRB140 model's own)" \
        in note


def test_a_limit_only_the_compensation_crosses(tmp_path):
    """A J2 limit the paper's points reach within as written but their
    compensated joints cross: refused (the robot cannot go there), and the
    note says it is the compensation that needs it, not the program."""
    r = CliRunner().invoke(main, ["check", str(FIXTURES / "cubes.mod"), "--profile", WARM,
                                  "--limit", "J2=-90:68.197", "--limit", "J5=-120:120"])
    refused = [line for line in r.output.splitlines()
               if line.startswith("  not compensable:") and "J2 beyond its limit by" in line]
    assert refused and not any("nominal:" in line for line in refused)
    assert _note(r.output) == []
    note = next(line for line in r.output.splitlines()
                if "the compensation needs joints beyond their limits" in line)
    assert (f"J2 at {len(refused)} target{'s' if len(refused) != 1 else ''}, by up to"
            in note)
    assert "(its limits -90..68.197 deg, set by --limit J2=-90:68.197)" in note


def test_a_urdf_robots_limits_are_its_files(tmp_path):
    r, _ = _run(tmp_path, "check", "--robot", str(FIXTURES / "robots" / "irb140.urdf"))
    note, = _note(r.output)
    assert "J5 at 1 target, by up to 3 deg (its limits -115..115 deg, the <limit> of " \
        "irb140.urdf)" in note
    assert "narrower" not in note


def test_out_of_reach_with_supervision_off_is_not_a_limit(tmp_path):
    """A target 2 m from the base (the IRB 140 reaches 0.81 m) after
    ConfL\\Off, where the controller takes the solution closest to the
    robot: no branch has any solution, so it is out of reach, as with
    supervision on, and no note blames the joint limits."""
    src = tmp_path / "reach.mod"
    src.write_text("""MODULE reach
  CONST robtarget pFar:=[[2000,0,500],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];
  CONST robtarget pNear:=[[500,0,500],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];
  PROC main()
    MoveJ pNear,v100,fine,tool0;
    ConfL\\Off;
    MoveL pFar,v100,fine,tool0;
  ENDPROC
ENDMODULE
""")
    r = CliRunner().invoke(main, ["check", str(src), "--profile", WARM])
    assert "line 7 MoveL pFar: nominal: out of reach by" in r.output, r.output
    assert "limit" not in r.output.split("line 7 MoveL pFar:")[1].splitlines()[0]
    assert _note(r.output) == []


def test_a_limit_inside_a_reason_with_two_cases_counts(tmp_path):
    """pS21 of the paper's side cube (J5 = 116.9 deg, beyond the model's
    115) after `IF nX = 1 ConfL\\Off;`: its reason gives both cases of the
    supervision, and the J5 limit inside it is in the note."""
    text = (FIXTURES / "cubes.mod").read_text()
    text = text.replace("    PROC main()", "    VAR num nX:=0;\n    PROC main()", 1)
    text = text.replace("        MoveL pS21,", "        IF nX = 1 ConfL\\Off;\n        MoveL pS21,", 1)
    src = tmp_path / "cubes2.mod"
    src.write_text(text)
    r = CliRunner().invoke(main, ["check", str(src), "--profile", WARM])
    row = next(line for line in r.output.splitlines()
               if line.startswith("  not compensable:") and "pS21" in line)
    assert "ConfL may be on or off here" in row and "J5 beyond its limit by 1.9134 deg" in row
    note, = _note(r.output)
    assert "J5 at 1 target, by up to 1.913 deg" in note
