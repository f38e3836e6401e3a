"""Grammar constructs, one snippet each, checked on the nodes they produce."""

import pytest

from rapidcomp.rapid import ast as A
from rapidcomp.rapid.parse import parse_text


def body(stmts: str, decls: str = ""):
    pf = parse_text(f"MODULE m\n{decls}\nPROC p()\n{stmts}\nENDPROC\nENDMODULE\n")
    return pf, pf.module.routines[0].node.body


def expr_of(text: str):
    pf, b = body(f"x := {text};")
    return pf, b[0].value


def shape(e):
    """A compact view of an expression tree for precedence checks."""
    if isinstance(e, A.Binary):
        return (e.op, shape(e.left), shape(e.right))
    if isinstance(e, A.Unary):
        return (e.op, shape(e.operand))
    if isinstance(e, A.Paren):
        return shape(e.expr)
    if isinstance(e, A.Ref):
        return e.name
    if isinstance(e, A.Num):
        return e.value
    return type(e).__name__


@pytest.mark.parametrize("text,expected", [
    ("a OR b AND c", ("OR", "a", ("AND", "b", "c"))),
    ("a AND b OR c", ("OR", ("AND", "a", "b"), "c")),
    ("a XOR b OR c", ("OR", ("XOR", "a", "b"), "c")),
    ("NOT a AND b", ("AND", ("NOT", "a"), "b")),
    ("a < b + 1", ("<", "a", ("+", "b", 1.0))),
    ("a = b AND c <> d", ("AND", ("=", "a", "b"), ("<>", "c", "d"))),
    ("a + b * c", ("+", "a", ("*", "b", "c"))),
    ("a - b - c", ("-", ("-", "a", "b"), "c")),
    ("a * b DIV c MOD d", ("MOD", ("DIV", ("*", "a", "b"), "c"), "d")),
    ("-a * b", ("*", ("-", "a"), "b")),
    ("(a + b) * c", ("*", ("+", "a", "b"), "c")),
    ("a >= -5", (">=", "a", -5.0)),
])
def test_precedence(text, expected):
    _, e = expr_of(text)
    assert shape(e) == expected




def test_component_on_call_is_rejected():
    from rapidcomp.errors import InputError
    with pytest.raises(InputError):
        expr_of("Offs(p, 0, 0, 10).trans")


def test_components_and_indexes():
    pf, e = expr_of("p.trans.x + arr{i + 1, 2}.rot.q1")
    left, right = e.left, e.right
    assert left.name == "p" and [s.name for s in left.selectors] == ["trans", "x"]
    assert right.name == "arr" and isinstance(right.selectors[0], A.Index)
    assert shape(right.selectors[0].indices[0]) == ("+", "i", 1.0)
    assert pf.text(right) == "arr{i + 1, 2}.rot.q1"


def test_call_arguments_all_forms():
    pf, b = body('Foo \\Opt, a \\B:=2 \\C?d, Param:=3, "s""q";')
    args = b[0].args
    assert [a.kind for a in args] == ["opt", "pos", "optval", "cond", "named", "pos"]
    assert args[-1].value.value == 's"q'
    assert args[3].name == "C" and pf.text(args[3].value) == "d"


def test_statements():
    pf, b = body("""
    IF a THEN x:=1; ELSEIF b THEN x:=2; ELSEIF c THEN x:=3; ELSE x:=4; ENDIF
    IF a x:=5;
    FOR i FROM 1 TO 10 STEP 2 DO x:=i; ENDFOR
    WHILE a DO x:=1; ENDWHILE
    TEST x CASE 1,2,3: y:=1; CASE 4: y:=2; DEFAULT: y:=3; ENDTEST
    GOTO lbl;
    lbl:
    RETURN;
    RAISE ERR_MY;
    RETRY; TRYNEXT; EXIT;
    CONNECT intno WITH tr;
    %"proc" + NumToStr(i,0)% a, b;
    %procname%;
    <SMT>
    """)
    kinds = [type(s).__name__ if not isinstance(s, A.Simple) else s.kind for s in b]
    assert kinds == ["If", "CompactIf", "For", "While", "Test", "GOTO", "LABEL", "RETURN",
                     "RAISE", "RETRY", "TRYNEXT", "EXIT", "CONNECT", "LateCall", "LateCall",
                     "PLACEHOLDER"]
    assert len(b[0].branches) == 3 and len(b[0].orelse) == 1
    assert pf.text(b[2].step) == "2"
    assert [len(vals) for vals, _ in b[4].cases] == [3, 1]


def test_routine_forms_and_parameters():
    pf = parse_text("""MODULE m
    LOCAL PROC a(num x \\num y | switch z, INOUT robtarget p, VAR num w, PERS tooldata t, num arr{*,*})
    ERROR
      RETRY;
    UNDO
      x := 0;
    ENDPROC
    PROC b()
      Stop;
    BACKWARD
      Stop;
    ENDPROC
    FUNC bool f(num x)
      RETURN x > 0;
    ERROR (ERR_A, 41)
      RETURN FALSE;
    ENDFUNC
    LOCAL TRAP t
      Stop;
    ERROR
      RETURN;
    ENDTRAP
    ENDMODULE
    """)
    a, b, f, t = (r.node for r in pf.module.routines)
    assert a.scope == "LOCAL" and [p.name for p in a.params] == ["x", "y", "z", "p", "w", "t", "arr"]
    assert [p.optional for p in a.params] == [False, True, True, False, False, False, False]
    assert [p.access for p in a.params][3:6] == ["INOUT", "VAR", "PERS"]
    assert a.params[-1].array == 2
    assert [h.kind for h in a.handlers] == ["ERROR", "UNDO"]
    assert [h.kind for h in b.handlers] == ["BACKWARD"]
    assert f.return_type == "bool" and len(f.handlers[0].errors) == 2
    assert t.kind == "TRAP" and t.scope == "LOCAL"


def test_declarations_and_module_items():
    pf = parse_text("""MODULE m(SYSMODULE, NOSTEPIN, VIEWONLY, READONLY, NOVIEW)
    RECORD r num a; string b; ENDRECORD
    LOCAL ALIAS num lvl;
    TASK PERS num n := 1;
    LOCAL VAR num grid{2,4};
    CONST num c{3} := [1, 2,
        ! comment between
        3];
    VAR num e{2,2,2};
    <DDN>
    ENDMODULE""")
    m = pf.module
    assert m.attributes == ("SYSMODULE", "NOSTEPIN", "VIEWONLY", "READONLY", "NOVIEW")
    assert m.records[0].components == (("num", "a"), ("string", "b"))
    assert m.aliases[0].scope == "LOCAL" and m.aliases[0].name == "lvl"
    d = {x.name: x for x in m.declarations}
    assert (d["n"].scope, d["n"].storage) == ("TASK", "PERS")
    assert d["grid"].dims == (2, 4) and d["e"].dims == (2, 2, 2)
    assert [i.value for i in d["c"].node.init.items] == [1, 2, 3]


def test_keywords_case_insensitive():
    pf = parse_text("module m\nproc p()\nif a then x:=1; endif\nendproc\nendmodule\n")
    assert isinstance(pf.module.routines[0].node.body[0], A.If)


def test_fast_path_refuses_reserved_words():
    # "a, TRUE" looks like a one-line call but TRUE is a keyword: lexed
    # normally, the argument is a Bool, not a data reference named TRUE.
    pf, b = body("Foo a, TRUE;")
    assert isinstance(b[0].args[1].value, A.Bool)
    pf, b = body("Foo a, b;")
    assert [x.value.name for x in b[0].args] == ["a", "b"]


def test_one_token_calls_give_the_general_grammars_tree(monkeypatch):
    """A one-line call lexed as one FAST_CALL token (its arguments after the
    first lexed once per distinct text) gives the tree the grammar's own
    rules give, spans included, for calls repeated at other offsets."""
    import random
    from rapidcomp.rapid.grammar import engine
    rnd = random.Random(11)
    agg = "[[1.5,-2,3E+2],[1,0,0,0],[0,-1,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
    # (Functions of names and aggregates too: fix --transient writes
    # rcTcR(p10, p10_dq) and rcTcR([[...]], [[...],[...]]).)
    funcs = ["rcTcR(p10, p10_dq)", "rcTcJ(jt_p1,jt_p1_dq)", f"f({agg},\t[[0.1,2],[0,1,0,0]])",
             "g( a ,b , c )", "h([0,1.25])",
             # (Optional arguments of the function, with or without a comma
             # before them; signed numbers.)
             "RelTool(p1, 0, 0, -10 \\Rz:=45)", "RelTool(p1,0,0,0\\Rx:=-10.5\\Rz:=+30)",
             "f(a \\B)", "f(a, \\B:=c, 2)", "f(a,\\B := 1.5 )"]
    # (A number first: WaitTime 0.2; AccSet 50, 100;)
    firsts = [agg, "p1", "pLong_2", *funcs, "[0,1.25]", "0.2", "-1", "+2.", "50"]
    tails = [",v100,z1,tool1\\WObj:=wobj1;", ",v1000,fine,tool0;", "\\Conc,v10,z5,t;",
             ",v5\\V:=100,z1,t\\WObj:=w;", ",a\\T:=1.5,b\\Opt;", ",v100,z1,tool1\\WObj:=wobj1;",
             # (Blanks around := as some posts write them.)
             ", v100, z1, tool1 \\WObj := wobj1;", ",v5\\V :=100,z1,t\\WObj:=\tw ;",
             ",a\\T:= 1.5,b \\Opt;",
             # (Numbers after the first (SetDO do1, 1;), signed too; none:
             # Reset do1;)
             ", 1;", ",0.5, -2\\T:=-3;", ";", " ;", ",+4.25,x;"]
    lines = []
    for _ in range(300):
        name = rnd.choice(["MoveL", "MoveJ", "Foo"])
        first = rnd.choice(firsts if name == "Foo" else firsts[:-5])
        lines.append(f"    {name}{rnd.choice([' ', '  ', chr(9)])}{first}{rnd.choice(tails)}")
    text = "MODULE m\n  PROC p()\n" + "\n".join(lines) + "\n  ENDPROC\nENDMODULE\n"
    fast = parse_text(text)
    eng = engine()
    assert sum(t.type == "FAST_CALL" for t in eng.tokens(text, runs=True)) == 300
    monkeypatch.setattr(type(eng), "_keyword_in", lambda self, call: True)
    general = parse_text(text)
    assert repr(fast.modules) == repr(general.modules)
    calls = fast.module.routines[0].node.body
    assert len(calls) == 300 and all(type(c) is A.ProcCall for c in calls)


@pytest.mark.parametrize("stmt", [
    "IF bFlag MoveL(p10),v100,z1,tool0;", "IF bDebug TPWrite(sMsg)\\Num:=nVal;",
    "IF a f([1,2]),c;", "IF x MoveL\\Conc,p,v,z,t;", "x := a f(b),c;",
    "Move L rcTcR(p10,p10_dq),v100,z1,tool1;", "Move L p10,v100,z1,tool1;",
    "MoveL rcTcR(p10, p10_dq),v100,z1,tool1;",
    # (A declaration without a value, a call of one argument after a
    # condition: the FAST_CALL of one argument has no place there.)
    "VAR num n;", "IF bFlag Reset doGrip;", "IF a WaitTime 0.5;",
    # (A number beyond a num's range: refused where the general parser
    # refuses it, not read as inf.)
    "MoveL p,v100\\V:=" + "1" * 400 + ",z1,t;", "WaitTime " + "9" * 40 + ";",
    "SetDO do1, " + "9" * 400 + ";", "MoveL RelTool(p, 0, 0, 0 \\Rz:=" + "4" * 400 + "),v,z,t;",
    # (A digit of another script: not RAPID, refused where it stands.)
    "WaitTime \u0661;", "Foo f(\u0661), v;", "MoveL p,v100\\V:=\uff11,z1,t;",
    "SetDO do1, \u0661;"])
def test_a_one_token_statement_where_none_fits_is_read_as_its_own_tokens(stmt, monkeypatch):
    """Text lexed as one FAST_CALL where the table has no place for a
    statement (its first word ends an IF's condition or an expression) is
    read as the general lexer reads it: the same tree, or the same error
    at the same place, as with the one-token path off."""
    from rapidcomp.errors import RapidcompError
    from rapidcomp.rapid.grammar import engine
    text = f"MODULE m\n  PROC p()\n    {stmt}\n  ENDPROC\nENDMODULE\n"

    def read():
        try:
            return repr(parse_text(text).modules)
        except RapidcompError as exc:
            return str(exc)
    fast = read()
    monkeypatch.setattr(type(engine()), "_keyword_in", lambda self, call: True)
    assert fast == read()


def test_numbers_split_one_way_only():
    """A statement that fails after its aggregates (continued on the next
    line: still RAPID) is not tried again at every split of each number's
    digits (two jointtargets of 4-digit integers took 40 s): it parses."""
    jt = "[[1000,2000,3000,4000,5000,6000],[9E9,9E9,9E9,9E9,9E9,9E9]]"
    text = (f"MODULE m\n  PROC p()\n    MoveAbsJ rcTcJ({jt}, {jt}),\n        v100,z1,tool0;\n"
            "  ENDPROC\nENDMODULE\n")
    call = parse_text(text).module.routines[0].node.body[0]
    assert call.name == "MoveAbsJ" and call.args[0].value.name == "rcTcJ"


@pytest.mark.parametrize("stmt", ["WaitTime \u0661;", "x := \uff11;",
                                  "MoveL [[\u0661,0,0],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,"
                                  "9E9]],v100,z1,tool0;"])
def test_a_digit_of_another_script_is_refused_where_it_stands(stmt):
    """The controller reads ASCII digits only: another script's digit (which
    Python's float() would read) is an unexpected character, said where."""
    from rapidcomp.errors import InputError
    text = f"MODULE m\n  PROC p()\n    {stmt}\n  ENDPROC\nENDMODULE\n"
    with pytest.raises(InputError) as err:
        parse_text(text, "m.mod")
    col = next(i for i, c in enumerate(stmt) if ord(c) > 127) + 5
    assert str(err.value).startswith(f"m.mod:3:{col}: unexpected character")


def test_numbers_as_tools_write_them_keep_the_one_token_path():
    """Exponents with leading zeros (9E+009, 1.2E-005: older Windows tools
    write them so), or none, and long fractions: a move with such a literal
    target is still one token, its target one number aggregate, and so is a
    declaration's value (the bounds that keep an aggregate's numbers finite
    let these through: a CAM program of them took 3x the time and 2x the
    memory otherwise). Numbers that may be beyond a dnum are read one by
    one, with the same values."""
    from rapidcomp.rapid import ast as A
    from rapidcomp.rapid.parse import parse_text
    lit = ("[[1.2E-005,-0.5e+01,3E0],[1,0,0,0.000000000000000000000000000000000001],[0,0,0,0],"
           "[9E+009,9E+009,9E+009,9E+009,9E+009,9E-0000]]")
    text = (f"MODULE m\n  CONST robtarget p:={lit};\n  PROC main()\n"
            + f"    MoveL {lit},v100,z1,tool0;\n" * 3 + "  ENDPROC\nENDMODULE\n")
    m = parse_text(text, "m.mod").module
    assert type(m.declarations[0].node.init) is A.NumAgg
    for mo in m.motions:
        assert type(mo.targets[0].expr) is A.NumAgg and type(mo.args) is A.TailArgs
        assert mo.targets[0].value.values == m.declarations[0].value.values
    assert m.declarations[0].value.values[:3] == (1.2e-5, -5.0, 3.0)
    assert m.declarations[0].value.values[11:] == (9e9,) * 5 + (9.0,)
    # Read one by one: the same numbers.
    far = lit.replace("3E0", "3E-100")
    other = parse_text(f"MODULE m\n  CONST robtarget p:={far};\nENDMODULE\n", "m.mod").module
    assert type(other.declarations[0].node.init) is A.Agg
    assert other.declarations[0].value.values[2] == 3e-100


def test_a_span_is_the_pair_of_its_offsets():
    """ast.Span holds (start, end) as one int: it reads, unpacks, orders,
    copies and prints as the pair does; equal only to a Span of that range."""
    import pickle
    import random
    rnd = random.Random(3)
    pairs = [(a, a + rnd.randrange(0, 5000)) for a in
             (rnd.randrange(0, 2 ** 32 - 6000) for _ in range(300))] + [(0, 0), (7, 7)]
    spans = [A.Span(*p) for p in pairs]
    for (a, b), s in zip(pairs, spans):
        assert (s.start, s.end) == (a, b) == tuple(s) == (s[0], s[1])
        x, y = s
        assert (x, y) == (a, b) and len(s) == 2 and bool(s)
        assert pickle.loads(pickle.dumps(s)) == s and type(pickle.loads(pickle.dumps(s))) is A.Span
        assert repr(s) == f"Span(start={a}, end={b})"
        assert s == A.Span(a, b) and s != (a, b)
    assert sorted(spans) == [A.Span(*p) for p in sorted(pairs)]
    # The parse's nodes, the one-token path's and the general one's.
    text = "MODULE M\n  PROC p()\n    MoveL [[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]],v1,z1,t;\n"
    pf = parse_text(text + "    x := 1;\n  ENDPROC\nENDMODULE\n", "m.mod")
    move, assign = pf.modules[0].routines[0].node.body
    assert text[move.span.start:move.span.end].startswith("MoveL [[1,2,3]")
    assert text[move.span.end - 1] == ";" and type(move.span) is A.Span
    assert [type(a.span) for a in move.args] == [A.Span] * 4
    assert type(assign.span) is A.Span and assign.span.start == len(text) + 4


def test_a_text_beyond_what_a_span_holds_is_refused(monkeypatch):
    from rapidcomp.errors import InputError
    monkeypatch.setattr(A, "SPAN_LIMIT", 40)
    with pytest.raises(InputError, match=r"m.mod:1:1: 48 characters: more than the 39 of the "
                                         "largest module rapidcomp reads"):
        parse_text("MODULE M\n  ! a comment of some length\nENDMODULE\n", "m.mod")
    parse_text("MODULE M\nENDMODULE\n", "m.mod")
