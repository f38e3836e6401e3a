"""The nodes of a one-line call's arguments after its first (rapid/build.py):
made by the generic loop for a text's first uses, then by a function
written for that text. Both must make the very same nodes (a parse's
result may not depend on how often a text was seen before)."""

from rapidcomp.rapid import build as B
from rapidcomp.rapid.parse import parse_text

TAILS = [",v1000,z50,tool0;", ",v100,z1,tSpindle\\WObj:=wPart;",
         ",v1000,z50,tool0\\V:=12.5\\Conc\\WObj:=wobj1;", "\\ID:=10,v200,fine,tool0;",
         ";", ",v100\\T:=3,z10,tool0\\TLoad:=load1;"]


def test_written_function_makes_the_loops_nodes():
    for tail in TAILS:
        loop, written = B._Tail(tail), B._Tail(tail)
        written.make = B._tail_maker(written.items)
        for at in (0, 7, 123456):
            got, want = written.nodes(at), loop.nodes(at)
            assert got == want and [type(a.value) for a in got] == [type(a.value) for a in want]
            assert [a.span for a in got] == [a.span for a in want]


def test_a_text_used_often_gets_its_function_and_the_parse_is_the_same():
    n = B.COMPILE_AFTER + 10
    lines = ["MODULE M"] + ["  PROC p()"]
    lines += [f"    MoveL [[{i},0,0],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]],"
              "v100,z1,tool0\\V:=7\\WObj:=wobj_q;" for i in range(n)]
    lines += ["  ENDPROC", "ENDMODULE", ""]
    text = "\n".join(lines)
    B._TAILS.clear()
    first = parse_text(text, "m.mod")
    (tail,) = [t for k, t in B._TAILS.items() if "wobj_q" in k]
    assert tail.make is not None          # written after COMPILE_AFTER uses
    again = parse_text(text, "m.mod")     # every call made by the written function
    assert again.modules == first.modules
    motions = again.modules[0].motions
    assert len(motions) == n
    for m in motions:                     # the spans lie on the text they name
        assert text[m.wobj.span.start:m.wobj.span.end] == "wobj_q"
        (v,) = m.optional
        assert (v.name, v.value.value, text[v.span.start:v.span.end]) == ("V", 7.0, "\\V:=7")


def test_distinct_texts_are_never_written_as_functions():
    B._TAILS.clear()
    for i in range(50):
        B._fast_tail(f"\\ID:={i},v200,fine,tool0;").nodes(0)
    assert all(t.make is None for t in B._TAILS.values())
