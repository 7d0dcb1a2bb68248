"""Outputs of several files written all at once: staged beside their place, then moved in.

Figures, the main job's plan with its page and plots, a URDF with its SRDF: written one by
one, a full disk or a Ctrl-C between two of them left some new files beside the old run's
others (or an empty folder, or an SRDF without its URDF). :func:`staged_folder` has a
folder's files written into a hidden folder beside it, on the same file system, and
:func:`write_together` writes a few text files to temporary files beside them; either moves
them in only when every one is written, while the command line's signals are held, and all
or none of them (:func:`_move_all`): a rename that fails halfway puts back what it replaced.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import socket
import tempfile
from collections.abc import Iterator, Mapping
from pathlib import Path

from .errors import FileError
from .files import check_replaceable, default_file_mode, signals_held

__all__ = ["remove_abandoned", "staged_folder", "write_together"]


@contextlib.contextmanager
def staged_folder(target: str | Path) -> Iterator[Path]:
    """A staging folder for ``target``'s files; on success they are moved into ``target``.

    The files are moved with ``os.replace`` (renames on one file system) while signals are
    held (:func:`~freefloat.files.signals_held`): an interruption, or a failure while they
    are written (a full disk) or moved (:func:`_move_all` puts back the files a failed rename
    replaced), leaves ``target`` as it was, never a mix of old and new files. Files of
    ``target`` the stage does not hold are left alone. On failure the staging folder and the
    folders made for it (``target``, missing parents, and those the move made) are removed.
    The stage is locked while it is in use; one that SIGKILL left behind is removed by the
    next stage made in the same folder (:func:`remove_abandoned`).
    """
    target = Path(target).expanduser().resolve()
    made = [p for p in (target, *target.parents) if not p.exists()]  # deepest first
    # inside a folder that exists (its own file system, a mount point say, and writable even
    # where its parent is not); beside one still to be made, which will be on the parent's
    home = target if target.is_dir() else target.parent
    home.mkdir(parents=True, exist_ok=True)
    remove_abandoned(home)
    stage, lock = home / _PREFIX, -1  # none yet
    try:
        stage, lock = _locked_stage(home)
        yield stage
        with signals_held():
            target.mkdir(exist_ok=True)
            moves = []
            for source in sorted(stage.rglob("*")):  # each folder before its files
                moved = target / source.relative_to(stage)
                if not source.is_dir():
                    moves.append((source, moved))
                elif not moved.is_dir():
                    moved.mkdir()
                    made.insert(0, moved)  # deepest first
            _move_all(moves)
        shutil.rmtree(stage, ignore_errors=True)
    except BaseException:
        shutil.rmtree(stage, ignore_errors=True)
        for folder in made:
            with contextlib.suppress(OSError):
                folder.rmdir()
        raise
    finally:
        if lock >= 0:
            os.close(lock)  # after the stage is gone: no one removes a stage that is in use


#: Start of a staging folder's name; the host and process that made it follow.
_PREFIX = ".freefloat-stage-"
#: Start of the name of a folder that keeps the files a move replaces until it is done.
_KEPT = ".freefloat-previous-"


def _move_all(moves: list[tuple[Path, Path]]) -> None:
    """Rename each source file onto its destination (one file system): all, or none.

    Every destination is first checked to be a regular file or missing (a folder, a FIFO or
    a device there is refused before any rename). Each file a destination holds is kept
    in a hidden folder beside it (:data:`_KEPT`) by a hard link, so the destination is never
    missing (by a rename where the file system has no hard links). When a rename fails or
    the move is interrupted, every destination whose new file was moved in gets its previous
    file back, or loses the new one when it had none, and the error is raised again; what
    happened is read from the files themselves (a source gone was moved in), not from a
    record an interruption could cut short. The kept files go when the move is done.

    Raises:
        FileError: a destination that is not a regular file; or a rename failed and a file
            could not be put back either (named, with the folder that holds its previous
            content, and how many others stayed changed).
    """
    for _, destination in moves:
        if destination.is_dir() and not destination.is_symlink():
            raise FileError(f"cannot write {destination}: it is a folder", str(destination))
        check_replaceable(destination)
    kept: dict[Path, Path] = {}  # per destination's folder, its hidden folder
    done: list[tuple[Path, Path, Path | None]] = []  # source, destination, its kept file
    try:
        for source, destination in moves:
            previous = None
            if os.path.lexists(destination):
                folder = destination.parent
                if folder not in kept:
                    kept[folder] = Path(tempfile.mkdtemp(prefix=_KEPT, dir=folder))
                previous = kept[folder] / destination.name
            done.append((source, destination, previous))  # before anything moves
            if previous is not None:
                _keep(destination, previous)
            os.replace(source, destination)
    except BaseException:
        left = _put_back(done)
        if left:
            where = kept.get(left[0].parent)
            more = f" ({len(left) - 1} more too)" if len(left) > 1 else ""
            raise FileError(
                f"moving the new files in failed, and {left[0]} could not be put back{more}"
                + (f": its previous content is in {where}" if where else ""),
                str(left[0]),
            ) from None
        _remove_kept(kept)
        raise
    _remove_kept(kept)


def _keep(destination: Path, previous: Path) -> None:
    """Keep the destination's file at ``previous``: a hard link (itself, if a symbolic link).

    By a rename where the file system makes no hard links (the destination is then missing
    until the new file is moved in).
    """
    try:
        os.link(destination, previous, follow_symlinks=False)
    except OSError:
        os.replace(destination, previous)


def _put_back(done: list[tuple[Path, Path, Path | None]]) -> list[Path]:
    """Undo :func:`_move_all`'s renames, last first; the destinations that stay changed."""
    left = []
    for source, destination, previous in reversed(done):
        moved_in = not os.path.lexists(source)
        try:
            if previous is None:  # had no file: the new one goes
                if moved_in:
                    destination.unlink()
            elif os.path.lexists(previous):
                if moved_in or not os.path.lexists(destination):  # (renamed, not linked)
                    os.replace(previous, destination)
            elif moved_in:  # its kept file is gone
                left.append(destination)
        except OSError:
            left.append(destination)
    return left


def _remove_kept(kept: dict[Path, Path]) -> None:
    """Remove the hidden folders of :func:`_move_all`."""
    for folder in kept.values():
        shutil.rmtree(folder, ignore_errors=True)


def _host() -> str:
    """This host's name with every character but letters and digits as an underscore."""
    return "".join(c if c.isalnum() else "_" for c in socket.gethostname()) or "host"


def _locked_stage(home: Path) -> tuple[Path, int]:
    """A new staging folder in ``home`` and a descriptor holding its lock (:func:`_lock`).

    Made, then locked, then found still there: a cleanup that came between the two cannot
    have removed the stage this returns (the attempt is made again, at most
    :data:`_ATTEMPTS` times). Where folders cannot be locked, the stage is used unlocked and
    no cleanup ever removes it.

    Raises:
        FileError: no stage could be made and kept (every attempt removed at once).
    """
    for _ in range(_ATTEMPTS):
        stage = Path(tempfile.mkdtemp(prefix=f"{_PREFIX}{_host()}-{os.getpid()}-", dir=home))
        try:
            lock = os.open(stage, os.O_RDONLY)
        except FileNotFoundError:  # removed by a cleanup before it could be locked
            continue
        state = _lock(lock)
        kept = state != "held" and stage.is_dir()
        if kept and os.path.samestat(os.fstat(lock), os.stat(stage)):
            return stage, lock
        os.close(lock)
        shutil.rmtree(stage, ignore_errors=True)
    raise FileError(f"cannot keep a staging folder in {home}: each was removed at once", str(home))


#: Attempts of :func:`_locked_stage` at most (a count).
_ATTEMPTS = 8


def _lock(descriptor: int) -> str:
    """Try an exclusive lock on an open folder without waiting.

    ``"locked"``; ``"held"`` when another holds it; ``"unsupported"`` where folders cannot be
    locked (not POSIX, or a file system that refuses: NFS without locks, say). The kernel
    drops a lock when its holder ends, however it ends (SIGKILL too).
    """
    try:
        import fcntl
    except ImportError:  # not POSIX
        return "unsupported"
    try:
        fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:  # EWOULDBLOCK / EAGAIN: another holds it
        return "held"
    except OSError:
        return "unsupported"
    return "locked"


def remove_abandoned(folder: Path) -> list[Path]:
    """Remove the staging folders in ``folder`` that nothing holds; returns those removed.

    A process killed by SIGKILL leaves its stage, and its lock goes with it. A stage is kept
    while its lock is held (its maker runs, in any process namespace), when another host
    made it (a shared file system, whose locks may not reach here), and when its name does
    not say who made it (an older freefloat's). Nothing is removed where folders cannot be
    locked (not POSIX, or a file system that refuses locks).
    """
    removed: list[Path] = []
    if os.name != "posix":
        return removed
    here = f"{_PREFIX}{_host()}-"
    with contextlib.suppress(OSError):
        for stage in folder.glob(f"{here}*"):
            if not stage.name.removeprefix(here).split("-", 1)[0].isdigit():
                continue
            try:
                descriptor = os.open(stage, os.O_RDONLY | os.O_DIRECTORY)
            except OSError:
                continue
            try:
                if _lock(descriptor) == "locked":  # no one holds it, and we can tell
                    shutil.rmtree(stage, ignore_errors=True)
                    removed.append(stage)
            finally:
                os.close(descriptor)
    return removed


def write_together(texts: Mapping[Path, str]) -> Path:
    """Write text files (UTF-8) at once: each to a temporary file beside it, then all renamed.

    Their folders are made as needed. The renames happen while signals are held, all or none
    (:func:`_move_all`); on any failure (a full disk, an interruption before the renames, a
    rename that fails) none of the files is changed,
    no temporary file is left, and no folder made for them. Returns the last path written.

    Raises:
        FileError: a file that cannot be written, named.
    """
    temporary: dict[Path, Path] = {}
    path = Path()
    folders = {p.parent for p in texts}
    made = sorted({f for p in folders for f in (p, *p.parents) if not f.exists()}, reverse=True)
    try:
        for folder in folders:
            folder.mkdir(parents=True, exist_ok=True)
        for path, text in texts.items():
            with signals_held():
                fd, name = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
                temporary[path] = Path(name)
            with os.fdopen(fd, "w", encoding="utf-8") as handle:
                handle.write(text)
                handle.flush()
                os.fsync(handle.fileno())
            os.chmod(name, default_file_mode())
        with signals_held():
            _move_all([(name, path) for path, name in temporary.items()])
            temporary.clear()
            made.clear()  # written: the folders stay
    except OSError as exc:
        raise FileError(f"cannot write {path}: {exc.strerror or exc}", str(path)) from None
    finally:
        with signals_held():
            for name_path in temporary.values():
                name_path.unlink(missing_ok=True)
            for folder in made:  # deepest first; only those this call made
                with contextlib.suppress(OSError):
                    folder.rmdir()
    return path
