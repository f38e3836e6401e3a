"""What the rapidcomp command sets for its own process (cli.run), and
only there: a program that imports rapidcomp keeps its own settings.

* The cyclic garbage collector is off. A command's data (1e5 targets:
  millions of nodes, uses and texts) hold no reference cycles and are freed
  by reference counting; collecting scanned them all again and again (~2 s
  of a 1e5-target run). Library calls pause it for their own part instead
  (collector.py).
* One malloc arena for all threads (glibc). The IK's worker threads
  (kinematics/ik.py) would each get an arena of their own, and the blocks
  freed there serve only threads attached to it, not the main thread that
  does everything else: 1e5 targets peaked 50 MB higher. A numpy block
  makes few allocations, so sharing the arena's lock costs nothing.
  Elsewhere than glibc there is nothing to set.
"""

from __future__ import annotations

import gc


def own() -> None:
    gc.disable()
    import ctypes
    try:
        ctypes.CDLL(None).mallopt(-8, 1)           # M_ARENA_MAX
    except (OSError, AttributeError, TypeError):
        pass
