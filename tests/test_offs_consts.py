"""Offs/RelTool whose numbers are CONST nums (`Offs(pB, 0, 0, nSafeZ)`, as
cells write their approach heights): the controller fixes a CONST when it
loads the module, so the move goes where the same Offs of the literal
values goes. The oracle is that program written by hand with the values
in place of the names: every compensated number must be the same. A VAR
or PERS num is known at run time only: the move is untouched, and says
why."""

from __future__ import annotations

import re

from click.testing import CliRunner

from rapidcomp.cli import main

from conftest import FIXTURES

HEAD = """MODULE OffC
    CONST robtarget pB:=[[500,0,400],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];
"""
NAMED = HEAD + """    CONST num nH:=50;
    CONST num nUp:=nH;
    CONST num nAng:=15.5;
    VAR num nVar:=20;
    PERS num nPers:=20;
    CONST num nSum:=10+5;
    PROC main()
        CONST num nLocal:=-12.5;
        MoveL Offs(pB, 0, 0, nH), v100, fine, tool0;
        MoveL Offs(pB, 0, nUp, (nLocal)), v100, fine, tool0;
        MoveJ Offs(pB, -nUp, 0, 0), v100, fine, tool0;
        MoveL RelTool(pB, 0, 0, nH \\Rz:=nAng), v100, fine, tool0;
        MoveL Offs(pB, 0, 0, nVar), v100, fine, tool0;
        MoveL Offs(pB, 0, 0, nPers), v100, fine, tool0;
        MoveL Offs(pB, 0, 0, nSum), v100, fine, tool0;
        MoveL RelTool(pB, 0, 0, 0 \\Rz:=nVar), v100, fine, tool0;
    ENDPROC
ENDMODULE
"""
# The same program with the values written in by hand where the moves
# read the CONSTs: the oracle.
LITERAL = NAMED.replace("""        MoveL Offs(pB, 0, 0, nH), v100, fine, tool0;
        MoveL Offs(pB, 0, nUp, (nLocal)), v100, fine, tool0;
        MoveJ Offs(pB, -nUp, 0, 0), v100, fine, tool0;
        MoveL RelTool(pB, 0, 0, nH \\Rz:=nAng), v100, fine, tool0;
""", """        MoveL Offs(pB, 0, 0, 50), v100, fine, tool0;
        MoveL Offs(pB, 0, 50, -12.5), v100, fine, tool0;
        MoveJ Offs(pB, -50, 0, 0), v100, fine, tool0;
        MoveL RelTool(pB, 0, 0, 50 \\Rz:=15.5), v100, fine, tool0;
""")
assert LITERAL != NAMED


def _fix(tmp_path, name, text, *options):
    src = tmp_path / f"{name}.mod"
    src.write_text(text)
    r = CliRunner().invoke(main, ["fix", str(src), "--profile", str(FIXTURES / "warm.csv"),
                                  "-o", str(tmp_path / f"{name}_out.mod"), *options])
    assert r.exit_code == 0, r.output
    out = (tmp_path / f"{name}_out.mod").read_text()
    rows = [line for line in (tmp_path / f"{name}_out.md").read_text().splitlines()
            if re.match(r"\| \d+ \|", line)]
    return r.output, out, rows


def _values(text: str) -> list[str]:
    """The values of the output's new declarations."""
    return [line.split(":=", 1)[1] for line in text.splitlines()
            if re.match(r"\s*LOCAL CONST (robtarget \w+_c(_\d+)?|jointtarget jt_\w+):=", line)]


def _cells(row: str) -> list[str]:
    cells = row.split(" | ")
    return cells[3:5] + cells[6:]


def test_offs_of_const_nums_goes_where_offs_of_their_values_goes(tmp_path):
    for mode in ("robtarget", "auto", "absj"):
        said, named, rows = _fix(tmp_path, f"named_{mode}", NAMED, "--emit", mode)
        _, literal, literal_rows = _fix(tmp_path, f"literal_{mode}", LITERAL, "--emit", mode)
        assert "4 of 8 target uses compensated, 0 not compensated, 4 untouched" in said
        # The same new values (their names may come in another order).
        assert sorted(_values(named)) == sorted(_values(literal)) and _values(named), mode
        # Row by row the same status, rule, joints, errors and residuals (the
        # target as written and the new name aside).
        cells = [_cells(row) for row in rows]
        assert cells == [_cells(row) for row in literal_rows], mode
    # (Each says which number and why.)
    for line in ("untouched (1): Offs number nVar is a VAR num: known at run time only [line 15]",
                 "untouched (1): Offs number nPers is a PERS num: known at run time only "
                 "[line 16]",
                 "untouched (1): Offs number nSum is a CONST whose value is not a literal number "
                 "(rapidcomp reads literal numbers and CONST nums of them) [line 17]",
                 "untouched (1): RelTool number nVar is a VAR num: known at run time only "
                 "[line 18]"):
        assert line in said, said


def test_an_offs_of_a_const_defined_through_itself_is_bad_input(tmp_path):
    text = NAMED.replace("CONST num nH:=50;", "CONST num nH:=nUp;")
    src = tmp_path / "loop.mod"
    src.write_text(text)
    r = CliRunner().invoke(main, ["fix", str(src), "--profile", str(FIXTURES / "warm.csv")])
    assert r.exit_code == 2
    assert "loop.mod:3:15: CONST nH is defined through itself (nH -> nUp -> nH)" in r.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["loop.mod"]


def test_a_for_loops_variable_hides_a_const_of_its_name(tmp_path):
    """In FOR k ... Offs(p, 0, 0, k) the k is the loop's, not a CONST num k
    of the module (RAPID: a loop's variable hides data of its name): known
    at run time only, untouched; outside the loop the CONST's value. An
    array index likewise: pA{j} in a loop on j of bounds not fixed is not
    the CONST j's element."""
    text = HEAD + """    CONST robtarget pA{3}:=[[[500,0,400],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]],[[500,10,400],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]],[[500,20,400],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]];
    CONST num k:=50;
    CONST num j:=2;
    VAR num n:=3;
    PROC main()
        FOR k FROM 1 TO 3 DO
            MoveL Offs(pB, 0, 0, k), v100, fine, tool0;
        ENDFOR
        FOR j FROM 1 TO n DO
            MoveL pA{j}, v100, fine, tool0;
        ENDFOR
        MoveL Offs(pB, 0, 0, k), v100, fine, tool0;
    ENDPROC
ENDMODULE
"""
    said, out, _ = _fix(tmp_path, "loops", text, "--emit", "robtarget", "--allow-partial")
    assert "1 of 5 target uses compensated, 0 not compensated, 4 untouched" in said
    assert ("untouched (3): Offs number k is the variable of an enclosing FOR loop: known at "
            "run time [line 9 (k=1, k=2, k=3)]") in said
    assert ("untouched (1): index of pA is not a literal or the variable of an enclosing FOR "
            "loop with constant bounds [line 12]") in said
    # (The move outside the loops: Offs(pB, 0, 0, 50).)
    _, literal, _ = _fix(tmp_path, "literal", HEAD + """    PROC main()
        MoveL Offs(pB, 0, 0, 50), v100, fine, tool0;
    ENDPROC
ENDMODULE
""", "--emit", "robtarget")
    # (There pB itself is rewritten: nothing else reads it.)
    assert _values(out) == [re.search(r"CONST robtarget pB:=(.*)$", literal, re.M).group(1)]


def test_an_inner_loops_bound_on_the_outer_variable_is_not_fixed(tmp_path):
    """FOR j FROM 1 TO i inside FOR i: the bound i is the outer loop's
    variable, not a CONST num i of the module (which made pA{3} go
    unvisited with i = 2, and was refused as past the array with i = 5):
    the move is untouched, its index not fixed."""
    for value in (2, 5):
        one = "[[500,0,400],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]"
        text = HEAD + f"""    CONST robtarget pA{{3}}:=[{one},{one},{one}];
    CONST num i:={value};
    PROC main()
        FOR i FROM 1 TO 3 DO
            FOR j FROM 1 TO i DO
                MoveL pA{{j}}, v100, fine, tool0;
            ENDFOR
        ENDFOR
    ENDPROC
ENDMODULE
"""
        said, _, _ = _fix(tmp_path, f"nested{value}", text, "--emit", "robtarget",
                          "--allow-partial")
        assert "0 of 1 target uses compensated, 0 not compensated, 1 untouched" in said, said


def test_an_offs_number_the_task_does_not_declare_is_a_gap_in_the_input(tmp_path):
    """A name no given module declares, or one another module declares
    LOCAL (the controller does not load the task), fails the move as a
    target's name would (exit 1), naming it and where it is LOCAL."""
    (tmp_path / "task").mkdir()
    (tmp_path / "task" / "Data.mod").write_text(
        "MODULE Data\n    LOCAL CONST num nHidden:=25;\nENDMODULE\n")
    (tmp_path / "task" / "Main.mod").write_text(HEAD.replace("MODULE OffC", "MODULE Main") + """    PROC main()
        MoveL Offs(pB, 0, 0, nNowhere), v100, fine, tool0;
        MoveL Offs(pB, 0, 0, -nHidden), v100, fine, tool0;
    ENDPROC
ENDMODULE
""")
    r = CliRunner().invoke(main, ["check", str(tmp_path / "task"), "--profile",
                                  str(FIXTURES / "warm.csv")])
    assert r.exit_code == 1, r.output
    assert ("Main.mod:4 MoveL Offs(pB, 0, 0, nNowhere): Offs number nNowhere is not declared in "
            "the given modules") in r.output
    assert ("Main.mod:5 MoveL Offs(pB, 0, 0, -nHidden): Offs number nHidden is declared LOCAL in "
            "another module (Data.mod:2)") in r.output
