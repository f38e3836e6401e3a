"""The cyclic garbage collector, paused while rapidcomp works.

A 1e5-target program makes millions of small objects (nodes, uses, texts)
and no reference cycles: they are freed by reference counting. The cyclic
collector would scan them all again and again for nothing (1e5 targets:
about 2 s of a 20 s run). Pauses nest; the collector's state is restored
on the way out.
"""

from __future__ import annotations

import gc
from contextlib import contextmanager


@contextmanager
def paused():
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()
