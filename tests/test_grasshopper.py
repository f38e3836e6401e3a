"""Programs as the Grasshopper plugin Robots writes them for an ABB robot:
every target inline, its external axes the data `extj` (a VAR extjoint of
9E9s declared at the top of the module), a MoveL's confdata the data `conf`
(under ConfL\\Off the controller does not read it): `[[x,y,z],[q],conf,extj]`,
`[[x,y,z],[q],[cf],extj]` and `[[j1,..,j6],extj]`. The literal numbers are
compensated, the names stay, and the compensated program, run by the
independent controller model (controller.py) on the warm robot, lands every
move where the input sends the ideal one; where the data may change at run
time, the move is left as written, and where a named confdata would have to
change (a move under configuration supervision), it is not compensated; the
report says why."""

from __future__ import annotations

import numpy as np
import pytest

from rapidcomp.rapid.parse import parse_file

import test_robodk_frames as RF
from test_real_programs import evaluate, rapidcomp
from test_robodk_frames import FRAMES, Q, TOOLS, pose_text, target


def program(moves: list[str], extra: str = "") -> str:
    tool, frame = pose_text(TOOLS["T1"]), pose_text(FRAMES["U1"])
    return "\n".join([
        "MODULE GH_T_ROB1",
        "VAR extjoint extj := [9E9,9E9,9E9,9E9,9E9,9E9];",
        "VAR confdata conf := [0,0,0,0];",
        f"PERS tooldata Tool1:=[TRUE,{tool},[0.001,[0,0,0.001],[1,0,0,0],0,0,0]];",
        f"TASK PERS wobjdata Frame1:=[FALSE,TRUE,\"\",{frame},[[0,0,0],[1,0,0,0]]];",
        "TASK PERS speeddata Speed000:=[300,180,5000,1080];",
        "PROC Main()", "ConfL \\Off;", extra,
        f"MoveAbsJ [[{','.join(f'{a:g}' for a in Q[0])}],extj],Speed000,fine,Tool1;",
        *moves, "ENDPROC", "ENDMODULE", ""])


def move(kind: str, i: int, ext: str = "extj", conf: str | None = None) -> str:
    text = target(i, "T1", "U1")
    text = text[:text.rindex(",[")] + "," + ext + "]"
    if conf is not None:
        head = text[:text.rindex("],[", 0, text.rindex(","))]
        text = head + "]," + conf + "," + ext + "]"
    return f"{kind} {text},Speed000,fine,Tool1 \\WObj:=Frame1;"


MOVES = [move("MoveJ", 1), move("MoveL", 2, conf="conf"), move("MoveL", 3, conf="conf"),
         move("MoveJ", 4)]


@pytest.mark.parametrize("mode", ["auto", "absj", "robtarget"])
def test_targets_whose_external_axes_are_named_data_are_compensated(mode, tmp_path):
    src = tmp_path / "GH.mod"
    src.write_text(program(MOVES))
    out = tmp_path / "out.mod"
    r = rapidcomp("fix", src, "--profile", "fixtures/warm.csv", "-o", out, "--emit", mode)
    assert "5 of 5 target uses compensated" in r.stdout, r.stdout
    before, after = src.read_text().splitlines(), out.read_text().splitlines()
    # (The same lines, the moves' numbers only changed: each keeps its kind
    # (a MoveAbsJ would write the value of extj, not follow the name) and
    # names extj.)
    assert len(before) == len(after)
    for a, b in zip(before, after):
        if a != b:
            assert a.split(" ")[0] == b.split(" ")[0] and b.count(",extj]") == 1, (a, b)
            assert (",conf,extj]" in a) == (",conf,extj]" in b), (a, b)
    assert sum(a != b for a, b in zip(before, after)) == 5
    rows = evaluate([parse_file(src, src.name)], [parse_file(out, src.name)], entry="Main")
    assert len(rows) == 5


def test_named_data_that_may_change_leave_the_move_as_written(tmp_path):
    src = tmp_path / "GH.mod"
    # (extj is given a value at run time.)
    src.write_text(program([move("MoveL", 2), move("MoveL", 3, conf="conf")],
                           extra="extj.eax_a := 100;"))
    out = tmp_path / "out.mod"
    r = rapidcomp("fix", src, "--profile", "fixtures/warm.csv", "-o", out, "--allow-partial")
    assert "0 of 3 target uses compensated, 0 not compensated, 3 untouched" in r.stdout, r.stdout
    assert "its external axes are extj, which is assigned at run time (GH.mod:9)" in r.stdout
    assert out.read_text() == src.read_text()


def test_a_named_confdata_that_would_have_to_change_is_not_compensated(tmp_path, monkeypatch):
    """A MoveJ under configuration supervision (ConfJ\\On, as the program
    starts) whose confdata is the data conf, taught with J4 at 0: the
    compensated joints lie a hundredth of a degree into the next quadrant,
    which conf, shared by other moves, cannot say. Not compensated, said
    why; the MoveL beside it, under ConfL\\Off, keeps conf and is."""
    monkeypatch.setattr(RF, "Q", np.vstack([Q, [[5, 25, 10, 0, -60, 20]]]))
    mine = move("MoveJ", len(Q))
    cf = mine[mine.index("],[", mine.index("],[") + 3) + 3:]
    cf = "[" + cf[:cf.index("]")] + "]"
    src = tmp_path / "GH.mod"
    text = program([move("MoveL", 2, conf="conf"), mine.replace(cf + ",extj]", "conf,extj]")])
    src.write_text(text.replace("conf := [0,0,0,0]", f"conf := {cf}"))
    out = tmp_path / "out.mod"
    r = rapidcomp("fix", src, "--profile", "fixtures/warm.csv", "-o", out, "--allow-partial",
                  check=False)
    assert r.returncode == 1 and "2 of 3 target uses compensated, 1 not compensated" in r.stdout, \
        r.stdout + r.stderr
    assert f"its confdata is the data conf ({cf}), which other moves share: the compensated " \
        "joints need" in r.stdout, r.stdout
    before, after = src.read_text().splitlines(), out.read_text().splitlines()
    assert [b for a, b in zip(before, after) if a != b and "MoveJ" in a] == []


def test_transient_keeps_the_name_of_the_external_axes(tmp_path, monkeypatch):
    """--transient writes each target as rcTcR/rcTcJ(as written, correction):
    the one written again (its confdata changes: a MoveJ taught with J4 at
    0, compensated a hundredth of a degree below) names extj as the input
    does, and the output verifies at every thermal state."""
    monkeypatch.setattr(RF, "Q", np.vstack([Q, [[5, 25, 10, 0, -60, 20]]]))
    src = tmp_path / "GH.mod"
    src.write_text(program(MOVES + [move("MoveJ", len(Q))]))
    out = tmp_path / "out.mod"
    r = rapidcomp("fix", src, "--profile", "fixtures/warm.csv", "-o", out, "--transient",
                  "--tau-heat", "30")
    assert "6 of 6 target uses compensated" in r.stdout, r.stdout
    changed = [b for a, b in zip(src.read_text().splitlines(), out.read_text().splitlines())
               if a != b]
    assert len(changed) == 6
    # (The MoveJ at J4 = 0 written again with its new confdata.)
    assert "[0,0,0,1]" not in changed[-1] and "[0,-1,0,1]" in changed[-1], changed[-1]
    assert all(("rcTcR(" in b or "rcTcJ(" in b) and b.count(",extj]") == 1 for b in changed)
    assert "9E9" not in "".join(changed)


@pytest.mark.parametrize("extra,said", [
    ("Add extj.eax_a, 100;", "its external axes are extj, which is changed by Add at run time "
     "(GH.mod:9)"),
    ("Incr extj.eax_b;", "its external axes are extj, which is changed by Incr at run time "
     "(GH.mod:9)"),
    ("TPReadNum extj.eax_a, \"Track?\";", "its external axes are extj, which is filled by "
     "TPReadNum at run time (GH.mod:9)"),
    ("Add Tool1.tframe.trans.z, 10;", "Tool1 is changed by Add at run time (GH.mod:9)")])
def test_data_an_instruction_changes_at_run_time_leaves_the_moves_as_written(extra, said,
                                                                            tmp_path):
    """Add, Incr, TPReadNum... write their argument: the external axes (or
    the tool) they change are not the declared value at run time."""
    src = tmp_path / "GH.mod"
    src.write_text(program(MOVES, extra=extra))
    out = tmp_path / "out.mod"
    r = rapidcomp("fix", src, "--profile", "fixtures/warm.csv", "-o", out, "--allow-partial")
    assert said in r.stdout, r.stdout
    # (The MoveAbsJ names extj too; a changed tool leaves the four
    # robtarget moves.)
    done = 1 if said.startswith("Tool1") else 0
    assert f"{done} of 5 target uses compensated, 0 not compensated, {5 - done} untouched" \
        in r.stdout, r.stdout


def test_external_axes_beyond_a_num_or_not_declared(tmp_path):
    """A number no num holds in extj's declaration is bad input, said where
    it is written; extj declared nowhere in what was given: not compensated,
    naming it (give the whole task)."""
    src = tmp_path / "GH.mod"
    src.write_text(program(MOVES).replace("extj := [9E9,", "extj := [4E38,"))
    r = rapidcomp("fix", src, "--profile", "fixtures/warm.csv", "-o", tmp_path / "o.mod",
                  check=False)
    assert r.returncode == 2 and "GH.mod:2:23: extj.eax_a is 4E38, beyond what a RAPID num" \
        in r.stderr, r.stderr
    text = "\n".join(line for line in program(MOVES).splitlines() if "extjoint" not in line)
    src.write_text(text)
    r = rapidcomp("fix", src, "--profile", "fixtures/warm.csv", "-o", tmp_path / "o.mod",
                  check=False)
    assert r.returncode == 1, r.stdout + r.stderr
    assert "its external axes are extj, which is not declared in the given modules (give " \
        "the whole task" in r.stdout, r.stdout
