"""The ``freefloat`` command line: the parser of every command, and how the command ends.

Angles are printed in degrees. Every expected failure (a :class:`FreeFloatError`) is printed
as one line ``freefloat: error: ...`` and exits with code 2, with no traceback and no file
written. Each command is a module of this package (:data:`COMMANDS`) that builds its own
sub-parser, checks its arguments before any work and runs; the plan summary lives in
:mod:`freefloat.viz.summary` and the work itself in the layers below.
"""

from __future__ import annotations

import argparse
import contextlib
import re
import sys
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from types import ModuleType
from typing import Any, NoReturn

from .. import __version__
from .._exits import (
    HungUp,
    Terminated,
    error_line,
    flush_output,
    handle_signals,
    ignore_late_signals,
    silence_output,
)
from .._interrupt import is_command
from ..errors import FreeFloatError, UnitsWarning
from ..excerpts import path_excerpt
from ..progress import LOGGER, configure
from . import (
    bounds,
    check,
    compose,
    correct,
    export,
    plan,
    plot,
    reach,
    sensitivity,
    show,
    sweep,
    verify,
)
from .messages import error_message

__all__ = ["COMMANDS", "build_parser", "main"]

#: The commands, in the order ``freefloat --help`` lists them: each module's ``add_parser``
#: adds its sub-parser, whose defaults are its ``check`` (or None) and ``run``.
COMMANDS: tuple[ModuleType, ...] = (
    plan,
    bounds,
    reach,
    check,
    verify,
    compose,
    show,
    export,
    plot,
    sensitivity,
    correct,
    sweep,
)


#: What reads as a negative number, not an option: ``-3``, ``-.5``, ``-1e9``, ``-2.5E-3``.
#: (argparse's own pattern has no exponent: ``--base-zyx-deg -1e9 0 0`` then read "expected 3
#: arguments" instead of the range check's message. Python 3.13's pattern takes it too.)
_NEGATIVE_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line ``freefloat: error: ...`` (exit code 2).

    Negative numbers in exponent notation are values, as plain ones are (:data:`_NEGATIVE_NUMBER`).
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = _NEGATIVE_NUMBER

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"freefloat: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``freefloat`` command."""
    parser = _Parser(
        prog="freefloat",
        description="Point-to-point motion planning for free-floating space manipulators. "
        "Angles on the command line and in scenario files are in degrees.",
    )
    parser.add_argument("--version", action="version", version=f"freefloat {__version__}")
    commands = parser.add_subparsers(
        dest="command", required=True, metavar="COMMAND", parser_class=_Parser
    )
    for command in COMMANDS:
        command.add_parser(commands)
    for sub in [parser, *commands.choices.values()]:
        _add_common_flags(sub)
    return parser


def _add_common_flags(parser: argparse.ArgumentParser) -> None:
    """-v/--verbose and -q/--quiet, before or after the command name."""
    parser.add_argument(
        "-v",
        "--verbose",
        action="count",
        default=argparse.SUPPRESS,
        help="log stage timings (-v) and details (-vv) on stderr",
    )
    parser.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        default=argparse.SUPPRESS,
        help="no progress display and no warnings; errors and results only",
    )


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit code.

    0: success; 1: ``verify`` found a failing check; 2: bad input, infeasible request, no
    plan, or standard output cannot be written (one line ``freefloat: error: ...`` on
    stderr); 130: interrupted by Ctrl-C; 143: terminated by SIGTERM; 129: SIGHUP (one line
    each, no partial file left); 141: standard output was closed (silently). The package's
    :class:`UnitsWarning` is one line ``freefloat: warning: ...`` (none with ``-q``).
    """
    with _escaping_streams(), warnings.catch_warnings():
        warnings.showwarning = _one_line_warnings(warnings.showwarning)
        return _main(argv)


@contextlib.contextmanager
def _escaping_streams() -> Iterator[None]:
    """Standard output and error write what their encoding lacks as backslash escapes.

    A joint named in another script, printed to an ASCII or Latin-1 terminal (``LC_ALL=C``),
    raised UnicodeEncodeError after the plan was written (exit 1, a traceback). Each stream's
    own setting is restored afterwards (a script calling :func:`main` keeps its own).
    """
    changed: list[tuple[Callable[..., None], str | None]] = []
    for stream in (sys.stdout, sys.stderr):
        reconfigure = getattr(stream, "reconfigure", None)
        before = getattr(stream, "errors", None)
        if reconfigure is not None and before != "backslashreplace":
            with contextlib.suppress(ValueError, OSError):  # a closed stream: left as it is
                reconfigure(errors="backslashreplace")
                changed.append((reconfigure, before))
    try:
        yield
    finally:
        for reconfigure, before in changed:
            with contextlib.suppress(ValueError, OSError):
                reconfigure(errors=before)


def _one_line_warnings(show: Callable[..., None]) -> Callable[..., None]:
    """``warnings.showwarning`` printing a :class:`UnitsWarning` as the package's warning line."""

    def showwarning(message: Warning | str, category: type[Warning], *rest: Any) -> None:
        if issubclass(category, UnitsWarning):
            LOGGER.warning("%s", message)
        else:
            show(message, category, *rest)

    return showwarning


def _main(argv: Sequence[str] | None) -> int:
    """:func:`main` under its warning display."""
    undo = handle_signals()
    try:
        parser = build_parser()
        try:
            args = parser.parse_args(check.joined_values(sys.argv[1:] if argv is None else argv))
        except SystemExit as exc:  # --help, --version, or a one-line argument error
            flush_output()
            return exc.code if isinstance(exc.code, int) else 2
        configure(getattr(args, "verbose", 0), getattr(args, "quiet", False))
        args.started = time.perf_counter()
        if args.check is not None:
            args.check(args)
        code = int(args.func(args))
        flush_output()
        return code
    except FreeFloatError as exc:
        error_line(f"error: {error_message(exc)}")
        return 2
    except BrokenPipeError:  # standard output closed (| head): nothing more to say
        silence_output(1)
        return 141
    except OSError as exc:  # a stream, not a file (files raise FileError): > /dev/full
        silence_output(1)
        name = getattr(exc, "filename", None)  # read or written: the file and the reason
        said = path_excerpt(str(name)) if name else "cannot write the output"
        error_line(f"error: {said}: {exc.strerror or exc}")
        return 2
    except KeyboardInterrupt:
        error_line("interrupted")
        return 130
    except Terminated:
        error_line("terminated")
        return 143
    except HungUp:
        error_line("hung up")
        return 129
    finally:
        undo()
        if is_command():  # the process leaves now: a late signal must not raise as it exits
            ignore_late_signals()
