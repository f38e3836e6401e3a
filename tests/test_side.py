"""Work a big job hands to a second process (side.py, issue #14): a call
gives what the function gives here, made by the helper when there is one
and here otherwise (no helper, or one that failed, died or is too slow);
the helper is always reaped. And fix with a helper writes what it writes
alone: the golden cases (outputs reviewed by eye) and CAM modules, with
the helper doing the work (counted)."""

import os
import signal
import time

import pytest

from rapidcomp import side
from rapidcomp.compensate import report
from rapidcomp.compensate.fix import fix
from rapidcomp.compensate.load import load_solver
from rapidcomp.compensate.plan import Task
from rapidcomp.rapid.parse import parse_text

import cam_variants
from conftest import FIXTURES
from regen_golden import FIX_CASES, GOLDEN, TASK_CASES, fix_golden, task_golden


def pid_and(x):
    return os.getpid(), x


def fails_away(parent):
    if os.getpid() != parent:
        raise RuntimeError("only in the helper")
    return "here"


def slow_away(parent):
    if os.getpid() != parent:
        time.sleep(30)
    return os.getpid()


@pytest.fixture
def helped(monkeypatch):
    """helping() forks for any size, as where two CPUs may be used."""
    monkeypatch.setattr(side, "HELP_FROM", 0)
    monkeypatch.setattr(side, "enabled", True)
    monkeypatch.setattr(side, "side_by_side", lambda: 2)


def _reaped(pid: int) -> bool:
    try:
        os.waitpid(pid, os.WNOHANG)
    except ChildProcessError:
        return True
    return False


def test_a_call_is_made_by_the_helper_and_gives_what_the_function_gives(helped):
    me = os.getpid()
    with side.helping(1):
        assert side.helps()
        helper = side._helper
        first = side.run(pid_and, [1.5, "x", None])
        second = side.run(pid_and, {"a": (1, 2)})          # (the first taken before)
        assert first.get() == (helper.pid, [1.5, "x", None])
        assert second.get() == (helper.pid, {"a": (1, 2)})
        assert helper.pid != me
    assert not side.helps()
    assert _reaped(helper.pid)


def test_the_helper_runs_its_work_one_piece_at_a_time(helped):
    """Its work runs beside the job's, which takes the other CPU: the IK
    it is handed (solve.nominal_ahead) runs on one thread there."""
    from rapidcomp import cpus
    with side.helping(1):
        pending = side.run(pid_and, None)
        there = side.run(cpus.side_by_side)
        assert pending.get()[0] != os.getpid()
        assert there.get() == 1


@pytest.mark.parametrize("why", ["disabled", "one CPU", "small"])
def test_without_a_helper_a_call_is_made_here(why, helped, monkeypatch):
    size = 1
    if why == "disabled":
        monkeypatch.setattr(side, "enabled", False)
    elif why == "one CPU":
        monkeypatch.setattr(side, "side_by_side", lambda: 1)
    else:
        monkeypatch.setattr(side, "HELP_FROM", 10)
    with side.helping(size):
        assert not side.helps()
        assert side.run(pid_and, 3).get() == (os.getpid(), 3)
    assert side.run(pid_and, 4).get() == (os.getpid(), 4)        # (outside: here)


@pytest.mark.parametrize("trouble", ["killed", "raises", "unpicklable", "too slow",
                                     "stuck before a large call"])
def test_a_helper_in_trouble_changes_where_the_call_is_made_only(trouble, helped,
                                                                   monkeypatch):
    me = os.getpid()
    with side.helping(1):
        helper = side._helper
        if trouble == "killed":
            call = side.run(pid_and, 1)
            os.kill(helper.pid, signal.SIGKILL)
            time.sleep(0.05)
            # (It writes a result only when it is fetched: this one is lost.)
            assert call.get() == (me, 1)
            assert side.run(pid_and, 3).get() == (me, 3)   # (nothing more handed to it)
        elif trouble == "raises":
            assert side.run(fails_away, me).get() == "here"
            assert not side.helps()
        elif trouble == "unpicklable":
            assert side.run(pid_and, lambda: 1).get()[0] == me
        elif trouble == "too slow":
            monkeypatch.setattr(side, "PATIENCE_S", 0.3)
            t = time.monotonic()
            assert side.run(slow_away, me).get() == me
            assert time.monotonic() - t < 5
            assert not side.helps()
        else:
            # A call larger than the pipe waits for the helper to read it,
            # within the same patience.
            monkeypatch.setattr(side, "PATIENCE_S", 0.3)
            t = time.monotonic()
            side.run(slow_away, me)
            large = side.run(pid_and, b"x" * (8 << 20))
            assert large.get() == (me, b"x" * (8 << 20))
            assert time.monotonic() - t < 5
            assert not side.helps()
    assert _reaped(helper.pid)


def test_leaving_with_a_call_in_the_helpers_hands_reaps_it(helped):
    t = time.monotonic()
    with pytest.raises(KeyError):
        with side.helping(1):
            helper = side._helper
            side.run(slow_away, os.getpid())
            raise KeyError("the job failed")
    assert _reaped(helper.pid) and time.monotonic() - t < 5     # (stopped, not waited for)


def _spy(monkeypatch) -> list:
    """The results the helper sent back."""
    made = []
    take = side.Helper.take

    def spy(self, pending):
        got = take(self, pending)
        made.append(pending.fn.__name__ if got is not None else None)
        return got

    monkeypatch.setattr(side.Helper, "take", spy)
    return made


def test_the_golden_cases_are_written_as_reviewed_with_a_helper(helped, monkeypatch):
    made = _spy(monkeypatch)
    for case in sorted(FIX_CASES):
        folder = GOLDEN / "fix" / case
        with side.helping(1):
            after, rep = fix_golden(case)
        assert after == (folder / "after.mod").read_bytes(), case
        assert rep == (folder / "report.md").read_text(encoding="utf-8"), case
    for case in sorted(TASK_CASES):
        folder = GOLDEN / "fix" / case
        with side.helping(1):
            after, rep = task_golden(case)
        for rel, data in after.items():
            assert data == (folder / "after" / rel).read_bytes(), (case, rel)
        assert rep == (folder / "report.md").read_text(encoding="utf-8"), case
    # The helper made the number cells of every case and the diffs of the
    # cases that change something (none made here instead).
    assert None not in made
    assert made.count("number_cells") == len(FIX_CASES) + len(TASK_CASES)
    # (And the nominal IK of each, made while the flow was analysed, and
    # the deformed robot's, made while the uses were grouped.)
    assert made.count("_nominal_and_candidates") == len(FIX_CASES) + len(TASK_CASES)
    assert made.count("_solve_deformed") == len(FIX_CASES) + len(TASK_CASES)
    assert made.count("columns_diff") >= len(FIX_CASES) + len(TASK_CASES) - 1


def _alone_and_helped(run, monkeypatch) -> tuple:
    """run() inside helping() without a helper, then with one."""
    with monkeypatch.context() as m:
        m.setattr(side, "enabled", False)
        with side.helping(1):
            alone = run()
    with side.helping(1):
        return alone, run()


@pytest.mark.parametrize("mode", ["absj", "robtarget", "auto"])
def test_a_cam_module_is_written_and_reported_as_without_a_helper(mode, helped, monkeypatch):
    """In blocks of a few literals (a CAM program's 1e5 in blocks of 8192):
    every other block's texts and decoding made by the helper."""
    from rapidcomp.compensate import edit as E
    from rapidcomp.compensate import verify as V
    monkeypatch.setattr(E, "PREPARE_BLOCK", 37)
    monkeypatch.setattr(V, "RELEX_BLOCK", 41)
    made = _spy(monkeypatch)
    solver = load_solver(str(FIXTURES / "warm.csv"), None, False)
    for text in (cam_variants.bench_module(300, 3, ""),
                 cam_variants.bench_module(300, 4, "    ConfL\\Off;\n"),
                 cam_variants.bench_module(300, 5, "    ConfL\\On;\n"),
                 cam_variants.not_called(5), cam_variants.broken_runs(6)):
        def run():
            result = fix(Task("cam.mod", (parse_text(text, "cam.mod"),)), solver, mode,
                         output_names={"cam.mod": "out.mod"}, json=True)
            return (result.modules, result.rows, report.markdown(result, {"mode": mode}),
                    report.as_json(result, {"mode": mode}))
        alone, got = _alone_and_helped(run, monkeypatch)
        assert got == alone
        kinds = {r.status for r in alone[1]}
        assert kinds == {"compensated"} or "not compensated" in kinds
    assert made and None not in made
    assert "columns_diff" in made
    # (The JSON report's number texts of each module: json=True.)
    assert made.count("json_cells") == 5
    assert made.count("_nominal_and_candidates") == made.count("_solve_deformed") == 5
    if mode != "absj":
        assert made.count("plain_block") >= 5 and made.count("_wanted_values") >= 5
    else:
        assert made.count("absj_literals_of") >= 3 and made.count("_joint_rows") >= 3


@pytest.mark.parametrize("mode", ["robtarget", "absj"])
def test_a_transient_cam_module_is_written_and_reported_as_without_a_helper(
        mode, helped, monkeypatch):
    """Transient: in blocks of a few literals, every other block's
    correction literals formatted by the helper (records.pose_literals),
    and every other block's residuals at a thermal state checked there
    (verify._state_residuals); the same output, rows and report."""
    from rapidcomp.compensate import edit as E
    from rapidcomp.compensate import verify as V
    from rapidcomp.compensate.load import load_state_solvers
    from rapidcomp.compensate.transient import Transient
    monkeypatch.setattr(E, "PREPARE_BLOCK", 37)
    monkeypatch.setattr(V, "VERIFY_BLOCK", 41)
    made = _spy(monkeypatch)
    warm = str(FIXTURES / "warm.csv")
    solver = load_solver(warm, None, False)
    states = load_state_solvers(warm, None, False)
    for text in (cam_variants.bench_module(300, 3, ""), cam_variants.not_called(5)):
        def run():
            result = fix(Task("cam.mod", (parse_text(text, "cam.mod"),)), solver, mode,
                         output_names={"cam.mod": "out.mod"},
                         transient=(Transient(45.0, 45.0, 2.0), states))
            return result.modules, result.rows, result.notes, report.markdown(result,
                                                                              {"mode": mode})
        alone, got = _alone_and_helped(run, monkeypatch)
        assert got == alone and alone[1].column("status").count("compensated") > 100
    if mode == "robtarget":
        assert made.count("pose_literals") >= 3
    assert made.count("_state_residuals") >= 10


def test_pose_literals_are_each_correction_formatted_alone():
    """records.pose_literals formats a block of corrections as
    Values.pose_literal formats one (numbers.mm, numbers.fmt with the
    quaternion's decimals), including -0.0, tiny and rounding cases."""
    import numpy as np

    from rapidcomp.rewrite import numbers
    from rapidcomp.rewrite.records import pose_literals
    rng = np.random.default_rng(7)
    d = np.concatenate([rng.normal(0, 0.2, (50, 3)),
                        [[-0.0, 1e-9, -0.00049999], [0.0005, -0.0005, 123.4565]]])
    dq = np.concatenate([rng.normal(0, 1e-4, (50, 4)),
                         [[-0.0, 5e-10, -5e-10, 1.0], [0.25, -0.125, 1e-7, -1e-7]]])
    want = ["[[" + ",".join(numbers.mm(float(v)) for v in d[j]) + "],["
            + ",".join(numbers.fmt(float(v), numbers.QUAT_DECIMALS) for v in dq[j]) + "]]"
            for j in range(len(d))]
    assert pose_literals(d, dq) == want


def _cam_rows(texts):
    """(solved, rows, each row's solved row) of each CAM module text, as
    check's plan, solve and rows make them."""
    from rapidcomp.compensate.plan import Plan
    from rapidcomp.compensate.rows import use_rows
    from rapidcomp.compensate.solve import solve
    solver = load_solver(str(FIXTURES / "warm.csv"), None, False)
    for text in texts:
        plan = Plan(Task("cam.mod", (parse_text(text, "cam.mod"),)))
        solved = solve(plan, solver)
        at: list = []
        rows = use_rows(plan, solved, at=at)
        yield solved, rows, at


def test_json_cells_are_the_texts_each_row_writes():
    """The JSON texts made ahead (report.json_cells, from the solved
    numbers) are those each row writes of its own numbers: every row's
    target text made with them (_json_block_made) is json_target's of the
    row (the encoder's, tested against json.dumps elsewhere), on CAM
    modules; a value of another kind goes the encoder's way."""
    import numpy as np

    from rapidcomp.compensate.rows import Rows
    for solved, rows, at in _cam_rows((cam_variants.bench_module(200, 7, ""),
                                       cam_variants.broken_runs(8),
                                       cam_variants.not_called(9))):
        made = report.json_cells(solved.nominal.q_deg, solved.deformed.q_deg, solved.err_p,
                                 solved.err_r)
        made = [None if i is None else made[i] for i in at]
        ks = range(len(rows))
        assert report._json_block_made(rows, ks, made) == [report.json_target(r) for r in rows]
        # A value of another kind (here a numpy float as a residual): None,
        # the block goes the encoder's way.
        odd = Rows([b[:9] + (np.float32(1.5),) + b[10:] for b in rows.bases(ks)], rows._codes,
                   rows._joints)
        assert report._json_block_made(odd, ks, made) is None
    # No solved target: nothing made ahead, whatever the arrays' shape.
    for shape in ((0, 6), (0,), (0, 0)):
        empty = np.zeros(shape)
        assert report.json_cells(empty, empty, np.zeros(0), np.zeros(0)) == []


def test_the_golden_cases_json_reports_are_the_same_with_texts_made_ahead(helped, monkeypatch):
    """fix(json=True) with a helper: each row's JSON number texts made
    there (report.json_cells); the report the same as without a helper,
    on every golden case: rows with no joints, with nominal joints only,
    with all three."""
    made = _spy(monkeypatch)
    codes = set()
    # (And joints at J2's bound: the compensated ones beyond it, the rows
    # not compensated with their nominal joints only.)
    at_bound = ("MODULE Lim\n  PROC Path()\n" + "".join(
        f"    MoveAbsJ [[{j1},10,10,0,45,0],[9E9,9E9,9E9,9E9,9E9,9E9]],v100,fine,tool0;\n"
        for j1 in (30, -30, 0)) + "    MoveAbsJ [[0,5,10,0,45,0],[9E9,9E9,9E9,9E9,9E9,9E9]],"
        "v100,fine,tool0;\n  ENDPROC\nENDMODULE\n")
    cases = [(GOLDEN / "fix" / case / "before.mod").read_text(encoding="utf-8") for case in
             sorted(FIX_CASES)] + [at_bound]
    settings = [FIX_CASES[case][1:] for case in sorted(FIX_CASES)] + [("auto", ["J2=-90:10"])]
    for case, text, (mode, limits) in zip(sorted(FIX_CASES) + ["at J2's bound"], cases,
                                          settings):
        solver = load_solver(str(FIXTURES / "warm.csv"), None, False, limits)

        def run():
            result = fix(Task("before.mod", (parse_text(text, "before.mod"),)), solver, mode,
                         output_names={"before.mod": "after.mod"}, json=True)
            return result.rows, report.as_json(result, {"mode": mode})
        alone, got = _alone_and_helped(run, monkeypatch)
        assert got == alone, case
        rows = alone[0]
        codes |= {(c >= 0) + (c >= 0 and c & 1) for c in map(rows.code, range(len(rows)))}
    assert made.count("json_cells") == len(FIX_CASES) + 1
    assert codes == {0, 1, 2}           # no joints, nominal joints only, all three


def test_number_cells_are_the_cells_of_each_row():
    """The cells made ahead (report.number_cells, from the solved numbers)
    are those a row writes of its own numbers (report._row), on every
    solved row of CAM modules: the function the helper runs, run here."""
    checked = 0
    for solved, rows, at in _cam_rows((cam_variants.bench_module(200, 7, ""),
                                       cam_variants.broken_runs(8))):
        cells = report.number_cells(solved.nominal.q_deg, solved.deformed.q_deg, solved.err_p,
                                    solved.err_r)
        assert len(at) == len(rows)
        for r, i in zip(rows, at):
            if i is None or not report._full(r):
                continue
            assert report._row(r, cells[i]) == report._row(r)
            checked += 1
    assert checked > 200


def test_a_child_forked_meanwhile_holds_none_of_the_helpers_pipes(helped, monkeypatch,
                                                                   tmp_path):
    """The parse's child (rapid/predecode.py), forked while the helper
    works, closes the helper's pipes: else the helper would not see its
    parent close them, and would be stopped rather than end."""
    from rapidcomp.rapid import predecode as PD
    monkeypatch.setattr(PD, "PREDECODE_FROM", 0)
    monkeypatch.setattr(PD, "enabled", True)
    monkeypatch.setattr(PD, "side_by_side", lambda: 2)
    settled = tmp_path / "settled"

    def decode_all(text):               # (in the child, once it is set up)
        settled.touch()
        time.sleep(30)
    monkeypatch.setattr(PD, "_decode_all", decode_all)
    with side.helping(1):
        h = side._helper
        pipes = {os.readlink(f"/proc/self/fd/{s.fileno()}") for s in (h.calls, h.results)}
        children: list = []
        PD.start("MODULE m\nENDMODULE\n", children)
        (child,) = children
        try:
            deadline = time.monotonic() + 10
            while not settled.exists():
                assert time.monotonic() < deadline
                time.sleep(0.01)
            held = {os.readlink(f"/proc/{child.pid}/fd/{n}")
                    for n in os.listdir(f"/proc/{child.pid}/fd")}
            assert len(pipes) == 2 and not pipes & held
        finally:
            child.close()
        helper = h
    assert helper.status == 0         # (it ended by itself: its calls' pipe closed)
