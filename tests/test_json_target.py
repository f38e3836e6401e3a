"""A target of the JSON report is written by a % template (report.json_target)
exactly as json's encoder writes it: the oracle is JSONEncoder(indent=2)
of the row's dict, indented to its place, on seeded random rows whose
values are of every kind a field may hold and some it should not (a
bool, numpy numbers, non-finite floats, -0.0, non-ASCII and escaped
texts, a file name that is not UTF-8)."""

import json
import random

import numpy as np
import pytest

from rapidcomp.compensate import report
from rapidcomp.compensate.report import json_target
from rapidcomp.compensate.rows import FIELDS, UseRow

ORACLE = json.JSONEncoder(indent=2).encode
TEXTS = ["cubes.mod", "caf\udce9.mod", "inline", "p{1,2} [i=3]", 'a "quoted" \\ text',
         "tab\there", "line\nbreak", "\u00e9\u00e8 \u2013 \U0001F600", "", "MoveL -> MoveAbsJ"]
FLOATS = [0.0, -0.0, 1.0, -1.5, 83.10558496065286, 2.0838448910508259e-07, 1e300, 1e-320,
          float("nan"), float("inf"), float("-inf"), 123456789.0]


def _number(rnd):
    k = rnd.random()
    if k < 0.8:
        return rnd.choice(FLOATS + [rnd.uniform(-400, 400)])
    if k < 0.9:
        return rnd.choice([0, 7, -3, 2 ** 60])
    return rnd.choice([True, False, np.float64(1.25), np.int64(3), np.float32(0.5)])


def _maybe(rnd, make, none=0.15):
    return None if rnd.random() < none else make()


def _numbers(rnd, n):
    k = rnd.random()
    items = [_number(rnd) for _ in range(n)]
    if k < 0.7:
        return tuple(items)
    if k < 0.8:
        return list(items)
    if k < 0.9:
        return ()
    return (tuple(items[:2]),)          # (nested: not a row's shape)


def _row(rnd) -> UseRow:
    values = {
        "file": rnd.choice(TEXTS), "line": rnd.choice([1, 87, 100000, True]),
        "instruction": rnd.choice(["MoveL", "MoveAbsJ", "MoveJ"]),
        "target": rnd.choice(TEXTS), "status": rnd.choice(["compensated", "untouched"]),
        "rule": _maybe(rnd, lambda: rnd.choice(TEXTS)),
        "action": _maybe(rnd, lambda: rnd.choice(TEXTS)),
        "nominal_deg": _maybe(rnd, lambda: _numbers(rnd, 6)),
        "compensated_deg": _maybe(rnd, lambda: _numbers(rnd, 6)),
        "delta_deg": _maybe(rnd, lambda: _numbers(rnd, rnd.choice([6, 7]))),
        "error_um": _maybe(rnd, lambda: _number(rnd)),
        "error_deg": _maybe(rnd, lambda: _number(rnd)),
        "residual_um": _maybe(rnd, lambda: _number(rnd)),
        "residual_deg": _maybe(rnd, lambda: _number(rnd)),
        "conf_before": _maybe(rnd, lambda: tuple(rnd.choice([-1, 0, 1, 2]) for _ in range(4))),
        "conf_after": _maybe(rnd, lambda: tuple(rnd.choice([-1, 0, 1, 2]) for _ in range(4))),
        "warnings": rnd.choice([(), (rnd.choice(TEXTS),), tuple(rnd.sample(TEXTS, 3)),
                                [rnd.choice(TEXTS)], (1.5,)]),
        "reason": _maybe(rnd, lambda: rnd.choice(TEXTS), none=0.7),
    }
    return UseRow(**values)


def test_template_writes_what_the_encoder_writes():
    rnd = random.Random(5)
    seen = {"template": 0, "encoder": 0, "refused": 0}
    for _ in range(20000):
        r = _row(rnd)
        try:
            want = ORACLE(r.as_dict()).replace("\n", "\n    ")
        except TypeError:          # (a numpy int: the encoder refuses it, and so here)
            with pytest.raises(TypeError):
                json_target(r)
            seen["refused"] += 1
            continue
        assert json_target(r) == want, r
        seen["encoder" if _other(r) else "template"] += 1
    assert min(seen.values()) > 500, seen


def _other(r) -> bool:
    """The row holds a value of a kind no field is meant to hold."""
    def odd(x):
        if isinstance(x, (tuple, list)):
            return any(isinstance(v, (tuple, list)) or odd(v) for v in x)
        return type(x) not in (str, int, float, type(None))
    return any(odd(getattr(r, name)) for name in FIELDS)


def test_every_field_is_written_under_its_own_name(monkeypatch):
    # Each field a value of its own, written by the template alone: one
    # that swaps two fields' values (or misses one) writes another text.
    monkeypatch.setattr(report, "_ENCODE", None)
    values = {"file": "f.mod", "line": 3, "instruction": "MoveL", "target": "p1",
              "status": "compensated", "rule": "confdata", "action": "edited",
              "nominal_deg": (1.0, 2.0, 3.0, 4.0, 5.0, 6.0),
              "compensated_deg": (1.5, 2.5, 3.5, 4.5, 5.5, 6.5),
              "delta_deg": (0.5, 0.25, 0.125, -0.5, -0.25, -0.125), "error_um": 11.0,
              "error_deg": 12.0, "residual_um": 13.0, "residual_deg": 14.0,
              "conf_before": (0, -1, 1, 0), "conf_after": (1, 0, -1, 2),
              "warnings": ("w1", "w2"), "reason": "why"}
    assert list(values) == list(FIELDS)
    got = json.loads(json_target(UseRow(**values)))
    assert list(got) == list(FIELDS)
    assert got == {k: list(v) if type(v) is tuple else v for k, v in values.items()}


def test_a_block_of_targets_is_written_as_each_alone():
    """report._json_block (a chunk of the report's targets, a column at a
    time) writes what json_target writes of each row, on seeded random
    blocks of the rows above (a text column with few values, confdata
    shared between rows, (1, 0) beside (1.0, 0), -0.0 beside 0.0, odd
    kinds anywhere: the block then goes row by row)."""
    from rapidcomp.compensate.rows import BASE_FIELDS
    rnd = random.Random(11)
    shared = [(0, -1, 1, 0), (1.0, 0, 0, 0), (1, 0, 0, 0), (-0.0, 0, 0, 1), (0, 0, 0, 1)]
    fast = 0

    def joints():
        return tuple(rnd.choice(FLOATS + [rnd.uniform(-400, 400)]) for _ in range(6))
    for _ in range(300):
        rows = []
        clean = rnd.random() < 0.5          # (a CAM block: the kinds each field holds)
        for _ in range(rnd.choice([1, 2, 17, 60])):
            r = _row(rnd)
            if clean:
                r = UseRow(**{**r.as_dict(), "line": rnd.randint(1, 10 ** 5),
                              "nominal_deg": joints(), "compensated_deg": joints(),
                              "delta_deg": _maybe(rnd, joints),
                              "error_um": rnd.choice(FLOATS), "error_deg": None,
                              "residual_um": rnd.choice(FLOATS), "residual_deg": 1.5,
                              "conf_before": rnd.choice(shared),
                              "conf_after": rnd.choice(shared + [None]),
                              "warnings": rnd.choice([(), ("w",), (TEXTS[1], TEXTS[7])])})
            rows.append(r)
        parts = [(tuple(getattr(r, f) for f in BASE_FIELDS),
                  (r.nominal_deg, r.compensated_deg, r.delta_deg)) for r in rows]
        try:
            want = [json_target(r) for r in rows]
        except TypeError:
            with pytest.raises(TypeError):
                report._json_block(parts)
            continue
        assert report._json_block(parts) == want
        fast += not any(_other(r) for r in rows)
    assert fast > 30, fast
