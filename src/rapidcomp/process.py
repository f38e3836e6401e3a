"""What the rapidcomp command sets for its own process (cli.run), and
only there: a program that imports rapidcomp keeps its own settings.

* The cyclic garbage collector is off. A command's data (1e5 targets:
  millions of nodes, uses and texts) hold no reference cycles and are freed
  by reference counting; collecting scanned them all again and again (~2 s
  of a 1e5-target run). Library calls pause it for their own part instead
  (collector.py).
* Freed memory handed back to the system between stages (glibc's
  malloc_trim, release()): the stages' batches free hundreds of MB of
  arrays and texts that malloc would otherwise keep, and the report's rows
  are then made on top of them (1e5 targets: the command peaked at
  1.25 GB, 1.18 GB so). A library call leaves the heap of the program
  that imports rapidcomp as it is.
* One malloc arena for all threads (glibc). The IK's worker threads
  (kinematics/ik.py) would each get an arena of their own, and the blocks
  freed there serve only threads attached to it, not the main thread that
  does everything else: 1e5 targets peaked 50 MB higher. A numpy block
  makes few allocations, so sharing the arena's lock costs nothing.
  Elsewhere than glibc there is nothing to set.
* What a job lets go of (let_go(): the parsed program, once its result is
  made) is kept until the next job starts or the process ends, whose exit
  takes the memory back at once (cli.run): freed object by object, a
  parsed 1e5-target program took ~0.15 s, and the memory freed was not
  needed (the process's peak is behind it then). A library call lets it
  go at once.
"""

from __future__ import annotations

import gc


_trim = None          # glibc's malloc_trim, once own() has run
_owned = False        # own() has run: this is the command's own process
_kept = None          # what the job let go of (let_go)


def own() -> None:
    global _trim, _owned
    _owned = True
    gc.disable()
    import ctypes
    try:
        libc = ctypes.CDLL(None)
        libc.mallopt(-8, 1)                        # M_ARENA_MAX
        _trim = libc.malloc_trim
    except (OSError, AttributeError, TypeError):
        pass


def release() -> None:
    """Hand the memory malloc holds free back to the system, in the
    command's own process (else nothing)."""
    if _trim is not None:
        _trim(0)


def let_go(obj) -> None:
    """Let go of `obj`, which the caller needs no longer: in the command's
    own process kept until the next let_go() (a job's start lets go of
    None) or the process's end, elsewhere at once."""
    global _kept
    _kept = obj if _owned else None
