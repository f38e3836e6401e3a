"""A run of plain moves walked again in the state it was walked in before
(flow._Walker._moves: main's second cycle meets a CAM program's moves so)
is not walked move by move again: the flow is the one the walk makes move
by move every time (the oracle: the same walk with what it remembers of
runs forgotten before each run), on programs whose cycles enter their runs
in the same state, in another state, through GOTO, RETRY and loops."""

import dataclasses
import sys
from pathlib import Path

import pytest

from rapidcomp.compensate import flow
from rapidcomp.compensate.plan import Plan, Task
from rapidcomp.rapid.parse import parse_text

from conftest import FIXTURES

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))
from fix import cam_module  # noqa: E402

T = "[[400,300,250],[0.707107,0,0.707107,0],[0,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
TAIL = ",v100,z1,tool0;"


def _module(main: list[str], path: list[str] | None = None, n: int = 6) -> str:
    lines = ["MODULE M"] + [f"  CONST robtarget p{i}:={T};" for i in range(n)]
    lines += ["  PROC main()"] + ["    " + s for s in main] + ["  ENDPROC"]
    if path is not None:
        lines += ["  PROC Path()"] + ["    " + s for s in path] + ["  ENDPROC"]
    return "\n".join(lines + ["ENDMODULE", ""])


MOVES = [f"MoveL p{i}{TAIL}" for i in range(6)]
PROGRAMS = {
    # Two cycles, the second entering Path's run as the first did but for
    # the move before.
    "cycle": _module(["Path;"], MOVES),
    # The cycle switches supervision off after Path: the second enters it
    # in another state.
    "switch": _module(["Path;", "ConfL\\Off;"], ["ConfL\\On;"] + MOVES[:3] + ["ConfJ\\Off;"]
                      + MOVES[3:]),
    "switch2": _module(["ConfL\\On;", "Path;", "ConfL\\Off;"], MOVES),
    # A GOTO back over the run; a handler's RETRY into it; a loop around it.
    "goto": _module(["Path;"], ["lbl:"] + MOVES + ["IF reg1 > 0 GOTO lbl;"]),
    "retry": _module(["Path;"], MOVES + ["ERROR", "  RETRY;"]),
    "loop": _module(["WHILE TRUE DO", "  Path;", "  ConfJ\\Off;", "ENDWHILE"], MOVES),
    "twice": _module(["Path;", "Path;"], MOVES),
    # A TRAP switching supervision: every state widened, a run's shared one
    # once.
    "trap": _module(["Path;"], MOVES).replace(
        "ENDMODULE", "  TRAP t1\n    ConfL\\Off;\n  ENDTRAP\nENDMODULE"),
    "cam": cam_module(200, seed=3, main=True),
    "cam_loose": cam_module(200, seed=4),
}


def _flow(text: str, forget: bool, monkeypatch) -> tuple[flow.Flow, int]:
    """The task's flow, and how many runs were taken as walked before."""
    walk = flow._Walker._moves
    taken = []

    def moves(self, stmts, i, st, rt):
        if forget:
            self.runs.clear()
        known = (id(stmts), i) in self.runs and self.runs[(id(stmts), i)][0] == st
        taken.append(known)
        return walk(self, stmts, i, st, rt)
    with monkeypatch.context() as m:
        m.setattr(flow._Walker, "_moves", moves)
        plan = Plan(Task("m.mod", (parse_text(text, "m.mod"),)))
    return plan.flow, sum(taken)


@pytest.mark.parametrize("name", sorted(PROGRAMS))
def test_a_run_walked_again_gives_the_flow_of_walking_it(name, monkeypatch):
    got, taken = _flow(PROGRAMS[name], False, monkeypatch)
    oracle, none = _flow(PROGRAMS[name], True, monkeypatch)
    assert none == 0
    assert dataclasses.asdict(got) == dataclasses.asdict(oracle)
    assert got.order == oracle.order            # (the first visits in the same order)
    if name in ("cycle", "cam", "twice", "goto"):
        assert taken > 0, name                   # (the run taken as walked before)


@pytest.mark.parametrize("path", sorted(p for p in (FIXTURES / "rapid").iterdir()
                                         if p.suffix in (".mod", ".sys")), ids=lambda p: p.name)
def test_the_fixtures_flows_are_those_walked_move_by_move(path, monkeypatch):
    text = path.read_text(encoding="utf-8", errors="replace").lstrip("\ufeff")
    got, _ = _flow(text, False, monkeypatch)
    oracle, _ = _flow(text, True, monkeypatch)
    assert dataclasses.asdict(got) == dataclasses.asdict(oracle)
