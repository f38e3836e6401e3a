"""Benchmark: parse + extract (typed targets) on CAM-style modules.

    python bench/parse.py [--sizes 1000,10000,100000]

Prints MB/s per size, and in the same run the MB/s of a plain Python regex
tokenizer on the same text (every RAPID token: names, numbers, strings,
operators, comments; no tree) and the ratio (issue #14: parse >= 0.2 x the
tokenizer, >= 0.5 x where the columnar path applies).
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from camgen import cam_module  # noqa: E402

from rapidcomp.rapid.grammar import engine  # noqa: E402
from rapidcomp.rapid.parse import parse_text  # noqa: E402


# The floor a Python parser is measured against: one pass of re.finditer
# over every token, nothing built.
TOKEN = re.compile(r"""\s+|!.*|"(?:[^"\r\n]|"")*"|[A-Za-z][A-Za-z0-9_]*"""
                   r"""|(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|:=|<>|<=|>=|[^\s]""")


def tokenize(text: str) -> int:
    n = 0
    for _ in TOKEN.finditer(text):
        n += 1
    return n


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default="1000,10000,100000")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    t0 = time.perf_counter()
    engine()
    print(f"grammar load: {time.perf_counter() - t0:.3f} s")
    print(f"{'targets':>8} {'MB':>7} {'best s':>8} {'MB/s':>7} {'targets/s':>11} "
          f"{'tokenizer MB/s':>15} {'ratio':>6}")
    for n in (int(s) for s in args.sizes.split(",")):
        text = cam_module(n)
        mb = len(text.encode()) / 1e6
        best = float("inf")
        for _ in range(args.repeat):
            t = time.perf_counter()
            pf = parse_text(text, "bench.mod")
            best = min(best, time.perf_counter() - t)
        m = pf.module
        decoded = sum(d.value is not None for d in m.declarations if d.type == "robtarget")
        decoded += sum(t.value is not None for mo in m.motions for t in mo.targets)
        assert decoded == n, (decoded, n)
        tok = float("inf")
        for _ in range(args.repeat):
            t = time.perf_counter()
            tokenize(text)
            tok = min(tok, time.perf_counter() - t)
        print(f"{n:>8} {mb:>7.2f} {best:>8.3f} {mb / best:>7.2f} {n / best:>11.0f} "
              f"{mb / tok:>15.2f} {tok / best:>6.2f}")


if __name__ == "__main__":
    main()
