"""The deformed robot's IK guessed ahead (solve._guess_deformed, issue #14):
made by the job's helper from each robtarget's confdata solution while the
job chooses the nominal solutions, and taken block by block only where a
block's inputs are the very ones the choice gives (ik.reusing). Whatever
the guess, the results are those computed without one, bit for bit."""

import numpy as np
import pytest

from rapidcomp.compensate import solve as S
from rapidcomp.compensate.load import load_solver
from rapidcomp.compensate.plan import Plan, Task
from rapidcomp.kinematics import ik
from rapidcomp.kinematics.frames import DEG
from rapidcomp.kinematics.ik import Solver, reusing
from rapidcomp.rapid.parse import parse_text

import cam_variants
from conftest import FIXTURES


@pytest.fixture(scope="module")
def solver():
    return load_solver(str(FIXTURES / "warm.csv"), None, False)


def _computed(monkeypatch, method) -> list:
    """The blocks `method` (a @_chunked Solver method) computes, by length."""
    made: list = []
    raw = method.__wrapped__

    def spy(*args):
        made.append(len(args[1]))
        return raw(*args)
    monkeypatch.setattr(method, "__wrapped__", spy)
    return made


def _bits(x):
    """Every array of a result as (dtype, shape, bytes), recursively."""
    if isinstance(x, ik.IKBatch):
        return _bits(tuple(getattr(x, f) for f in x.__dataclass_fields__))
    if isinstance(x, tuple):
        return tuple(_bits(v) for v in x)
    if x is None:
        return None
    x = np.asarray(x)
    return x.dtype.str, x.shape, x.tobytes()


def _fake(batch: ik.IKBatch) -> ik.IKBatch:
    """A result no solve gives: every number of batch plus one."""
    return ik.IKBatch(*(None if v is None else np.asarray(v) + 1
                        for v in (getattr(batch, f) for f in batch.__dataclass_fields__)))


def test_reusing_takes_a_block_only_where_its_inputs_are_the_guess(solver, monkeypatch):
    monkeypatch.setattr(ik, "CHUNK", 7)
    rng = np.random.default_rng(4)
    q = rng.uniform(-60, 60, (30, 6))
    R, p, seed = solver.seed_from_joints(q)
    tcp = np.tile([0.0, 0.0, 150.0], (30, 1))
    args = (R, p, seed, tcp)
    full = solver.solve_deformed(*args)
    # A "result" no solve gives, for inputs equal to these: taken as it is
    # in every block (nothing computed).
    fake = _fake(full)
    made = _computed(monkeypatch, Solver.solve_deformed)
    assert _bits(reusing(Solver.solve_deformed, solver, args, (args, fake))) == _bits(fake)
    assert made == []
    # One input of row 9 (block 1 of rows 7-13) otherwise, one bit of row
    # 29 (block 4, rows 28-29): those blocks computed, the others taken.
    p2, tcp2 = p.copy(), tcp.copy()
    p2[9, 0] += 1.0
    tcp2[29, 2] = np.nextafter(tcp2[29, 2], 0.0)
    got = reusing(Solver.solve_deformed, solver, args, ((R, p2, seed, tcp2), fake))
    assert made == [7, 2]
    assert _bits(got) == _bits(ik._join([ik._rows(full if k in (1, 4) else fake,
                                                  slice(k * 7, k * 7 + 7)) for k in range(5)]))
    # -0.0 is == 0.0 but not the same input: computed.
    fk_made = _computed(monkeypatch, Solver.nominal_pose_and_wrist)
    q0 = np.zeros((3, 6))
    q1 = q0.copy()
    q1[1, 2] = -0.0
    reusing(Solver.nominal_pose_and_wrist, solver, (q0,), ((q1,), None))
    assert fk_made == [3]
    # Another length: computed as the method does, whole.
    made.clear()
    assert _bits(reusing(Solver.solve_deformed, solver, args, (
        tuple(ik._rows(a, slice(0, 29)) for a in args), fake))) == _bits(full)


@pytest.mark.parametrize("text", [cam_variants.bench_module(60, 11, "    ConfL\\Off;\n"),
                                  cam_variants.broken_runs(12), cam_variants.not_called(13)])
def test_the_solve_is_the_same_whatever_was_guessed(text, solver, monkeypatch):
    """_solve_deformed on the choice's inputs gives what it gives without a
    guess: with the guess the helper makes (the confdata solutions), with
    some blocks guessed wrong, and with another call's guess (not taken)."""
    monkeypatch.setattr(ik, "CHUNK", 8)
    plan = Plan(Task("cam.mod", (parse_text(text, "cam.mod"),)))
    uses = [u for u in plan.uses if u.reason is None]
    chooser = S._Chooser(plan, solver, uses, {u.key: i for i, u in enumerate(uses)})
    assert chooser.guessed is None              # (no helper here: nothing handed)
    chooser.run()
    q_nom, rob = chooser.q, list(chooser.rob_row)
    failed = np.array([pk.failure is not None for pk in chooser.picks])
    R, p, _, nominal = S._seed_of(solver, q_nom, rob, *chooser.flange, failed)
    args = (solver, R, p, nominal, chooser.tcp, np.nan_to_num(q_nom) * DEG)
    alone = _bits(S._solve_deformed(None, *args))
    made = _computed(monkeypatch, Solver.solve_deformed)

    def guessed(number, q):
        S._guess_deformed(number, solver, q, rob, *chooser.flange, chooser.tcp)
        made.clear()
        got = _bits(S._solve_deformed(1, *args))
        assert S._guessed is None                  # (taken once)
        return got, len(made)
    # The guess as handed: the joints the choice is expected to take.
    # (Here every choice is the one expected, bit for bit, supervision off
    # too: every block taken.)
    got, computed = guessed(1, chooser._expected(np.flatnonzero(np.array(chooser.quick) == 1)))
    assert got == alone and computed == 0
    # One solved row of block 1 and one of the last block a hundredth of a
    # degree off: those two blocks computed again, the same results.
    q_wrong = q_nom.copy()
    solved = np.flatnonzero(~np.isnan(q_nom).any(axis=1))
    for at in (solved[solved >= 8][0], solved[-1]):
        q_wrong[at, 0] += 0.01
    got, computed = guessed(1, q_wrong)
    assert got == alone and computed == 2
    # All right: nothing computed.
    got, computed = guessed(1, q_nom)
    assert got == alone and computed == 0
    # Another call's guess is not taken (were it, this one's results would
    # be a result no solve gives).
    deformed = S._solve_deformed(None, *args)[0]
    fake = _fake(deformed)
    S._guessed = (2, {"ik": ((R, p, nominal, chooser.tcp), fake)})
    assert _bits(S._solve_deformed(1, *args)) == alone
    assert S._guessed is None
    S._guessed = (1, {"ik": ((R, p, nominal, chooser.tcp), fake)})
    assert _bits(S._solve_deformed(1, *args)[0]) == _bits(fake)


class _Now:
    """side.run made at once, in this process (a helper stand-in)."""

    def __init__(self, fn, *args):
        self.value = fn(*args)

    def get(self):
        return self.value


@pytest.mark.parametrize("confl, guessed", [("", True), ("    ConfL\\On;\n", True),
                                            ("    ConfL\\Off;\n", False)])
def test_the_job_guesses_where_the_choice_is_foreseen(confl, guessed, solver, monkeypatch):
    """As the job runs it (Solving, with a helper: here one that makes each
    call at once): the guess is handed where supervision may be on, and
    every block of the deformed robot's IK is then taken from it; under
    ConfL\\Off (each move follows the one before as it really went) none is
    handed. The solve is the one made without a helper, bit for bit."""
    from rapidcomp import side
    monkeypatch.setattr(ik, "CHUNK", 16)
    text = cam_variants.bench_module(100, 21, confl)

    def solved():
        plan = Plan(Task("cam.mod", (parse_text(text, "cam.mod"),)))
        s = S.solve(plan, solver)
        return _bits((s.nominal, s.deformed, s.err_p, s.err_r, s.flange_R, s.flange_p,
                      s.conf_after))
    alone = solved()
    calls: list = []

    def run(fn, *args):
        calls.append(fn.__name__)
        return _Now(fn, *args)
    made = _computed(monkeypatch, Solver.solve_deformed)
    known: list = []

    def reused(method, solver, args, guess):
        known.append(guess is not None)
        return reusing(method, solver, args, guess)
    with monkeypatch.context() as m:
        m.setattr(side, "helps", lambda: True)
        m.setattr(side, "run", run)
        m.setattr(S, "reusing", reused)
        got = solved()
    assert got == alone
    assert ("_guess_deformed" in calls) == guessed
    assert "_solve_deformed" in calls
    # The IK, the error and the FK each given the guess (and no block of
    # the IK computed again), or none; the guess's own made without one.
    assert known == ([False] * 3 + [True] * 3 if guessed else [False] * 3)
    assert made == []
    assert S._guessed is None
