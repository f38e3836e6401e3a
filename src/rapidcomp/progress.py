"""Stage progress on stderr, shown only on a terminal and only once a run
has taken more than ~2 s (short runs and pipes stay quiet)."""

from __future__ import annotations

import sys
import time


class Progress:
    def __init__(self, label: str, enabled: bool | None = None, delay_s: float = 2.0):
        self.label = label
        self.enabled = sys.stderr.isatty() if enabled is None else enabled
        self.start = time.monotonic()
        self.delay = delay_s
        self.shown = False

    def stage(self, text: str) -> None:
        if not self.enabled or time.monotonic() - self.start < self.delay:
            return
        elapsed = time.monotonic() - self.start
        sys.stderr.write(f"\r\x1b[Krapidcomp: {self.label}: {text} ({elapsed:.1f} s)")
        sys.stderr.flush()
        self.shown = True

    def done(self) -> None:
        if self.shown:
            sys.stderr.write("\r\x1b[K")
            sys.stderr.flush()
