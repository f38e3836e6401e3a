"""rapidcomp: thermal compensation of ABB RAPID programs."""

__version__ = "0.1.0"
