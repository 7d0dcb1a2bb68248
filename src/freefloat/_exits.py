"""How the ``freefloat`` command ends: on a signal, or when its output streams fail.

Signals: Ctrl-C (SIGINT) raises ``KeyboardInterrupt``, SIGTERM :class:`Terminated` and SIGHUP
:class:`HungUp`, so that the atomic writers (:mod:`freefloat.files`) unwind and remove their
temporary files; while a writer creates, renames or removes its temporary file the exception
waits until it is done (:func:`freefloat.files.signals_held`). The first of these signals also
makes every later one do nothing, so a second Ctrl-C cannot interrupt the cleanup the first
began.

Streams: a closed pipe on standard output (``freefloat plan ... | head -1``) ends the
command quietly; any other failure to write standard output (a full disk, ``> /dev/full``)
ends it with one line on standard error. Either way the stream is then pointed at the null
device, so Python's own flush at exit has nothing left to fail on, and no traceback is shown.
"""

from __future__ import annotations

import contextlib
import os
import re
import signal
import sys
import threading
from collections.abc import Callable
from types import FrameType

from .files import raise_when_free

__all__ = [
    "HungUp",
    "Terminated",
    "error_line",
    "flush_output",
    "handle_signals",
    "ignore_late_signals",
    "silence_output",
]


class Terminated(BaseException):
    """SIGTERM, raised like Ctrl-C's ``KeyboardInterrupt`` so that writers clean up."""


class HungUp(BaseException):
    """SIGHUP (the terminal closed), raised like SIGTERM."""


def _names() -> tuple[str, ...]:
    return tuple(n for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n))


def _nothing(signum: int, frame: FrameType | None) -> None:
    """Do nothing: a later signal, while the command already ends.

    A Python no-op rather than ``SIG_IGN``, which would make CPython print "Signal N ignored
    due to race condition" for a signal already on its way.
    """


def _first(exc: BaseException) -> None:
    for name in _names():
        signal.signal(getattr(signal, name), _nothing)
    raise_when_free(exc)


def _interrupt(signum: int, frame: FrameType | None) -> None:
    _first(KeyboardInterrupt())


def _terminate(signum: int, frame: FrameType | None) -> None:
    _first(Terminated())


def _hang_up(signum: int, frame: FrameType | None) -> None:
    _first(HungUp())


def handle_signals() -> Callable[[], None]:
    """Install the handlers above for SIGINT, SIGTERM and SIGHUP; return an undo.

    Outside the main thread (a caller's thread) nothing is installed.
    """
    if threading.current_thread() is not threading.main_thread():
        return lambda: None
    handlers = {"SIGINT": _interrupt, "SIGTERM": _terminate, "SIGHUP": _hang_up}
    previous = {
        getattr(signal, name): signal.signal(getattr(signal, name), handlers[name])
        for name in _names()
    }

    def undo() -> None:
        for number, handler in previous.items():
            signal.signal(number, handler if handler is not None else signal.SIG_DFL)

    return undo


def ignore_late_signals() -> None:
    """Make SIGINT, SIGTERM and SIGHUP do nothing from now on (the main thread only).

    For the ``freefloat`` command once its work has ended: the process is leaving with its
    code, and a signal arriving while it exits (its output flushed, logging shut down) must not
    raise there, where it would print a traceback ("Exception ignored in atexit callback").
    """
    if threading.current_thread() is threading.main_thread():
        for name in _names():
            signal.signal(getattr(signal, name), _nothing)


def silence_output(stream_fd: int = 1) -> None:
    """Point file descriptor ``stream_fd`` at the null device (nothing left to flush)."""
    with contextlib.suppress(OSError):
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, stream_fd)
        os.close(null)


def flush_output() -> None:
    """Flush standard output; a failure raises ``OSError`` (``BrokenPipeError`` if closed)."""
    if sys.stdout is not None:
        sys.stdout.flush()


#: Lines of a C++ (Pinocchio, coal) exception that say where in the library it was raised.
_CPP_CONTEXT = re.compile(r"(From file|in function|at line): [^\n]*\n|\n?Hint: [^\n)]*|message: ")


def error_line(text: str) -> None:
    """Print ``freefloat: TEXT`` as one line on standard error; say nothing if it fails.

    Line breaks in ``text`` (a C++ loader's multi-line message) become ``; ``, so the line
    is one line whatever a library put into it; a C++ exception's source file, function,
    line number and hint are left out (what failed, and on which file, stays).
    """
    text = _CPP_CONTEXT.sub("", text)
    flat = "; ".join(part.strip() for part in text.splitlines() if part.strip())
    if sys.stderr is None:  # started with descriptor 2 closed
        return
    try:
        print(f"freefloat: {flat}", file=sys.stderr, flush=True)
    except (OSError, ValueError, AttributeError):  # stderr full, closed or absent
        silence_output(2)
