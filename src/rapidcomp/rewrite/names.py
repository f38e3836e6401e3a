"""New identifiers that collide with nothing.

RAPID identifiers are case-insensitive and at most 32 characters. Every
word of every given module (code, comments and strings alike: being
over-careful costs nothing) is taken; new names are built from the name of
the data they come from and made unique with a number suffix.
"""

from __future__ import annotations

import re

from ..rapid.ast import NAME_PATTERN

MAX_LEN = 32
_WORD = re.compile(NAME_PATTERN)


def words(text: str) -> frozenset[str]:
    """Every word of a text, lower case."""
    # (Each distinct word lower-cased once: a CAM module has 1e6 words, 5e4
    # of them distinct.)
    return frozenset(map(str.lower, set(_WORD.findall(text))))


class NameAllocator:
    def __init__(self, texts: list[str], known: list | None = None):
        """known: for each text, its words() when they are known already
        (a large module's, found while it was parsed: rapid/predecode.py),
        else None."""
        self._texts = texts
        self._known = known or [None] * len(texts)
        self._taken: set[str] | None = None
        # Per stem, the first suffix not known to be taken: names are only
        # ever added, so the search resumes there (1e5 names of one stem
        # would otherwise cost 1e10 probes).
        self._next: dict[str, int] = {}

    @property
    def taken(self) -> set[str]:
        """Every word of the texts, lower case; collected when a first name
        is asked for (an edit of numbers only needs none: a CAM module's
        millions of words are not read for nothing)."""
        if self._taken is None:
            self._taken = set()
            for text, known in zip(self._texts, self._known):
                self._taken.update(known if known is not None else words(text))
        return self._taken

    def new(self, stem: str) -> str:
        """A fresh identifier like `stem`, or `stem_2`, `stem_3`, ..."""
        key = stem.lower()
        n = self._next.get(key, 1)
        taken = self.taken
        while True:
            suffix = "" if n == 1 else f"_{n}"
            name = stem[:MAX_LEN - len(suffix)] + suffix
            low = name.lower()
            if low not in taken:
                taken.add(low)
                # (A stem's first name, `stem` itself, leaves no entry: its
                # next request probes it once more. 1e5 declared targets
                # each make one name of a stem of its own.)
                if n > 1:
                    self._next[key] = n + 1
                return name
            n += 1
