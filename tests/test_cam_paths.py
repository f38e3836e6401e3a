"""The CAM-scale paths of parsing, planning, choosing, printing and
checking (issue #14) give what the general ones give.

Each shortcut is compared with the way it replaces, on every fixture and
on CAM-like modules whose runs of moves are broken in every way a real
program breaks them (cam_variants.py): the lexer's runs with lexing one
token at a time, the parser's appends with the table's reductions, the
resolver's plain moves with resolve(), the flow's plain calls with calls that are not, frozen nodes made by
construct.maker with their classes' own constructors; and `fix` as a
whole with every shortcut that can be switched off switched off.
"""

from __future__ import annotations

import dataclasses
import random
from pathlib import Path

import numpy as np
import pytest

from cam_variants import VARIANTS, bench_module, jointtarget, robtarget, targets
from rapidcomp.compensate import fix as F
from rapidcomp.compensate import place as P
from rapidcomp.compensate import report
from rapidcomp.compensate import solve as S
from rapidcomp.compensate import targets as T
from rapidcomp.compensate import verify as V
from rapidcomp.compensate.load import load_solver
from rapidcomp.compensate.plan import Plan, Task
from rapidcomp.construct import maker, twin
from rapidcomp.rapid import ast as A
from rapidcomp.rapid.grammar import engine
from rapidcomp.rapid.model import Motion, Roles
from rapidcomp.rapid.parse import parse_file, parse_text
from rapidcomp.rapid.values import RobTarget, decode
from rapidcomp.source import SourceText

ROOT = Path(__file__).resolve().parents[1]
PROFILE = ROOT / "fixtures" / "warm.csv"
FIXTURES = (sorted((ROOT / "fixtures").glob("*.mod")) + sorted((ROOT / "fixtures" / "rapid").iterdir())
            + sorted((ROOT / "fixtures" / "tasks").rglob("*.mod"))
            + sorted((ROOT / "fixtures" / "tasks").rglob("*.sys")))


def _texts() -> list[tuple[str, str]]:
    out = [(p.name, p.read_bytes().decode("utf-8", "replace")) for p in FIXTURES]
    out += [(f"{name}_{seed}", make(seed)) for name, make in VARIANTS.items() for seed in (1, 2)]
    return out


TEXTS = _texts()


@pytest.fixture(scope="module")
def solver():
    return load_solver(str(PROFILE), None, False, ("J5=-120:120",))


# ---------------------------------------------------------------- construct

def test_maker_makes_what_the_class_makes():
    """maker(cls)(*values) is cls(*values): equal, of the class, every field
    set; for slotted classes and for one with a __dict__ (NumAgg keeps its
    cached items there)."""
    span = A.Span(3, 9)
    cases = [(A.Arg, ("pos", None, A.Ref("p1", (), span), span)),
             (A.Ref, ("p1", (), span)), (A.NumAgg, ("[1,2]", span)),
             (A.ProcCall, ("MoveL", (), span, True)),
             (Motion, ("MoveL", None, span, "Path", (), (), (),
                       Roles((), -1, -1, -1, -1, (), False)))]
    for cls, values in cases:
        made = maker(cls)(*values)
        assert type(made) is cls and made == cls(*values)
        assert [getattr(made, f.name) for f in dataclasses.fields(cls)] == list(values)
    agg = maker(A.NumAgg)("[1,2]", span)
    assert [n.value for n in agg.items] == [1.0, 2.0]       # its cached view still works
    with pytest.raises(dataclasses.FrozenInstanceError):
        maker(A.Ref)("p", (), span).name = "q"


def test_a_move_says_whether_it_names_its_target_parameter():
    """Motion.to_point: an argument ToPoint:= (any letter case) among the
    move's, as a look at its arguments finds it, on every fixture and a
    snippet of each kind."""
    text = ("MODULE m\n  PROC p()\n    MoveL ToPoint:=p1,v100,z1,tool0;\n"
            "    MoveJ p1,v100,z1,tool0;\n    MoveL topoint:=p1,v100,z1,tool0\\WObj:=w;\n"
            "    MoveC p1,ToPoint:=p2,v100,z1,tool0;\n  ENDPROC\nENDMODULE\n")
    moves = [mo for m in parse_text(text, "m.mod").modules for mo in m.motions]
    assert [mo.to_point for mo in moves] == [True, False, True, True]
    for task in _tasks():
        for pf in task.all_files:
            for m in pf.modules:
                for mo in m.motions:
                    assert mo.to_point == any(a.kind == "named" and a.name.lower() == "topoint"
                                              for a in mo.args)


def test_maker_refuses_what_it_cannot_make_alike():
    @dataclasses.dataclass
    class Open:
        a: int

    @dataclasses.dataclass(frozen=True)
    class Checked:
        a: int

        def __post_init__(self):
            raise ValueError

    for cls in (Open, Checked, int):
        with pytest.raises(TypeError):
            maker(cls)

    # A slots class is made as its twin, of its layout: one based on a
    # class that sets fields of its own (a frozen dataclass) has none.
    @dataclasses.dataclass(frozen=True, slots=True)
    class Based:
        a: int

    @dataclasses.dataclass(frozen=True, slots=True)
    class Derived(Based):
        b: int

    assert twin(Based).__slots__ == Based.__slots__
    with pytest.raises(TypeError):
        twin(Derived)
    with pytest.raises(TypeError):
        maker(Derived)
    made = maker(RobTarget)(tuple(map(float, range(17))), "[x]", A.Span(0, 3))
    assert type(made) is RobTarget and made == RobTarget(tuple(map(float, range(17))), "[x]",
                                                         A.Span(0, 3))


# ---------------------------------------------------------------- lexer, parser

def _tokens(text: str, runs: bool) -> list[tuple]:
    return [(t.type, t.value, t.start_pos, t.end_pos) for t in engine().tokens(text, runs)]


@pytest.mark.parametrize("name,text", TEXTS, ids=[n for n, _ in TEXTS])
def test_runs_lex_as_one_token_at_a_time(name, text):
    try:
        one = _tokens(text, False)
    except Exception as exc:          # (an invalid fixture fails alike)
        with pytest.raises(type(exc)):
            _tokens(text, True)
        return
    assert _tokens(text, True) == one


def test_runs_stop_where_a_statement_is_not_the_same_call():
    """A run ends at a reserved word as target, another argument list or
    name, anything that is not an aggregate of numbers, a comment; each of
    those is lexed as one by one lexes it."""
    base = "MoveL p1,v100,z1,tool0;\n"
    others = ["MoveL IF,v100,z1,tool0;", "MoveL p2,v100,z1,tool1;", "MoveJ p2,v100,z1,tool0;",
              "MoveL [[1,2,3],[1,0,0,0]],v100,z1,tool0;", "MoveL [[1,2,x],[1,0,0,0]],v100,z1,tool0;",
              "MoveL [[1, 2,3] ,[1,0,0,0]],v100,z1,tool0;", "! MoveL p2,v100,z1,tool0;",
              "MoveL p2 ,v100,z1,tool0;", "MoveL\tp2,v100,z1,tool0;", "MoveL p2,v100,z1,tool0 ;",
              "movel p2,v100,z1,tool0;", "MoveL p_2,v100,z1,tool0;\r\n", "MoveL 0x1F,v100,z1,tool0;",
              "MoveL [[1,2,3],[1,0,0,0],[0,0,0,0],[9E+09,9e9,1.,.5,+1,-2]],v100,z1,tool0;"]
    rnd = random.Random(3)
    for _ in range(300):
        lines = [base] + [rnd.choice([base] + others) + "\n" for _ in range(rnd.randint(1, 8))]
        text = "".join(lines)
        assert _tokens(text, True) == _tokens(text, False), text


def test_runs_tried_seldom_in_a_hand_written_text_lex_as_one_at_a_time():
    """A hand-written program's moves are seldom alike twice in a row: a
    pattern made for a pair of them fails on most of the moves it is tried
    on, and is tried no more in that text; a run of that very call later
    in the text lexes as one by one lexes it, and so does the next text."""
    rnd = random.Random(5)
    speeds, tools = ["v50", "v100", "v200"], ["tA", "tB\\WObj:=w1"]
    lines = []
    for _ in range(1500):
        call = (f"{rnd.choice(['MoveL', 'MoveJ'])} p{rnd.randrange(40)}, "
                f"{rnd.choice(speeds)}, z1, {rnd.choice(tools)};")
        lines += [call] * rnd.choice([1, 1, 1, 2])
    text = "\n".join(lines + ["MoveL p1, v50, z1, tA;"] * 50) + "\n"
    for _ in range(2):
        assert _tokens(text, True) == _tokens(text, False)


def test_declaration_runs_stop_where_a_declaration_is_not_the_same_kind():
    """A run of one-line declarations ends at a reserved word as name,
    another storage, type, letter case or blank before the name, a value
    that is not an aggregate of numbers, a comment, a statement; each of
    those is lexed as one by one lexes it (and so is a run that goes on
    after them)."""
    base = "CONST robtarget p1:=[[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
    lit = "[[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]"
    others = [f"CONST robtarget IF:={lit};", f"CONST robtarget ENDPROC:={lit};",
              f"PERS robtarget p2:={lit};", f"CONST jointtarget j2:={lit};",
              f"const robtarget p2:={lit};", f"CONST robtarget  p2:={lit};",
              f"CONST\trobtarget p2:={lit};", f"CONST robtarget p2 := {lit} ;",
              f"LOCAL CONST robtarget p2:={lit};", "CONST robtarget p2:=[[1,2,x],[1,0,0,0]];",
              "CONST robtarget p2:=[[1, 2,3] ,[1,0,0,0]];", f"! CONST robtarget p2:={lit};",
              f"CONST robtarget p2:={lit};\r\n", f"CONST robtarget p_2:={lit}; ! note",
              "CONST robtarget p2:=[[1,2,3],\n  [1,0,0,0]];", "CONST num n:=1;",
              f"CONST robtarget p2:={lit}; CONST robtarget p3:={lit};",
              "MoveL p1,v100,z1,tool0;", f"CONST robtarget robtarget:={lit};"]
    rnd = random.Random(5)
    for _ in range(300):
        lines = [base] + [rnd.choice([base] * 3 + others) + "\n"
                          for _ in range(rnd.randint(1, 8))]
        text = "".join(lines)
        assert _tokens(text, True) == _tokens(text, False), text


def _token_by_token(monkeypatch) -> None:
    """The parser without its appends and the lexer without its runs."""
    class Never(dict):
        def get(self, key, default=None):
            return False
    eng = engine()
    monkeypatch.setattr(eng, "_appends", Never())
    monkeypatch.setattr(eng, "tokens", lambda text, runs=False, _t=eng.tokens: _t(text, False))


def _parse_one_by_one(monkeypatch, text: str):
    _token_by_token(monkeypatch)
    try:
        return _tree(engine().parse(text))
    finally:
        monkeypatch.undo()


def _tree(parsed):
    """(header text, module nodes): tokens compare by identity."""
    header, nodes = parsed
    return (None if header is None else header.value), nodes


@pytest.mark.parametrize("name,text", TEXTS, ids=[n for n, _ in TEXTS])
def test_appends_build_the_tree_the_reductions_build(name, text, monkeypatch):
    """A statement after one of its kind appended at once (lalr parse's
    shortcut, with the lexer's runs) gives the very tree the table's
    reductions give token by token."""
    try:
        slow = _parse_one_by_one(monkeypatch, text)
    except Exception as exc:
        with pytest.raises(type(exc)):
            engine().parse(text)
        return
    assert _tree(engine().parse(text)) == slow


def test_source_lines_are_positions_lines():
    text = "a\nbb\r\n\nccc\rd\n" * 50
    src = SourceText.from_text(text)
    offsets = list(range(len(text)))
    assert src.lines(offsets) == [src.position(k)[0] for k in offsets]
    assert src.lines([]) == []


# ---------------------------------------------------------------- plan

def _fields(u) -> list:
    """Every field of a use; nodes, files and modules by identity (a record
    by identity where the parse made it, else by value: an inline target
    whose external axes are named data, or an Offs's inline target, is read
    by each resolver)."""
    out = []
    for f in dataclasses.fields(u):
        v = getattr(u, f.name)
        if f.name in ("motion", "file", "module"):
            v = id(v)
        elif f.name == "source" and v is not None:
            named = ((type(v.expr) is A.Agg and type(v.expr.items[-1]) is A.Ref)
                     or (v.call is not None and type(v.ref) is A.NumAgg))
            v = [x if named and g.name == "record" else
                 id(x) if isinstance(x, (A.Ref, A.NumAgg, A.Agg, A.Call)) or g.name in (
                "record", "decl", "home", "home_module") else
                 (x.tolist() if isinstance(x, np.ndarray) else x)
                 for g in dataclasses.fields(v) for x in [getattr(v, g.name)]]
        elif f.name == "flange":
            v = None if v is None else (u.R.tolist(), u.p.tolist())
        elif f.name == "tool" or f.name == "wobj":
            v = None if v is None else (v[0], np.asarray(v[1][0]).tolist(),
                                        np.asarray(v[1][1]).tolist())
        out.append(v)
    return out


def _tasks():
    tasks = [Task(n, (parse_text(t, n),)) for n, t in TEXTS if n.startswith(tuple(VARIANTS))]
    tasks.append(Task("offs.mod", (parse_text(_offs_text(), "offs.mod"),)))
    tasks += [Task(p.name, (parse_file(p, p.name),)) for p in FIXTURES if "tasks" not in p.parts
              and p.suffix in (".mod", ".sys")]
    from rapidcomp.compensate.load import load_task
    from rapidcomp.rapid.task import tasks_of
    for folder in ("cell", "glue/Glue.pgf", "backup_irbt"):
        source = tasks_of(str(ROOT / "fixtures" / "tasks" / folder))[0]
        tasks.append(load_task(source, ()))
    return tasks


@pytest.mark.parametrize("track", [(), ((0, np.array([1.0, 0, 0])),)])
def test_plain_moves_resolve_as_resolve_does(track, monkeypatch):
    """Resolver.resolve_all's plain moves are the uses resolve() gives, field
    for field, and their flange poses bit for bit (with a track: resolve()'s
    own way, as before)."""
    taken = []
    real = T.Resolver._plain_use

    def spy(self, *args):
        u = real(self, *args)
        taken.append(u is not None)
        return u
    for task in _tasks():
        monkeypatch.setattr(T.Resolver, "_plain_use", spy)
        fast = Plan(task, track)
        monkeypatch.setattr(T.Resolver, "_plain_moves", lambda self: False)
        slow = Plan(task, track)
        monkeypatch.undo()
        assert [_fields(u) for u in fast.uses] == [_fields(u) for u in slow.uses], task.name
        assert fast.notes() == slow.notes()
    assert (sum(taken) > 300) == (not track)


OFFS = r"""MODULE M
  PERS tooldata tSpindle:=[TRUE,[[0,0,150],[1,0,0,0]],[2,[0,0,75],[1,0,0,0],0,0,0]];
  PERS wobjdata wPart:=[FALSE,TRUE,"",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];
  CONST robtarget p1:=%(a)s;
  CONST robtarget arr{2}:=[%(a)s,%(b)s];
  VAR robtarget pv:=%(b)s;
  CONST jointtarget j1:=%(j)s;
  VAR num n:=2;
  PROC P()
    MoveL Offs(p1, 0, 0, 10), v100, z1, tSpindle\WObj:=wPart;
    MoveL Offs(p1,-1.5,+2,.5),v100,fine,tool0;
    moveL offs(P1,1,2,3),v100,z1,tSpindle\WObj:=wPart;
    MoveJ Offs(p1,1,2,3)\Conc,v100,z1,tSpindle\WObj:=wPart;
    MoveL Offs(arr{2},0,0,1),v100,z1,tSpindle\WObj:=wPart;
    MoveL Offs(pv,0,0,1),v100,z1,tSpindle\WObj:=wPart;
    MoveL RelTool(p1,0,0,1\Rz:=10),v100,z1,tSpindle\WObj:=wPart;
    MoveL RelTool(p1,0,0,1),v100,z1,tSpindle\WObj:=wPart;
    MoveL Offs(%(a)s,1,2,3),v100,z1,tSpindle\WObj:=wPart;
    MoveL Offs(p1,n,0,0),v100,z1,tSpindle\WObj:=wPart;
    MoveL Offs(p1,1e1,0,0),v100,z1,tSpindle\WObj:=wPart;
    MoveL Offs(j1,0,0,1),v100,z1,tSpindle\WObj:=wPart;
    MoveL Offs(nowhere,0,0,1),v100,z1,tSpindle\WObj:=wPart;
    MoveL Offs(p1,0,0,1),v100,z1,tNone\WObj:=wPart;
    FOR i FROM 1 TO 2 DO
      MoveL Offs(p1,i,0,0),v100,z1,tSpindle\WObj:=wPart;
      MoveL Offs(p1,0,0,1),v100,z1,tSpindle\WObj:=wPart;
    ENDFOR
    pv := Offs(p1, 1, 1, 1);
    MoveL Shifted(p1, 5),v100,z1,tSpindle\WObj:=wPart;
  ENDPROC
  FUNC robtarget Shifted(robtarget p, num d)
    MoveL p1,v100,fine,tSpindle\WObj:=wPart;
    RETURN Offs(p, 0, 0, d);
  ENDFUNC
ENDMODULE
"""


def _offs_text(**changes) -> str:
    t = targets(2, 7)
    return OFFS % {"a": robtarget(t[0]), "b": robtarget(t[1]), "j": jointtarget(t[0]),
                   **changes}


def test_offs_moves_resolve_as_resolve_does(monkeypatch):
    """A move to Offs/RelTool(<target>, <numbers>) (an Offs-relative
    pattern's 1e5 moves) is a plain move: the same use, field for field,
    its flange pose bit for bit, and the same notes as resolve() gives (of
    a declared name, an array element, an inline target, with a rotation);
    one that resolve() does not compensate (of data the program writes, a
    run-time number, a jointtarget, an undeclared name or tool, inside a
    FOR loop, a function of the program) is resolve()'s own."""
    taken = []
    real = T.Resolver._plain_use

    def spy(self, pf, module, motion, *args):
        u = real(self, pf, module, motion, *args)
        if u is not None and type(u.source.call) is A.Call:
            taken.append(pf.source.text[motion.span.start:motion.span.end])
        return u
    task = Task("m.mod", (parse_text(_offs_text(), "m.mod"),))
    monkeypatch.setattr(T.Resolver, "_plain_use", spy)
    fast = Plan(task)
    monkeypatch.setattr(T.Resolver, "_plain_moves", lambda self: False)
    slow = Plan(task)
    monkeypatch.undo()
    assert [_fields(u) for u in fast.uses] == [_fields(u) for u in slow.uses]
    assert fast.notes() == slow.notes()
    # (1e1: a number the one-token form does not take; the parser's Num
    # all the same.)
    assert [t.split(",")[0] for t in taken] == [
        "MoveL Offs(p1", "MoveL Offs(p1", "moveL offs(P1", "MoveJ Offs(p1", "MoveL Offs(arr{2}",
        "MoveL RelTool(p1", "MoveL RelTool(p1", "MoveL Offs([[650.922", "MoveL Offs(p1"]
    assert "\\Rz:=10" in taken[5] and "1e1" in taken[-1]
    reasons = {u.label: u.reason for u in slow.uses if u.reason}
    assert any(" is an expression: rapidcomp reads literal numbers" in r or
               " num: known at run time" in r for r in reasons.values()), reasons


@pytest.mark.parametrize("far", ["200000, 0, 0", "0, -1E+09, 0"])
def test_an_offs_beyond_reach_is_the_same_error_either_way(monkeypatch, far):
    # (1E+09 is not the one-token form's number: the move is lexed token by
    # token, a plain move all the same.)
    text = _offs_text().replace("MoveL Offs(p1,-1.5,+2,.5)", f"MoveL Offs(p1, {far})")
    task = Task("m.mod", (parse_text(text, "m.mod"),))
    from rapidcomp.errors import InputError
    with pytest.raises(InputError) as fast:
        Plan(task)
    monkeypatch.setattr(T.Resolver, "_plain_moves", lambda self: False)
    with pytest.raises(InputError) as slow:
        Plan(task)
    assert str(fast.value) == str(slow.value)
    assert "m.mod:11:" in str(fast.value) and "Offs displacement" in str(fast.value)


def test_an_earlier_moves_error_comes_first_with_plain_moves():
    """An input error met while resolving a plain move (its tool's
    quaternion of norm 0) is raised after the error of a use before it (a
    position 200 m away, checked with the batch), as resolve() one by one
    raises them."""
    from rapidcomp.errors import InputError
    far = "[[200000,0,0],[1,0,0,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
    near = robtarget(targets(1, 1)[0])
    text = "\n".join([
        "MODULE M",
        "  PERS tooldata tBad:=[TRUE,[[0,0,150],[0,0,0,0]],[2,[0,0,75],[1,0,0,0],0,0,0]];",
        "  PROC P()", f"    MoveL {far},v100,z1,tool0;", f"    MoveL {near},v100,z1,tBad;",
        "  ENDPROC", "ENDMODULE", ""])
    pf = parse_text(text, "m.mod")
    with pytest.raises(InputError) as got:
        Plan(Task("m.mod", (pf,)))
    assert "m.mod:4:" in str(got.value) and "beyond" in str(got.value), str(got.value)
    # Alone, the second move's error is its own.
    pf = parse_text(text.replace(far, near), "m.mod")
    with pytest.raises(InputError) as got:
        Plan(Task("m.mod", (pf,)))
    assert "norm 0" in str(got.value), str(got.value)


def _not_plain(node):
    """The same tree with every call marked not plain (the flow walks those
    without its shortcut)."""
    if type(node) is tuple:
        return tuple(_not_plain(x) for x in node)
    if type(node) is A.ProcCall:
        # (Its arguments as nodes: a call lexed as one token, A.TailArgs,
        # read as any other.)
        return dataclasses.replace(node, plain=False, args=_not_plain(tuple(node.args)))
    if dataclasses.is_dataclass(node) and not isinstance(node, type) and type(node) is not A.NumAgg:
        changes = {f.name: _not_plain(getattr(node, f.name)) for f in dataclasses.fields(node)
                   if type(getattr(node, f.name)) is tuple or dataclasses.is_dataclass(
                       getattr(node, f.name))}
        return dataclasses.replace(node, **changes)
    return node


def test_the_flow_of_plain_calls_is_that_of_any_call(monkeypatch):
    """The flow walks a plain move without its function-call memo, and a
    run of moves that call no function the flow follows (MoveL Offs(...))
    at once; the states, order and notes are those of the same program
    walked without either, statement by statement."""
    def rebuilt(pf):
        # (The routines the flow walks too, not only the module's node.)
        return dataclasses.replace(pf, modules=tuple(
            dataclasses.replace(m, node=_not_plain(m.node), routines=tuple(
                dataclasses.replace(r, node=_not_plain(r.node)) for r in m.routines))
            for m in pf.modules))
    from test_flow_runs import PROGRAMS     # (runs entered again: by RETRY, GOTO, cycles)
    runs = 0
    from rapidcomp.compensate import flow
    offs = 0
    for task in _tasks() + [Task(n, (parse_text(t, n),)) for n, t in sorted(PROGRAMS.items())]:
        plan = Plan(task)
        fast = plan.flow
        offs += sum(1 for k in fast.previous if plan.by_key[k].source is not None
                    and plan.by_key[k].source.call is not None)
        with monkeypatch.context() as m:
            m.setattr(flow._Walker, "_moves", lambda self, stmts, i, st, rt: (i, st))
            slow = Plan(dataclasses.replace(task, files=tuple(map(rebuilt, task.files)),
                                            context=tuple(map(rebuilt, task.context)))).flow
        assert fast.order == slow.order and fast.notes == slow.notes
        assert fast.before.keys() == slow.before.keys() and fast.entry == slow.entry
        # (A run's moves share one state, their last the move before each.)
        assert {k: fast.state(k) for k in fast.before} == slow.before
        assert not slow.previous
        runs += len(fast.previous)
    assert runs > 1000 and offs > 0


def test_the_references_of_plain_calls_are_those_of_any_call():
    """usage() reads a plain move's references itself: the references,
    writes, assignments and calls are those of the same module with no
    call plain, in the same order."""
    from rapidcomp.rapid.refs import nodes, usage
    plain = 0
    for task in _tasks():
        for pf in task.all_files:
            for m in pf.modules:
                fast, slow = usage(m.node), usage(_not_plain(m.node))
                assert fast.refs == slow.refs and list(fast.refs) == list(slow.refs)
                assert fast.writes == slow.writes and fast.assigns == slow.assigns
                assert [c.span for c in fast.calls] == [c.span for c in slow.calls]
                plain += sum(1 for n in nodes(m.node) if type(n) is A.ProcCall and n.plain)
    assert plain > 100


def test_a_resolver_of_the_same_files_takes_the_plans_tables():
    """verify.py's resolver takes the plan's tables of the declarations
    where its files are the plan's very objects: the tables it would make;
    of other files (an output parsed again) it makes its own."""
    for task in _tasks():
        plan = Plan(task)
        files = plan.files
        own = T.Resolver(files, float32=True, usages=plan.resolver.usages, writes=False)
        taken = T.Resolver(files, float32=True, usages=plan.resolver.usages, writes=False,
                           like=plan.resolver)
        for name in ("params", "home", "home_module", "module_decls", "globals",
                     "routine_decls"):
            assert getattr(taken, name) == getattr(own, name), (task.name, name)
            assert getattr(taken, name) is getattr(plan.resolver, name)
        for resolver in (own, taken):
            _homes_are(resolver, files)
        again = [parse_text(pf.source.text, pf.source.display_path) for pf in files]
        other = T.Resolver(again, float32=True, writes=False, usages={}, like=plan.resolver)
        assert other.home is not plan.resolver.home
        _homes_are(other, again)


def _homes_are(resolver, files) -> None:
    """Each declaration's file and module, as the resolver has them (no
    entry each where the files hold one module)."""
    one = sum(len(pf.modules) for pf in files) == 1
    for pf in files:
        for m in pf.modules:
            for d in m.declarations:
                assert resolver.home[id(d)] is pf and resolver.home_module[id(d)] is m
    assert (len(resolver.home) == 0) == one
    if not one:
        with pytest.raises(KeyError):           # (not a declaration of the files)
            resolver.home[id(resolver)]


def _pick(p):
    return (p.rule, p.failure, p.kind, p.caution, p.line,
            None if p.q is None else p.q.tolist(), None if p.prev is None else p.prev.tolist())


def test_the_choices_quick_cases_are_the_general_rules(solver, monkeypatch):
    """Each of run()'s three quick cases gives the solutions (all of them,
    not only the one compensated) the general rules give, and each is
    taken."""
    tasks = [Task("cam", (parse_text(bench_module(n, seed, confl), "cam.mod"),))
             for n, seed, confl in ((2000, 1, ""), (300, 2, "    ConfL\\Off;\n"),
                                    (300, 3, "    ConfL\\On;\n"))]
    tasks += _tasks()
    cases = [0, 0, 0, 0]
    for task in tasks:
        plan = Plan(task)
        uses = [u for u in plan.uses if u.reason is None]
        rows = {u.key: i for i, u in enumerate(uses)}
        fast = S._Chooser(plan, solver, uses, rows)
        fast.run()
        cases = [a + b for a, b in zip(cases, fast.taken)]
        monkeypatch.setattr(S._Chooser, "QUICK", False)
        slow = S._Chooser(plan, solver, uses, rows)
        slow.run()
        monkeypatch.undo()
        assert slow.taken == [0, 0, 0, 0]
        assert [[_pick(p) for p in sols] for sols in fast.sols] == \
            [[_pick(p) for p in sols] for sols in slow.sols], task.name
        assert [_pick(p) for p in fast.picks] == [_pick(p) for p in slow.picks]
        assert np.array_equal(fast.q, slow.q, equal_nan=True)
    assert min(cases[1:]) > 30, cases


def test_the_choices_comparisons_are_numpys():
    """same_joints/_apart give np.linalg.norm(a - b) <= / > SAME_DEG, and
    _turns_only what its numpy form gives, on random joints, whole turns
    apart, pairs at the bound's edge, NaN and infinity; _has_nan is
    np.isnan(q).any()."""
    rng = np.random.default_rng(11)
    same = S.SAME_DEG

    def numpy_turns_only(a, b, scaled):
        d = b - a
        if np.any(np.abs(d[[1, 2, 4]]) > same):
            return False
        turns = d[[0, 3, 5]] / 360.0
        with np.errstate(invalid="ignore"):
            if np.any(np.abs(turns - np.round(turns)) > same):
                return False
        return not any(abs(d[j]) > same for j in scaled)
    pairs = []
    for _ in range(3000):
        a = rng.uniform(-180, 180, 6)
        kind = rng.integers(0, 5)
        if kind == 0:
            b = rng.uniform(-180, 180, 6)
        elif kind == 1:                      # at the bound, either side by an ulp or so
            u = rng.normal(size=6)
            b = a + u / np.linalg.norm(u) * same * (1 + rng.integers(-3, 4) * 1e-16)
        elif kind == 2:                      # whole turns of J1/J4/J6, a little off
            b = a.copy()
            b[[0, 3, 5]] += 360.0 * rng.integers(-2, 3, 3) + rng.normal(0, same, 3)
        elif kind == 3:
            b = a + rng.normal(0, same, 6)
        else:
            b = a.copy()
            b[rng.integers(0, 6)] = rng.choice([np.nan, np.inf, -np.inf])
        pairs.append((a, b))
    seen = set()
    for a, b in pairs:
        with np.errstate(invalid="ignore"):
            norm = np.linalg.norm(a - b)
        assert S.same_joints(a, b) == bool(norm <= same)
        assert S._apart(a, b) == bool(norm > same)
        assert S._has_nan(b) == bool(np.isnan(b).any())
        seen.add((bool(norm <= same), bool(norm > same)))
        for scaled in ([], [0, 3]):
            chooser = S._Chooser.__new__(S._Chooser)
            chooser.scaled = scaled
            picks = [S.Pick(a, "", None), S.Pick(b, "", None)]
            with np.errstate(invalid="ignore"):
                want = numpy_turns_only(a, b, scaled)
            assert chooser._turns_only(picks) == want
    assert seen == {(True, False), (False, True), (False, False)}


def test_the_choices_comparisons_ask_the_norm_near_the_bound(monkeypatch):
    """Within 0.1 % of SAME_DEG (and for NaN) same_joints and _apart take
    np.linalg.norm's verdict, whatever the sum of squares says; farther
    away they decide by the sum of squares without asking it. (A stand-in
    norm that says otherwise than the numbers shows who decided.)"""
    same = S.SAME_DEG
    asked = []

    def norm(x, *args, **kw):
        asked.append(1)
        return norm.says
    monkeypatch.setattr(S.np.linalg, "norm", norm)
    a = np.zeros(6)
    unit = np.array([1.0, 2.0, -2.0, 0.5, 0.0, 1.0])
    unit /= np.sqrt((unit * unit).sum())
    for scale, says, want_same in ((0.9995, 1.01, False), (1.0005, 0.5, True),
                                   (0.99, 1.5, True), (1.01, 0.5, False),
                                   (np.nan, np.nan, None)):
        asked.clear()
        norm.says = says * same
        b = unit * scale * same
        near = not abs(scale - 1.0) > 0.001     # (NaN: near, the norm decides)
        if near:
            assert S.same_joints(a, b) == bool(says * same <= same)
            assert S._apart(a, b) == bool(says * same > same)
            assert len(asked) == 2
        else:
            assert S.same_joints(a, b) == want_same and S._apart(a, b) == (not want_same)
            assert not asked


# ---------------------------------------------------------------- numbers

def test_row_dots_are_each_rows_dot():
    from rapidcomp.kinematics.frames import row_dots
    rng = np.random.default_rng(4)
    for k in (3, 4, 6):
        a = rng.normal(size=(5000, k)) * rng.choice([1e-9, 1e-3, 1.0, 1e4], size=(5000, 1))
        want = np.array([row.dot(row) for row in a])
        assert np.array_equal(row_dots(a), want)
        assert np.array_equal(row_dots(np.asfortranarray(a)), want)
        assert np.array_equal(row_dots(a[::2]), want[::2])
    assert row_dots(np.zeros((0, 4))).shape == (0,)


def test_absj_literals_are_those_of_one():
    from rapidcomp.rewrite import records
    from rapidcomp.rapid.values import decode
    ts = targets(60, 7)
    recs = [decode("robtarget", A.NumAgg(robtarget(t, k % 3), A.Span(0, 0))) for k, t in
            enumerate(ts)]
    q = np.array([t[3] for t in ts]) + np.random.default_rng(1).normal(size=(60, 6)) * 1e-3
    q[0] = [-0.0, 0, 1e-7, -1e-7, 180, -180]
    for group in (recs, [r for r in recs if type(r.lexed) is str and " " not in r.lexed]):
        qs = q[:len(group)]
        assert records.absj_literals(qs, group) == [
            records.jointtarget_literal(records.absj_texts(row, r)) for row, r in zip(qs, group)]


def test_one_pose_stacked_is_each_pose_stacked():
    R = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])
    pose = (R, np.array([1.5, -2, 3]))
    same = T.stacked_poses([pose] * 5)
    equal = T.stacked_poses([(R.copy(), pose[1].copy()) for _ in range(5)])
    for a, b in zip(same, equal):
        assert np.array_equal(a, b) and a.flags.c_contiguous and a.flags.writeable


# ---------------------------------------------------------------- relex_absj

def test_plain_numaggs_are_what_the_lexer_reads_as_one_aggregate():
    """_plain_numaggs (after _joint_rows) says a literal is one NUMAGG token
    only where the lexer reads it so."""
    eng = engine()
    rnd = random.Random(8)
    good = ["1", "-2.5", "+3", ".5", "5.", "1e5", "9E+09", "1e-5", "+.5e-3", "0", "-0"]
    bad = ["1e", "e5", "1.2.3", "--1", "0x1F", "1_0", " 1", "", "nan", "inf", "1 ", "+", "."]
    fast_seen = slow_seen = 0
    for _ in range(4000):
        fields = [rnd.choice(bad if rnd.random() < 0.02 else good) for _ in range(12)]
        lit = "[[" + ",".join(fields[:6]) + "],[" + ",".join(fields[6:]) + "]]"
        fast = V._joint_rows([lit]) is not None and V._plain_numaggs([lit])
        try:
            lexed = [t.type for t in eng.tokens(lit)] == ["NUMAGG", "$END"]
        except Exception:
            lexed = False
        assert not fast or lexed, lit                       # never says so wrongly
        assert fast or not all(f in good for f in fields), lit    # and knows every plain one
        fast_seen += fast
        slow_seen += not fast
    assert fast_seen > 1000 and slow_seen > 500


def _plain(eng, pieces: list[str]):
    """_plain_declared of pieces as inserted texts of an output (each after
    a line of something else)."""
    text, starts = "", []
    for piece in pieces:
        text += "\n  ! before"
        starts.append(len(text))
        text += piece
    return V._plain_declared(eng, text + "\n", starts, [len(p) for p in pieces]), text, starts


def test_plain_declarations_read_as_the_lexer_reads_them():
    """_plain_declared reads the editor's new declarations as lexing them
    does, and gives up (None) on anything else."""
    eng = engine()
    t = targets(3, 2)
    good = [f"\n  CONST jointtarget jt_p{i}:={jointtarget(x)};" for i, x in enumerate(t)]
    pieces = ["".join(good), good[0] + "\r\n\tLOCAL CONST jointtarget a := "
              + jointtarget(t[1]) + " ;", "\n  const JointTarget Bb:=" + jointtarget(t[2]) + ";"]
    got, text, _ = _plain(eng, pieces)
    assert list(zip(got.piece.tolist(), got.type, got.name, list(got.scoped))) == [
        *((0, "jointtarget", f"jt_p{i}", False) for i in range(3)),
        (1, "jointtarget", "jt_p0", False), (1, "jointtarget", "a", True),
        (2, "jointtarget", "bb", False)]
    assert got.storage == {"CONST", "const"}
    # Each aggregate's place in the output.
    want = [t[0], t[1], t[2], t[0], t[1], t[2]]
    bounds = got.bounds.tolist()
    assert [text[x:y] for x, y in zip(bounds[::2], bounds[1::2])] == [jointtarget(x) for x in want]
    # The joints of each declaration, in order: as decoding each reads them.
    assert got.rows.tolist() == [list(decode("jointtarget", A.NumAgg(jointtarget(x), A.Span(
        0, len(jointtarget(x))))).joints) for x in want]
    for bad in [good[0] + " ! note", "\n  CONST jointtarget IF:=" + jointtarget(t[0]) + ";",
                "\n  CONST ENDFOR a:=" + jointtarget(t[0]) + ";",
                "\n  CONST jointtarget a:=[[1,2,3,4,5,6],[1,2,3,4,5,x]];",
                "\n  CONST jointtarget a:=[[1,2,3,4,5,6] ,[1,2,3,4,5,6]];", "\n  MoveL p1,v1,z1,t;",
                good[0] + "\n  MoveL p1,v1,z1,t;" + good[1], good[0][:-1]]:
        # (Alone, and among good ones: before, after or between them.)
        for where in range(4):
            assert _plain(eng, [*good[:where], bad, *good[where:]])[0] is None, (bad, where)


# ---------------------------------------------------------------- the whole fix

def _slow(monkeypatch):
    """Every shortcut that can be switched off, off."""
    _token_by_token(monkeypatch)
    _groups_only(monkeypatch)
    monkeypatch.setattr(T.Resolver, "_plain_moves", lambda self: False)
    monkeypatch.setattr(S._Chooser, "QUICK", False)
    monkeypatch.setattr(V, "_plain_declared", lambda eng, pieces, *how: None)
    monkeypatch.setattr(V, "_plain_numaggs", lambda lits: False)


def _groups_only(monkeypatch):
    """fix's groups a Group each, no Singles (what check groups)."""
    real = P.grouping
    monkeypatch.setattr(P, "grouping", lambda *a, **k: real(*a, **{**k, "singles": False}))


@pytest.mark.parametrize("mode", ["auto", "absj", "robtarget"])
@pytest.mark.parametrize("name", sorted(VARIANTS))
def test_fix_gives_what_the_general_paths_give(name, mode, solver, monkeypatch):
    text = VARIANTS[name](3)
    fast = F.fix(Task(name, (parse_text(text, name + ".mod"),)), solver, mode)
    _slow(monkeypatch)
    slow = F.fix(Task(name, (parse_text(text, name + ".mod"),)), solver, mode)
    monkeypatch.undo()
    assert [m.text for m in fast.modules] == [m.text for m in slow.modules]
    assert fast.rows == slow.rows and fast.notes == slow.notes
    meta = {"mode": mode}
    assert report.markdown(fast, meta) == report.markdown(slow, meta)
    assert report.as_json(fast, meta) == report.as_json(slow, meta)
    assert fast.summary()["compensated"] > 40


def test_a_run_pattern_is_compiled_only_for_an_argument_list_met_again():
    """Compiling a run's pattern costs ~1 ms: a program whose every line has
    an argument list of its own (\\ID:=n of a MultiMove program) compiles
    none, and lexes as one by one; a list met again gets its pattern."""
    eng = engine()
    lines = [f"MoveL [[{i},2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]\\ID:={i},v100,"
             f"z1,tool_unique_run_test;\n" for i in range(300)]
    text = "".join(lines)
    before = {k for k in eng._runs if "tool_unique_run_test" in k[1][1]}
    assert _tokens(text, True) == _tokens(text, False)
    assert {k for k in eng._runs if "tool_unique_run_test" in k[1][1]} == before == set()
    same = "MoveL p1,v100,z1,tool_again_run_test;\n" * 5
    assert _tokens(same, True) == _tokens(same, False)
    assert [k for k in eng._runs if k[1][1].endswith("tool_again_run_test;")]


def test_a_function_of_numbers_as_first_argument_is_the_call_the_grammar_makes(monkeypatch):
    """MoveL Offs(p1, 0, 0, -10), ... is one token (FAST_CALL) when its
    function's arguments are names, numeric aggregates and plain decimal
    numbers: the nodes are those the grammar's rules make of its tokens
    (a sign right before a number folded into it); a number the one-token
    form does not take (an exponent, hex, a sign apart) is lexed as usual."""
    lines = ["MODULE M", "  PROC p()"]
    args = ["0, 0, 10", "0,0,-10", "+5, -0, .5", "10., 0.25 , -7.125", "1e3, 0, 0", "0x1F, 0, 0",
            "- 10, 0, 0", "123456789012345678901234567890, 0, 0", "[1,2,3], -1, 2"]
    for a in args:
        lines.append(f"    MoveL Offs(p1, {a}), v100, z1, tool0;")
        lines.append(f"    MoveL RelTool(p1,{a}),v100,fine,tool0\\WObj:=wobj1;")
    text = "\n".join(lines + ["  ENDPROC", "ENDMODULE", ""])
    eng = engine()
    kinds = [t.type for t in eng.tokens(text)]
    assert kinds.count("FAST_CALL") == 2 * 6   # (all but the exponent, the hex, the sign apart)
    fast = _tree(eng.parse(text))
    # (One token: the function's node kept, the arguments after it made
    # when read, as a plain move's; the call is not plain.)
    calls = [s for s in parse_text(text, "m.mod").modules[0].node.items[0].body
             if type(s.args) is A.TailArgs]
    assert len(calls) == 12 and not any(c.plain for c in calls)
    assert all(type(c.args.first) is A.Call and c.args.nodes()[0].value is c.args.first
               for c in calls)
    monkeypatch.setattr(eng, "_master", eng._master_plain)
    monkeypatch.setattr(eng, "tokens", lambda t, runs=False, _t=eng.tokens: _t(t, False))
    assert [t.type for t in eng.tokens(text)].count("FAST_CALL") == 0
    assert _tree(eng.parse(text)) == fast


def test_two_aggregates_first_are_the_call_the_grammar_makes(monkeypatch):
    """MoveC [[...]],[[...]],v100,z1,tool0; (a CAM program's arcs: 5e4 of
    them) is one token (FAST_CIRC) when its two first arguments are numeric
    aggregates, or a name (a declared circle point) and an aggregate: the
    nodes are those the grammar's rules make of its tokens, whatever the
    blanks and nesting; a reserved word where a name must be is lexed token
    by token, and refused as the parser refuses it."""
    t = robtarget(targets(1, 5)[0], 1)
    lines = ["MODULE M", "  PROC p()"]
    for sep in (",", " , ", ",\t", "\t,"):
        lines += [f"    MoveC {t}{sep}{t},v100,z1,tool0;",
                  f"    MoveC [1,2]{sep}[[3],[4]] ,v100 , fine,tool0\\WObj:=wobj1;",
                  f"    Foo [1, 2 ]{sep}[ [3,4] , 5 ];",
                  f"    MoveC {t}{sep}{t},v100,z1,tool0\\T1:=2;",
                  f"    MoveC c_10{sep}{t},v100,z1,tool0\\WObj:=wobj1;",
                  f"    Foo a{sep}[ [3,4] , 5 ];"]
    text = "\n".join(lines + ["  ENDPROC", "ENDMODULE", ""])
    eng = engine()
    kinds = [t.type for t in eng.tokens(text)]
    assert kinds.count("FAST_CIRC") == 24 and kinds.count("FAST_CALL") == 0
    fast = _tree(eng.parse(text))
    # (The arguments as the grammar splits them: two aggregates first.)
    pf = parse_text("\n".join(lines[:3] + ["  ENDPROC", "ENDMODULE", ""]), "m.mod")
    call = pf.modules[0].node.items[0].body[0]
    assert len(pf.modules[0].motions[0].targets) == 2
    assert [type(a.value).__name__ for a in call.args][:3] == ["NumAgg", "NumAgg", "Ref"]
    pf = parse_text("\n".join(lines[:2] + lines[6:7] + ["  ENDPROC", "ENDMODULE", ""]), "m.mod")
    call = pf.modules[0].node.items[0].body[0]
    assert [type(a.value).__name__ for a in call.args][:3] == ["Ref", "NumAgg", "Ref"]
    assert call.args[0].value.name == "c_10" and pf.modules[0].motions[0].targets[0].role == "cir"
    bad = text.replace("z1,tool0;", "z1,IF;", 1)
    with monkeypatch.context() as m:
        m.setattr(eng, "_master", eng._master_plain)
        m.setattr(eng, "tokens", lambda t, runs=False, _t=eng.tokens: _t(t, False))
        assert [t.type for t in eng.tokens(text)].count("FAST_CIRC") == 0
        assert _tree(eng.parse(text)) == fast
        with pytest.raises(Exception) as plain:
            eng.parse(bad)
    with pytest.raises(Exception) as one:
        eng.parse(bad)
    assert type(one.value) is type(plain.value) and str(one.value) == str(plain.value)


def test_a_run_pattern_is_compiled_only_where_a_run_may_follow():
    """Argument lists met again, but never twice in a row (a hand-written
    program's speeds change from move to move), get no pattern; two in a
    row do. The tokens are the same either way."""
    eng = engine()
    alternating = "".join(f"MoveL p{i},{'v100' if i % 2 else 'v200'},z1,tool_alt_run_test;\n"
                          for i in range(40))
    assert _tokens(alternating, True) == _tokens(alternating, False)
    assert not [k for k in eng._runs if k[1][1].endswith("tool_alt_run_test;")]
    twice = "MoveL p1,v300,z1,tool_alt_run_test;\n" * 3
    assert _tokens(twice, True) == _tokens(twice, False)
    assert [k for k in eng._runs if k[1][1] == ",v300,z1,tool_alt_run_test;"]


def test_a_plan_keeps_no_list_or_array_per_declared_target():
    """Issue #14 (no per-target object past its stage): a program of
    declared targets, each moved to once (RobotStudio's way), leaves no
    list (the resolver's global names) and no array (where each name is
    referred to) per target: the plan of 300 such targets holds as many of
    them as the plan of 150, and reads each target where it is declared."""
    import gc
    from array import array

    def held(n: int) -> tuple[int, int]:
        ts = targets(n, 8)
        text = "\n".join([
            "MODULE M", *(f"  CONST robtarget p{i}:={robtarget(t)};" for i, t in enumerate(ts)),
            "  PROC P()", *(f"    MoveL p{i},v100,z1,tool0;" for i in range(n)),
            "  ENDPROC", "ENDMODULE", ""])
        plan = Plan(Task("m.mod", (parse_text(text, "m.mod"),)))
        assert [u.source.decl.name for u in plan.uses] == [f"p{i}" for i in range(n)]
        gc.collect()
        kinds = [type(o) for o in gc.get_objects()]
        return kinds.count(list), kinds.count(array)

    held(10)
    (lists150, arrays150), (lists300, arrays300) = held(150), held(300)
    assert lists300 - lists150 < 20 and arrays300 - arrays150 < 20


def test_offs_and_reltool_poses_in_one_batch_as_one_by_one():
    """poses() moves every Offs/RelTool target in one batch: the same bits
    as _relative of each on its own (oracle: the one-by-one function), for
    Offs, RelTool with and without turns, and plain targets among them."""
    from rapidcomp.compensate.targets import _relative, _relative_many
    from rapidcomp.kinematics.frames import unit_quat_matrices
    ts = targets(7, 5)
    decls = [f"  CONST robtarget p{i}:={robtarget(t)};" for i, t in enumerate(ts)]
    moves = ["MoveL Offs(p0,1.5,-2,3.25),v100,fine,tool0;",
             "MoveL RelTool(p1,1,2,3\\Rx:=30\\Rz:=45),v100,fine,tool0;",
             "MoveL p2,v100,fine,tool0;",
             "MoveL RelTool(p3,-4,0.1,1.5),v100,fine,tool0;",
             "MoveJ Offs(p4,0,0,-10),v100,fine,tool0;",
             "MoveL RelTool(p5,7,-8,9\\Ry:=-12.5),v100,fine,tool0;",
             "MoveL p6,v100,fine,tool0;"]
    text = "\n".join(["MODULE M", *decls, "  PROC P()", *(f"    {m}" for m in moves),
                      "  ENDPROC", "ENDMODULE", ""])
    plan = Plan(Task("m.mod", (parse_text(text, "m.mod"),)))
    srcs = [u.source for u in plan.uses]
    assert [s.call.name if s.call else None for s in srcs] == [
        "Offs", "RelTool", None, "RelTool", "Offs", "RelTool", None]
    q = np.array([s.record.quat_wxyz for s in srcs], float)
    q /= np.linalg.norm(q, axis=1)[:, None]
    R = unit_quat_matrices(q)
    p = np.array([s.record.xyz for s in srcs], float)
    one = [_relative(s, R[i], p[i]) for i, s in enumerate(srcs)]
    _relative_many(R, p, srcs)
    for i, (Ri, pi) in enumerate(one):
        assert np.array_equal(R[i], Ri) and np.array_equal(p[i], pi), i
    assert not np.array_equal(one[1][0], unit_quat_matrices(q[1:2])[0])


def test_reltool_rotations_are_the_tools_own_turns():
    """RelTool(p, dx, dy, dz \\Rx:=a \\Rz:=c) as the controller takes it:
    the displacement along the target's own axes, then turns about its x,
    then the new z (tool0, wobj0: the flange at the target). Oracle: the
    rotation matrices written out here; moves turned alike share one matrix
    (made once), and one turned otherwise gets its own."""
    from math import cos, radians, sin
    t = targets(1, 21)[0]
    text = "\n".join([
        "MODULE M", f"  CONST robtarget p1:={robtarget(t)};", "  PROC P()",
        "    MoveL RelTool(p1,1,2,3\\Rx:=30\\Rz:=45),v100,fine,tool0;",
        "    MoveL RelTool(p1,-4,0,1.5\\Rx:=30\\Rz:=45),v100,fine,tool0;",
        "    MoveL RelTool(p1,1,2,3\\Rz:=-20),v100,fine,tool0;",
        "  ENDPROC", "ENDMODULE", ""])
    plan = Plan(Task("m.mod", (parse_text(text, "m.mod"),)))

    def rx(a):
        a = radians(a)
        return np.array([[1, 0, 0], [0, cos(a), -sin(a)], [0, sin(a), cos(a)]])

    def rz(a):
        a = radians(a)
        return np.array([[cos(a), -sin(a), 0], [sin(a), cos(a), 0], [0, 0, 1]])
    w, x, y, z = (float(v) for v in robtarget(t).split("],[")[1].split(","))
    n = (w * w + x * x + y * y + z * z) ** 0.5
    w, x, y, z = w / n, x / n, y / n, z / n
    R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                  [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                  [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
    p = np.array([float(v) for v in robtarget(t)[2:].split("]")[0].split(",")])
    want = [(R @ rx(30) @ rz(45), p + R @ [1, 2, 3]), (R @ rx(30) @ rz(45), p + R @ [-4, 0, 1.5]),
            (R @ rz(-20), p + R @ [1, 2, 3])]
    uses = plan.uses
    for u, (Rw, pw) in zip(uses, want):
        assert np.allclose(u.R, Rw, atol=1e-12) and np.allclose(u.p, pw, atol=1e-9)
    assert uses[0].source.rel_R is uses[1].source.rel_R
    assert uses[2].source.rel_R is not uses[0].source.rel_R
    assert not uses[0].source.rel_R.flags.writeable
