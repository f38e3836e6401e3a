"""The rewriter primitive: splice span edits into source text.

Output text = original text with exactly the edited spans replaced
(sqlfluff-style fix patches). Overlapping edits are a programming error of
the caller and are refused rather than silently merged.
"""

from __future__ import annotations

from operator import attrgetter
from typing import NamedTuple


class SpanEdit(NamedTuple):
    """Replace text[start:end] with replacement (why: for messages).
    Immutable; a NamedTuple, not a frozen dataclass: a CAM program makes
    7e5 of them, and a frozen dataclass's __init__ costs three times as
    much."""

    start: int
    end: int
    replacement: str
    why: str = ""


# The order edits are applied in (a C-level key: 1e5-target programs sort
# 1e6 edits more than once).
BY_SPAN = attrgetter("start", "end")


class OverlappingEdits(ValueError):
    pass


def apply_edits(text: str, edits: list[SpanEdit] | tuple[SpanEdit, ...]) -> str:
    """Return `text` with every edit applied. No edits -> `text` itself."""
    if not edits:
        return text
    ordered = sorted(edits, key=BY_SPAN)
    parts: list[str] = []
    pos = 0
    for edit in ordered:
        if edit.start < pos or edit.end < edit.start or edit.end > len(text):
            raise OverlappingEdits(
                f"edit {edit.start}:{edit.end} ({edit.why}) overlaps the previous edit "
                f"ending at {pos} or lies outside the text")
        parts.append(text[pos:edit.start])
        parts.append(edit.replacement)
        pos = edit.end
    parts.append(text[pos:])
    return "".join(parts)
