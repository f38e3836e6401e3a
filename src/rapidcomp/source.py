"""Lossless source text: bytes -> text with the original encoding and newlines.

Everything downstream works on character offsets into `SourceText.text`; the
rewriter splices edits into that text and `encode()` gives back bytes. Because
no newline translation is done, CRLF, LF and mixed files survive unchanged.
"""

from __future__ import annotations

import bisect
import os
import stat
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import InputError

# Bytes that never occur in a RAPID text module. Encrypted or binary modules
# are full of them; a cp1252 fallback would otherwise "decode" garbage.
# A module with this many control bytes, and this share of its first 64 KB,
# is binary (encrypted); fewer are stray bytes in a text.
BINARY_MIN = 8
BINARY_SHARE = 0.01
_BINARY_BYTES = set(range(0, 9)) | {11, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23,
                                      24, 25, 26, 27, 28, 29, 30, 31, 127}


@dataclass(frozen=True)
class SourceText:
    """A decoded source file. `display_path` is what messages show."""

    display_path: str
    text: str
    encoding: str  # "utf-8", "utf-16-le/-be" (BOM kept as U+FEFF in text), "cp1252", "latin-1"
    line_starts: tuple[int, ...] = field(repr=False, compare=False)

    @classmethod
    def from_text(cls, text: str, display_path: str = "<text>",
                  encoding: str = "utf-8") -> "SourceText":
        starts = [0]
        find = text.find
        pos = find("\n")
        while pos != -1:
            starts.append(pos + 1)
            pos = find("\n", pos + 1)
        return cls(display_path, text, encoding, tuple(starts))

    @property
    def has_bom(self) -> bool:
        return self.text.startswith("\ufeff")

    @property
    def newline(self) -> str:
        """'CRLF', 'LF', 'CR', 'mixed' or 'none' — reported by inspect."""
        crlf = self.text.count("\r\n")
        lf = self.text.count("\n") - crlf
        cr = self.text.count("\r") - crlf
        kinds = [name for name, n in (("CRLF", crlf), ("LF", lf), ("CR", cr)) if n]
        if not kinds:
            return "none"
        return kinds[0] if len(kinds) == 1 else "mixed"

    def position(self, offset: int) -> tuple[int, int]:
        """1-based (line, column) of a character offset."""
        line = bisect.bisect_right(self.line_starts, offset) - 1
        return line + 1, offset - self.line_starts[line] + 1

    def lines(self, offsets) -> list[int]:
        """The 1-based line of each offset (position()'s, for 1e5 offsets at
        once: one search of all of them)."""
        starts = np.fromiter(self.line_starts, np.int64, len(self.line_starts))
        return (np.searchsorted(starts, np.asarray(offsets, np.int64), "right")).tolist()

    def line_text(self, line: int) -> str:
        start = self.line_starts[line - 1]
        end = self.line_starts[line] if line < len(self.line_starts) else len(self.text)
        return self.text[start:end]

    def error(self, offset: int, message: str) -> InputError:
        line, col = self.position(offset)
        return InputError(self.display_path, message, line, col, self.line_text(line))

    def encode(self, text: str | None = None) -> bytes:
        return (self.text if text is None else text).encode(self.encoding)


def decode_bytes(data: bytes, display_path: str) -> SourceText:
    """Decode a module: UTF-16 with its byte order mark (RobotStudio can
    save modules so), else UTF-8 first, then cp1252, then latin-1
    (reported)."""
    if data.startswith((b"\xff\xfe\x00\x00", b"\x00\x00\xfe\xff")):
        # (Its byte order mark begins as UTF-16's: read so, every character
        # was followed by a NUL.)
        raise InputError(display_path, "UTF-32 text (its byte order mark): expected RAPID source "
                         "text in UTF-8, cp1252, latin-1 or UTF-16, as a controller or "
                         "RobotStudio saves it", 1, 1)
    for bom, encoding in ((b"\xff\xfe", "utf-16-le"), (b"\xfe\xff", "utf-16-be")):
        if data.startswith(bom):
            try:
                text = data.decode(encoding)   # the BOM stays in the text as U+FEFF
            except UnicodeDecodeError as exc:
                raise InputError(display_path, f"invalid {encoding.upper()} text at byte "
                                 f"{exc.start}") from None
            return SourceText.from_text(text, display_path, encoding)
    head = data[:65536]
    bad = next((i for i, b in enumerate(head) if b in _BINARY_BYTES), None)
    if bad is not None:
        line = data.count(b"\n", 0, bad) + 1
        col = bad - (data.rfind(b"\n", 0, bad) + 1) + 1
        message = (f"binary or encrypted module (byte 0x{data[bad]:02x} at offset {bad}); "
                   "expected RAPID source text")
        # (Encrypted or binary: control bytes throughout, as ciphertext has
        # them (a real one: 11 %); a text with a stray one, a Ctrl-Z at its
        # end, is a text file to mend, not a module to pass over.)
        many = sum(b in _BINARY_BYTES for b in head)
        raise (EncryptedModule if many >= max(BINARY_MIN, BINARY_SHARE * len(head))
               else InputError)(display_path, message, line, col)
    for encoding in ("utf-8", "cp1252", "latin-1"):
        try:
            text = data.decode(encoding)
        except UnicodeDecodeError:
            continue
        # The round trip must be exact, or splicing could change untouched bytes.
        if text.encode(encoding) == data:
            return SourceText.from_text(text, display_path, encoding)
    raise InputError(display_path, "cannot decode as UTF-8, cp1252 or latin-1")


class EncryptedModule(InputError):
    """A module that is no RAPID text: encrypted (the controller loads it,
    no one reads it) or binary. A task's is taken as a module not given
    (compensate/load.py); one given alone is bad input."""


def not_a_file(path: str | Path, shown: str | None = None) -> None:
    """Bad input where `path` is a FIFO, a device or a socket, which reading
    would wait on forever or read without end (a folder, a missing or
    unreadable file: the reader's own error says so)."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return
    if not (stat.S_ISREG(mode) or stat.S_ISDIR(mode)):
        raise InputError(shown if shown is not None else str(path),
                         "not a regular file (a pipe or a device: give the file itself)")


def read_source(path: str | Path, display_path: str | None = None) -> SourceText:
    path = Path(path)
    shown = display_path if display_path is not None else str(path)
    not_a_file(path, shown)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputError(shown, f"cannot read file: {exc.strerror or exc}") from None
    return decode_bytes(data, shown)
