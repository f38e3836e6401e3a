"""Invalid input: path:line:col, what was expected in RAPID terms, exit 2, no output."""

import subprocess
import sys

import pytest
from click.testing import CliRunner

from rapidcomp.cli import main
from rapidcomp.errors import InputError
from rapidcomp.rapid.parse import parse_text

from conftest import FIXTURES

CASES = {
    "text_after_endmodule.mod": ("6:1", "text after ENDMODULE"),
    "module_name_digit.mod": ("1:8", "module name must start with a letter"),
    "identifier_parentheses.mod": ("2:20", "'speed' cannot be followed by parentheses"),
    "unclosed_aggregate.mod": ("2:98", "an aggregate '[' is not closed"),
    "encrypted.mod": ("2:", "binary or encrypted module"),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_invalid_fixture_cli(name):
    path = FIXTURES / "invalid" / name
    where, phrase = CASES[name]
    before = path.read_bytes()
    result = CliRunner().invoke(main, ["inspect", str(path)])
    assert result.exit_code == 2
    assert result.stdout == ""
    first = result.stderr.splitlines()[0]
    assert first.startswith(f"{path}:{where}")
    assert phrase in first
    assert path.read_bytes() == before  # input never modified


def test_caret_points_at_column():
    with pytest.raises(InputError) as exc:
        parse_text("MODULE m\nPROC p()\n  MoveL p1, v100 z10;\nENDPROC\nENDMODULE\n", "x.mod")
    lines = exc.value.format().splitlines()
    assert lines[0].startswith("x.mod:3:18: unexpected identifier 'z10'; expected ")
    assert "','" in lines[0] and "';'" in lines[0]
    assert lines[1] == "      MoveL p1, v100 z10;"
    assert lines[2] == "    " + " " * 17 + "^"


@pytest.mark.parametrize("text,where,phrase", [
    ("MODULE m\nPROC p()\n", "3:1", "unexpected end of file; expected a declaration, a statement"),
    # (A ';' missing where a line ends: said there, not where the next
    # line starts; a comment between changes nothing.)
    ("MODULE m\nPROC p()\n x := 1\nENDPROC\nENDMODULE\n", "3:8",
     "';' missing after number 1: the next line goes on with 'ENDPROC'; expected ';' or an "
     "operator here"),
    ("MODULE m\nPROC p()\n MoveL p1, v100, fine, tool0 ! to p1\r\n MoveJ p1, v100, fine, "
     "tool0;\nENDPROC\nENDMODULE\n", "3:29", "';' or ',' missing after identifier 'tool0': the "
     "next line goes on with identifier 'MoveJ'; expected ';' or an operator, '(', ','"),
    # (An aggregate of several lines is quoted on one.)
    ("MODULE m\nPROC p()\n x := [1,\n   2]\n y := 1;\nENDPROC\nENDMODULE\n", "4:6",
     "';' missing after '[1, 2]': the next line goes on with identifier 'y'"),
    ("MODULE m\nPROC p()\n IF x THEN\n ENDPROC\nENDMODULE\n", "4:2", "ELSE, ELSEIF or ENDIF"),
    ("MODULE m\n VAR num x := 1 @ 2;\nENDMODULE\n", "2:17", "unexpected character '@'"),
    ("MODULE m\n VAR num if := 1;\nENDMODULE\n", "2:10", "unexpected 'if'; expected an identifier"),
    # (What the controller does not load: a name of more than 32
    # characters, a name declared twice in a module or a routine.)
    ("MODULE m\n VAR num a23456789012345678901234567890123 := 1;\nENDMODULE\n", "2:10",
     "the name a23456789012345678901234567890123 has 33 characters: the controller loads names "
     "of at most 32"),
    ("MODULE m\n PROC P()\n ENDPROC\n VAR num p;\nENDMODULE\n", "4:10",
     "p is declared twice in module m (first at line 2): the controller does not load it"),
    ("MODULE m\n PROC q()\n  VAR num a;\n  VAR num A;\n ENDPROC\nENDMODULE\n", "4:11",
     "A is declared twice in routine q (first at line 3)"),
    # (A number no RAPID type holds, in an aggregate of numbers, which is
    # one token: in a declaration, a move's argument, an assignment, an
    # array, by exponent or by digits.)
    ("MODULE m\n CONST speeddata vX := [1E999,500,5000,1000];\nENDMODULE\n", "2:25",
     "number 1E999 is out of range (a num holds +-3.4E38, a dnum +-1.8E308)"),
    ("MODULE m\n PROC p()\n  MoveL [[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]],"
     "[1E999,500,5000,1000],fine,tool0;\n ENDPROC\nENDMODULE\n", "3:66", "number 1E999 is out"),
    ("MODULE m\n PROC p()\n  j := [[0,0,0,0,30,0],[9E9,9E9,9E9,9E9,9E9,1e400]];\n ENDPROC\n"
     "ENDMODULE\n", "3:45", "number 1e400 is out of range"),
    ("MODULE m\n VAR num a{2} := [-1E999, 0];\nENDMODULE\n", "2:20", "number 1E999 is out"),
    ("MODULE m\n VAR num a{2} := [1" + "0" * 310 + ", 0];\nENDMODULE\n", "2:19",
     "number 10000000000000000000... (311 characters) is out of range"),
    # (Past a dnum by digits and exponent together, each within the token's
    # bounds alone: 1E349, 1E309.)
    ("MODULE m\n CONST speeddata vX := [1" + "0" * 250 + "E99,500,5000,1000];\nENDMODULE\n",
     "2:25", "number 10000000000000000000... (254 characters) is out of range"),
    ("MODULE m\n VAR num a{2} := [" + "9" * 300 + "E9, 0];\nENDMODULE\n", "2:19",
     "number 99999999999999999999... (302 characters) is out of range"),
    # (Not the lexer's names of its own tokens: FAST_DECL is a declaration.)
    ("MODULE m\n PROC main()\n ENDPROC\n", "4:1",
     "unexpected end of file; expected a declaration, ALIAS, ENDMODULE, FUNC, PROC, RECORD, "
     "TRAP or a placeholder such as <SMT> (is ENDMODULE missing?)"),
])
def test_messages(text, where, phrase):
    with pytest.raises(InputError) as exc:
        parse_text(text, "m.mod")
    first = exc.value.format().splitlines()[0]
    assert first.startswith(f"m.mod:{where}: ")
    assert phrase in first


def test_missing_file_is_bad_input(tmp_path):
    # (As check and fix say it.)
    for command in (["inspect"], ["check", "--profile", str(FIXTURES / "warm.csv")]):
        result = CliRunner().invoke(main, [*command, str(tmp_path / "nope.mod")])
        assert result.exit_code == 2 and "nope.mod: no such file or folder" in result.stderr


def test_python_dash_m_entry_point():
    proc = subprocess.run([sys.executable, "-m", "rapidcomp", "inspect",
                           str(FIXTURES / "invalid" / "module_name_digit.mod")],
                          capture_output=True, text=True)
    assert proc.returncode == 2 and proc.stdout == ""
    assert "module_name_digit.mod:1:8:" in proc.stderr


@pytest.mark.parametrize("consts, where, chain", [
    ("  CONST num a:=b;\n  CONST num b:=a;\n", "2:13", "a -> b -> a"),
    ("  CONST num a:=(-a);\n", "2:13", "a -> a"),
])
def test_a_const_defined_through_itself_is_bad_input(tmp_path, consts, where, chain):
    """A CONST num an index or a loop bound reads, defined through itself,
    has no value: file:line:col of its declaration, the chain, exit 2 and
    no output (found by review: Python's recursion limit gave a message
    with no place)."""
    path = tmp_path / "cyc.mod"
    path.write_text("MODULE Cyc\n" + consts + "  CONST robtarget pA{2}:=[[[400,0,400],[0,0,1,0],"
                    "[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]],[[400,0,400],[0,0,1,0],[0,0,0,0],"
                    "[9E9,9E9,9E9,9E9,9E9,9E9]]];\n  PROC main()\n    FOR i FROM 1 TO 2 DO\n"
                    "      MoveL pA{i},v10,fine,tool0;\n    ENDFOR\n    MoveL pA{a},v10,fine,tool0;\n"
                    "  ENDPROC\nENDMODULE\n")
    result = CliRunner().invoke(main, ["fix", str(path), "--profile",
                                       str(FIXTURES / "warm.csv")])
    assert result.exit_code == 2
    first = result.stderr.splitlines()[0]
    assert first.startswith(f"cyc.mod:{where}") and f"({chain}): it has no value" in first
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cyc.mod"]


def _nested_ifs(n: int, handler: bool = False) -> str:
    return "\n".join(["MODULE Deep", "  CONST robtarget p1:=[[400,0,250],[0.707107,0,0.707107,0],"
                      "[0,0,0,1],[9E9,9E9,9E9,9E9,9E9,9E9]];", "  PROC main()"]
                     + (["    MoveL p1,v100,fine,tool0;", "  ERROR"] if handler else [])
                     + ["    IF TRUE THEN"] * n + ["      MoveL p1,v100,fine,tool0;"]
                     + ["    ENDIF"] * n + ["  ENDPROC", "ENDMODULE", ""])


def test_blocks_nested_thousands_deep(tmp_path):
    """10,000 nested IFs: followed as a flow too large (the safe choice for
    every move, said), not refused for Python's frames with a message
    naming no place; 30,000, past what the parse follows: file:line:col of
    the deepest statement, exit 2, nothing written (run in a process of
    its own: the command sets its own frame limit)."""
    path = tmp_path / "deep.mod"
    path.write_text(_nested_ifs(10_000))
    proc = subprocess.run([sys.executable, "-m", "rapidcomp", "check", str(path), "--profile",
                           str(FIXTURES / "warm.csv")], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "1 of 1 target uses compensable" in proc.stdout
    assert "blocks or calls nested thousands of levels deep" in proc.stdout
    # (In an ERROR handler: the deepest statement is found there too.)
    path.write_text(_nested_ifs(30_000, handler=True))
    proc = subprocess.run([sys.executable, "-m", "rapidcomp", "fix", str(path), "--profile",
                           str(FIXTURES / "warm.csv")], capture_output=True, text=True)
    assert proc.returncode == 2
    assert proc.stderr.startswith("deep.mod:30006:7: blocks nest 30000 levels deep here")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["deep.mod"]


def test_a_line_of_a_megabyte_is_shown_around_its_column(tmp_path):
    """A generated line of 1e6 characters with a number out of range at its
    end: the message shows the number by its start and length and the line
    around the column, the caret under the number (it was 2 MB of stderr)."""
    path = tmp_path / "long.mod"
    path.write_text("MODULE L\n  PROC main()\n    " + "WaitTime 0.1; " * 70_000
                    + "WaitTime 1" + "0" * 400 + ";\n  ENDPROC\nENDMODULE\n")
    r = CliRunner().invoke(main, ["inspect", str(path)])
    assert r.exit_code == 2 and len(r.stderr) < 1000, len(r.stderr)
    first, line, caret = r.stderr.splitlines()[:3]
    assert first == (f"{path}:3:980014: number 10000000000000000000... (401 characters) is "
                     "out of range (a num holds +-3.4E38, a dnum +-1.8E308)")
    assert line.startswith("    ...") and line.endswith("...")
    assert line[caret.index("^"):].startswith("1000")


def test_messages_that_say_what_is_wrong(tmp_path):
    """A string not closed on its line says so (it said "unexpected
    character '\"'"); --profile '' names the option (it said ". : Is a
    directory"); a measured file with fewer rows than discover's 6 poses
    says 6 (it said 3)."""
    bad = tmp_path / "s.mod"
    bad.write_text('MODULE M\n  PROC main()\n    TPWrite "hello;\n  ENDPROC\nENDMODULE\n')
    r = CliRunner().invoke(main, ["inspect", str(bad)])
    assert r.exit_code == 2
    assert r.stderr.startswith(f"{bad}:3:13: a string not closed on its line: expected a "
                               "closing '\"' before the end of the line")
    r = CliRunner().invoke(main, ["check", str(FIXTURES / "cubes.mod"), "--profile", ""])
    assert r.exit_code == 2 and r.stderr.startswith("--profile: no file named"), r.stderr
    m = tmp_path / "m.csv"
    m.write_text("point,j1,j2,j3,j4,j5,j6,x,y,z\nA,0,0,0,0,30,0,515,0,600\n")
    r = CliRunner().invoke(main, ["discover", str(m)])
    assert r.exit_code == 2 and "1 point(s), expected at least 6" in r.stderr, r.stderr
