"""The numbers of a large module's literals, decoded by a second process
while this one parses the module (issue #14: both cores for one big
module).

A CAM program's module holds 1e5 robtarget literals; float() of their 1.7e6
numbers is a fifth of its parse. They depend on the text alone, so a child
forked before the parse reads every plain literal it finds (values.
plain_values, else values.spaced_values for one with blanks after its
commas: the very functions the parse would run on the same text) and
hands back the values, keyed by each literal's span, while the parent runs
the grammar; the parent's decoding then takes them where a NumAgg has that
span and that class, and decodes any other itself. The child also collects
the text's words, which new names must not take (rewrite/names.py). The
results are the same either way: only where the work is done differs.

The child is a helper. If it fails, dies, is slow or is not there (not
Linux, one core or a CPU quota of one, a small text, the process pool's workers, which already
use both cores), everything is decoded here. It is silent (no signal
handler, no terminal), dies with its parent, sends its result whole or not
at all, and is always reaped: a Ctrl-C is held back from the pipe to the
caller's list of children, and the caller closes what that list holds.
"""

from __future__ import annotations

import os
import pickle
import re
import select
import signal
import sys
import time

import numpy as np

from ..cpus import side_by_side
from ..side import HELD, fork, settle_child
from ..rewrite.names import words
from .values import (JointTarget, RobTarget, frame_fields, head_size, plain_values,
                     share_tail, spaced_values, tail_text)

# Texts from this size on (characters) are decoded ahead: a fork costs a few
# ms (1e4 targets, 1.7 MB: the parse 0.26 -> 0.25 s; 1e5: 2.64 -> 2.35 s).
PREDECODE_FROM = 1 << 20
# Off in the process pool's workers (job.py): two modules already keep
# both cores busy there.
enabled = True
# A plain literal (group 1): two or more bracketed groups of anything but
# brackets (the numbers), blanks around the commas between them, in
# brackets, on one line. Strings and comments
# are matched whole and passed over: a commented-out program would cost the
# child more than its parse. The parse's NumAgg spans of the literals a
# CAM program writes are these matches; any other text found is looked up
# by no NumAgg.
_SCAN = re.compile(r'"[^"\n\r]*"|![^\n\r]*'
                   r"|(\[\[[^\[\]\n\r;]*\](?:[ \t]*,[ \t]*\[[^\[\]\n\r;]*\])+\])")
_BY_COUNT = {17: RobTarget, 12: JointTarget}
_KINDS = (RobTarget, JointTarget)


def start(text: str, children: list) -> None:
    """Fork a child decoding text's literals and append it (an Ahead) to
    `children`, or do nothing (see the module's text). The child is in the
    list before a Ctrl-C can interrupt this process again: whatever
    happens, the caller's `finally` closes what the list holds."""
    if (not enabled or len(text) < PREDECODE_FROM or not sys.platform.startswith("linux")
            or side_by_side() < 2):                     # (one core: nothing to gain)
        return
    parent = os.getpid()
    # (Ctrl-C held back from the pipe to the list, and during the fork's
    # own hooks, which run in both processes.)
    held = signal.pthread_sigmask(signal.SIG_BLOCK, HELD)
    try:
        try:
            read, write = os.pipe()
        except OSError:
            return
        try:
            pid = fork()
        except Exception:          # (OSError; or anything else: no child then)
            os.close(read)
            os.close(write)
            return
        if pid == 0:
            _child(text, parent, read, write, held)        # (never returns)
        os.close(write)
        children.append(Ahead(pid, read))
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)


def _child(text: str, parent: int, read: int, write: int, held) -> None:
    """The child's life: silent, gone with its parent, and its result
    sent whole (an 8-byte length, then the pickle) or not at all."""
    code = 1
    try:
        os.close(read)
        settle_child(parent, held)
        data = pickle.dumps(_decode_all(text), protocol=pickle.HIGHEST_PROTOCOL)
        for part in (len(data).to_bytes(8, "little"), data):
            view = memoryview(part)
            while view:
                view = view[os.write(write, view):]
        code = 0
    except BaseException:
        pass
    finally:
        os._exit(code)


def _decode_all(text: str) -> tuple:
    """(starts, ends, kinds, heads per kind, tail ids, tails, words): of
    every plain literal found its span, its class (an index into _KINDS),
    the values before its shared tail, which tail; each distinct tail's
    text and values; and the text's words (a module whose moves become MoveAbsJ
    gets 1e5 new names, none of them a word of the text)."""
    starts, ends, kinds, tail_ids = [], [], [], []
    heads: tuple[list, list] = ([], [])
    tails: dict[str, int] = {}
    tail_values: list = []
    for m in _SCAN.finditer(text):
        lit = m.group(1)
        if lit is None:                  # (a string or a comment)
            continue
        fields = frame_fields(lit)
        cls = _BY_COUNT.get(len(fields))
        if cls is None:
            continue
        values = plain_values(cls, fields, lit)
        if values is None:
            # (Blanks after its commas, as people write them: as the parse
            # reads it then.)
            values = spaced_values(cls, lit)
            if values is None:
                continue
        kind = _KINDS.index(cls)
        head = head_size(cls)
        # (A robtarget's tail has two groups, a jointtarget's one: a tail
        # text is one kind's.)
        tail = tail_text(cls, lit)
        t = tails.get(tail)
        if t is None:
            t = tails[tail] = len(tail_values)
            tail_values.append(values[head:])
        starts.append(m.start(1))
        ends.append(m.end(1))
        kinds.append(kind)
        heads[kind].extend(values[:head])
        tail_ids.append(t)
    return (np.array(starts, np.int64), np.array(ends, np.int64), np.array(kinds, np.int8),
            tuple(np.array(h, float) for h in heads), np.array(tail_ids, np.int64),
            list(zip(tails, tail_values)), words(text))


class Ahead:
    """The child at work: result() its values (None if it failed), close()
    it either way (no process is left behind)."""

    def __init__(self, pid: int, fd: int):
        self.pid = pid
        self.fd = fd
        self.status: int | None = None        # the child's exit code, once reaped

    def result(self, patience: float) -> "Known | None":
        """The child's values; None when it failed or has not finished
        within `patience` seconds (its work is a fraction of the parse's:
        a child that takes longer is stopped, not waited for). Whether it
        succeeded is told by its result arriving whole, not by its exit
        status (which a process ignoring SIGCHLD never sees)."""
        data = bytearray()
        deadline = time.monotonic() + patience
        whole = False
        try:
            poll = select.poll()
            poll.register(self.fd, select.POLLIN)
            while True:
                left = deadline - time.monotonic()
                if left <= 0 or not poll.poll(left * 1000):
                    return None
                chunk = os.read(self.fd, 1 << 20)
                if not chunk:
                    break
                data += chunk
            whole = len(data) >= 8 and int.from_bytes(data[:8], "little") == len(data) - 8
        except OSError:
            return None
        finally:
            self.close(finished=whole)
        if not whole:
            return None
        try:
            return Known(pickle.loads(memoryview(data)[8:]))
        except Exception:          # (not what a child sends: decoded here instead)
            return None

    def close(self, finished: bool = False) -> None:
        """Reap the child: one that sent its result whole is ending by
        itself; any other is stopped first."""
        fd, self.fd = self.fd, -1
        if fd >= 0:
            os.close(fd)
        if self.status is None:
            try:
                done, st = os.waitpid(self.pid, 0 if finished else os.WNOHANG)
                if done == 0:
                    os.kill(self.pid, signal.SIGKILL)
                    done, st = os.waitpid(self.pid, 0)
                self.status = os.waitstatus_to_exitcode(st)
            except ChildProcessError:      # (reaped already: SIGCHLD ignored)
                self.status = -1


class Known:
    """The child's values: values(cls, span) is plain_values (else
    spaced_values) of the literal at span when the child decoded one of class cls exactly
    there, else None; words: the text's words (rewrite/names.words), which
    new names must not take."""

    def __init__(self, payload: tuple):
        starts, ends, kinds, heads, tail_ids, tails, self.words = payload
        self._at = dict(zip(starts.tolist(), range(len(starts))))
        self._ends = ends.tolist()
        self._kinds = kinds.tolist()
        self._tail_ids = tail_ids.tolist()
        # Each literal's head as a list (its row in its kind's heads).
        rows: list = [None] * len(starts)
        for kind, cls in enumerate(_KINDS):
            at = np.flatnonzero(kinds == kind).tolist()
            flat = heads[kind].reshape(len(at), head_size(cls)).tolist() if at else []
            for i, row in zip(at, flat):
                rows[i] = row
        self._rows = rows
        # The tails shared as the parse shares them (values._TAIL_FLOATS).
        self._tails = [share_tail(text, tuple(v)) for text, v in tails]
        self.hits = 0

    def values(self, cls, span) -> tuple[float, ...] | None:
        i = self._at.get(span.start)
        if i is None or self._ends[i] != span.end or _KINDS[self._kinds[i]] is not cls:
            return None
        self.hits += 1
        return tuple(self._rows[i]) + self._tails[self._tail_ids[i]]
