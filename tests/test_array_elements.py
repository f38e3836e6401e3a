"""An element of a FOR-walked array that a move reads by its literal index
and the loop does not reach (`MoveL pArr{1}` before `FOR i FROM 2 TO 3`):
its value is written in the array, where it is, as the loop's elements
are; not into a copy with the move renamed to it. The oracle: the same
target declared alone, read by the same move, gets the same numbers."""

from __future__ import annotations

import re

from click.testing import CliRunner

from rapidcomp.cli import main

from conftest import FIXTURES

P1 = "[[400,-300,250],[0.707107,0,0.707107,0],[-1,-1,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
P2 = "[[400,-300,400],[0.707107,0,0.707107,0],[-1,-1,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
P3 = "[[400,-150,400],[0.707107,0,0.707107,0],[-1,-1,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
ARRAY = f"""MODULE Arr
    CONST robtarget pArr{{3}}:=[
        {P1},
        {P2},
        {P3}];
    PROC main()
        MoveL pArr{{1}}, v200, fine, tool0;
        FOR i FROM 2 TO 3 DO
            MoveL pArr{{i}}, v200, fine, tool0;
        ENDFOR
    ENDPROC
ENDMODULE
"""
ALONE = f"""MODULE Alone
    CONST robtarget pOne:={P1};
    PROC main()
        MoveL pOne, v200, fine, tool0;
    ENDPROC
ENDMODULE
"""


def _fix(tmp_path, name, text, mode):
    src = tmp_path / f"{name}.mod"
    src.write_text(text)
    out = tmp_path / f"{name}_{mode}.mod"
    r = CliRunner().invoke(main, ["fix", str(src), "--profile", str(FIXTURES / "warm.csv"),
                                  "--emit", mode, "-o", str(out)])
    assert r.exit_code == 0, r.output
    return r.output, out.read_text()


def test_an_element_the_loop_does_not_reach_is_written_in_the_array(tmp_path):
    _, alone = _fix(tmp_path, "alone", ALONE, "robtarget")
    want = re.search(r"pOne:=(\[.*\]);", alone).group(1)
    said, out = _fix(tmp_path, "arr", ARRAY, "robtarget")
    assert "3 of 3 target uses compensated" in said and "new declarations" not in said
    assert out.splitlines()[2] == f"        {want},"
    assert "MoveL pArr{1}, v200" in out and "_c" not in out
    # Turned into MoveAbsJ: the move reads the array's jointtarget element.
    _, alone = _fix(tmp_path, "alone", ALONE, "absj")
    want = re.search(r"jt_pOne:=(\[.*\]);", alone).group(1)
    said, out = _fix(tmp_path, "arr", ARRAY, "absj")
    assert "3 of 3 target uses compensated" in said
    assert "MoveAbsJ jt_pArr{1}, v200" in out and "jt_pArr_1" not in out
    assert re.search(r"jt_pArr\{3\}:=\[\s*" + re.escape(want) + ",", out), out
