"""A transient output and PERS targets: a row says "<name> is PERS: this
move now reads a CONST copy" exactly where the written move reads a copy
and not the PERS itself (a cold value with the confdata every thermal state
needs, <name>_cold), whatever the group's placement. The oracle is the
written statement of each row's line: does it still name the PERS?"""

from __future__ import annotations

import re

from click.testing import CliRunner

from rapidcomp.cli import main

from conftest import FIXTURES

WARM = str(FIXTURES / "warm.csv")
ROB = "[0,0,1,0],{conf},[9E9,9E9,9E9,9E9,9E9,9E9]]"
# The array's confdata cf4 0: the warm robot needs -1 (the output declares
# a cold copy pArr_cold); pB's -1 serves every state (no copy).
ARRAY = """MODULE PA
  PERS robtarget pArr{3}:=[[[500,0,400],A],[[500,50,400],A],[[500,100,400],A]];
  PERS robtarget pB:=[[500,0,400],B];
  PROC main()
    FOR i FROM 1 TO 3 DO
      MoveL pArr{i}, v100, fine, tool0;
    ENDFOR
    MoveL Offs(pArr{1},0,0,10), v100, fine, tool0;
    MoveL pB, v100, fine, tool0;
    MoveL Offs(pB,0,0,10), v100, fine, tool0;
  ENDPROC
ENDMODULE
""".replace("A]", ROB.format(conf="[0,0,0,0]")).replace("B]", ROB.format(conf="[0,-1,0,0]"))
WARNING = "is PERS: this move now reads a CONST copy"


def test_the_pers_warning_is_on_the_rows_whose_move_reads_a_copy(tmp_path):
    src = tmp_path / "pa.mod"
    src.write_text(ARRAY)
    out = tmp_path / "out.mod"
    r = CliRunner().invoke(main, ["fix", str(src), "--profile", WARM, "--transient",
                                  "--tau-heat", "45", "-o", str(out)])
    assert r.exit_code == 0, r.output
    written = out.read_text().splitlines()
    # The statement each input line became (the output declares new data
    # above the routine: its lines follow the input's by that many).
    shift = written.index("  PROC main()") - ARRAY.splitlines().index("  PROC main()")
    rows = [line for line in out.with_suffix(".md").read_text().splitlines()
            if re.match(r"\| \d+ \| Move", line)]
    assert len(rows) == 6
    warned = {}
    for row in rows:
        line = int(row.split("|")[1])
        statement = written[line - 1 + shift]
        name = "pArr" if "pArr" in statement else "pB"
        reads_pers = re.search(rf"\b{name}\b(?!_)", statement) is not None
        warned[row.split("|")[3].strip()] = (WARNING in row, reads_pers)
    # (Each row: warned exactly where its move no longer reads the PERS.)
    assert all(w == (not pers) for w, pers in warned.values()), warned
    # The loop's three and the Offs of pArr read copies; pB's two read pB.
    assert [w for w, _ in warned.values()] == [True, True, True, True, False, False], warned
    # (The console says it once: which PERS data, how many moves.)
    assert ("note: 4 moves now read a CONST copy of PERS data (pArr): a change to it at run "
            "time (ModPos, another task) no longer reaches those moves") in r.output
