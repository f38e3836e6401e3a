"""Benchmark: parse + extract (typed targets) on CAM-style modules.

    python bench/parse.py [--sizes 1000,10000,100000]

Prints MB/s per size, and in the same run the MB/s of a plain Python regex
tokenizer on the same text (every RAPID token: names, numbers, strings,
operators, comments; no tree) and the ratio (issue #14: parse >= 0.2 x the
tokenizer, >= 0.5 x where the columnar path applies): for CAM modules, then
for hand-written ones of as many moves (camgen.hand_module: blanks, changing
speeds and tools, Offs/RelTool, blocks, comments, CRLF).

The process is set up as the `rapidcomp` command sets up its own (cli.run,
process.py: no cyclic collector), as bench/fix.py does, and each parse's
result is freed before the next is timed (freeing 1e5 targets' nodes takes
~0.17 s, which is no part of parsing). Last, the largest size parsed as a
library call in a program whose collector is on: the collector then scans
the parse's millions of new objects once it runs again (process.py).
"""

from __future__ import annotations

import argparse
import gc
import re
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from camgen import cam_module, hand_module  # noqa: E402

from rapidcomp.process import own  # noqa: E402
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


def best_parse(text: str, repeat: int) -> tuple[float, object]:
    """The best of `repeat` parses of text (s), and the last result."""
    best, pf = float("inf"), None
    for _ in range(repeat):
        pf = None                      # (the last result freed before the clock starts)
        t = time.perf_counter()
        pf = parse_text(text, "bench.mod")
        best = min(best, time.perf_counter() - t)
    return best, pf


def best_tokenize(text: str, repeat: int) -> float:
    tok = float("inf")
    for _ in range(repeat):
        t = time.perf_counter()
        tokenize(text)
        tok = min(tok, time.perf_counter() - t)
    return tok


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default="1000,10000,100000")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    own()
    t0 = time.perf_counter()
    engine()
    print(f"grammar load: {time.perf_counter() - t0:.3f} s")
    print(f"{'targets':>8} {'MB':>7} {'best s':>8} {'MB/s':>7} {'targets/s':>11} "
          f"{'tokenizer MB/s':>15} {'ratio':>6}")
    sizes = [int(s) for s in args.sizes.split(",")]
    largest = None
    for n in sizes:
        text = cam_module(n)
        if n == max(sizes):
            largest = text
        mb = len(text.encode()) / 1e6
        best, pf = best_parse(text, args.repeat)
        m = pf.module
        decoded = sum(d.value is not None for d in m.declarations if d.type == "robtarget")
        decoded += sum(t.value is not None for mo in m.motions for t in mo.targets)
        assert decoded == n, (decoded, n)
        pf = m = None
        tok = best_tokenize(text, args.repeat)
        print(f"{n:>8} {mb:>7.2f} {best:>8.3f} {mb / best:>7.2f} {n / best:>11.0f} "
              f"{mb / tok:>15.2f} {tok / best:>6.2f}")
    # The general path: programs as people write them (hand_module), whose
    # moves the CAM path does not take as runs (goal: >= 0.2 x).
    print("hand-written programs (no runs of the CAM path):")
    for n in sizes:
        text = hand_module(n)
        mb = len(text.encode()) / 1e6
        best, pf = best_parse(text, args.repeat)
        assert len(pf.module.motions) == n, (len(pf.module.motions), n)
        pf = None
        tok = best_tokenize(text, args.repeat)
        print(f"{n:>8} {mb:>7.2f} {best:>8.3f} {mb / best:>7.2f} {n / best:>11.0f} "
              f"{mb / tok:>15.2f} {tok / best:>6.2f}")
    # The same parse as a library call, the collector on (the command's
    # process has it off): the largest size.
    text = largest
    mb = len(text.encode()) / 1e6
    gc.enable()
    best, pf = best_parse(text, args.repeat)
    pf = None
    gc.disable()
    tok = best_tokenize(text, args.repeat)
    print(f"as a library call, the cyclic collector on: {max(sizes)} targets {best:.3f} s, "
          f"{mb / best:.2f} MB/s, ratio {tok / best:.2f} (the collector scans the parse's new "
          "objects once it runs again)")


if __name__ == "__main__":
    main()
