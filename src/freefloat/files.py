"""Files in and out: checked reads, checked output paths, atomic writes.

Every file freefloat reads (scenario, URDF, sweep file) goes through :func:`read_text_file`,
and every file it writes through :func:`atomic_write` (after :func:`check_output` at the
command line, before any work): a path with a NUL byte, a symbolic-link loop, a directory, a
FIFO or a device (``/dev/zero``), a file larger than the limit for its kind, a read-only
folder, a file where a folder should be, all become one :class:`~freefloat.errors.FileError`
with a one-line message instead of a hang, a memory runaway or a traceback.

Atomic writes: a reader never sees half a file, and a failure (or Ctrl-C, SIGTERM or SIGHUP at
the command line, at any instant) leaves nothing behind and the previous file intact; only a
regular file is ever replaced (never a FIFO or a device). Files are created with the
permissions of an ordinary ``open()``: ``0666`` less the process umask (``0644`` under the
usual umask 022), not the ``0600`` of a temporary file.
"""

from __future__ import annotations

import errno
import os
import re
import stat
import sys
import tempfile
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from .errors import FileError, FreeFloatError
from .excerpts import path_excerpt

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = [
    "absolute_path",
    "atomic_write",
    "atomic_write_text",
    "check_output",
    "check_replaceable",
    "default_file_mode",
    "other_kind_hint",
    "raise_when_free",
    "read_text_file",
    "signals_held",
]

#: A factory of the error to raise: an error class taking the one-line message.
ErrorClass = Callable[[str], FreeFloatError]


def _reason(exc: OSError) -> str:
    """A short account of an OS error: its text, without the path Python appends."""
    if exc.errno == errno.ELOOP:
        return "a symbolic-link loop"
    return exc.strerror or str(exc)


def absolute_path(path: str | Path, what: str, error: ErrorClass = FileError) -> Path:
    """``path`` made absolute, symbolic links resolved, or a one-line error.

    Args:
        path: the path as given (``~`` is expanded).
        what: what the file is, for messages (``"scenario"``, ``"URDF"``, ``"output"``).
        error: the error class to raise (it takes the message).

    Raises:
        error: a NUL byte in the path, or a symbolic-link loop.
    """
    text = os.fspath(path)
    if "\x00" in text:
        raise error(f"{what} path {path_excerpt(text)} contains a NUL byte; give a file name")
    try:
        resolved = Path(text).expanduser().resolve()
    except RuntimeError:  # Python < 3.13 reports a loop this way
        raise error(f"{what} path {path_excerpt(text)}: a symbolic-link loop") from None
    except OSError as exc:
        raise error(f"{what} path {path_excerpt(text)}: {_reason(exc)}") from None
    if not resolved.exists() and Path(text).expanduser().exists():  # /dev/fd/63 -> pipe:[..]
        raise error(
            f"{what} {path_excerpt(text)} is a pipe or socket with no file name (as <(...) "
            "gives), not a file; give a file (a piped input written to one first)"
        )
    return resolved


def _kind(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a directory"
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def read_text_file(path: str | Path, what: str, limit: int, error: ErrorClass = FileError) -> str:
    """The UTF-8 text of a regular file of at most ``limit`` bytes.

    The file is checked before it is read (a FIFO is opened without blocking, and at most
    ``limit + 1`` bytes are ever read), so a device or a huge file costs nothing.

    Args:
        path: the file.
        what: what it is, for messages (``"scenario"``, ``"URDF"``, ``"sweep"``).
        limit: the largest accepted size (bytes).
        error: the error class to raise (it takes the message).

    A UTF-8 byte-order mark at the start is dropped.

    Raises:
        error: a NUL byte in the path, a missing file, a symbolic-link loop, not a regular
            file, larger than ``limit``, unreadable, or not UTF-8.
    """
    target = absolute_path(path, what, error)
    try:
        fd = os.open(target, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise error(f"{what} file not found: {target}") from None
    except OSError as exc:
        raise error(f"cannot read {what} {target}: {_reason(exc)}") from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise error(f"{what} {target} is {_kind(info.st_mode)}, not a regular file")
        if info.st_size > limit:
            raise error(
                f"{what} {target} is {info.st_size} bytes, above the limit of {limit} bytes "
                f"for a {what} file"
            )
        chunks = []
        size = 0
        while size <= limit:
            chunk = os.read(fd, limit + 1 - size)
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
        if size > limit:  # it grew while being read
            raise error(f"{what} {target} is above the limit of {limit} bytes for a {what} file")
    except OSError as exc:
        raise error(f"cannot read {what} {target}: {_reason(exc)}") from None
    finally:
        os.close(fd)
    try:  # a byte-order mark is accepted (and dropped)
        return b"".join(chunks).decode("utf-8").removeprefix("\ufeff")
    except UnicodeDecodeError as exc:
        raise error(
            f"{what} {target} is not UTF-8 text (byte {exc.object[exc.start]:#04x} at offset "
            f"{exc.start})"
        ) from None


def check_output(path: str | Path, what: str = "output", folder: bool = False) -> Path:
    """Check that ``path`` can be written (before any work); return it absolute.

    The target must not be a directory (or, with ``folder``, must be one or not exist yet);
    its nearest existing ancestor must be a writable directory (missing folders below it are
    created when the file is written).

    Args:
        path: the file (or folder) to write.
        what: what it is, for messages (``"-o"``, ``"--html"``...).
        folder: the output is a folder (plots, a ROS 2 bag) rather than a file.

    Raises:
        FileError: a NUL byte, a symbolic-link loop, a directory, FIFO or device in the way
            (or a file where the folder should be), a parent that is a file, a read-only
            folder.
    """
    target = absolute_path(path, what)
    shown = os.fspath(path)
    if target.is_dir() and not folder:
        raise FileError(f"{what} {path_excerpt(shown)} is a directory; give a file name", shown)
    if not folder and shown.endswith((os.sep, "/")):  # a folder meant, even one not there yet
        raise FileError(
            f"{what} {path_excerpt(shown)} names a folder; give a file name (in it, say)", shown
        )
    if not folder and target.exists() and not target.is_file():
        raise FileError(
            f"{what} {path_excerpt(shown)} is {_kind(target.stat().st_mode)}; freefloat replaces "
            "regular files only: give a file name",
            shown,
        )
    if folder and target.exists() and not target.is_dir():
        mode = target.stat().st_mode
        kind = "a file" if stat.S_ISREG(mode) else _kind(mode)
        raise FileError(f"{what} {path_excerpt(shown)} is {kind}; give a folder", shown)
    given = Path(shown).expanduser()
    dangling = next((p for p in given.parents if p.is_symlink() and not p.exists()), None)
    if given.is_symlink() and not (target.exists() if folder else target.parent.exists()):
        dangling = given  # a folder is not made at a link's end (mkdir follows no link)
    if dangling is not None:  # no folders made at a link's end
        raise FileError(
            f"{what} {path_excerpt(shown)} goes through a symbolic link to nothing ({dangling}); "
            "give a file name in a folder that exists",
            shown,
        )
    ancestor = target if folder and target.is_dir() else target.parent
    while not ancestor.exists():
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise FileError(
            f"cannot write {what} {path_excerpt(shown)}: {ancestor} is a file, not a folder", shown
        )
    if not os.access(ancestor, os.W_OK | os.X_OK):
        raise FileError(
            f"cannot write {what} {path_excerpt(shown)}: folder {ancestor} is not writable", shown
        )
    try:  # the permission bits do not bind root, nor tell a read-only file system (/sys)
        handle, probe = tempfile.mkstemp(prefix=".freefloat-probe-", dir=ancestor)
        os.close(handle)
        os.unlink(probe)
    except OSError as exc:
        # /proc answers "no such file" to a new file in a folder that exists: say what it means
        why = "it takes no new files" if exc.errno == errno.ENOENT else _reason(exc)
        raise FileError(
            f"cannot write {what} {path_excerpt(shown)}: folder {ancestor} is not writable ({why})",
            shown,
        ) from None
    return target


def default_file_mode() -> int:
    """``0o666`` less the current umask: the mode ``open()`` gives a new file."""
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


#: Test hook: seconds to pause after the temporary file is written and before the rename
#: (``FREEFLOAT_TEST_WRITE_PAUSE``), so that a test can interrupt a write deterministically.
_PAUSE_ENV = "FREEFLOAT_TEST_WRITE_PAUSE"


class _Held:
    """Signal exceptions held back in the main thread: how deep, and the first one pending."""

    depth = 0
    pending: BaseException | None = None


@contextmanager
def signals_held() -> Iterator[None]:
    """Hold back the exceptions the command line's signal handlers raise, until the block ends.

    A temporary file is created, and renamed or removed, in such a block, so that its name is
    known to the cleanup by the time a signal can raise: no instant leaves a file behind. The
    handlers (:mod:`freefloat._exits`) hand their exception to :func:`raise_when_free`, which
    keeps it until the outermost block ends. Only the main thread (where Python runs signal
    handlers) holds anything; the mask of the operating system is not used, because a signal
    may arrive on any thread (NumPy's, Pinocchio's) and Python still runs its handler.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _Held.depth += 1
    try:
        yield
    finally:
        _Held.depth -= 1
        if _Held.depth == 0 and _Held.pending is not None:
            pending, _Held.pending = _Held.pending, None
            raise pending


def raise_when_free(exc: BaseException) -> None:
    """Raise ``exc`` now, or when the current :func:`signals_held` block ends."""
    if _Held.depth and threading.current_thread() is threading.main_thread():
        if _Held.pending is None:
            _Held.pending = exc
        return
    raise exc


def check_replaceable(target: Path) -> None:
    """Refuse to replace anything but a regular file (a FIFO, a device, a socket).

    Raises:
        FileError: ``target`` (or what a link at it leads to) is not a regular file.
    """
    try:
        mode = os.stat(target).st_mode
    except FileNotFoundError:
        return
    except OSError as exc:
        raise FileError(f"cannot write {target}: {_reason(exc)}", str(target)) from None
    if not stat.S_ISREG(mode):
        raise FileError(
            f"cannot write {target}: it is {_kind(mode)}; freefloat replaces regular files only",
            str(target),
        )


def atomic_write(path: str | Path, write: Callable[[Path], None], suffix: str = "") -> Path:
    """Call ``write(temporary path)`` in the target's folder, then rename over the target.

    The temporary file (``.NAME.XXXXXXXX``) is removed whatever happens: an error, Ctrl-C
    (``KeyboardInterrupt``), SIGTERM or SIGHUP (the command line turns them into exceptions),
    at any instant: it is created, and renamed or removed, in a :func:`signals_held` block. Only
    a regular file (or nothing) is replaced.

    Args:
        path: the file to produce (its folder is created if needed).
        write: writes the whole content to the path it is given.
        suffix: suffix of the temporary file (some writers choose the format from it).

    Returns:
        The absolute path written.

    Raises:
        FileError: the file cannot be written (read-only folder, a directory, FIFO or device
            in the way, a parent that is a file, a full disk...).
    """
    target = absolute_path(path, "output")
    check_replaceable(target)
    tmp: str | None = None
    try:
        with signals_held():
            target.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=suffix, dir=target.parent)
            os.close(fd)
        write(Path(tmp))
        if Path(tmp).is_file():
            os.chmod(tmp, default_file_mode())
        pause = os.environ.get(_PAUSE_ENV)
        if pause:
            import time

            time.sleep(float(pause))
        with signals_held():
            check_replaceable(target)
            os.replace(tmp, target)
            tmp = None
    except OSError as exc:
        raise FileError(f"cannot write {target}: {_reason(exc)}", str(target)) from None
    finally:
        if tmp is not None:
            with signals_held():
                Path(tmp).unlink(missing_ok=True)
    return target


def atomic_write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` (UTF-8) atomically, flushed to disk before the rename."""

    def write(tmp: Path) -> None:
        with open(tmp, "w", encoding="utf-8") as handle:
            handle.write(text)
            handle.flush()
            os.fsync(handle.fileno())

    return atomic_write(path, write)


#: The start of a TOML file: a comment, a table header or a ``key =`` line.
_TOML_START = re.compile(r"\s*(#|\[\[?\s*[A-Za-z_]|[A-Za-z_][\w.-]*\s*=)")


def other_kind_hint(path: str | Path, text: str, expected: str) -> str:
    """A hint for a file that failed to parse as ``expected`` but looks like the other kind.

    ``expected``: ``"plan"`` (JSON; ``text`` the whole file) or ``"toml"`` (a scenario or
    sweep file; ``text`` its start). A would-be plan is called a scenario only when it is
    TOML with a ``robot`` key (a Markdown or ``pyproject.toml`` file is not); a would-be
    scenario is called a plan by its suffix or first characters. The hint names the command
    that reads the other kind (``"; it looks like ..."``), or is empty.
    """
    if expected == "plan" and _TOML_START.match(text) and _has_robot_key(text):
        return f"; it looks like a scenario file (TOML): freefloat plan {path} plans it"
    suffix = Path(path).suffix.lower()
    if expected == "toml" and (suffix == ".json" or text.lstrip().startswith("{")):
        return (
            f"; it looks like a plan file (JSON): freefloat verify {path} checks it "
            "(show, plot and export read plans too)"
        )
    return ""


#: Text longer than this (characters) is not parsed for a hint: a scenario file is at most
#: 1 MB (:data:`~freefloat.problem.limits.MAX_SCENARIO_BYTES`), and a corrupt plan file can be
#: 200 times that.
_HINT_PARSE_CHARS = 1_000_000


def _has_robot_key(text: str) -> bool:
    """Whether ``text`` is TOML with a top-level ``robot`` key, as every scenario has."""
    if len(text) > _HINT_PARSE_CHARS:
        return False
    try:
        return "robot" in tomllib.loads(text)
    except (tomllib.TOMLDecodeError, ValueError, RecursionError):  # nested too deeply
        return False
