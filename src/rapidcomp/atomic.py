"""All-or-nothing file output: every file is written to a temporary file
beside its destination first, and only renamed into place once all of them
were written. A failure leaves no partial output behind."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterable
from pathlib import Path
from typing import Protocol


class Chunked(Protocol):
    """File data given in pieces (a report rendered as it is written)."""

    def chunks(self) -> Iterable[bytes]: ...


def utf8(text: str) -> bytes:
    """A report's text as it is written: UTF-8, and a file name in it that
    is not UTF-8 (decoded as the file system does, os.fsdecode) as the
    bytes it is."""
    return text.encode("utf-8", "surrogateescape")


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_all(files: list[tuple[Path, bytes | Chunked]]) -> None:
    """Write every file or none. OSError (with .filename) on failure. A
    file's data are bytes, or an object whose chunks() gives them in
    pieces (a report rendered as it is written)."""
    temps: list[tuple[str, Path]] = []
    # The folders made for the files, outermost first: taken away again
    # when a file fails (no empty output folders left behind).
    made: list[Path] = []
    # mkstemp creates 0600 files; a written file gets what open() would give.
    mode = 0o666 & ~_umask()
    done = False
    try:
        for path, data in files:
            try:
                missing = [d for d in (path.parent, *path.parent.parents) if not d.exists()]
                path.parent.mkdir(parents=True, exist_ok=True)
                made += reversed(missing)
                fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp",
                                           dir=path.parent)
                temps.append((tmp, path))
                with os.fdopen(fd, "wb") as f:
                    if isinstance(data, (bytes, bytearray)):
                        f.write(data)
                    else:
                        for piece in data.chunks():
                            f.write(piece)
                os.chmod(tmp, mode)
            except OSError as exc:
                # Name the file the user asked for, not our temporary one.
                raise OSError(exc.errno, exc.strerror, str(path)) from None
        for tmp, path in temps:
            try:
                os.replace(tmp, path)
            except OSError as exc:
                raise OSError(exc.errno, exc.strerror, str(path)) from None
        done = True
    finally:
        for tmp, _ in temps:
            if os.path.exists(tmp):
                os.unlink(tmp)
        for d in reversed(made) if not done else ():
            try:
                d.rmdir()               # (only if empty: nothing of anyone else's)
            except OSError:
                pass
