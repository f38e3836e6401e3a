"""A second process for work a big job hands off while it goes on (issue
#14: both cores for one big module).

Past the parse a job is one chain of stages on one core. Some of its work
is a function of numbers and texts alone: needed only later (the report's
number cells of every target, known once the joints are solved, written
with the report; the diff of a module, known once its output is printed),
or in blocks that follow one another (the new texts of 8192 literals, the
numbers of 8192 literals read back, a transient output's residuals of 8192
uses at one thermal state: alternate() hands every other block).
run(fn, *args) hands such a call to the helper and returns at once; get()
then gives what fn(*args) returns, made by the helper, or here when there
is no helper or it failed. The result is the same either way: the same
function on the same (pickled) values; only where the work is done
differs.

The helper is forked where the job starts, before the parse: the process
is small then, and its later writes to its own memory copy few pages a
fork shares (forked later, a 900 MB process paid more in copied pages than
the helper saved). It exists only inside helping(), the command's own job
(not in a library call, not in the process pool's workers, which keep both
cores busy already, not on one CPU, not for a small task). It is silent,
dies with its parent, and is always reaped when helping() ends. It makes
the calls in the order given and keeps each result until it is fetched
(get()): a result waiting for its turn is in its memory, not this one's.
"""

from __future__ import annotations

import io
import os
import pickle
import select
import signal
import sys
import time
import warnings
from collections.abc import Iterable, Iterator
from contextlib import contextmanager

from .cpus import side_by_side, work_beside

# Tasks from this size on (bytes of their modules) get a helper: below it
# the work handed off is about what handing it off costs (in-process,
# alternating: 6e3 targets, 1 MB, 0.71-0.74 s either way; 1e4 targets,
# 1.7 MB, 1.02-1.26 s against 1.15-1.28 s).
HELP_FROM = 1 << 20
# Off in the process pool's workers (job.py).
enabled = True
# How long handing a call off or fetching its result may wait on the
# helper (for room in its pipe, for the result): a helper that takes longer
# is stopped and the call made here.
PATIENCE_S = 30.0
_BUFFER = 1 << 20

_helper: "Helper | None" = None
# The signals held back while a child is forked.
HELD = {signal.SIGINT, signal.SIGTERM}
_PR_SET_PDEATHSIG = 1


@contextmanager
def helping(size: int):
    """A helper for the calls run() makes inside, when `size` (bytes of
    input) is worth one and the process may use two CPUs; reaped on leaving,
    whatever happens."""
    global _helper
    if (_helper is not None or not enabled or size < HELP_FROM
            or not sys.platform.startswith("linux") or side_by_side() < 2):
        yield
        return
    started: list = []
    try:
        _start(started)
        _helper = started[0] if started else None
        yield
    finally:
        _helper = None
        for h in started:
            h.close()


def helps() -> bool:
    """Whether there is a helper to hand calls to (else run() makes them
    here, when their result is asked for)."""
    return _helper is not None and _helper.alive


def run(fn, *args) -> "Pending":
    """fn(*args), made by the helper if there is one (fn: a module-level
    function; args and result: picklable)."""
    return _helper.call(fn, args) if helps() else Pending(None, fn, args)


def alternate(fn, parts: Iterable[tuple]) -> Iterator:
    """fn(*part) of each of `parts` (argument tuples), in order. With a
    helper, of each two parts the second is handed to it before this
    process makes the first (parts read one ahead: the inputs of two are
    alive at a time)."""
    it = iter(parts)
    for first in it:
        second = next(it, None) if helps() else None
        handed = run(fn, *second) if second is not None else None
        yield fn(*first)
        if handed is not None:
            yield handed.get()


class Pending:
    """A call handed off: get() its result."""

    def __init__(self, helper: "Helper | None", fn, args):
        self.helper = helper
        self.number = 0                 # (its number in the helper's calls)
        self.fn = fn
        self.args = args
        self._done = False
        self._value = None

    def get(self):
        if not self._done:
            got = self.helper.take(self) if self.helper is not None else None
            # (Made here when the helper failed: the same function.)
            self._value = got[0] if got is not None else self.fn(*self.args)
            self._done = True
            self.helper = self.args = None
        return self._value


def _start(started: list) -> None:
    """Fork the helper and append it to `started` before a Ctrl-C can
    interrupt this process again (the caller reaps what the list holds)."""
    parent = os.getpid()
    held = signal.pthread_sigmask(signal.SIG_BLOCK, HELD)
    try:
        fds = []
        try:
            for _ in range(2):
                fds += os.pipe()
        except OSError:
            for fd in fds:
                os.close(fd)
            return
        calls_r, calls_w, results_r, results_w = fds
        import fcntl                      # (Unix only: here on Linux)
        for fd in (calls_w, results_w):
            try:          # (fewer switches between the two: ~0.1 s per 60 MB -> ~0.06)
                fcntl.fcntl(fd, fcntl.F_SETPIPE_SZ, 1 << 20)
            except (OSError, AttributeError):
                pass
        try:
            pid = fork()
        except Exception:          # (OSError; or anything else: no child then)
            for fd in fds:
                os.close(fd)
            return
        if pid == 0:
            os.close(calls_w)
            os.close(results_r)
            _serve(parent, calls_r, results_w, held)      # (never returns)
        os.close(calls_r)
        os.close(results_w)
        started.append(Helper(pid, calls_w, results_r))
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)


def fork() -> int:
    """os.fork, where a child of rapidcomp's is forked: without the warning
    Python 3.12 gives for a process with threads (numpy's BLAS keeps one;
    the child runs none of their code), which a warnings filter set to
    error would raise after the child exists, leaving it unknown."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        return os.fork()


def settle_child(parent: int, held) -> None:
    """What a child rapidcomp forks (the helper, rapid/predecode.py's)
    does first: the default signals (a Ctrl-C ends it without a word; its
    parent decides), dying with its parent, holding none of the caller's
    terminal open nor a helper's pipes (a helper ends when its parent
    closes them); then the signals its parent held back while it forked."""
    for sig in HELD:
        signal.signal(sig, signal.SIG_DFL)
    import ctypes
    ctypes.CDLL(None).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)
    if os.getppid() != parent:
        os._exit(1)
    if _helper is not None:
        _helper.drop_pipes()
    null = os.open(os.devnull, os.O_RDWR)
    for fd in (0, 1, 2):
        os.dup2(null, fd)
    signal.pthread_sigmask(signal.SIG_SETMASK, held)


def _serve(parent: int, calls: int, results: int, held) -> None:
    """The helper's life: each call read (a pickle: its number, function
    and arguments) and made, its result ((value,), or None when the call
    raised) kept until the parent fetches it (a pickle: the number) and
    then sent as a pickle; it ends when its parent closes the calls' pipe
    or dies. It writes only what is fetched, which its parent reads at
    once: neither waits on the other's pipe while the other waits on its."""
    code = 1
    try:
        settle_child(parent, held)
        work_beside()
        source = os.fdopen(calls, "rb", buffering=_BUFFER)
        sink = os.fdopen(results, "wb", buffering=_BUFFER)
        made: dict = {}
        while True:
            try:
                asked = pickle.load(source)
            except EOFError:
                break
            if len(asked) == 3:              # (a call: made, kept until fetched)
                n, fn, args = asked
                asked = None
                try:
                    made[n] = (fn(*args),)
                except Exception:
                    made[n] = None
                fn = args = None
                continue
            try:
                pickle.dump(made.pop(asked[0], None), sink, protocol=pickle.HIGHEST_PROTOCOL)
            except Exception:                  # (not picklable: made by the parent)
                os._exit(1)
            sink.flush()
        code = 0
    except BaseException:
        pass
    finally:
        os._exit(code)


class _Pipe(io.RawIOBase):
    """One end of a pipe to the helper, read or written with a deadline
    (TimeoutError past it): a result is read as it is unpickled, not whole
    first (the diff of a CAM program is 30 MB, at the process's peak); a
    call is written as it is pickled, and a helper stuck in a call before
    it does not hold this process (a call is larger than the pipe)."""

    def __init__(self, fd: int, writing: bool):
        self.fd = fd
        self.deadline = 0.0
        self._writing = writing
        if writing:
            os.set_blocking(fd, False)     # (a write takes what the pipe has room for)
        self._poll = select.poll()
        self._poll.register(fd, select.POLLOUT if writing else select.POLLIN)

    def readable(self) -> bool:
        return not self._writing

    def writable(self) -> bool:
        return self._writing

    def fileno(self) -> int:
        return self.fd

    def close(self) -> None:
        if not self.closed:
            os.close(self.fd)
        super().close()

    def _wait(self) -> None:
        left = self.deadline - time.monotonic()
        if left <= 0 or not self._poll.poll(left * 1000):
            raise TimeoutError

    def readinto(self, buffer) -> int:
        self._wait()
        return os.readv(self.fd, [buffer])

    def write(self, data) -> int:
        while True:
            self._wait()
            try:
                return os.write(self.fd, data)
            except BlockingIOError:        # (room for less than PIPE_BUF: wait again)
                pass


class Helper:
    """The helper at work: call() hands it a call, take() its result,
    close() reaps it."""

    def __init__(self, pid: int, calls: int, results: int):
        self.pid = pid
        # (Calls are pickled into the pipe as they are made: no copy of a
        # call's 30 MB alive as bytes.)
        self._ends = (_Pipe(calls, True), _Pipe(results, False))
        self.calls = io.BufferedWriter(self._ends[0], _BUFFER)
        self.results = io.BufferedReader(self._ends[1], _BUFFER)
        self.alive = True
        self._calls = 0
        self.status: int | None = None

    def call(self, fn, args) -> Pending:
        pending = Pending(self, fn, args)
        if not self.alive:
            pending.helper = None
            return pending
        self._calls += 1
        pending.number = self._calls
        self._give(PATIENCE_S)
        try:
            # (A call the pipe holds returns at once; a larger one when the
            # helper, done with the calls before it, has read it.)
            pickle.dump((pending.number, fn, args), self.calls,
                        protocol=pickle.HIGHEST_PROTOCOL)
            self.calls.flush()
        except Exception:             # (not picklable, or the helper is gone)
            self._fail()
            pending.helper = None
        return pending

    def take(self, pending: Pending):
        """(value,) of the call, fetched, or None (made here then)."""
        if not self.alive:
            return None
        self._give(PATIENCE_S)
        try:
            pickle.dump((pending.number,), self.calls, protocol=pickle.HIGHEST_PROTOCOL)
            self.calls.flush()
            got = pickle.load(self.results)
        except Exception:     # (the helper died, is too slow, or sent a broken result)
            got = None
        if got is None:
            self._fail()
        return got

    def _give(self, seconds: float) -> None:
        """What is written and read from now on is so within `seconds`."""
        deadline = time.monotonic() + seconds
        for end in self._ends:
            end.deadline = deadline

    def drop_pipes(self) -> None:
        """In a child forked meanwhile: the pipes' descriptors closed, their
        buffers left as they are (the child never writes them)."""
        for stream in (self.calls, self.results):
            if stream is not None:
                os.close(stream.fileno())

    def _fail(self) -> None:
        """Nothing more is handed to a helper that failed once."""
        self.alive = False
        self.close()

    def close(self) -> None:
        calls, self.calls = self.calls, None
        if calls is not None:
            self._give(0.1)
            try:
                calls.close()
            except OSError:           # (what the buffer held could not go: the helper is gone)
                pass
        results, self.results = self.results, None
        if results is not None:
            results.close()
        self.alive = False
        if self.status is None:
            try:
                # (Its calls' pipe closed: it ends by itself at once, unless
                # it is inside a call or stuck: then it is stopped.)
                done, st = os.waitpid(self.pid, os.WNOHANG)
                if done == 0:
                    time.sleep(0.001)
                    done, st = os.waitpid(self.pid, os.WNOHANG)
                if done == 0:
                    os.kill(self.pid, signal.SIGKILL)
                    done, st = os.waitpid(self.pid, 0)
                self.status = os.waitstatus_to_exitcode(st)
            except ChildProcessError:
                self.status = -1
