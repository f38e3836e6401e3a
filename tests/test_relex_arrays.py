"""Moves on an array's elements turned into MoveAbsJ on a new jointtarget
array (`--emit absj` of a Grasshopper program: `FOR i ... MoveL path{i}`)
are checked by reading that array's declaration and those statements again
where the output holds them (verify.relex_absj, _array_decl), not by
parsing the whole output again. Oracle: the same `fix` with the output
parsed again (relex_absj switched off), on arrays of one and two
dimensions, CONST, VAR and routine-local, walked by FOR or named by a
fixed subscript, with spare elements, CRLF; and an output that is not
what was meant (its storage, dimensions, name, scope, a statement's
subscript) is not taken, while the numbers read are those written."""

from pathlib import Path

import numpy as np
import pytest

from rapidcomp.compensate import verify as V
from rapidcomp.compensate.plan import Task
from rapidcomp.rapid.parse import parse_text
from rapidcomp.rapid.values import decode
from rapidcomp.rapid import ast as A

from cam_variants import HEAD, TAIL, robtarget, targets
from test_relex_absj import _converted, _fix_both, _same, solver  # noqa: F401

ROOT = Path(__file__).resolve().parents[1]


def _module(decl: list[str], body: list[str], routine_decl: list[str] = (),
            ending: str = "\n") -> str:
    lines = ["MODULE GH_Array", *HEAD, *decl, "  PROC GhPath()", *routine_decl,
             *("    " + s for s in body), "  ENDPROC", "  PROC main()", "    VAR num n:=0;",
             "    GhPath;", "  ENDPROC", "ENDMODULE", ""]
    return ending.join(lines)


def _array(kind: str, name: str, lits: list[str], dims: str, indent: str = "  ") -> list[str]:
    return ([f"{indent}{kind} robtarget {name}{{{dims}}}:=["]
            + [f"{indent}  {x}," for x in lits[:-1]] + [f"{indent}  {lits[-1]}];"])


def _lits(n: int, seed: int) -> list[str]:
    return [robtarget(t) for t in targets(n, seed)]


ONE = _module(_array("CONST", "path", _lits(12, 3), "12"),
              ["FOR i FROM 1 TO 10 DO", f"  MoveL path{{i}}{TAIL}", "ENDFOR",
               f"MoveJ path{{12}}{TAIL}"])
VAR = _module(_array("VAR", "path", _lits(9, 4), "9"),
              ["FOR i FROM 9 TO 1 STEP -2 DO", f"  MoveL path{{i}}{TAIL}", "ENDFOR"])
LOCAL = _module([], ["FOR k FROM 1 TO 5 DO", f"  MoveL pts{{k}}{TAIL}", "ENDFOR"],
                routine_decl=_array("CONST", "pts", _lits(5, 5), "5", indent="    "))
TWO = _module(_array("CONST", "grid", _lits(12, 6), "3,4").__add__([]),
              ["FOR i FROM 1 TO 3 DO", "  FOR j FROM 1 TO 4 DO",
               f"    MoveL grid{{i,j}}{TAIL}", "  ENDFOR", "ENDFOR"])


def _two_dims(text: str) -> str:
    # (A {3,4} array's value nests: [[a,b,c,d],[e,f,g,h],[i,j,k,l]].)
    head, _, rest = text.partition("grid{3,4}:=[\n")
    body, _, tail = rest.partition("];\n")
    items = [line.strip().rstrip(",") for line in body.split("\n")]
    rows = ["[" + ",".join(items[4 * r:4 * r + 4]) + "]" for r in range(3)]
    return head + "grid{3,4}:=[\n    " + ",\n    ".join(rows) + "];\n" + tail


TWO = _two_dims(TWO)


@pytest.mark.parametrize("text, uses", [
    (ONE, 11), (VAR, 5), (LOCAL, 5), (TWO, 12), (ONE.replace("\n", "\r\n"), 11)],
    ids=["const-for-and-fixed", "var-step", "routine-local", "two-dims", "crlf"])
def test_arrays_turned_into_moveabsj_are_read_again(monkeypatch, solver, text, uses):
    task = Task("gh.mod", (parse_text(text, "gh.mod"),))
    read, parsed, served = _fix_both(monkeypatch, task, solver, "absj")
    _same(read, parsed)
    assert served == [uses]
    out = read.modules[0].text
    assert out.count("MoveAbsJ jt_") == text.count("MoveL ") + text.count("MoveJ ")
    assert "CONST jointtarget jt_" in out
    assert all(r.status == "compensated" for r in read.rows)


def _changed(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


@pytest.mark.parametrize("old, new", [
    ("LOCAL CONST jointtarget jt_path{12}", "LOCAL VAR jointtarget jt_path{12}"),
    ("jt_path{12}:=", "jt_path{13}:="),                       # its dimensions
    ("jt_path{12}:=", "jt_pth{12}:="),                        # its name
    ("MoveAbsJ jt_path{i},", "MoveAbsJ jt_path{i+1},"),         # a subscript
    ("MoveAbsJ jt_path{i},", "MoveAbsJ jt_path_12{i},"),    # another new name
    ("MoveAbsJ jt_path{i},v100", "MoveAbsJ jt_path{i},v200"),   # the rest of a statement
    ("]],\n", "]];\n"),                                       # not one declaration
    ("]],\n", "]] ,,\n"),
])
def test_an_array_that_is_not_what_was_meant_is_not_taken(solver, old, new):
    plan, editor, edits, texts = _converted(solver, ONE)
    assert V.relex_absj(plan, editor.converted, edits, texts) is not None
    at = texts[0].index("jt_path{12}:=")
    bad = texts[0][:at] + _changed(texts[0][at:], old, new) if old.startswith("]]") \
        else _changed(texts[0], old, new)
    assert V.relex_absj(plan, editor.converted, edits, {0: bad}) is None


def test_an_array_out_of_the_moves_scope_is_not_taken(solver):
    # The routine's own array put in another routine (after its
    # declaration): not seen by the move.
    plan, editor, edits, texts = _converted(solver, LOCAL)
    assert V.relex_absj(plan, editor.converted, edits, texts) is not None
    k = next(i for i, e in enumerate(edits[0]) if e.start == e.end)
    src = plan.files[0].source.text
    e = edits[0][k]
    at = src.index("VAR num n:=0;") + len("VAR num n:=0;")
    moved = sorted(edits[0][:k] + edits[0][k + 1:] + [e._replace(start=at, end=at)],
                   key=lambda x: (x.start, x.end))
    from rapidcomp.edits import apply_edits
    bad = apply_edits(src, moved)
    parse_text(bad, "gh.mod")            # (a program still, its move's array elsewhere)
    assert V.relex_absj(plan, editor.converted, {0: moved}, {0: bad}) is None


def test_the_numbers_read_are_those_written(solver):
    # An element's number changed after the splice: read as written (the
    # verification then says what the controller would do with it), as
    # parsing the output again reads it; the other elements as meant.
    plan, editor, edits, texts = _converted(solver, ONE)
    good = V.relex_absj(plan, editor.converted, edits, texts)
    text = texts[0]
    decl = text.index("jt_path{12}:=")
    first = text.index("[[", text.index("\n", decl))          # element 1
    end = text.index("]]", first) + 2
    literal = text[first:end]
    # (A digit of its first joint another one: the output's length as meant.)
    at = next(i for i, c in enumerate(literal) if c.isdigit())
    changed = literal[:at] + ("7" if literal[at] != "7" else "3") + literal[at + 1:]
    bad = text[:first] + changed + text[end:]
    got = V.relex_absj(plan, editor.converted, edits, {0: bad})
    assert got is not None
    want = decode("jointtarget", A.NumAgg(changed, A.Span(0, len(changed)))).joints
    loop = [k for k in editor.converted if editor.converted[k][0].source.element == 0]
    assert len(loop) == 1
    assert got.get(loop[0]) == tuple(np.asarray(want, np.float32).astype(float).tolist())
    assert got.get(loop[0]) != good.get(loop[0])
    assert all(got.get(k) == good.get(k) for k in editor.converted if k != loop[0])
