"""The syntax walk (refs.nodes) and the calls a statement makes
(flow._function_calls) take calls of plain arguments (MoveL Offs(p, 0, 0,
10), ...: a hand-written or Offs-relative program's every move) without
the general per-field walk (issue #14: 2e4 such moves walked 1.1e6 nodes,
~1 s). Oracle: the general walk written here as it was, on statements of
every shape around it."""

from dataclasses import fields

from rapidcomp.compensate import flow as F
from rapidcomp.rapid import ast as A
from rapidcomp.rapid.parse import parse_text
from rapidcomp.rapid.refs import nodes

STATEMENTS = """MODULE m
  PROC main()
    MoveL Offs(p1, 0, 0, 10), v100, z1, tool1;
    MoveL Offs(p1,-1.5,+2,.5),v100,z1,tool1\\WObj:=wobj1;
    MoveL RelTool(p1, 0, 0, 10 \\Rz:=45), v100, fine, tool1;
    MoveL Offs(Offs(p1, 0, 0, 10), 1, 2, 3), v100, z1, tool1;
    MoveL myTarget(p1, TRUE), v100, z1, tool1;
    MoveL myTarget(p1, 1), v100, z1, tool1 \\WObj:=wObj{2};
    MoveJ pArr{i}, v100, z1, tool1;
    MoveL Offs(p1, n * 2, 0, 0), v100, z1, tool1;
    MoveL p1, vSpeed(3), z1, tool1;
    MoveC Offs(p1, 0, 1, 0), Offs(p1, 1, 0, 0), v100, z1, tool1;
    SetDO do1, 1;
    TPWrite "x" \\Num:=myFunc(2);
    x := myFunc(a) + Abs(y);
    MoveL [[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]], v100, z1, tool1;
  ENDPROC
ENDMODULE
"""


def _general(root):
    """refs.nodes as it walked every node: each dataclass's fields (a
    call's arguments read as their tuple where they are made when read,
    A.TailArgs)."""
    stack = [root]
    while stack:
        node = stack.pop()
        t = type(node)
        if t is tuple or t is list or t is A.TailArgs:
            stack.extend(node)
        elif not (t is A.NumAgg or node is None or t in (str, int, float, bool)):
            yield node
            if hasattr(t, "__dataclass_fields__"):
                for f in fields(t):
                    if f.name not in ("span", "name_span"):
                        stack.append(getattr(node, f.name))


def _calls(s):
    out: dict = {}
    for node in _general(F._heads(s)):
        if type(node) is A.Call and node.name.lower() not in F.BUILTIN_FUNCTIONS:
            out.setdefault(node.name.lower(), node.name)
    return tuple(out.values())


def test_walk_and_calls_are_the_general_walks():
    pf = parse_text(STATEMENTS, "m.mod")
    body = pf.module.routines[0].node.body
    assert len(body) == 14
    for s in body:
        assert list(nodes(s)) == [n for n in _general(s) if type(n) is not A.Span], s
        assert F._function_calls(s) == _calls(s), s
    # (The fast way taken where it applies, the general one elsewhere: a
    # nested call, a Bool argument, an index, an expression.)
    assert [F._plain_calls(s.args) is not None for s in body if type(s) is A.ProcCall] == [
        True, True, True, False, False, False, False, False, True, True, True, True, True]
    assert [F._function_calls(s) for s in body][4:6] == [("myTarget",), ("myTarget",)]
    assert F._function_calls(body[8]) == ("vSpeed",)
