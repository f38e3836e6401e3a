"""A new declaration's indentation is read from the line it follows
(edit._indent): the text from the last line break ('\\n', '\\r' or '\\r\\n')
before the position to the first character that is not a blank. Oracle:
the last of either break found over the whole text before it, on seeded
random texts with every kind of line break."""

import random

from rapidcomp.compensate.edit import _indent


def _oracle(text: str, pos: int) -> str:
    start = max(text.rfind("\n", 0, pos), text.rfind("\r", 0, pos)) + 1
    end = start
    while end < len(text) and text[end] in " \t":
        end += 1
    return text[start:end]


def test_indent_is_read_after_the_last_line_break_of_any_kind():
    rnd = random.Random(3)
    for _ in range(3000):
        text = "".join(rnd.choice(["\n", "\r", "\r\n", " ", "\t", "  ", "x", "CONST", ";"])
                       for _ in range(rnd.randint(0, 30)))
        for pos in range(len(text) + 1):
            assert _indent(text, pos) == _oracle(text, pos), (text, pos)
