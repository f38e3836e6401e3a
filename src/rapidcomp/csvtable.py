"""CSV input with a header row, shared by the profile and measured-data
readers: '#' comment lines and blank lines are skipped with the line
numbers kept, and the header must hold the required columns (any order,
case-insensitive)."""

from __future__ import annotations

import csv
import io

from .errors import InputError


def header_and_rows(text: str, source: str, required, what: str = "file"):
    """(header names lower-cased, [(line, row), ...] after the header)."""
    rows = list(csv.reader(io.StringIO(text)))
    numbered = [(i + 1, r) for i, r in enumerate(rows)
                if r and any(c.strip() for c in r) and not r[0].strip().startswith("#")]
    if not numbered:
        raise InputError(source, f"empty {what}; expected the header " + ",".join(required), 1)
    head_line, header = numbered[0]
    header = [h.strip().lower() for h in header]
    missing = [c for c in required if c not in header]
    if missing:
        raise InputError(source, f"missing column(s) {', '.join(missing)}; expected the header "
                         + ",".join(required), head_line)
    return header, numbered[1:]
