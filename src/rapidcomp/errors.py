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
        text = f"{where}: {self.message}"
        if self.source_line is not None:
            shown = self.source_line.rstrip("\r\n").replace("\t", " ")
            text += f"\n    {shown}"
            if self.col is not None:
                text += "\n    " + " " * (self.col - 1) + "^"
        return text


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
