"""The ``proleg`` command line: one argparse parser (``build_parser``) built from the
per-command modules of this package; ``main`` turns every ``ProlegError`` into one line."""

from .main import build_parser, main

__all__ = ["build_parser", "main"]
