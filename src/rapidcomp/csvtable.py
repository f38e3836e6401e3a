"""CSV input with a header row, shared by the profile and measured-data
readers: '#' comment lines and blank lines are skipped with the line
numbers kept, and the header must hold the required columns (any order,
case-insensitive)."""

from __future__ import annotations

import csv
import io
import re

from .errors import InputError

# A number as a file writes one: Python's float() also takes "1_0" (ten)
# and " 1 ", which no spreadsheet or controller writes. nan and inf pass,
# for the callers' message about finite numbers.
_NUMBER = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?|[+-]?(?:nan|inf|infinity)",
                     re.IGNORECASE)


def number(text: str) -> float:
    """The number a file's cell or value writes; ValueError if it is none."""
    if _NUMBER.fullmatch(text) is None:
        raise ValueError(text)
    return float(text)


def _delimiter(text: str) -> str:
    """',' unless the header line is split by ';' (a spreadsheet in a
    locale with decimal commas) or by tabs."""
    for line in text.splitlines():
        if line.strip() and not line.lstrip().startswith("#"):
            if ";" in line and "," not in line.split(";", 1)[0]:
                return ";"
            if "\t" in line and "," not in line:
                return "\t"
            return ","
    return ","


def header_and_rows(text: str, source: str, required, what: str = "file", known=None):
    """(header names lower-cased, [(line, row), ...] after the header);
    known: the only columns the file may have, when given.

    A file saved by a spreadsheet with ';' between cells and decimal commas
    (1,5 for 1.5) is read as such: the commas become points."""
    delimiter = _delimiter(text)
    # (A cell or a comment line as long as the text is one cell: the csv
    # module's default limit, 128 KiB, is no limit of the file's.)
    if len(text) >= csv.field_size_limit():
        csv.field_size_limit(len(text) + 1)
    reader = csv.reader(io.StringIO(text), delimiter=delimiter)
    try:
        rows = list(reader)
    except csv.Error as exc:
        raise InputError(source, f"not a CSV {what}: {exc}", reader.line_num + 1) from None
    if delimiter == ";":
        rows = [[c.replace(",", ".") for c in r] for r in rows]
    numbered = [(i + 1, r) for i, r in enumerate(rows)
                if r and any(c.strip() for c in r) and not r[0].strip().startswith("#")]
    if not numbered:
        raise InputError(source, f"empty {what}; expected the header " + ",".join(required), 1)
    head_line, header = numbered[0]
    header = [h.strip().lower() for h in header]
    # (A file without its header: the first row is numbers.)
    if any(c not in header for c in required) and any(
            _NUMBER.fullmatch(h) for h in header):
        raise InputError(source, f"no header: this row holds numbers; expected the header "
                         + ",".join(required) + " first", head_line)
    # A column named twice: which one is meant cannot be told (one would
    # be read and the other silently not).
    for k, h in enumerate(header):
        if h and h in header[:k]:
            raise InputError(source, f"column {h} is named twice (columns {header.index(h) + 1} "
                             f"and {k + 1}): which one is meant cannot be told", head_line)
    unknown = [h for h in header if h and known is not None and h not in known]
    if unknown:
        raise InputError(source, f"unknown column {', '.join(unknown)}; a {what}'s columns are "
                         + ", ".join(known), head_line)
    # A column the header leaves unnamed (a spreadsheet's trailing ','):
    # empty, it is no column; a value in it is meant for one, which cannot
    # be told (it was silently dropped).
    for k in [k for k, h in enumerate(header) if not h]:
        for line, r in numbered[1:]:
            if len(r) > k and r[k].strip():
                raise InputError(source, f"a value ({r[k].strip()}) in column {k + 1}, which "
                                 "the header leaves unnamed: name the column, or remove the "
                                 "value", line)
    missing = [c for c in required if c not in header]
    if missing:
        found = ", ".join(h for h in header if h) or "nothing"
        raise InputError(source, f"missing column(s) {', '.join(missing)}; the header names "
                         f"{found}; expected " + ",".join(required), head_line)
    return header, numbered[1:]
