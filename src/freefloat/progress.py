"""Logging and progress for the command line (standard :mod:`logging` plus a rich display).

The package logs to the ``freefloat`` logger: warnings (a missing mesh drawn as a simple
shape...), stage timings at INFO, details at DEBUG. :func:`configure` installs the command
line's handler: ``freefloat: warning: ...`` lines on stderr by default, INFO with ``-v``,
DEBUG with ``-vv``, errors only with ``-q``.

:func:`stage` wraps a step that can take more than a second (solving, sampling and verifying,
writing the page, the plots, an export). On a terminal (stderr is a TTY and ``-q`` not given)
it shows a live spinner with the elapsed time (h:mm:ss), then one line
``done <stage> (<s> s)``; when stderr is not a terminal it draws nothing (no control
characters). Every stage's wall time (s) is kept in :data:`TIMINGS` for the summaries.
"""

from __future__ import annotations

import logging
import os
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, TextIO

__all__ = ["LOGGER", "TIMINGS", "configure", "progress_enabled", "stage"]

#: The package's logger.
LOGGER = logging.getLogger("freefloat")

#: Wall time (s) of every stage run since the last :func:`configure`, by stage name.
TIMINGS: dict[str, float] = {}

_settings: dict[str, Any] = {"quiet": False, "stream": None}


class _Formatter(logging.Formatter):
    def format(self, record: logging.LogRecord) -> str:
        level = record.levelname.lower()
        return f"freefloat: {level}: {record.getMessage()}"


def configure(verbosity: int = 0, quiet: bool = False, stream: TextIO | None = None) -> None:
    """Set up logging and progress for one command-line run.

    Args:
        verbosity: 0 warnings, 1 (``-v``) stage timings and info, 2+ (``-vv``) debug.
        quiet: only errors, and no progress display (``-q``).
        stream: where logs and progress go (default ``sys.stderr`` at each call).
    """
    _settings.update(quiet=quiet, stream=stream)
    TIMINGS.clear()
    level = (
        logging.ERROR
        if quiet
        else (logging.WARNING, logging.INFO, logging.DEBUG)[min(max(verbosity, 0), 2)]
    )
    for handler in list(LOGGER.handlers):
        if getattr(handler, "_freefloat_cli", False):
            LOGGER.removeHandler(handler)
    handler = logging.StreamHandler(stream if stream is not None else _Stderr())
    handler.setFormatter(_Formatter())
    handler._freefloat_cli = True  # type: ignore[attr-defined]
    LOGGER.addHandler(handler)
    LOGGER.setLevel(level)
    LOGGER.propagate = False


class _Stderr:
    """A file-like that writes to whatever ``sys.stderr`` is at the time (pytest swaps it)."""

    def write(self, text: str) -> int:
        return sys.stderr.write(text)

    def flush(self) -> None:
        sys.stderr.flush()


def _stream() -> TextIO:
    stream = _settings["stream"]
    return stream if stream is not None else sys.stderr


def progress_enabled() -> bool:
    """Whether the live display is drawn: a terminal, not ``-q``, not ``TERM=dumb``."""
    if _settings["quiet"] or os.environ.get("TERM") == "dumb":
        return False
    isatty = getattr(_stream(), "isatty", None)
    return bool(isatty and isatty())


@contextmanager
def stage(name: str) -> Iterator[None]:
    """Time a step (s, into :data:`TIMINGS`), log it, and show it live on a terminal."""
    start = time.perf_counter()
    LOGGER.debug("%s ...", name)
    if progress_enabled():
        from rich.console import Console
        from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

        console = Console(file=_stream(), highlight=False)
        columns = (SpinnerColumn(), TextColumn(f"{name} ..."), TimeElapsedColumn())
        live = Progress(*columns, console=console, transient=True)
        live.add_task(name, total=None)  # before the first frame is drawn
        with live:
            yield
        elapsed = time.perf_counter() - start
        console.print(f"[green]done[/green] {name} ({elapsed:.2f} s)")
    else:
        yield
        elapsed = time.perf_counter() - start
    TIMINGS[name] = TIMINGS.get(name, 0.0) + elapsed
    LOGGER.info("%s: %.3f s", name, elapsed)
