"""A CAM program's robtarget values are prepared and printed in blocks of
PREPARE_BLOCK literals (issue #14: the batch's intermediate numbers and
texts alive for one block, not for 1e5). Oracle: the whole `fix` with
every literal in one block; the values and texts of a literal are its own
whatever block it is in, plain literals and spaced ones (which decline the
printing by block) mixed across blocks."""

import sys
from pathlib import Path

import pytest

from rapidcomp.compensate import edit as E
from rapidcomp.compensate import fix as F
from rapidcomp.compensate import report
from rapidcomp.compensate.load import load_solver
from rapidcomp.compensate.plan import Task
from rapidcomp.edits import EditColumns
from rapidcomp.rapid.parse import parse_text
from rapidcomp.rewrite import records

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def solver():
    return load_solver(str(ROOT / "fixtures" / "warm.csv"), None, False, ("J5=-120:120",))


@pytest.mark.parametrize("mode", ["robtarget", "absj"])
def test_values_prepared_in_blocks_are_those_prepared_at_once(mode, solver, monkeypatch):
    sys.path.insert(0, str(ROOT / "bench"))
    from fix import cam_module
    lines = cam_module(600, 6).replace("  PROC Path()\n", "  PROC Path()\n    ConfL\\Off;\n"
                                       ).split("\n")
    # Every 50th literal written with a space after its first comma: the
    # blocks holding one go the per-literal way, the others by block.
    spaced = 0
    for n, line in enumerate(lines):
        if "[[" in line and n % 50 == 0:
            lines[n] = line.replace(",", ", ", 1)
            spaced += 1
    text = "\n".join(lines)
    assert spaced >= 10
    task = Task("cam.mod", (parse_text(text, "cam.mod"),))
    monkeypatch.setattr(E, "PREPARE_BLOCK", 10 ** 9)
    whole = F.fix(task, solver, mode)
    served = []
    real = records.robtarget_block

    def spy(recs, *args):
        out = real(recs, *args)
        served.append((len(recs), out is not None))
        return out
    monkeypatch.setattr(records, "robtarget_block", spy)
    monkeypatch.setattr(E, "PREPARE_BLOCK", 37)
    blocks = F.fix(task, solver, mode)
    # Blocks of 37, some printed by block and some not.
    assert len(served) >= 600 // 37 and max(n for n, _ in served) == 37
    assert {ok for _, ok in served} == {True, False}
    assert [m.text for m in blocks.modules] == [m.text for m in whole.modules]
    assert blocks.modules[0].text != text
    assert blocks.edits == whole.edits and len(blocks.edits) > 1000
    assert type(blocks.modules[0].edits) is EditColumns
    assert blocks.rows == whole.rows and blocks.summary() == whole.summary()
    assert blocks.notes == whole.notes
    meta = {"mode": mode}
    assert report.markdown(blocks, meta) == report.markdown(whole, meta)
    assert report.as_json(blocks, meta) == report.as_json(whole, meta)


@pytest.mark.parametrize("name", ["cam", "cubes.mod", "paper_front.mod",
                                  "rapid/robotstudio_crlf.mod", "rapid/cam_confoff.mod"])
def test_a_retry_prepares_each_value_as_the_first_round_did(solver, name):
    """Once written, the values are forgotten (fix.py); a retry (a group
    whose written value would miss) prepares the others again, in batches
    of other members. Oracle: each value prepared in the first round's
    batch of all groups, compared bit for bit with the same value prepared
    in a batch of every third group, and with it prepared alone; on CAM
    programs and on programs with two tools and work objects, Offs and
    RelTool, an array (cubes, robotstudio_crlf)."""
    import numpy as np
    from rapidcomp.compensate import place as P
    from rapidcomp.compensate.plan import Plan
    from rapidcomp.compensate.solve import solve
    from rapidcomp.rapid.parse import parse_source
    from rapidcomp.source import read_source
    sys.path.insert(0, str(ROOT / "bench"))
    from fix import cam_module
    pf = (parse_text(cam_module(400, 8), "cam.mod") if name == "cam"
          else parse_source(read_source(ROOT / "fixtures" / name)))
    plan = Plan(Task(name, (pf,)))
    solved = solve(plan, solver)
    gs = [g for g in P.groups(plan, solved, "robtarget")
          if g.failure is None and g.mode == "rob"]
    items = [(g, k) for g in gs for k in g.elements]
    assert len(items) >= (400 if name == "cam" else 5)
    first = E.Values(plan, solved, 2.0)
    first.prepare(gs)
    retry = E.Values(plan, solved, 2.0)
    retry.prepare(gs[1::3])
    for g in gs[1::3]:
        for k in g.elements:
            a, b = first.robtarget_value(g, k), retry.robtarget_value(g, k)
            alone = E.Values(plan, solved, 2.0).robtarget_value(g, k)
            assert all(np.array_equal(x, y) and np.array_equal(x, z) and x.dtype == y.dtype
                       for x, y, z in zip(a, b, alone))
            assert first.field_texts(g, k) == retry.field_texts(g, k)
    first.forget()
    assert not first._values
