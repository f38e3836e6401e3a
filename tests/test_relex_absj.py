"""Moves turned into MoveAbsJ on jointtargets of their own (inline or newly
declared) are checked on the output by reading those statements and
declarations again where it holds them (verify.relex_absj), not by parsing
the whole output again. Oracle: the same `fix` with the output parsed
again (relex_absj switched off), on a CAM program entered from main
(1500 MoveL, declared and inline), the cubes program (MoveJ, MoveL) and
the real-program fixtures; and an output that is not what was meant (a
number, a name, a statement changed after the splice) is not taken."""

import sys
from pathlib import Path

import pytest

from rapidcomp.compensate import fix as F
from rapidcomp.compensate import place as P
from rapidcomp.compensate import verify as V
from rapidcomp.compensate.edit import Editor, Values
from rapidcomp.compensate.load import load_solver
from rapidcomp.compensate.plan import Plan, Task
from rapidcomp.compensate.solve import solve
from rapidcomp.edits import apply_edits
from rapidcomp.rapid.parse import parse_source, parse_text
from rapidcomp.source import read_source

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))
from fix import cam_module  # noqa: E402


@pytest.fixture(scope="module")
def solver():
    return load_solver(str(ROOT / "fixtures" / "warm.csv"), None, False, ("J5=-120:120",))


def _cam(n: int) -> str:
    return cam_module(n, 5, main=True)


def _fix_both(monkeypatch, task, solver, mode):
    served = []
    real = F.relex_absj

    def spy(*args):
        out = real(*args)
        served.append(out is not None and len(out))
        return out
    monkeypatch.setattr(F, "relex_absj", spy)
    read = F.fix(task, solver, mode)
    monkeypatch.setattr(F, "relex_absj", lambda *args: None)
    parsed = F.fix(task, solver, mode)
    monkeypatch.setattr(F, "relex_absj", real)
    return read, parsed, served


def _same(a, b):
    assert [m.text for m in a.modules] == [m.text for m in b.modules]
    assert a.rows == b.rows and a.notes == b.notes and a.modules == b.modules


@pytest.mark.parametrize("mode, block", [("absj", None), ("absj", 7), ("auto", None)])
def test_cam_program_entered_from_main(monkeypatch, solver, mode, block):
    """(block: the moves read RELEX_BLOCK at a time, a last one short.)"""
    if block is not None:
        monkeypatch.setattr(V, "RELEX_BLOCK", block)
    task = Task("cam.mod", (parse_text(_cam(1500), "cam.mod"),))
    read, parsed, served = _fix_both(monkeypatch, task, solver, mode)
    _same(read, parsed)
    if mode == "absj":
        # Every MoveL turned, read again (not parsed): 750 declared, 750 inline.
        assert served == [1500]
        assert read.modules[0].text.count("MoveAbsJ") == 1500
    else:
        assert served == []        # (auto keeps MoveL: numbers only)


@pytest.mark.parametrize("mode, turned", [("absj", 180), ("auto", 1)])
def test_a_real_cam_program_is_read_again(monkeypatch, solver, mode, turned):
    # (The only fixture whose moves turned into MoveAbsJ are read again:
    # the others write new robtargets too, and their output is parsed
    # again. Every fixture's whole fix, shortcuts on and off: test_fast_general.py.)
    pf = parse_source(read_source(ROOT / "fixtures" / "rapid" / "cam_confoff.mod"))
    read, parsed, served = _fix_both(monkeypatch, Task("cam_confoff.mod", (pf,)), solver, mode)
    assert served == [turned]
    _same(read, parsed)


def _converted(solver, text, mode="absj"):
    """The first round of fix's print on `text` (a module's, or a Task) in
    `mode`: the plan, the editor (its conversions and copies), the file
    edits and the output texts, by file."""
    task = text if isinstance(text, Task) else Task("cam.mod", (parse_text(text, "cam.mod"),))
    plan = Plan(task)
    solved = solve(plan, solver)
    gs = P.groups(plan, solved, mode)
    values = Values(plan, solved, solver.options.quadrant_tol_deg)
    values.prepare(gs)
    P.place(plan, gs)
    P.fill_slots(plan, solver, gs)
    editor = Editor(plan, values)
    for g in gs:
        if g.failure is None:
            editor.apply(g)
    edits = editor.file_edits()
    return plan, editor, edits, {fi: apply_edits(task.files[fi].source.text, es)
                                 for fi, es in edits.items()}


def _flip(text: str, at: int) -> str:
    """text with the first digit from `at` on another digit (the same
    length)."""
    at = next(i for i in range(at, len(text)) if text[i].isdigit())
    return text[:at] + ("1" if text[at] != "1" else "2") + text[at + 1:]


@pytest.mark.parametrize("change", [
    ("jt_p3:=[[", 0),                           # a declared joint's first digit
    ("MoveAbsJ [[", 0),                         # an inline joint's first digit
    ("MoveAbsJ jt_p4,", "MoveAbsJ jt_p3,"),     # the name a move reads
    ("MoveAbsJ jt_p5,v100", "MoveAbsJ jt_p5,v200"),   # the rest of a statement
    ("LOCAL CONST jointtarget jt_p6", "LOCAL PERS  jointtarget jt_p6"),
    ("MoveAbsJ jt_p7,v", "MoveAbsJ jt_p7 ,"),   # not one statement of the grammar
])
def test_an_output_that_is_not_what_was_meant_is_not_taken(solver, change):
    plan, editor, edits, texts = _converted(solver, _cam(20))
    assert V.relex_absj(plan, editor.converted, edits, texts) is not None
    old, new = change
    text = texts[0]
    assert old in text
    if type(new) is int:
        bad = _flip(text, text.index(old) + len(old) + new)
    else:
        bad = text.replace(old, new, 1)
    assert len(bad) == len(text) or new.endswith(" ,")
    assert V.relex_absj(plan, editor.converted, edits, {0: bad}) is None


HAND = """MODULE Hand
  PERS tooldata tSpindle:=[TRUE,[[0,0,150],[1,0,0,0]],[2,[0,0,75],[1,0,0,0],0,0,0]];
  PERS wobjdata wPart:=[FALSE,TRUE,"",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];
  VAR num n:=1;
  PROC main()
    CONST robtarget q1:=%s; ! the first point
    movel q1,v100,z1,tSpindle\\WObj:=wPart;
    IF n=1 THEN
      MOVEL %s, v200, fine, tSpindle \\WObj:=wPart;
    ENDIF
    MoveL q1,v100,z1,tSpindle\\WObj:=wPart;
  ENDPROC
ENDMODULE
"""


def _hand(ending: str = "\n", after: str = " ! the first point") -> str:
    lits = [line.split(":=", 1)[1].rstrip(";")
            for line in cam_module(2, 9).split("\n") if "CONST robtarget" in line]
    lits.append(cam_module(2, 9).split("MoveL ")[-1].split(",v100")[0])
    text = HAND % (lits[0], lits[1])
    return text.replace("; ! the first point", ";" + after).replace("\n", ending)


@pytest.mark.parametrize("ending", ["\n", "\r\n"])
def test_hand_written_moves_in_a_routine_and_an_if(monkeypatch, solver, ending):
    # A routine's own target, moves in an IF body, letter case and spaces
    # of the writer's own, CRLF: read again, as parsing it again gives.
    task = Task("hand.mod", (parse_text(_hand(ending), "hand.mod"),))
    read, parsed, served = _fix_both(monkeypatch, task, solver, "absj")
    _same(read, parsed)
    assert served == [3] and "CONST jointtarget jt_q1:=" in read.modules[0].text


@pytest.mark.parametrize("after", [" n:=1;", " IF n=1 THEN n:=2; ENDIF", " ! a comment",
                                   " n:=1; ! a comment"])
def test_a_declaration_line_going_on_with_a_statement(monkeypatch, solver, after):
    # The new declaration goes right after the one it comes from, the rest
    # of that line after it (after the line, it would follow a statement:
    # the output did not parse); after a comment, at the line's end.
    text = _hand(after=after)
    task = Task("hand.mod", (parse_text(text, "hand.mod"),))
    read, parsed, served = _fix_both(monkeypatch, task, solver, "absj")
    _same(read, parsed)
    assert served == [3]
    out = read.modules[0].text
    decl = out.index("CONST jointtarget jt_q1:=")
    line = out[decl:out.index("\n", decl)]
    assert line.endswith(";" + after if after.startswith(" n") or after.startswith(" IF")
                         else "]];")


def test_a_declaration_after_a_statement_is_not_taken(solver):
    # Were the new declaration put after its line as it goes on with a
    # statement, the output (which does not parse) is not taken.
    plan, editor, edits, texts = _converted(solver, _hand(after=" n:=1;"))
    assert V.relex_absj(plan, editor.converted, edits, texts) is not None
    src = plan.files[0].source.text
    k = next(i for i, e in enumerate(edits[0]) if e.start == e.end)
    e = edits[0][k]
    at = src.index("\n", e.start)
    moved = sorted(edits[0][:k] + edits[0][k + 1:] + [e._replace(start=at, end=at)],
                   key=lambda x: (x.start, x.end))
    bad = apply_edits(src, moved)
    with pytest.raises(Exception):
        parse_text(bad, "hand.mod")
    assert V.relex_absj(plan, editor.converted, {0: moved}, {0: bad}) is None


def test_joint_rows_are_the_decoders_joints():
    """verify._joint_rows (the moves' literals decoded as one batch) against
    values.decode of each literal, by repr of each float (a -0 keeps its
    sign), on seeded random batches: plain literals, and ones the batch must
    leave to the decoder (a space, a hexadecimal number, a number beyond a
    num's range, a field too many or too few; each a numeric aggregate as
    the lexer reads one)."""
    import random

    import numpy as np

    from rapidcomp.rapid.ast import NumAgg, Span
    from rapidcomp.rapid.values import DecodeIssue, decode
    rnd = random.Random(5)
    plain = ["0", "-0", "12.5", "-170.25", "1E+09", "9E+09", ".5", "2.", "1e-3", "-0.0"]
    odd = ["4E38", "-3.5E38", " 1", "1 ", "1,2"]
    served = declined = 0
    for _ in range(400):
        lits = []
        for _ in range(rnd.randint(1, 12)):
            fields = [rnd.choice(plain) for _ in range(12)]
            if rnd.random() < 0.05:
                fields[rnd.randrange(12)] = rnd.choice(odd)
            lit = f"[[{','.join(fields[:6])}],[{','.join(fields[6:])}]]"
            if rnd.random() < 0.02:
                lit = lit.replace("],[", "],[0,", 1)
            lits.append(lit)
        got = V._joint_rows(lits)
        want = []
        try:
            for lit in lits:
                want.append(decode("jointtarget", NumAgg(lit, Span(0, len(lit)))).joints)
        except DecodeIssue:
            want = None
        if got is None:
            declined += 1
            continue
        served += 1
        assert want is not None and got.shape == (len(lits), 6)
        assert [[repr(v) for v in row] for row in got.tolist()] == \
            [[repr(v) for v in row] for row in want]
        assert got.dtype == np.float64
    assert served > 150 and declined > 40
    assert V._joint_rows([]) is None


def _data_and_main(n: int, local: str = "", array: bool = False) -> Task:
    """A task of two modules as a cell writes it: the targets (and the tool
    and work object) in a data module, the moves in another."""
    from cam_variants import HEAD, TAIL, robtarget, targets
    lits = [robtarget(t) for t in targets(n, 11)]
    if array:
        decls = [f"  {local}CONST robtarget path{{{n}}}:=[", *(f"    {x}," for x in lits[:-1]),
                 f"    {lits[-1]}];"]
        moves = [f"    FOR i FROM 1 TO {n} DO", f"      MoveL path{{i}}{TAIL}", "    ENDFOR"]
    else:
        decls = [f"  {local}CONST robtarget p{k}:={x};" for k, x in enumerate(lits)]
        moves = [f"    MoveL p{k}{TAIL}" for k in range(n)]
    data = "\n".join(["MODULE PathData", *HEAD, *decls, "ENDMODULE", ""])
    main = "\n".join(["MODULE PathMain", "  PROC main()", *moves, "  ENDPROC", "ENDMODULE", ""])
    return Task("PathMain.mod", (parse_text(main, "PathMain.mod"),
                                 parse_text(data, "PathData.mod")))


@pytest.mark.parametrize("array", [False, True])
def test_targets_in_a_data_module_are_read_again(monkeypatch, solver, array):
    # The new jointtargets go next to the targets, in the data module, not
    # LOCAL (another module's moves read them): read again there, as
    # parsing the output again gives.
    task = _data_and_main(40, array=array)
    read, parsed, served = _fix_both(monkeypatch, task, solver, "absj")
    _same(read, parsed)
    assert served == [40]
    main, data = read.modules[0].text, read.modules[1].text
    assert main.count("MoveAbsJ jt_p") == (1 if array else 40)
    assert ("CONST jointtarget jt_path{40}:=" if array else "CONST jointtarget jt_p39:=") in data
    assert "LOCAL CONST jointtarget" not in data


@pytest.mark.parametrize("array", [False, True])
def test_a_data_modules_new_target_made_local_is_not_taken(solver, array):
    # Were it LOCAL, the other module's moves would not see it.
    plan, editor, edits, texts = _converted(solver, _data_and_main(6, array=array))
    assert V.relex_absj(plan, editor.converted, edits, texts) is not None
    text = texts[1]
    new = "CONST jointtarget jt_path{6}" if array else "CONST jointtarget jt_p3:"
    assert new in text
    bad = dict(texts)
    bad[1] = text.replace(new, "LOCAL " + new, 1)
    moved = dict(edits)
    k = next(i for i, e in enumerate(edits[1]) if e.start == e.end and new in e.replacement)
    e = edits[1][k]
    at = e.replacement.index(new)
    moved[1] = edits[1][:k] + [e._replace(replacement=e.replacement[:at] + "LOCAL "
                                          + e.replacement[at:])] + edits[1][k + 1:]
    assert apply_edits(plan.files[1].source.text, moved[1]) == bad[1]
    assert V.relex_absj(plan, editor.converted, moved, bad) is None


@pytest.mark.parametrize("array", [False, True])
def test_a_new_name_declared_in_two_modules_is_not_taken(solver, array):
    # (Found by a review.) The moves' own module declaring the data
    # module's new name too, LOCAL: the moves see their own; which one is
    # not looked into, the output is parsed again.
    plan, editor, edits, texts = _converted(solver, _data_and_main(6, array=array))
    assert V.relex_absj(plan, editor.converted, edits, texts) is not None
    src = plan.files[0].source.text
    at = src.index("\n")                          # the end of the MODULE line
    zero = "[[0,0,0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
    decl = (f"LOCAL CONST jointtarget jt_path{{6}}:=[{','.join([zero] * 6)}];" if array
            else f"LOCAL CONST jointtarget jt_p3:={zero};")
    e = edits[1][0]
    moved = dict(edits)
    moved[0] = sorted(list(edits.get(0, [])) + [e._replace(start=at, end=at,
                                                           replacement="\n  " + decl)],
                      key=lambda x: (x.start, x.end))
    bad = dict(texts)
    bad[0] = apply_edits(src, moved[0])
    parse_text(bad[0], "PathMain.mod")
    assert V.relex_absj(plan, editor.converted, moved, bad) is None
