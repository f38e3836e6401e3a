"""Domain errors. The CLI maps these to exit codes in one place (cli.py)."""

from __future__ import annotations


class RapidcompError(Exception):
    """Base class of every error rapidcomp reports to a user."""


class InputError(RapidcompError):
    """Bad input (exit code 2): a file that is not what it should be.

    Carries a location so the message can say `path:line:col: ...` and show
    the offending source line with a caret under the column.
    """

    def __init__(self, path: str, message: str, line: int | None = None,
                 col: int | None = None, source_line: str | None = None):
        self.path = path
        self.message = message
        self.line = line
        self.col = col
        self.source_line = source_line
        super().__init__(self.format())

    def __reduce__(self):
        # Errors cross process boundaries (fix runs tasks in worker processes).
        return (type(self), (self.path, self.message, self.line, self.col, self.source_line))

    def format(self) -> str:
        where = self.path
        if self.line is not None:
            where += f":{self.line}"
            if self.col is not None:
                where += f":{self.col}"
        text = f"{where}: {_short(self.message, MESSAGE_CHARS)}"
        if self.source_line is not None:
            shown = self.source_line.rstrip("\r\n").replace("\t", " ")
            caret = self.col - 1 if self.col is not None else None
            if len(shown) > LINE_CHARS:
                # (A line of a megabyte, a generated one: the part around
                # the column, not all of it.)
                start = max(0, min(caret or 0, len(shown)) - LINE_CHARS // 2)
                cut = shown[start:start + LINE_CHARS]
                shown = ("..." if start else "") + cut + (
                    "..." if start + LINE_CHARS < len(shown) else "")
                if caret is not None:
                    caret = caret - start + (3 if start else 0)
            text += f"\n    {shown}"
            if caret is not None:
                text += "\n    " + " " * caret + "^"
        return text


# What a message and its source line show at most (characters): a number or
# a name of a megabyte is shown by its ends.
MESSAGE_CHARS = 2000
LINE_CHARS = 200


def _short(text: str, most: int) -> str:
    if len(text) <= most:
        return text
    return f"{text[:most // 2]}...({len(text) - most} characters)...{text[-most // 2:]}"


class InternalError(RapidcompError):
    """The output failed its own check (a defect of rapidcomp, not of the
    input); nothing is written."""


class Errors(RapidcompError):
    """Several bad inputs at once (every program of a multi-program run
    that failed), reported together."""

    def __init__(self, errors: list[RapidcompError]):
        self.errors = errors
        super().__init__(self.format())

    def __reduce__(self):
        return (type(self), (self.errors,))

    def format(self) -> str:
        return "\n".join(e.format() if isinstance(e, InputError) else f"rapidcomp: error: {e}"
                         for e in self.errors)
