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

:func:`counted` is the same for work of a known number of items (the directions of
``freefloat reach``): a bar on a terminal, and with ``-v`` one line per item, on a terminal or
piped. :func:`heartbeat` lets long loops (continuation) say where they are at least every
:data:`HEARTBEAT_S` seconds with ``-v``. Time only decides when a line is printed; budgets and
results never depend on it.
"""

from __future__ import annotations

import logging
import os
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, TextIO

__all__ = [
    "HEARTBEAT_S",
    "LOGGER",
    "TIMINGS",
    "configure",
    "counted",
    "heartbeat",
    "progress_enabled",
    "stage",
]

#: With ``-v``, long loops print a line at least this often (s of wall time; display only).
HEARTBEAT_S = 5.0

#: The package's logger.
LOGGER = logging.getLogger("freefloat")

#: Wall time (s) of every stage run since the last :func:`configure`, by stage name.
TIMINGS: dict[str, float] = {}

_settings: dict[str, Any] = {"quiet": False, "stream": None, "beat": 0.0}


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
    _settings.update(quiet=quiet, stream=stream, beat=0.0)
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


@contextmanager
def counted(name: str, total: int) -> Iterator[Callable[[str], None]]:
    """Work of ``total`` items: yields ``advance(text)``, called once per item done.

    On a terminal a bar with the count and elapsed time; at INFO (``-v``) one log line per item
    (``name i/total: text``), piped or not. The wall time goes into :data:`TIMINGS`.
    """
    start = time.perf_counter()
    done = [0]

    def log(text: str) -> None:
        done[0] += 1
        LOGGER.info("%s %d/%d: %s", name, done[0], total, text)

    if progress_enabled():
        from rich.console import Console
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
        )

        console = Console(file=_stream(), highlight=False)
        columns = (TextColumn(f"{name}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn())
        live = Progress(*columns, console=console, transient=True)
        task = live.add_task(name, total=total)

        def advance(text: str) -> None:
            live.advance(task)
            log(text)

        with live:
            yield advance
        console.print(f"[green]done[/green] {name} ({time.perf_counter() - start:.2f} s)")
    else:
        yield log
    elapsed = time.perf_counter() - start
    TIMINGS[name] = TIMINGS.get(name, 0.0) + elapsed
    LOGGER.info("%s: %.3f s", name, elapsed)


def heartbeat(text: Callable[[], str], every: float = HEARTBEAT_S) -> None:
    """Log ``text()`` at INFO when ``every`` s have passed since the last heartbeat line.

    ``text`` is only called when a line is due (it may format numbers). The first call after
    :func:`configure` starts the clock.
    """
    if not LOGGER.isEnabledFor(logging.INFO):
        return
    now = time.perf_counter()
    last = _settings["beat"]
    if last == 0.0:
        _settings["beat"] = now
    elif now - last >= every:
        _settings["beat"] = now
        LOGGER.info("%s", text())
