"""The nodes of a one-line call's arguments after its first (rapid/build.py):
made by the generic loop for a text's first uses, then by a function
written for that text. Both must make the very same nodes (a parse's
result may not depend on how often a text was seen before)."""

import pytest

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


def test_a_text_read_often_gets_its_function_and_the_nodes_are_the_same():
    """A move's arguments after its first are made each time they are
    read (A.TailArgs): by the loop at first, by the written function once
    the text was read COMPILE_AFTER times; the same nodes either way."""
    n = B.COMPILE_AFTER + 10
    lines = ["MODULE M"] + ["  PROC p()"]
    lines += [f"    MoveL [[{i},0,0],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]],"
              "v100,z1,tool0\\V:=7\\WObj:=wobj_q;" for i in range(n)]
    lines += ["  ENDPROC", "ENDMODULE", ""]
    text = "\n".join(lines)
    B._TAILS.clear()
    first = parse_text(text, "m.mod")
    (tail,) = [t for k, t in B._TAILS.items() if "wobj_q" in k]
    motions = first.modules[0].motions
    assert len(motions) == n and tail.make is None   # (nothing read yet)
    by_loop = [tuple(m.args) for m in motions]
    assert tail.make is not None          # written after COMPILE_AFTER reads
    assert [tuple(m.args) for m in motions] == by_loop
    assert parse_text(text, "m.mod").modules == first.modules
    for m in motions:                     # the spans lie on the text they name
        assert text[m.wobj.span.start:m.wobj.span.end] == "wobj_q"
        (v,) = m.optional
        assert (v.name, v.value.value, text[v.span.start:v.span.end]) == ("V", 7.0, "\\V:=7")


def test_tail_args_read_as_the_tuple_of_their_nodes():
    """A.TailArgs is read as the tuple of its Arg nodes: each value alone
    (value(j)) is the node's, and it compares, hashes and copies (pickle)
    as that tuple."""
    import pickle

    from rapidcomp.rapid import ast as A
    for tail in TAILS:
        t = B._Tail(tail)
        first = A.Ref("p1", (), A.Span(3, 5))
        args = A.TailArgs(first, t, 5)
        nodes = (A.Arg("pos", None, first, A.Span(3, 5)),) + t.nodes(5)
        assert len(args) == len(nodes) and tuple(args) == nodes and args == nodes
        assert nodes == args and hash(args) == hash(nodes)
        assert list(reversed(args)) == list(reversed(nodes)) and args[-1] == nodes[-1]
        assert [args.value(j) for j in range(len(args))] == [a.value for a in nodes]
        assert pickle.loads(pickle.dumps(args)) == nodes
        assert type(pickle.loads(pickle.dumps(args))) is tuple


def test_distinct_texts_are_never_written_as_functions():
    B._TAILS.clear()
    for i in range(50):
        B._fast_tail(f"\\ID:={i},v200,fine,tool0;").nodes(0)
    assert all(t.make is None for t in B._TAILS.values())


def test_a_cam_moves_parse_keeps_no_node_per_argument():
    """Issue #14, memory: what the parse keeps of a CAM move is its call,
    its motion and its target (call, span, arguments, first value and its
    span, motion, target and the tuple of them, and an inline target's
    decoded value), not a node per argument: at most 9 objects a move, in
    the marginal count of objects the collector tracks (the parse before
    this kept 22.5: speed, zone, tool and \\WObj as Arg, Ref and Span
    each)."""
    import gc

    def cam(n):
        lines = ["MODULE CAM", "  PROC Path()"]
        lines += [f"    MoveL [[{500 + i % 7},{i % 11},{400 + i % 13}],[1,0,0,0],[0,0,0,0],"
                  "[9E9,9E9,9E9,9E9,9E9,9E9]],v100,z1,tSpindle\\WObj:=wobj0;" for i in range(n)]
        lines += [f"    MoveL p{i},v100,z1,tSpindle\\WObj:=wobj0;" for i in range(n)]
        return "\n".join(lines + ["  ENDPROC", "ENDMODULE", ""])

    def kept(n):
        text = cam(n)
        gc.collect()
        before = len(gc.get_objects())
        pf = parse_text(text, "cam.mod")
        gc.collect()
        assert len(pf.module.motions) == 2 * n
        return len(gc.get_objects()) - before

    kept(200)                                # (what a first parse makes once)
    per_move = (kept(2000) - kept(1000)) / 2000
    assert per_move <= 9, per_move


def test_moves_sharing_a_tail_resolve_their_own_routines_tool_without_its_nodes(monkeypatch):
    """A move lexed as one token resolves its tool and work object once per
    (module, routine, tail) (targets.Resolver._tool_wobj): not from nodes
    made for each move, and each routine's own data where a routine
    declares a tool of the same name (RAPID looks in the routine first).
    Expected tools written here by hand: the tframe's x of each."""
    from rapidcomp.compensate.plan import Plan, Task

    def module(name, x_by_routine, n):
        lines = [f"MODULE {name}", "  PERS tooldata tCut := [TRUE,[[0,0,100],[1,0,0,0]],"
                 "[1,[0,0,1],[1,0,0,0],0,0,0]];"]
        for r, x in x_by_routine.items():
            lines.append(f"  PROC {r}()")
            if x is not None:
                lines.append(f"    VAR tooldata tCut := [TRUE,[[{x},0,100],[1,0,0,0]],"
                             "[1,[0,0,1],[1,0,0,0],0,0,0]];")
            lines += [f"    MoveL [[{400 + i},0,400],[0,0,1,0],[0,0,0,0],"
                      "[9E9,9E9,9E9,9E9,9E9,9E9]],v100,z1,tCut\\WObj:=wobj0;" for i in range(n)]
            lines.append("  ENDPROC")
        return "\n".join(lines + ["ENDMODULE", ""])

    n = 50
    B._TAILS.clear()
    a = parse_text(module("A", {"r1": None, "r2": 7, "r3": 9}, n), "a.mod")
    b = parse_text(module("B", {"r1": 11}, n), "b.mod")
    made = []
    value = B._Tail.value
    monkeypatch.setattr(B._Tail, "value", lambda self, at, j: made.append(j) or value(self, at, j))
    plan = Plan(Task("t", (a, b)))
    want = {("a.mod", "r1"): 0.0, ("a.mod", "r2"): 7.0, ("a.mod", "r3"): 9.0,
            ("b.mod", "r1"): 11.0}
    got = {}
    for u in plan.uses:
        assert u.reason is None
        got.setdefault((u.file.source.display_path, u.motion.routine), set()).add(
            float(u.tool[1][1][0]))
    assert got == {k: {x} for k, x in want.items()}
    # One resolution per (module, routine): tool and work object, not 2 per move.
    assert len(made) <= 2 * len(want) < 2 * len(plan.uses)


@pytest.mark.parametrize("main", [False, True])
def test_fixing_a_cam_module_makes_no_node_of_its_moves_tails(main, monkeypatch):
    """fix of a CAM module (Path entered from outside, or called from main:
    every MoveL turned into MoveAbsJ) reads the tool and work object of
    its moves once per shared tail (resolve, verify, the notes): the count
    of tail nodes made is the same for 150 moves as for 300."""
    import sys
    from pathlib import Path

    from rapidcomp.compensate.fix import fix
    from rapidcomp.compensate.load import load_solver
    from rapidcomp.compensate.plan import Task
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))
    from fix import cam_module
    solver = load_solver(str(Path(__file__).resolve().parents[1] / "fixtures" / "warm.csv"),
                         None, False)
    made = []
    value, nodes = B._Tail.value, B._Tail.nodes
    monkeypatch.setattr(B._Tail, "value", lambda self, at, j: made.append(j) or value(self, at, j))
    monkeypatch.setattr(B._Tail, "nodes", lambda self, at: made.append(at) or nodes(self, at))
    counts = {}
    for n in (150, 300):
        for mode in ("absj", "robtarget"):
            pf = parse_text(cam_module(n, main=main), "c.mod")
            made.clear()
            result = fix(Task("c.mod", (pf,)), solver, mode)
            assert result.failed == 0
            counts[(n, mode)] = len(made)
    assert counts[(150, "absj")] == counts[(300, "absj")] <= 8
    assert counts[(150, "robtarget")] == counts[(300, "robtarget")] <= 8
