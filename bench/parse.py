"""Benchmark: parse + extract (typed targets) on CAM-style modules.

    python bench/parse.py [--sizes 1000,10000,100000]

Prints MB/s per size. Goal: >= 3 MB/s on a 2-core machine.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from camgen import cam_module  # noqa: E402

from rapidcomp.rapid.grammar import engine  # noqa: E402
from rapidcomp.rapid.parse import parse_text  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default="1000,10000,100000")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    t0 = time.perf_counter()
    engine()
    print(f"grammar load: {time.perf_counter() - t0:.3f} s")
    print(f"{'targets':>8} {'MB':>7} {'best s':>8} {'MB/s':>7} {'targets/s':>11}")
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
        print(f"{n:>8} {mb:>7.2f} {best:>8.3f} {mb / best:>7.2f} {n / best:>11.0f}")


if __name__ == "__main__":
    main()
