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


def _literal(rng, tail):
    nums = [f"{v:.3f}" for v in rng.uniform(-900, 900, 3)] + [
        f"{v:.6f}" for v in rng.uniform(-1, 1, 4)]
    return f"[[{','.join(nums[:3])}],[{','.join(nums[3:])}{tail}"


@pytest.mark.parametrize("odd", [None, "hex", "word", "space", "short"])
def test_plain_values_reads_what_the_field_by_field_reading_reads(odd):
    """_plain_values converts each distinct confdata/external-axes text
    once: the same array, and the same verdicts (None: not plain, False:
    a field not a decimal number), as splitting every literal into its 17
    field texts and converting each (_flat_texts, _decimals)."""
    import numpy as np
    rng = np.random.default_rng(7)
    tails = ["],[0,-1,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]",
             "],[-1,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]",
             "],[0,0,0,0],[1.5,-2,3E+02,9E+09,9E+09,.5]]"]
    lits = [_literal(rng, tails[k]) for k in rng.integers(0, 3, 200)]
    if odd == "hex":
        lits[57] = lits[57].replace("9E+09]]", "0x218711A00]]")
    elif odd == "word":
        lits[3] = lits[3].replace("[[", "[[e", 1)
    elif odd == "space":
        lits[120] = lits[120].replace("[[", "[ [")
    elif odd == "short":
        lits[9] = lits[9].replace(",9E+09]]", "]]")
    flat = V._flat_texts(lits)
    want = None if flat is None else V._decimals(flat)
    got = V._plain_values(lits)
    if flat is None:
        assert got is None
    elif want is None:
        assert got is False
    else:
        assert got.shape == (200, 17)
        assert got.tobytes() == want.tobytes()
    assert (odd is None) == (got is not None and got is not False)
