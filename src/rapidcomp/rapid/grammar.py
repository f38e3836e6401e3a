"""Loads the RAPID grammar once per process, with Lark's analysis cached.

The grammar ships inside the wheel as package data (rapidcomp/grammars/);
in a source checkout (editable install) it is read from the top-level
grammars/ folder, which is where it is maintained.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from functools import lru_cache
from importlib import resources
from pathlib import Path

from lark import Lark

from .build import NodeBuilder
from .lalr import Engine

GRAMMAR_NAME = "rapid.lark"


def grammar_path() -> Path:
    packaged = resources.files("rapidcomp").joinpath("grammars").joinpath(GRAMMAR_NAME)
    if packaged.is_file():
        return Path(str(packaged))
    checkout = Path(__file__).resolve().parents[3] / "grammars" / GRAMMAR_NAME
    if checkout.is_file():
        return checkout
    raise FileNotFoundError(f"{GRAMMAR_NAME} is neither packaged with rapidcomp nor in a checkout")


def grammar_text() -> str:
    return grammar_path().read_text(encoding="utf-8")


def _cache_file(text: str) -> str:
    # Keyed by grammar content and lark version, so an edited grammar never
    # meets a stale analysis.
    import lark
    key = hashlib.sha256((text + lark.__version__).encode()).hexdigest()[:16]
    folder = Path(os.environ.get("XDG_CACHE_HOME", Path(tempfile.gettempdir()))) / "rapidcomp"
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        return ""
    return str(folder / f"grammar-{key}.lark-cache")


@lru_cache(maxsize=None)
def compiled() -> Lark:
    """Lark's compilation of the grammar: terminals, rules, LALR table."""
    text = grammar_text()
    options = dict(parser="lalr", lexer="basic", maybe_placeholders=False)
    cache = _cache_file(text)
    if cache:
        options["cache"] = cache
    return Lark(text, **options)


@lru_cache(maxsize=None)
def engine() -> Engine:
    """The parser that builds frozen syntax nodes (see lalr.py)."""
    return Engine(compiled(), NodeBuilder())
