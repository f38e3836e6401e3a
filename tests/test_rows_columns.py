"""A result's rows are held as columns (rows.Rows: per row its fields but
the joints, and where its joints are in the solved numbers' rounded
arrays), a UseRow made when asked for (issue #14: a CAM program's 1e5
rows kept 3e5 tuples of joints, ~75 MB). Oracles: the Markdown row read
from the columns is the row a UseRow writes (report._row), with and
without the number cells made ahead; the summary read by column is the
summary of the UseRows; a row asked for twice is the same row."""

from pathlib import Path

import pytest

from rapidcomp.compensate import report
from rapidcomp.compensate.check import check
from rapidcomp.compensate.fix import fix
from rapidcomp.compensate.load import load_solver
from rapidcomp.compensate.plan import Task
from rapidcomp.compensate.rows import BASE_FIELDS, FIELDS, Rows, UseRow, summary
from rapidcomp.rapid.parse import parse_file

ROOT = Path(__file__).resolve().parents[1]
FIXTURES = ROOT / "fixtures"
PROGRAMS = [FIXTURES / "cubes.mod", FIXTURES / "paper_front.mod",
            *sorted((FIXTURES / "rapid").iterdir()),
            ROOT / "tests" / "golden" / "fix" / "refusals" / "before.mod"]


@pytest.fixture(scope="module")
def solver():
    return load_solver(str(FIXTURES / "warm.csv"), None, False, ("J5=-120:120",))


@pytest.fixture(scope="module")
def solver_115():
    # (The data sheet's J5 limits: cubes.mod's S21 not compensated, its
    # joints known.)
    return load_solver(str(FIXTURES / "warm.csv"), None, False)


@pytest.mark.parametrize("path", PROGRAMS, ids=lambda p: p.name)
@pytest.mark.parametrize("mode", ["auto", "absj"])
def test_rows_read_by_column_are_the_rows(path, mode, solver, solver_115):
    seen = set()
    for s in (solver, solver_115):
        result = fix(Task(path.name, (parse_file(path, path.name),)), s, mode)
        rows = result.rows
        assert isinstance(rows, Rows)
        made = list(rows)
        assert all(type(r) is UseRow for r in made) and len(made) == len(rows)
        assert rows == made and rows[:] == made and rows[-1] == made[-1]
        assert rows[0] is not rows[0] and rows[0] == rows[0]
        assert hash(rows) == hash(tuple(made)) and hash(result)
        with pytest.raises(IndexError):
            rows[-len(rows) - 1]
        with pytest.raises(IndexError):
            rows[len(rows)]
        for k, r in enumerate(made):
            assert rows.base(k) == tuple(getattr(r, f) for f in BASE_FIELDS)
            assert rows.joints(k) == (r.nominal_deg, r.compensated_deg, r.delta_deg)
            assert report._row_of(rows, k) == report._row(r)
            assert rows.full(k) == report._full(r)
            seen.add((r.status, r.nominal_deg is None, r.compensated_deg is None))
        for name in BASE_FIELDS:
            assert rows.column(name) == [getattr(r, name) for r in made]
        # Blocks of fields, as the reports take them: a range, a list of
        # consecutive rows, rows apart or out of order, none.
        n = len(made)
        bases = [tuple(getattr(r, f) for f in BASE_FIELDS) for r in made]
        for ks in (range(n), range(1, n, 2), list(range(1, n - 1)), [n - 1, 0],
                   [0, n - 1], [], range(0)):
            assert rows.bases(ks) == [bases[k] for k in ks], ks
        # (No tuple of fields kept per row: a column per field.)
        assert not hasattr(rows, "_base") and len(rows._cols) == len(BASE_FIELDS)
        assert summary(rows) == summary(made)
        if result.cells is not None:
            for k, r in enumerate(made):
                assert report._row_of(rows, k, result.cells[k]) == report._row(r, result.cells[k])
    # (Across the programs: compensated rows, rows not compensated with and
    # without their nominal joints, untouched rows.)
    assert seen


def test_every_kind_of_row_is_read(solver, solver_115):
    kinds = set()
    for path in PROGRAMS:
        for s in (solver, solver_115):
            rows = fix(Task(path.name, (parse_file(path, path.name),)), s, "auto").rows
            kinds |= {(r.status, r.nominal_deg is not None, r.compensated_deg is not None)
                      for r in rows}
    assert {("compensated", True, True), ("not compensated", True, False),
            ("not compensated", False, False), ("untouched", False, False)} <= kinds


def test_check_rows_too(solver):
    path = FIXTURES / "cubes.mod"
    result = check(Task(path.name, (parse_file(path, path.name),)), solver)
    assert isinstance(result.rows, Rows) and len(result.rows) == 76
    made = list(result.rows)
    assert summary(result.rows, "compensable", "not compensable") == summary(
        made, "compensable", "not compensable")
    assert result.failed == sum(r.status == "not compensable" for r in made)
    assert set(FIELDS) == set(made[0].as_dict())


def _failure(line: int, reason: str) -> UseRow:
    return UseRow("m.mod", line, "MoveL", "inline", "not compensated", None, None, None, None,
                  None, None, None, None, None, None, None, (), reason)


def test_failures_alike_but_for_their_numbers():
    # More than ALIKE reasons the same but for their numbers (a CAM program
    # near J5 = 0: its J5 and its line each) are one line with the first
    # one's reason; up to ALIKE, one line each; a reason shared exactly,
    # one line as before.
    many = [_failure(10 + k, f"at J5 {k / 10:.2f} deg: follows line {9 + k}")
            for k in range(report.ALIKE + 1)]
    few = [_failure(100 + k, f"out of reach by {k + 0.5} mm") for k in range(report.ALIKE)]
    same = [_failure(200 + k, "tool t9 is not declared") for k in range(3)]
    lines = report.failure_lines(many + few + same, several=False)
    assert lines[0] == (f"not compensated ({report.ALIKE + 1} alike, each with numbers of its "
                        "own; as line 10): at J5 0.00 deg: follows line 9 [lines 10-20]")
    assert lines[1:1 + report.ALIKE] == [f"not compensated: line {100 + k} MoveL inline: out of "
                                         f"reach by {k + 0.5} mm" for k in range(report.ALIKE)]
    assert lines[1 + report.ALIKE:] == ["not compensated (3): tool t9 is not declared "
                                        "[lines 200-202]"]


def test_failures_alike_but_for_their_own_targets_name():
    # Each move's own target named in its reason (p0 is not declared ...,
    # 1e5 of them where a data module is missing), written plainly or in an
    # Offs: one line past ALIKE, whether each target is used once or three
    # times; a reason naming another name than the row's target (each its
    # own tool) is not folded, however many.
    def named(line, target, reason):
        return UseRow("m.mod", line, "MoveL", target, "not compensated", None, None, None, None,
                      None, None, None, None, None, None, None, (), reason)
    n = report.ALIKE + 1
    own = [named(10 + k, f"p{k}", f"p{k} is declared LOCAL in another module (d.mod:{k + 3})")
           for k in range(n)]
    tools = [named(40 + k, f"q{k}", f"tool t{k} is not declared") for k in range(n)]
    lines = report.failure_lines(own + tools, several=False)
    assert lines[0] == (f"not compensated ({n} alike, each with target and numbers of its own; "
                        "as line 10): p0 is declared LOCAL in another module (d.mod:3) "
                        "[lines 10-20]")
    assert lines[1:] == [f"not compensated: line {40 + k} MoveL q{k}: tool t{k} is not declared"
                         for k in range(n)]
    # (Up to ALIKE of them: each its own line, as before.)
    assert len(report.failure_lines(own[:report.ALIKE], several=False)) == report.ALIKE
    # Each base target moved to three times, plainly and in Offs: one line.
    thrice = [named(100 + 3 * k + j, f"Offs(b{k},0,0,{j})" if j else f"b{k}",
                    f"b{k} is not declared") for k in range(n) for j in range(3)]
    assert report.failure_lines(thrice, several=False) == [
        f"not compensated ({3 * n} alike, each with target and numbers of its own; as line "
        f"100): b0 is not declared [lines 100-{100 + 3 * n - 1}]"]
    # Up to ALIKE such reasons: a line each, with its count and places.
    few = thrice[:3 * (report.ALIKE - 1)]
    assert report.failure_lines(few, several=False)[0] == (
        "not compensated (3): b0 is not declared [lines 100-102]")


def test_failures_alike_keep_their_names_apart():
    # A joint's name (J1, J5) and a target's (pS21) are names, not numbers:
    # failures of J1 and of J5 are not one line (found by a review).
    j1 = [_failure(10 + k, f"nominal: J1 beyond its limit by {k + 4.5} deg")
          for k in range(report.ALIKE + 1)]
    j5 = [_failure(40 + k, f"nominal: J5 beyond its limit by {k + 1.25} deg")
          for k in range(report.ALIKE + 1)]
    lines = report.failure_lines(j5 + j1, several=False)
    assert len(lines) == 2
    assert lines[0].startswith(f"not compensated ({report.ALIKE + 1} alike") and "J5" in lines[0]
    assert "J1 beyond its limit by 4.5 deg [lines 10-20]" in lines[1]

