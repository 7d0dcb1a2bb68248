"""What C++ code (urdfdom) prints while parsing, collected instead of shown.

urdfdom reports a value it cannot read on file descriptor 2 and goes on; the loaders collect
those lines so that an error can quote them (one line) and nothing else reaches the terminal.
"""

from __future__ import annotations

import os
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager

from ..progress import LOGGER

__all__ = ["parser_messages"]


@contextmanager
def parser_messages() -> Iterator[list[str]]:
    """Collect what C++ code (urdfdom) prints on file descriptor 2 instead of showing it.

    The lines are in the yielded list after the block; they are logged at DEBUG level (and an
    error message quotes the first). Without a usable descriptor 2 nothing is captured.
    """
    lines: list[str] = []
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError, AttributeError):
        yield lines
        return
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), 2)
        try:
            yield lines
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            sink.seek(0)
            lines += sink.read(100_000).decode("utf-8", "replace").splitlines()
            for line in lines:
                LOGGER.debug("URDF parser: %s", line)
