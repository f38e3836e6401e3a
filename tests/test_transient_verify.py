"""`fix --transient` verifies the written program at every thermal state by
reading it once and evaluating each rcTcJ/rcTcR(cold, dq) at each state
(verify.verify_states, targets.Resolver). Oracle: the program materialized
at each state (every call replaced by its value's text), parsed again and
verified as any output (tests/transient_oracle.py, the way it was first
made). Both must give the same residual of every use at every state, bit
for bit, and so the same output and report; on the fixtures in both
modes, and on programs with declared, inline and array targets, FOR loops,
Offs, MoveAbsJ on jointtargets, MoveC."""

import sys
from pathlib import Path

import numpy as np
import pytest

import transient_oracle
from rapidcomp.compensate import fix as F
from rapidcomp.compensate import report
from rapidcomp.compensate.load import load_solver, load_state_solvers
from rapidcomp.compensate.plan import Task
from rapidcomp.compensate.transient import Transient, state_values
from rapidcomp.rapid.parse import parse_source, parse_text
from rapidcomp.source import read_source

ROOT = Path(__file__).resolve().parents[1]
WARM = str(ROOT / "fixtures" / "warm.csv")
LIMITS = ("J5=-120:120",)
EXT = "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]"
LOOPS = f"""MODULE Loops
  CONST robtarget pArr{{3}}:=[[[400,300,250],[0.707107,0,0.707107,0],[0,0,-1,1],{EXT}],
    [[400,200,250],[0.707107,0,0.707107,0],[0,0,-1,1],{EXT}],
    [[400,100,260],[0.707107,0,0.707107,0],[0,0,-1,1],{EXT}]];
  CONST robtarget pOne:=[[450,0,300],[0.707107,0,0.707107,0],[0,0,-1,1],{EXT}];
  CONST jointtarget jStart:=[[35,40,25,40,-70,-10],{EXT}];
  PROC main()
    MoveAbsJ jStart,v100,fine,tool0;
    MoveAbsJ [[30,35,20,35,-65,-5],{EXT}],v100,fine,tool0;
    FOR i FROM 1 TO 3 DO
      MoveL pArr{{i}},v100,z1,tool0;
      MoveL Offs(pArr{{i}},0,0,20),v100,z1,tool0;
    ENDFOR
    MoveJ pOne,v100,z1,tool0;
    MoveL [[420,50,280],[0.707107,0,0.707107,0],[0,0,-1,1],{EXT}],v100,fine,tool0;
    MoveC [[430,60,280],[0.707107,0,0.707107,0],[0,0,-1,1],{EXT}],pOne,v100,fine,tool0;
  ENDPROC
ENDMODULE
"""


@pytest.fixture(scope="module")
def solvers():
    return (load_solver(WARM, None, False, LIMITS),
            load_state_solvers(WARM, None, False, LIMITS))


def _task(name: str) -> Task:
    if name == "loops":
        pf = parse_text(LOOPS, "loops.mod")
    elif name == "cam":
        sys.path.insert(0, str(ROOT / "bench"))
        from fix import cam_module
        pf = parse_text(cam_module(300, 5, main=True), "cam.mod")
    else:
        pf = parse_source(read_source(ROOT / "fixtures" / name))
    return Task(name, (pf,))


def _fix(task, solvers, mode, monkeypatch, oracle: bool, relexed: bool = False):
    """fix --transient, its states verified by verify_states (the output
    parsed again) or by the oracle; also what each gave at every state.
    relexed: as the command runs it, the output read again where
    relex_transient can (what verify_states_relexed gave)."""
    seen = []
    if relexed:
        real = F.verify_states_relexed

        def states(*args):
            got = real(*args)
            if got is not None:
                # (As verify_states gives them: state -> use key -> residual.)
                keys, um, deg = got
                seen.append({s: dict(zip(keys, zip(um[n].tolist(), deg[n].tolist())))
                             for n, s in enumerate(args[-1])})
            return got
        monkeypatch.setattr(F, "verify_states_relexed", states)
        solver, state_solvers = solvers
        result = F.fix(task, solver, mode,
                       transient=(Transient(45.0, 45.0, 2.0), state_solvers))
        monkeypatch.undo()
        return result, seen
    monkeypatch.setattr(F, "relex_transient", lambda *args: None)
    if oracle:
        def states(plan, solved, keys, out_files, state_solvers):
            texts = {fi: pf.source.text for fi, pf in out_files.items()}
            got = transient_oracle.verify_states(plan, solved, keys, texts, out_files,
                                                 state_solvers)
            seen.append(got)
            return got
    else:
        real = F.verify_states

        def states(*args):
            got = real(*args)
            seen.append(got)
            return got
    monkeypatch.setattr(F, "verify_states", states)
    solver, state_solvers = solvers
    result = F.fix(task, solver, mode, transient=(Transient(45.0, 45.0, 2.0), state_solvers))
    monkeypatch.undo()
    return result, seen


@pytest.mark.parametrize("mode", ["auto", "absj"])
@pytest.mark.parametrize("name", ["cubes.mod", "paper_front.mod", "rapid/robotstudio_crlf.mod",
                                  "rapid/robodk.mod", "rapid/cam_confoff.mod", "loops", "cam"])
def test_states_read_once_give_what_the_materialized_program_gives(name, mode, solvers,
                                                                  monkeypatch):
    task = _task(name)
    fast, fast_seen = _fix(task, solvers, mode, monkeypatch, False)
    slow, slow_seen = _fix(task, solvers, mode, monkeypatch, True)
    assert len(fast_seen) == len(slow_seen) >= 1
    _same(fast, fast_seen, slow, slow_seen, mode)


def _same(fast, fast_seen, slow, slow_seen, mode: str) -> None:
    """Two runs of fix gave the same residual of every use at every state,
    bit for bit, and the same output and report."""
    for a, b in zip(fast_seen, slow_seen):
        assert list(a) == list(b)
        for s in a:
            assert a[s].keys() == b[s].keys() and len(a[s]) > 0
            assert all(a[s][k] == b[s][k] for k in a[s]), s       # (floats: bit for bit)
    assert [m.text for m in fast.modules] == [m.text for m in slow.modules]
    assert fast.rows == slow.rows and fast.notes == slow.notes
    meta = {"mode": mode}
    assert report.markdown(fast, meta) == report.markdown(slow, meta)


def test_the_loops_program_is_written_with_every_kind_of_call(solvers, monkeypatch):
    """What the comparison above reads: the loop program's output holds
    rcTcJ on declared and inline jointtargets, rcTcR on an array element
    in a FOR loop (with and without Offs), inline robtargets and MoveC."""
    result, _ = _fix(_task("loops"), solvers, "auto", monkeypatch, False)
    text = result.modules[0].text
    assert result.failed == 0
    for piece in ("MoveAbsJ rcTcJ(jStart, jStart_dq)", "MoveAbsJ rcTcJ([[30,", "rcTcR(pArr{i}",
                  "Offs(rcTcR(pArr{i}", "MoveL rcTcR([[420,", "MoveC rcTcR([[430,",
                  "MoveAbsJ rcTcJ(jt_pOne, jt_pOne_dq)"):
        assert piece in text, piece


def test_state_values_are_those_of_one_state_at_a_time():
    """state_values of several states at once: each row is the row of that
    state alone (float32 arithmetic elementwise; the quaternion's norm a
    vector's own, as np.linalg.norm computes it), on random values."""
    rng = np.random.default_rng(7)
    states = (0.0, 0.25, 0.5, 0.75, 1.0)
    for _ in range(200):
        cold = np.concatenate([rng.uniform(-900, 900, 3), rng.normal(size=4)])
        dq = np.concatenate([rng.normal(scale=0.1, size=3), rng.normal(scale=1e-4, size=4)])
        for joint, c, d in ((True, cold[:6], dq[:6]), (False, cold, dq)):
            many = state_values(c, d, states, joint)
            for n, s in enumerate(states):
                assert np.array_equal(many[n], state_values(c, d, (s,), joint)[0])
        q = state_values(cold, dq, states, False)[:, 3:].astype(float)
        assert np.allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-6)
    # The quaternion normalized as np.linalg.norm of the one vector does it.
    one = state_values(cold, dq, (0.5,), False)[0]
    raw = (np.float32(cold[3:]) + np.float32(np.float32(0.5) * np.float32(dq[3:]))).astype(float)
    assert np.array_equal(one[3:], np.float32(raw / np.linalg.norm(raw)))


@pytest.mark.parametrize("name, mode, everyone", [("cam", "absj", True), ("cam", "auto", True),
                                                  ("loops", "auto", False)])
def test_states_after_the_first_take_the_calls_values_as_arrays(name, mode, everyone, solvers,
                                                               monkeypatch):
    """Past the first state, every use whose target is a call takes its
    values as arrays (Resolver.state_many): all of a CAM program's (rcTcJ
    of MoveAbsJ, rcTcR of MoveL); of the loop program's all but the MoveL
    to an Offs around an rcTcR (resolved again)."""
    from rapidcomp.compensate.targets import Resolver
    taken = []
    real = Resolver.state_many

    def spy(self, uses):
        got = real(self, uses)
        taken.append((len(got[0]) + len(got[4]), len(uses)))
        return got
    monkeypatch.setattr(Resolver, "state_many", spy)
    # (The output parsed again: what the command does where relex_transient
    # does not read it.)
    monkeypatch.setattr(F, "relex_transient", lambda *args: None)
    solver, state_solvers = solvers
    F.fix(_task(name), solver, mode, transient=(Transient(45.0, 45.0, 2.0), state_solvers))
    assert len(taken) == len(state_solvers) - 1
    for n, total in taken:
        assert n == total if everyone else 0 < n < total, (n, total)


RT = "[0.707107,0,0.707107,0],[0,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"


def _module(name: str, body: str) -> str:
    return f"MODULE {name}\n{body}ENDMODULE\n"


@pytest.mark.parametrize("case", ["with", "local", "const index"])
def test_calls_are_read_as_the_controller_scopes_their_names(case, solvers, monkeypatch):
    """The resolver looks the calls' arguments up as the controller does:
    data of a --with module, LOCAL data of one name in two modules, an
    index that is a CONST num. The oracle looks names up bare among the
    written modules (it refused or misread these): it verifies the same
    program written so that it can read it (the data in the written module,
    the names made unique, the index written out); every residual at every
    state is the same, bit for bit, and every use is compensated."""
    data = "  CONST robtarget pG:=[[600,100,300]," + RT + ";\n"
    if case == "with":
        main = _module("Main", "  PROC main()\n    MoveL pG,v100,fine,tool0;\n  ENDPROC\n")
        task = Task("t", (parse_text(main, "Main.mod"),),
                    context=(parse_text(_module("Data", data), "Data.mod"),))
        same = Task("t", (parse_text(main.replace("MODULE Main\n", "MODULE Main\n" + data),
                                     "Main.mod"),))
    elif case == "local":
        def two(a: str, b: str) -> Task:
            return Task("t", tuple(parse_text(_module(
                m, f"  LOCAL CONST robtarget {n}:=[[{x},100,300]," + RT + ";\n"
                f"  PROC go{m}()\n    MoveL {n},v100,fine,tool0;\n  ENDPROC\n"), f"{m}.mod")
                for m, n, x in (("A", a, 600), ("B", b, 560))))
        task, same = two("pX", "pX"), two("pXa", "pXb")
    else:
        arr = ("  CONST num N:=2;\n  CONST robtarget pA{3}:=[" + ",".join(
            f"[[{x},100,300]," + RT for x in (600, 580, 560)) + "];\n")
        prog = arr + "  PROC main()\n    MoveL pA{N},v100,fine,tool0;\n  ENDPROC\n"
        task = Task("t", (parse_text(_module("M", prog), "M.mod"),))
        same = Task("t", (parse_text(_module("M", prog.replace("pA{N}", "pA{2}")), "M.mod"),))
    fast, fast_seen = _fix(task, solvers, "auto", monkeypatch, False)
    _, slow_seen = _fix(same, solvers, "auto", monkeypatch, True)
    assert fast.failed == 0 and len(fast.rows) >= 1
    assert fast_seen == slow_seen and len(fast_seen[0]) == 5


# Every target an rcTcR of a robtarget as written: declared in a routine and
# in the module, inline, a MoveC's two, a move in a second module and a
# FOR loop's move of one target, in CRLF.
PLAIN = f"""MODULE Plain
  CONST robtarget pA:=[[600,100,300],{RT};
  CONST robtarget pB:=[[560,50,320],{RT};
  PROC main()
    CONST robtarget pR:=[[580,20,280],{RT};
    MoveL pA,v100,z1,tool0;
    MoveL pR,v100,z1,tool0;
    MoveL [[590,60,310],{RT},v100,fine,tool0;
    MoveC [[570,40,300],{RT},pB,v100,z1,tool0;
    FOR i FROM 1 TO 2 DO
      MoveL pB,v100,z1,tool0;
    ENDFOR
  ENDPROC
ENDMODULE
""".replace("\n", "\r\n")
OTHER = f"""MODULE Other
  PROC side()
    MoveL pA,v100,z1,tool0;
    MoveL [[610,80,290],{RT},v100,z1,tool0;
  ENDPROC
ENDMODULE
"""


def _plain_task() -> Task:
    return Task("t", (parse_text(PLAIN, "Plain.mod"), parse_text(OTHER, "Other.mod")))


@pytest.mark.parametrize("mode", ["auto", "absj"])
@pytest.mark.parametrize("name", ["cubes.mod", "paper_front.mod", "rapid/robotstudio_crlf.mod",
                                  "rapid/robodk.mod", "rapid/cam_confoff.mod", "loops", "cam",
                                  "plain"])
def test_the_output_read_again_gives_what_it_parsed_again_gives(name, mode, solvers,
                                                                monkeypatch):
    """Where relex_transient reads the output (every target an rcTcR of
    the robtarget as written, an rcTcJ of a MoveAbsJ's jointtarget or of a
    move turned into MoveAbsJ), each use's residual at every state is what
    verify_states gives on the output parsed again, bit for bit; and so the
    same output and report. It reads the CAM programs, the RoboDK one and
    the plain one in both modes; the others hold arrays in FOR loops or a
    target whose cold value needs other confdata."""
    task = _plain_task() if name == "plain" else _task(name)
    fast, fast_seen = _fix(task, solvers, mode, monkeypatch, False, relexed=True)
    slow, slow_seen = _fix(task, solvers, mode, monkeypatch, False)
    if name in ("cam", "plain", "rapid/robodk.mod", "rapid/cam_confoff.mod"):
        assert len(fast_seen) == 1
    if fast_seen:
        assert len(slow_seen) == 1
    _same(fast, fast_seen, slow, slow_seen[:len(fast_seen)], mode)


def test_the_plain_program_is_written_with_every_kind_of_rctcr(solvers, monkeypatch):
    """What the comparison above reads of the plain program: rcTcR on
    declared targets (in the routine, in the module, from another module),
    inline ones, both of a MoveC, a FOR loop's, in CRLF; every one of its 8 uses
    compensated."""
    result, seen = _fix(_plain_task(), solvers, "auto", monkeypatch, False, relexed=True)
    text = result.modules[0].text + result.modules[1].text
    assert result.failed == 0 and len(seen) == 1 and len(seen[0][1.0]) == 8
    for piece in ("    MoveL rcTcR(pA, pA_dq)", "MoveL rcTcR(pR, pR_dq)",
                  "MoveL rcTcR([[590,", "MoveC rcTcR([[570,", "]]),rcTcR(pB, pB_dq),v100",
                  "    CONST pose pR_dq:=", "  CONST pose pA_dq:=", "LOCAL CONST pose pB_dq:=",
                  "      MoveL rcTcR(pB, pB_dq)", "MoveL rcTcR([[610,"):
        assert piece in text, piece
    assert "\r\n" in result.modules[0].text and "\n" not in result.modules[0].text.replace(
        "\r\n", "")


def _captured(solvers, monkeypatch, mode: str = "auto"):
    """The arguments relex_transient was called with on the plain program,
    and what it returned."""
    got = []
    real = F.relex_transient

    def spy(*args):
        got.append((args, real(*args)))
        return got[-1][1]
    monkeypatch.setattr(F, "relex_transient", spy)
    solver, state_solvers = solvers
    F.fix(_plain_task(), solver, mode, transient=(Transient(45.0, 45.0, 2.0), state_solvers))
    monkeypatch.undo()
    assert len(got) == 1 and got[0][1] is not None
    return got[0][0]


@pytest.mark.parametrize("old, new", [
    ("CONST pose pA_dq:=[[", "CONST pose pA_dq:=[[1"),              # another number
    ("pose pA_dq:=", "robtarget pA_dq:="),                           # another type
    ("CONST pose pR_dq:=", "VAR pose pR_dq:="),                      # not CONST
    ("MoveL rcTcR(pA, pA_dq)", "MoveL rcTcJ(pA, pA_dq)"),            # another function
    ("MoveL rcTcR(pA, pA_dq)", "MoveL rcTcR(pB, pA_dq)"),            # another cold value
    ("MoveL rcTcR([[590,", "MoveL rcTcR([[591,"),                   # another inline target
    ("]]),rcTcR(pB, pB_dq)", "]] ),rcTcR(pB, pB_dq)"),               # not written plainly
    ("tool0;\r\n    MoveC", "tool0;\r\n    MoveL pA,v100,z1,tool0;\r\n    MoveC"),  # a move more
])
def test_an_output_not_as_meant_is_not_read_again(old, new, solvers, monkeypatch):
    """relex_transient reads nothing of an output that differs from what
    the editor meant (the command then parses it again): each change here
    to the plain program's written text."""
    _not_read(old, new, solvers, monkeypatch, "auto")


@pytest.mark.parametrize("old, new", [
    ("MoveAbsJ rcTcJ(jt_pA, jt_pA_dq)", "MoveJ rcTcJ(jt_pA, jt_pA_dq)"),   # another instruction
    ("CONST jointtarget jt_pR:=[[", "CONST jointtarget jt_pR:=[[1"),    # another cold value
    ("jointtarget jt_pA_dq:=", "pose jt_pA_dq:="),                     # another type
    ("MoveAbsJ rcTcJ([[6", "MoveAbsJ rcTcJ([[7"),                      # another inline cold
    ("jt_pR_dq:=[[-0.", "jt_pR_dq:=[[+0."),                            # another correction
    ("MoveAbsJ rcTcJ(jt_pA, jt_pA_dq)", "MoveAbsJ rcTcR(jt_pA, jt_pA_dq)"),  # another function
])
def test_a_move_turned_into_moveabsj_not_as_meant_is_not_read_again(old, new, solvers,
                                                                     monkeypatch):
    """The same of the plain program written with --emit absj (its moves
    but the other module's turned into MoveAbsJ on rcTcJ of new cold
    values, declared and inline)."""
    _not_read(old, new, solvers, monkeypatch, "absj")


def _not_read(old: str, new: str, solvers, monkeypatch, mode: str) -> None:
    plan, calls, file_edits, texts = _captured(solvers, monkeypatch, mode)
    fi = 0 if old in texts[0] else 1
    assert texts[fi].count(old) >= 1, old
    changed = dict(texts)
    changed[fi] = texts[fi].replace(old, new, 1)
    assert F.relex_transient(plan, calls, file_edits, texts) is not None
    assert F.relex_transient(plan, calls, file_edits, changed) is None


@pytest.mark.parametrize("name", ["plain", "cam"])
def test_declarations_lexed_one_by_one_are_read_alike(name, solvers, monkeypatch):
    """relex_transient with the plain reading of the new declarations off
    (each lexed as the parser lexes it, each literal read alone) reads the
    same numbers: the same residuals at every state, bit for bit."""
    from rapidcomp.compensate import verify as V
    task = _plain_task() if name == "plain" else _task(name)
    _, fast_seen = _fix(task, solvers, "auto", monkeypatch, False, relexed=True)
    monkeypatch.setattr(V, "_plain_declared", lambda eng, pieces, *how: None)
    _, slow_seen = _fix(task, solvers, "auto", monkeypatch, False, relexed=True)
    assert len(fast_seen) == len(slow_seen) == 1 and fast_seen == slow_seen


@pytest.mark.parametrize("head", ["MODULE B", "MODULE B(SYSMODULE) ! the path", "MODULE B ! x"])
def test_declarations_after_the_module_line_are_read_again(head, solvers, monkeypatch):
    """A module with no declaration before its routines (its targets in a
    --with module) gets its corrections after its MODULE line: read again
    there too (attributes and a comment on the line), with the same
    residuals as the output parsed again."""
    data = (f"MODULE D\n  CONST jointtarget jHome:=[[0,20,10,0,50,0],{EXT}];\n"
            f"  CONST robtarget pX:=[[600,100,300],{RT};\nENDMODULE\n")
    main = (f"{head}\n  PROC main()\n    MoveAbsJ jHome, v100, fine, tool0;\n"
            "    MoveL pX,v100,z1,tool0;\n  ENDPROC\nENDMODULE\n")

    def task():
        return Task("t", (parse_text(main, "B.mod"),), context=(parse_text(data, "D.mod"),))
    fast, fast_seen = _fix(task(), solvers, "auto", monkeypatch, False, relexed=True)
    slow, slow_seen = _fix(task(), solvers, "auto", monkeypatch, False)
    assert len(fast_seen) == len(slow_seen) == 1 and fast.failed == 0
    assert fast.modules[0].text.startswith(head + "\n    LOCAL CONST jointtarget jHome_dq")
    _same(fast, fast_seen, slow, slow_seen, "auto")


def test_a_joint_value_beyond_its_bound_leaves_the_check_to_the_output_parsed_again(
        solvers, monkeypatch):
    """A MoveAbsJ's value at a state beyond a joint's bound: the numbers
    read do not serve (verify_states_relexed gives None, whichever block
    and state it is found in) and the output parsed again is checked: the
    same result as where they serve."""
    from rapidcomp.compensate import verify as V
    solver, state_solvers = solvers
    tr = (Transient(45.0, 45.0, 2.0), state_solvers)
    want = F.fix(_task("cam"), solver, "absj", transient=tr)
    gave = []
    real = F.verify_states_relexed

    def spy(*args):
        got = real(*args)
        gave.append(got is None)
        return got
    monkeypatch.setattr(V, "VERIFY_BLOCK", 5)
    monkeypatch.setattr(V, "MAX_JOINT_DEG", 1e-9)     # (every joint value beyond it)
    monkeypatch.setattr(F, "verify_states_relexed", spy)
    got = F.fix(_task("cam"), solver, "absj", transient=tr)
    assert gave == [True]
    assert got.modules == want.modules and got.rows == want.rows and got.notes == want.notes
