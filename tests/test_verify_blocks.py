"""The written values are checked VERIFY_BLOCK uses at a time (issue #14:
a CAM program's arrays and records alive for one block, not for 1e5).
Oracle: the whole `fix` with every use in one block; each use's residual
is its own whatever block it is in: robtargets read as arrays and through
the resolver (Offs, RelTool), MoveAbsJ joints, moves without supervision
(the solution closest to the previous move)."""

import sys
from pathlib import Path

import pytest

from rapidcomp.compensate import fix as F
from rapidcomp.compensate import verify as V
from rapidcomp.compensate.load import load_solver
from rapidcomp.compensate.plan import Task
from rapidcomp.rapid.parse import parse_file, parse_text

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def solver():
    return load_solver(str(ROOT / "fixtures" / "warm.csv"), None, False, ("J5=-120:120",))


def _tasks():
    sys.path.insert(0, str(ROOT / "bench"))
    from fix import cam_module
    cam = cam_module(300, 8).replace("  PROC Path()\n", "  PROC Path()\n    ConfL\\Off;\n")
    return [Task("cubes.mod", (parse_file(ROOT / "fixtures" / "cubes.mod", "cubes.mod"),)),
            Task("cam.mod", (parse_text(cam, "cam.mod"),))]


@pytest.mark.parametrize("mode", ["robtarget", "auto"])
def test_written_values_checked_in_blocks_are_those_checked_at_once(mode, solver, monkeypatch):
    for task in _tasks():
        monkeypatch.setattr(V, "VERIFY_BLOCK", 10 ** 9)
        whole = F.fix(task, solver, mode)
        calls = []
        real = V._residuals

        def spy(solved, solver_, rows, *args):
            calls.append(len(rows))
            return real(solved, solver_, rows, *args)
        monkeypatch.setattr(V, "_residuals", spy)
        monkeypatch.setattr(V, "VERIFY_BLOCK", 3)
        blocks = F.fix(task, solver, mode)
        monkeypatch.setattr(V, "_residuals", real)
        assert blocks.rows == whole.rows and blocks.modules == whole.modules
        assert blocks.notes == whole.notes and blocks.failed == whole.failed == 0
        # Every compensated use checked once, in blocks of 3: the output is
        # read again (the CAM module's edits are numbers; in robtarget and
        # auto modes cubes.mod's are numbers and copies of targets).
        assert sum(calls) == sum(r.status == "compensated" for r in whole.rows) > 60
        assert max(calls) == 3
        kinds = {r.rule.split(" ")[0] for r in whole.rows if r.rule}
        assert {"confdata", "as"} <= kinds if task.name == "cubes.mod" else "closest" in kinds
