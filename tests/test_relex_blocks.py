"""The written literals are read back RELEX_BLOCK at a time (verify.relex):
where one block holds a kept number that is not written as a decimal
(a hexadecimal external axis, decoded field by field) and the others do
not, the verdict is the one reading everything at once gives (values.relex
reads no hexadecimal number: the output is parsed again), not the last
block's. Oracle: the same `fix` with one block; the output parsed again."""

import sys
from pathlib import Path

import pytest

from rapidcomp.compensate import fix as F
from rapidcomp.compensate import verify as V
from rapidcomp.compensate.load import load_solver
from rapidcomp.compensate.plan import Task
from rapidcomp.rapid.parse import parse_text

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("where", [0, 2, 29])
def test_a_block_with_a_hex_number_reads_back_like_one_block(monkeypatch, where):
    sys.path.insert(0, str(ROOT / "bench"))
    from fix import cam_module
    solver = load_solver(str(ROOT / "fixtures" / "warm.csv"), None, False)
    text = cam_module(60, 4).replace("  PROC Path()\n", "  PROC Path()\n    ConfL\\Off;\n")
    # The `where`-th inline literal's last external axis as hexadecimal
    # (9E+09 exactly): kept as written, so its block is not all decimals.
    lines = text.split("\n")
    moves = [i for i, line in enumerate(lines) if line.startswith("    MoveL [[")]
    k = moves[where]
    head, _, tail = lines[k].rpartition("9E+09]]")
    lines[k] = head + "0x218711A00]]" + tail
    text = "\n".join(lines)
    task = Task("cam.mod", (parse_text(text, "cam.mod"),))

    served = []
    real = F.relex

    def spy(*args):
        out = real(*args)
        served.append(out)
        return out
    monkeypatch.setattr(F, "relex", spy)
    whole = F.fix(task, solver, "robtarget")
    monkeypatch.setattr(V, "RELEX_BLOCK", 5)
    blocks = F.fix(task, solver, "robtarget")
    # Parsed again both times: no block's numbers are taken for the rest.
    assert served == [None, None]
    assert blocks.failed == 0 and len(blocks.rows) == 60
    assert blocks.rows == whole.rows and blocks.modules == whole.modules
    assert "0x218711A00]]" in blocks.modules[0].text
    # The output as parsed again holds the values the rows were checked on.
    again = parse_text(blocks.modules[0].text, "cam.mod").modules[0]
    inline = [t.value for m in again.motions for t in m.targets if t.value is not None]
    assert len(inline) == 30 and all(abs(v.values[-1] - 9e9) < 1 for v in inline)
