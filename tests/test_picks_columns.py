"""Past the choice of the nominal solutions, every row's Pick is held as
columns (solve.Picks; issue #14: a CAM program's 1e5 rows kept a tuple and
a joint array each, ~20 MB to the report). Oracle: the Picks the chooser
made, caught as they are handed over: each row read from the columns is
that Pick, field by field (the joints where it has a solution), in
programs whose choices are as written (MoveAbsJ), by confdata, closest to
the move before (ConfL\\Off) and failures."""

from pathlib import Path

import numpy as np
import pytest

from rapidcomp.compensate import solve
from rapidcomp.compensate.load import load_solver
from rapidcomp.compensate.plan import Plan, Task
from rapidcomp.rapid.parse import parse_file

ROOT = Path(__file__).resolve().parents[1]
FIXTURES = ROOT / "fixtures"
PROGRAMS = [FIXTURES / "cubes.mod", FIXTURES / "rapid" / "cam_confoff.mod",
            FIXTURES / "rapid" / "robodk.mod",
            ROOT / "tests" / "golden" / "fix" / "refusals" / "before.mod"]


@pytest.mark.parametrize("path", PROGRAMS, ids=lambda p: p.name)
def test_each_row_read_from_the_columns_is_the_pick_the_chooser_made(path, monkeypatch):
    made = []
    real = solve.Picks

    def catch(picks, q):
        made.append(list(picks))
        return real(picks, q)

    monkeypatch.setattr(solve, "Picks", catch)
    solver = load_solver(str(FIXTURES / "warm.csv"), None, False)
    solved = solve.solve(Plan(Task(path.name, (parse_file(path, path.name),))), solver)
    (picks,) = made
    assert len(solved.picks) == len(picks) > 0
    kinds = set()
    for i, want in enumerate(picks):
        got = solved.picks[i]
        assert (got.rule, got.failure, got.kind, got.line, got.caution) == (
            want.rule, want.failure, want.kind, want.line, want.caution)
        assert (got.prev is None) == (want.prev is None)
        if want.prev is not None:
            assert np.array_equal(got.prev, want.prev)
        if want.failure is None:
            assert np.array_equal(got.q, want.q, equal_nan=True)
        kinds.add(want.kind if want.failure is None else "failure")
    # (The programs between them make every kind of choice.)
    made_kinds.update(kinds)


made_kinds: set = set()


def test_the_programs_make_every_kind_of_choice():
    assert made_kinds >= {"joint", "conf", "closest", "failure"}, made_kinds
