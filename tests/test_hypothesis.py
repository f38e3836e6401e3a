"""Random whitespace and comments between tokens never change extracted values."""

import re

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rapidcomp.rapid.grammar import engine
from rapidcomp.rapid.inspect import report
from rapidcomp.rapid.parse import parse_text

from conftest import FIXTURES

SOURCE = (FIXTURES / "rapid" / "robotstudio_crlf.mod").read_text(encoding="utf-8")
# Gaps between tokens; FAST_CALL and NUMAGG tokens are split further into
# their own separators so insertions also land inside one-token fast paths.
TOKENS = [(t.start_pos, t.end_pos, t.type) for t in engine().tokens(SOURCE) if t.type != "$END"]


def _gaps():
    gaps = set()
    for start, end, kind in TOKENS:
        gaps.add(start)
        gaps.add(end)
        if kind in ("FAST_CALL", "NUMAGG"):
            for i in range(start, end):
                if SOURCE[i] in ",[]":
                    gaps.add(i)
                    gaps.add(i + 1)
    return sorted(gaps)


GAPS = _gaps()
FILLERS = st.sampled_from([" ", "\t", "\n", "\r\n", "  ! a comment, with [brackets];\n",
                           "\n! x := 1;\n   ", "\n\n"])


def _squash(x):
    """Expression text without layout: comments and whitespace removed."""
    if isinstance(x, str):
        return re.sub(r"![^\n]*\n|\s+", "", x)
    if isinstance(x, list):
        return [_squash(v) for v in x]
    if isinstance(x, dict):
        return {k: _squash(v) for k, v in x.items()}
    return x


def values(text):
    rep = report(parse_text(text, "f.mod"))
    for m in rep["modules"]:
        for row in m["declarations"] + m["motions"] + m["routines"]:
            row.pop("line")  # lines move with inserted newlines; values must not
    return _squash(rep["modules"])


BASELINE = values(SOURCE)


@settings(max_examples=60, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.sampled_from(GAPS), FILLERS), min_size=1, max_size=25))
def test_insertions_between_tokens_keep_values(insertions):
    text = SOURCE
    for pos, filler in sorted(insertions, reverse=True):
        text = text[:pos] + filler + text[pos:]
    assert values(text) == BASELINE
