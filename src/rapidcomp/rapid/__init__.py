"""RAPID language: grammar, parser, frozen model, typed values."""
