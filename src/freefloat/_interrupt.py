"""Ctrl-C while the ``freefloat`` command starts up: one line, exit code 130, no traceback.

Importing the package takes a few tenths of a second (NumPy, Pinocchio). A Ctrl-C in that
time would end in a traceback from the import machinery, before :func:`freefloat.cli.main`
can catch it. So when, and only when, this process is the ``freefloat`` command (its console
script, or ``python -m freefloat.cli``), the package's first line installs
:func:`interrupted_while_starting` as the SIGINT handler; ``main`` then installs its own.
Importing freefloat as a library changes no signal handler.
"""

from __future__ import annotations

import contextlib
import itertools
import os
import signal
import sys
import threading
from types import FrameType

__all__ = ["guard_startup", "interrupted_while_starting", "is_command"]


def is_command() -> bool:
    """Whether this process runs the ``freefloat`` command line."""
    if os.path.basename(sys.argv[0]) == "freefloat":
        return True
    argv = list(getattr(sys, "orig_argv", []))
    modules = ("freefloat", "freefloat.cli")
    return any(a == "-m" and b in modules for a, b in itertools.pairwise(argv))


def interrupted_while_starting(signum: int, frame: FrameType | None) -> None:
    """Say ``freefloat: interrupted`` and leave with code 130 (nothing is written yet)."""
    with contextlib.suppress(OSError):
        os.write(2, b"freefloat: interrupted\n")
    raise SystemExit(130)


def guard_startup() -> None:
    """Install :func:`interrupted_while_starting` for SIGINT if this is the command line."""
    if (
        is_command()
        and threading.current_thread() is threading.main_thread()
        and signal.getsignal(signal.SIGINT) is signal.default_int_handler
    ):
        signal.signal(signal.SIGINT, interrupted_while_starting)
