"""Extracted values against what the fixtures say (read by eye)."""

import pytest

from rapidcomp.rapid import ast as A
from rapidcomp.rapid.parse import parse_file, parse_text
from rapidcomp.rapid.values import RobTarget, ToolData, WobjData


@pytest.fixture(scope="module")
def rs():
    from conftest import FIXTURES
    return parse_file(FIXTURES / "rapid" / "robotstudio_crlf.mod")


def decl(pf, name):
    return next(d for d in pf.module.declarations if d.name == name)


def test_robtarget_fields(rs):
    p = decl(rs, "pPlace")
    assert p.scope == "LOCAL" and p.storage == "PERS" and p.type == "robtarget"
    v = p.value
    assert v.xyz == (550.0, -150.0, 400.0)
    assert v.quat_wxyz == (0.707107, 0.0, 0.707107, 0.0)
    assert v.conf == (-1, -1, 0, 0)
    assert v.ext == (9e9,) * 6
    assert [f.text for f in v.extax] == ["9E+09"] * 6


def test_array_with_comment_inside(rs):
    p = decl(rs, "pPath")
    assert p.dims == (4,)
    assert [v.xyz for v in p.value] == [(400, 300, 250), (400, 150, 250), (400, 0, 250),
                                        (400, -150, 250)]
    assert p.value[3].conf == (-1, -1, 0, 0)


def test_tool_and_wobj(rs):
    t = decl(rs, "tGripper").value
    assert isinstance(t, ToolData) and t.robhold.value is True
    assert t.tframe.xyz == (0, 0, 150) and t.tframe.quat_wxyz == (1, 0, 0, 0)
    assert t.tload.mass.value == 1.5 and tuple(f.value for f in t.tload.cog) == (0, 0, 75)
    assert decl(rs, "tGripper").scope == "TASK"
    w = decl(rs, "wobjTable").value
    assert isinstance(w, WobjData)
    assert (w.robhold.value, w.ufprog.value, w.ufmec.value) == (False, True, "")
    assert w.uframe.xyz == (600, -200, 100)
    assert w.uframe.quat_wxyz == (0.9238795, 0, 0, 0.3826834)


def test_declaration_without_value_and_record_typed_value(rs):
    assert decl(rs, "pCurrent").value is None
    assert decl(rs, "pCurrent").issue == "declared without a value"
    assert decl(rs, "grid").dims == (2, 3)
    assert decl(rs, "cube").dims == (2, 2, 2)
    assert decl(rs, "i").routine == "main"


def test_motions_roles_and_context(rs):
    ms = rs.module.motions
    assert [m.spec.name for m in ms][:6] == ["MoveAbsJ", "MoveJ", "MoveL", "MoveL", "MoveL", "MoveC"]
    loop_move = ms[2]
    assert [lp.var for lp in loop_move.loops] == ["i"]
    assert rs.text(loop_move.targets[0].expr) == "pPath{i}"
    assert rs.text(loop_move.wobj) == "wobjTable"
    reltool = ms[4]
    assert rs.text(reltool.speed) == "v50" and rs.text(reltool.zone) == "z5"
    assert [rs.text(a) for a in reltool.optional] == ["\\V:=80", "\\Z:=3"]
    call = reltool.targets[0].expr
    assert isinstance(call, A.Call) and call.name == "RelTool"
    assert [a.kind for a in call.args] == ["pos", "pos", "pos", "pos", "optval"]
    movec = ms[5]
    assert [t.role for t in movec.targets] == ["cir", "to"]
    assert ms[0].optional[0].name == "NoEOffs" and ms[0].optional[0].kind == "opt"
    inline = next(m for m in ms if m.routine == "routine1")
    assert isinstance(inline.targets[0].value, RobTarget)
    assert inline.targets[0].value.xyz == (550, 0, 550)
    assert rs.line(inline.span) == 105


def test_number_spellings(fixtures_dir):
    pf = parse_file(fixtures_dir / "rapid" / "system_bom.sys")
    vals = {d.name: d.node.init for d in pf.module.declarations if d.type == "num" and d.node.init}
    assert vals["nBig"].value == 9e9 and vals["nBig2"].value == 9e9
    assert vals["nFrac"].value == 1.0 and vals["nFrac"].text == "1.00000000"
    assert vals["nHex"].value == 255 and vals["nOct"].value == 15 and vals["nBin"].value == 5
    assert vals["nDot"].value == 5.0
    assert vals["nNeg"].value == -1.5e-3 and vals["nNeg"].text == "-1.5E-3"
    tool = next(d for d in pf.module.declarations if d.name == "tWeld").value
    assert tool.tload.inertia[2].value == 0.005 and tool.tload.inertia[2].text == ".005"


def test_lowercase_keywords_and_cp1252(fixtures_dir):
    pf = parse_file(fixtures_dir / "rapid" / "handwritten_cp1252.mod")
    m = pf.module
    assert m.name == "handwork" and m.attributes == ("NOSTEPIN",)
    assert [mo.spec.name for mo in m.motions] == ["MoveJ", "MoveL", "MoveL"]
    assert decl(pf, "pAuf").value.xyz == (480, -60, 320)
    assert decl(pf, "bFertig").scope == "LOCAL"


def test_robodk_comma_before_optional_argument(fixtures_dir):
    pf = parse_file(fixtures_dir / "rapid" / "robodk.mod")
    moves = pf.module.motions
    assert all(pf.text(mo.wobj) == "rdkWObj" for mo in moves)
    assert moves[0].targets[0].value.joints == (41.85, 44.63, 25.88, 43.53, -75.61, -13.29)
    assert moves[1].targets[0].value.conf == (0, 0, -1, 0)


def test_non_literal_inline_target_is_reported_not_guessed():
    pf = parse_text("MODULE m\nPROC p()\nMoveL [[x,0,0],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]], v100, fine, tool0;\nENDPROC\nENDMODULE\n")
    (a,) = pf.module.motions
    assert a.targets[0].value is None and "inline robtarget.trans.x is not a literal" in a.targets[0].issue


@pytest.mark.parametrize("value, col, message", [
    ("[[0,0,0],[1,0,0,0],[0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]", 26,
     "inline robtarget.robconf has 3 components, expected 4 (the robtarget of MoveL)"),
    ("[[0,0],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]", 8,
     "inline robtarget.trans has 2 components, expected 3"),
    ("[[0,0,0],[1,0,0,0],[0,0,0,\"a\"],[9E9,9E9,9E9,9E9,9E9,9E9]]", 33,
     "inline robtarget.robconf.cfx is not a number"),
    # (Past every RAPID type: the parser's own word, at the number.)
    ("[[0,0,1E999],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]", 13,
     "number 1E999 is out of range (a num holds +-3.4E38, a dnum +-1.8E308)"),
    ("[[0,0,0],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E40]]", 57,
     "component 9E40 is beyond what a RAPID num holds"),
])
def test_a_value_no_controller_loads_is_bad_input_at_its_place(value, col, message):
    from rapidcomp.errors import InputError
    with pytest.raises(InputError) as e:
        parse_text(f"MODULE m\nPROC p()\nMoveL {value}, v100, fine, tool0;\nENDPROC\nENDMODULE\n",
                   "m.mod")
    assert (e.value.line, e.value.col) == (3, col) and message in e.value.message


def test_numeric_literals_decode_by_their_frame_as_the_regex_decodes_them():
    """_compact reads a NumAgg by the frame of its shape (numbers between
    brackets and commas). Oracle: the shape regex's groups, float() of
    each, on literals with whitespace anywhere NUMAGG allows it, every
    number spelling, wrong shapes (they must go the regex's way: its
    DecodeIssue), and a number beyond a num's range (its message and
    place). The lexer's number inside NUMAGG is NUMBER_RE (what makes the
    frame's fields numbers)."""
    import random
    import re
    from pathlib import Path
    from rapidcomp.rapid.values import DecodeIssue, _FAST, decode
    grammar = (Path(__file__).resolve().parents[1] / "grammars" / "rapid.lark").read_text()
    assert re.search(r"^_N: /(.*)/$", grammar, re.M).group(1) == A.NUMBER_RE.pattern
    rnd = random.Random(3)
    nums = ["1", "-2.5", "+3.", ".5", "-.25e-3", "1E+05", "9E9", "0", "-0", "007", "1e400",
            "3.5E38", "-3.4028234663852886e38"]
    # Every kind \s matches; float() refuses \x1c-\x1f around a number.
    ws = ["", "", "", "", "", " ", "\t", "\n", "\r\n  ", "\v", "\f", "\x1c", "\x1d", "\x1e",
          "\x1f", "\x85", "\xa0", "\u2003", "\u3000"]

    def lit(shape):
        parts = []
        for n in shape:
            inner = (rnd.choice(ws) + ",").join(rnd.choice(ws) + rnd.choice(nums) for _ in range(n))
            parts.append("[" + rnd.choice(ws) + inner + rnd.choice(ws) + "]")
        return "[" + rnd.choice(ws) + ("," + rnd.choice(ws)).join(parts) + rnd.choice(ws) + "]"
    shapes = {"robtarget": [(3, 4, 4, 6), (3, 4, 4, 5), (3, 4, 5, 5), (4, 4, 4, 6), (17,)],
              "jointtarget": [(6, 6), (6, 5, 1), (12,), (7, 5)]}
    seen = set()
    for _ in range(3000):
        kind = rnd.choice(sorted(shapes))
        shape = rnd.choice(shapes[kind])
        text = lit(shape)
        expr = A.NumAgg(text, A.Span(100, 100 + len(text)))
        m = _FAST[kind].fullmatch(text)
        try:
            got = decode(kind, expr, "t")
        except DecodeIssue as exc:
            got = (exc.reason, exc.span, exc.illegal)
        if m is not None and all(abs(float(t)) <= 3.4028234663852886e38 for t in m.groups()):
            want = (tuple(float(t) for t in m.groups()), text, expr.span)
            assert (got.values, got.lexed, got.span) == want, text
            seen.add("decoded")
        else:
            assert isinstance(got, tuple), text
            seen.add("beyond" if m is not None else "shape")
            if m is not None:
                assert "is beyond what a RAPID num holds" in got[0] and got[2]
                k = next(i for i, t in enumerate(m.groups())
                         if not abs(float(t)) <= 3.4028234663852886e38)
                assert got[1] == A.Span(100 + m.start(k + 1), 100 + m.end(k + 1))
    assert seen == {"decoded", "beyond", "shape"}
