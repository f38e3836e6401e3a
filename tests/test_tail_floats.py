"""A plain robtarget's confdata and external axes (a jointtarget's
external axes) are decoded once per distinct text and their floats shared
between literals (values._floats). Oracle: float() of each number as
written, compared by repr (the sign of a zero too), on seeded random
literals of both types, declared and inline, that repeat some tails with
other heads (a last quaternion component or joint that differs where the
rest is the same)."""

import random

from rapidcomp.rapid import values as V
from rapidcomp.rapid.parse import parse_text

NUMBERS = ["0", "-0", "1", "-1", "0.5", "-0.0", "9E+09", "9e9", "1E-3", "123.456", "-0.70710",
           "4", "2.", ".25"]


def _module(rnd, n):
    lines, expected = ["MODULE T"], []
    routine = []
    for i in range(n):
        rob = rnd.random() < 0.6
        count = (3, 4, 4, 6) if rob else (6, 6)
        groups = [[rnd.choice(NUMBERS) for _ in range(k)] for k in count]
        if rnd.random() < 0.5:
            # The same tail as an earlier literal's, another head: a
            # quaternion's or joint's last number differs.
            groups[-2 if rob else -1] = ["0", "0", "-1", "1"] if rob else ["9E+09"] * 6
            groups[0][-1] = f"{rnd.uniform(-1e3, 1e3):.3f}"
            if rob:
                groups[1][-1] = rnd.choice(["0.1", "-0.1", "0", "-0"])
                groups[3] = ["9E+09"] * 6
        text = "[" + ",".join("[" + ",".join(g) + "]" for g in groups) + "]"
        fields = [f for g in groups for f in g]
        type_ = "robtarget" if rob else "jointtarget"
        if rnd.random() < 0.5:
            lines.append(f"  CONST {type_} t{i}:={text};")
            expected.append(("decl", f"t{i}", fields))
        else:
            move = "MoveL" if rob else "MoveAbsJ"
            routine.append(f"    {move} {text},v100,z1,tool0;")
            expected.append(("inline", None, fields))
    lines += ["  PROC main()"] + routine + ["  ENDPROC", "ENDMODULE", ""]
    return "\n".join(lines), expected


def _decoded(pf):
    m = pf.modules[0]
    decls = {d.name: d.value for d in m.declarations}
    inline = iter(t.value for mo in m.motions for t in mo.targets)
    return decls, inline


def test_plain_literals_decode_to_the_floats_of_their_texts():
    rnd = random.Random(11)
    text, expected = _module(rnd, 1500)
    decls, inline = _decoded(parse_text(text, "t.mod"))
    for where, name, fields in expected:
        record = decls[name] if where == "decl" else next(inline)
        assert list(map(repr, record.values)) == [repr(float(f)) for f in fields], fields


def test_equal_tails_share_their_floats_and_the_cache_is_bounded(monkeypatch):
    monkeypatch.setattr(V, "TAIL_FLOATS_MAX", 5)
    monkeypatch.setattr(V, "_TAIL_FLOATS", {})
    tail = "[0,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
    text = "\n".join(
        ["MODULE T"]
        + [f"  CONST robtarget a{i}:=[[{i},2,3],[1,0,0,{i % 2}],{tail};" for i in range(4)]
        + [f"  CONST robtarget b{i}:=[[1,2,3],[1,0,0,0],[{i},0,0,0],[1,2,3,4,5,6]];"
           for i in range(12)]
        + ["  CONST jointtarget j1:=[[1,2,3,4,5,6],[7,8,9,10,11,12]];",
           "  CONST jointtarget j2:=[[6,5,4,3,2,1],[7,8,9,10,11,12]];",
           "ENDMODULE", ""])
    decls, _ = _decoded(parse_text(text, "t.mod"))
    a = [decls[f"a{i}"].values for i in range(4)]
    assert all(x[k] is a[0][k] for x in a for k in range(7, 17))
    assert [x[6] for x in a] == [0.0, 1.0, 0.0, 1.0]
    assert all(decls["j1"].values[k] is decls["j2"].values[k] for k in range(6, 12))
    assert decls["j1"].values[:6] == (1.0, 2.0, 3.0, 4.0, 5.0, 6.0)
    assert decls["j2"].values[:6] == (6.0, 5.0, 4.0, 3.0, 2.0, 1.0)
    assert 0 < len(V._TAIL_FLOATS) <= 5


def test_a_resolvers_uses_share_equal_confdata_and_external_axes_of_the_same_signs():
    """Each use's confdata and external axes are one tuple per distinct
    value in a resolver (Resolver._one). Oracle: the numbers as written,
    by repr (a -0 keeps its sign), and which uses share which tuple."""
    from rapidcomp.compensate.plan import Plan, Task
    ext = ["9E+09,9E+09,9E+09,9E+09,9E+09,9E+09", "0,9E+09,9E+09,9E+09,9E+09,9E+09",
           "-0,9E+09,9E+09,9E+09,9E+09,9E+09", "0,9E+09,9E+09,9E+09,9E+09,9E+09"]
    conf = ["0,-1,0,1", "0,0,0,1", "0,-1,0,1", "-0,-1,0,1"]
    moves = "".join(f"    MoveL [[500,{i},600],[0,0,1,0],[{c}],[{e}]],v100,fine,tool0;\n"
                    for i, (c, e) in enumerate(zip(conf, ext)))
    text = f"MODULE M\n  PROC main()\n{moves}  ENDPROC\nENDMODULE\n"
    uses = Plan(Task("m.mod", (parse_text(text, "m.mod"),))).uses
    assert len(uses) == 4 and all(u.reason is None for u in uses)
    assert [repr(u.ext[0]) for u in uses] == ["9000000000.0", "0.0", "-0.0", "0.0"]
    assert uses[1].ext is uses[3].ext and uses[1].ext is not uses[2].ext
    assert [u.conf for u in uses] == [(0, -1, 0, 1), (0, 0, 0, 1), (0, -1, 0, 1), (0, -1, 0, 1)]
    assert uses[0].conf is uses[2].conf is uses[3].conf
