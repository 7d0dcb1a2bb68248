"""The ``freefloat`` command line: one module per command, :func:`main` runs them."""

from .main import build_parser, main

__all__ = ["build_parser", "main"]
