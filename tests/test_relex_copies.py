"""A declared target that some of its uses read as a copy of their own
(`<name>_c`: another tool or work object, an Offs, a MoveC) is checked on
the output by reading the statements naming the copy and the copy's
declaration again where the output holds them (verify.relex_copies), not
by parsing the whole output again (issue #14: one copy in a 1e5-target
program took 14 s and 1.3 GB instead of 10 s and 1 GB). Oracle: the same
`fix` with the output parsed again (relex_copies switched off); and an
output that is not what was meant (a digit, a name, a storage, the rest of
a statement changed after the splice, a copy out of its move's scope) is
not taken."""

import sys
from pathlib import Path

import pytest

from rapidcomp.compensate import fix as F
from rapidcomp.compensate import verify as V
from rapidcomp.compensate.load import load_solver
from rapidcomp.compensate.plan import Task
from rapidcomp.edits import apply_edits
from rapidcomp.rapid.parse import parse_source, parse_text
from rapidcomp.source import read_source

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))
from fix import cam_module  # noqa: E402
from test_relex_absj import _converted  # noqa: E402


@pytest.fixture(scope="module")
def solver():
    return load_solver(str(ROOT / "fixtures" / "warm.csv"), None, False, ("J5=-120:120",))


def _literals(n: int) -> list[str]:
    """n reachable robtarget literals (tSpindle in wPart, both as CAM writes
    them: wPart is the world frame)."""
    return [line.split(":=", 1)[1].rstrip(";") for line in cam_module(2 * n, 11).split("\n")
            if "CONST robtarget" in line]


PROGRAM = """MODULE Copies
  PERS tooldata tSpindle:=[TRUE,[[0,0,150],[1,0,0,0]],[2,[0,0,75],[1,0,0,0],0,0,0]];
  PERS wobjdata wPart:=[FALSE,TRUE,"",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];
  CONST robtarget p1:=%s;
  CONST robtarget p2:=%s; ! second
  PROC main()
    MoveL p1,v100,z1,tSpindle\\WObj:=wPart;
    MoveL p2,v100,z1,tSpindle\\WObj:=wPart;
    MoveL Offs(p1,0,0,20),v100,z1,tSpindle\\WObj:=wPart;
    MoveL p2,v100,fine,tSpindle\\WObj:=wPart;
    MoveC p1,p2,v100,z1,tSpindle;
    path;
  ENDPROC
  PROC path()
    CONST robtarget q1:=%s;
    MoveL q1,v100,z1,tSpindle\\WObj:=wPart;
    MoveL q1, v200, z1, tSpindle;
  ENDPROC
  PROC other()
    VAR num k:=0;
    k:=k+1;
  ENDPROC
ENDMODULE
"""


def _program(ending: str = "\n") -> str:
    return (PROGRAM % tuple(_literals(3))).replace("\n", ending)


def _fix_both(monkeypatch, task, solver, mode):
    served = []
    real = F.relex_copies

    def spy(plan, copies, *args):
        out = real(plan, copies, *args)
        served.append(out is not None and len(out.uses))
        return out
    monkeypatch.setattr(F, "relex_copies", spy)
    reparsed = []
    real_reparse = F.reparse
    monkeypatch.setattr(F, "reparse", lambda *a: reparsed.append(1) or real_reparse(*a))
    read = F.fix(task, solver, mode)
    assert not reparsed
    monkeypatch.setattr(F, "relex_copies", lambda *args: None)
    parsed = F.fix(task, solver, mode)
    assert reparsed
    monkeypatch.undo()
    return read, parsed, served


def _same(a, b):
    assert [m.text for m in a.modules] == [m.text for m in b.modules]
    assert a.rows == b.rows and a.notes == b.notes and a.modules == b.modules


@pytest.mark.parametrize("ending", ["\n", "\r\n"])
@pytest.mark.parametrize("mode", ["auto", "robtarget"])
def test_copies_are_read_again(monkeypatch, solver, mode, ending):
    task = Task("copies.mod", (parse_text(_program(ending), "copies.mod"),))
    read, parsed, served = _fix_both(monkeypatch, task, solver, mode)
    _same(read, parsed)
    out = read.modules[0].text
    # The Offs, the MoveC's two targets (wobj0: another work object) and
    # the routine's own target moved in wobj0 read copies of their own.
    assert served == [4]
    assert "MoveL Offs(p1_offs_c,0,0,20)," in out
    assert "MoveC p1_c,p2_c,v100,z1,tSpindle;" in out
    assert "MoveL q1_c, v200, z1, tSpindle;" in out
    assert read.failed == 0


def test_copies_beside_moves_turned_into_moveabsj(monkeypatch, solver):
    # (A real module: MoveJ turned into MoveAbsJ on jointtargets of their
    # own, and targets copied for some of their uses, read again together.)
    pf = parse_source(read_source(ROOT / "fixtures" / "rapid" / "robotstudio_crlf.mod"))
    read, parsed, served = _fix_both(monkeypatch, Task("robotstudio_crlf.mod", (pf,)), solver,
                                     "absj")
    _same(read, parsed)
    assert served == [2] and "MoveAbsJ" in read.modules[0].text


def _printed(solver, text, mode="robtarget"):
    """The first round of fix's print on `text` (test_relex_absj)."""
    return _converted(solver, Task("copies.mod", (parse_text(text, "copies.mod"),)), mode)


def _relexed(plan, editor, edits, texts, bad=None):
    """relex_copies of the output texts (bad: of those texts instead, the
    rest read on `texts`): None where fix parses the output again."""
    written = V.relex(plan, editor.fields, edits, texts)
    assert written is not None
    return V.relex_copies(plan, editor.copies, edits, bad or texts, written)


def _flip(text: str, at: int) -> str:
    at = next(i for i in range(at, len(text)) if text[i].isdigit())
    return text[:at] + ("1" if text[at] != "1" else "2") + text[at + 1:]


@pytest.mark.parametrize("change", [
    ("p2_c:=[[", 0),                                # a copy's first digit
    ("p1_c:=[[", 60),                               # a copy's quaternion
    ("MoveC p1_c,p2_c,", "MoveC p2_c,p2_c,"),       # the name a move reads
    ("MoveC p1_c,p2_c,", "MoveC q1_c,p2_c,"),       # a copy it does not see
    ("q1_c, v200", "q1_c, v300"),                   # the rest of a statement
    ("LOCAL CONST robtarget p2_c", "LOCAL PERS  robtarget p2_c"),
    ("CONST robtarget p2_c:=[[", "CONST robtarget p2_d:=[["),   # the copy's name
])
def test_an_output_that_is_not_what_was_meant_is_not_taken(solver, change):
    plan, editor, edits, texts = _printed(solver, _program())
    assert len(editor.copies) == 4 and not editor.others
    assert _relexed(plan, editor, edits, texts) is not None
    old, new = change
    text = texts[0]
    assert old in text
    bad = (_flip(text, text.index(old) + len(old) + new) if type(new) is int
           else text.replace(old, new, 1))
    assert bad != text
    assert _relexed(plan, editor, edits, texts, {0: bad}) is None


def test_a_copy_out_of_its_moves_scope_is_not_taken(solver):
    # The routine's own target's copy, were it declared in another
    # routine (after its declaration, where a declaration may go), is not
    # seen by the move naming it: not taken.
    plan, editor, edits, texts = _printed(solver, _program())
    assert _relexed(plan, editor, edits, texts) is not None
    src = plan.files[0].source.text
    es = list(edits[0])
    k = next(i for i, e in enumerate(es) if e.start == e.end and "q1_c:=" in e.replacement)
    at = src.index("VAR num k:=0;") + len("VAR num k:=0;")
    moved = sorted(es[:k] + es[k + 1:] + [es[k]._replace(start=at, end=at)],
                   key=lambda x: (x.start, x.end))
    bad = apply_edits(src, moved)
    written = V.relex(plan, editor.fields, {0: moved}, {0: bad})
    assert written is not None
    assert V.relex_copies(plan, editor.copies, {0: moved}, {0: bad}, written) is None


DATA = """MODULE PartData
  PERS tooldata tSpindle:=[TRUE,[[0,0,150],[1,0,0,0]],[2,[0,0,75],[1,0,0,0],0,0,0]];
  PERS wobjdata wPart:=[FALSE,TRUE,"",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];
  CONST robtarget p1:=%s;
  CONST robtarget p2:=%s;
  LOCAL CONST robtarget p3:=%s;
  PROC near()
    MoveL p3,v100,fine,tSpindle;
    MoveL p3,v100,fine,tSpindle\\WObj:=wPart;
  ENDPROC
ENDMODULE
"""

PATH = """MODULE PartPath
  PROC main()
    MoveL p1,v100,z1,tSpindle\\WObj:=wPart;
    MoveL Offs(p1,0,0,20),v100,z1,tSpindle\\WObj:=wPart;
    MoveL p2,v100,z1,tSpindle\\WObj:=wPart;
    MoveL p2,v100,z1,tSpindle;
    MoveC p1,p2,v100,z1,tSpindle;
    near;
  ENDPROC
ENDMODULE
"""


@pytest.mark.parametrize("mode", ["auto", "robtarget"])
def test_copies_declared_in_a_data_module(monkeypatch, solver, mode):
    # A task's data module holds the targets, another module the moves: the
    # copies are declared in the data module (not LOCAL: the other module
    # reads them), read again there; the moves naming them in theirs.
    data = parse_text(DATA % tuple(_literals(3)), "PartData.mod")
    path = parse_text(PATH, "PartPath.mod")
    read, parsed, served = _fix_both(monkeypatch, Task("part", (data, path)), solver, mode)
    _same(read, parsed)
    # (p1's Offs and circle point, p2 in wPart, p3 in wPart.)
    assert served == [4] and read.failed == 0
    out_data, out_path = (m.text for m in read.modules)
    assert "\n  CONST robtarget p1_offs_c:=" in out_data and "LOCAL CONST robtarget p3_c" in out_data
    assert "MoveC p1_c,p2,v100,z1,tSpindle;" in out_path


def test_a_copy_another_module_does_not_see_is_not_taken(solver):
    # Were a copy another module reads declared LOCAL, that module would not
    # see it: not taken.
    data = parse_text(DATA % tuple(_literals(3)), "PartData.mod")
    path = parse_text(PATH, "PartPath.mod")
    plan, editor, edits, texts = _converted(solver, Task("part", (data, path)), "robtarget")
    written = V.relex(plan, editor.fields, edits, texts)
    assert V.relex_copies(plan, editor.copies, edits, texts, written) is not None
    bad = dict(texts)
    bad[0] = texts[0].replace("  CONST robtarget p2_c:=", "  LOCAL CONST robtarget p2_c:=")
    moved = dict(edits)
    moved[0] = [e._replace(replacement=e.replacement.replace(
        "CONST robtarget p2_c:=", "LOCAL CONST robtarget p2_c:=")) for e in edits[0]]
    assert bad[0] != texts[0]
    assert V.relex_copies(plan, editor.copies, moved, bad, V.relex(plan, editor.fields, moved,
                                                                   bad)) is None
