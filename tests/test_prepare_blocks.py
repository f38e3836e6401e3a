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
