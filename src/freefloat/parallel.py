"""Independent tasks on forked worker processes, their results in task order.

:func:`run_tasks` calls ``task(i)`` for ``i = 0 .. count - 1`` and returns the results as a
list in that order, whether it ran them one after the other or on ``jobs`` worker processes.
The workers are *forked* from the caller once the caller has built what the tasks need (a
problem, a collision model): a child starts with a copy of that state, so nothing is pickled
but the task index going in and the result coming out, and nothing is imported again. A task
must therefore depend on its index and that state alone, not on what the other tasks did, for
the results to be the same as a serial run's (the callers test this).

The work runs serially, in the calling process, when ``jobs`` is 1, when there is one task,
on a platform other than Linux (no ``fork``; on macOS forking a process that has loaded system
frameworks is unsafe, and spawned workers would rebuild everything), inside a daemonic process
(a ``multiprocessing`` or Dask worker may not start children), and when not a single worker
can be started (out of processes or file descriptors: a warning is logged; fewer workers
than asked when some can). Each child runs BLAS on one
thread, ignores Ctrl-C (the caller handles it) and dies with SIGTERM. Whatever happens to the
caller (a task that raises, Ctrl-C, SIGTERM), every child is terminated and reaped before
:func:`run_tasks` returns or raises: none is left running or as a zombie.

A task that raises in a child raises the same exception type, message and attributes in the
caller (rebuilt without calling its ``__init__``; the child's traceback is added as a note).
A worker that dies (killed, or a crash in a library), while running a task or before it is
handed the next, is a :class:`WorkerError` of that task. When several tasks fail, the one
with the lowest index is raised, as a serial run would. On a terminal the children log
warnings only: their progress lines would break into the caller's progress bar (the caller
reports each task as it completes).
"""

from __future__ import annotations

import contextlib
import logging
import multiprocessing as mp
import numbers
import os
import pickle
import signal
import sys
import time
import traceback
from collections.abc import Callable, Sequence
from multiprocessing.connection import Connection, wait
from typing import Any, TypeVar

from ._blas import one_blas_thread
from .errors import FreeFloatError, InputLimitError
from .progress import LOGGER

__all__ = [
    "MAX_JOBS",
    "WorkerError",
    "check_jobs",
    "default_jobs",
    "run_tasks",
    "serial_reason",
    "usable_cores",
    "where_run",
]

#: Most worker processes a caller may ask for (``--jobs``).
MAX_JOBS = 1024

#: Time (s) idle workers get to leave before they are terminated (cleanup only; no result
#: depends on it).
LEAVE_S = 0.5

T = TypeVar("T")

#: The task of the children forked by the running :func:`run_tasks` (inherited, not pickled).
_TASK: list[Callable[[int], Any]] = []


class WorkerError(FreeFloatError):
    """A worker process ended without answering (killed, or crashed in a library).

    Attributes:
        task: the index of the task it was running.
        exitcode: its exit code (negative: the signal that ended it), or None.
    """

    def __init__(self, task: int, exitcode: int | None) -> None:
        self.task = task
        self.exitcode = exitcode
        super().__init__(
            f"a worker process ended (exit code {exitcode}) at task {task}; "
            "--jobs 1 runs every task in this process"
        )


def check_jobs(jobs: object, name: str = "jobs") -> None:
    """Refuse a ``jobs`` that is neither None (the default) nor a whole number 1..MAX_JOBS.

    Raises:
        InputLimitError: naming ``name`` (``"--jobs"`` on the command line).
    """
    if jobs is None:
        return
    whole = isinstance(jobs, numbers.Integral) and not isinstance(jobs, bool)
    if not whole or not 1 <= int(jobs) <= MAX_JOBS:  # type: ignore[call-overload]
        why = "" if whole else "a whole number of worker processes"
        raise InputLimitError(name, jobs, 1, MAX_JOBS, why=why)


def usable_cores() -> int:
    """The cores this process may run on (its CPU affinity where known), at least 1."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


def default_jobs(count: int) -> int:
    """Worker processes for ``count`` tasks by default: the usable cores, at most ``count``."""
    return max(1, min(usable_cores(), count))


def serial_reason(jobs: int, count: int) -> str:
    """Why :func:`run_tasks` would run ``count`` tasks serially with ``jobs`` ("" if not)."""
    if jobs <= 1:
        return "one job asked"
    if count <= 1:
        return "one task"
    if not sys.platform.startswith("linux") or "fork" not in mp.get_all_start_methods():
        return "workers are forked on Linux only"
    if mp.current_process().daemon:
        return "a daemonic process cannot start workers"
    return ""


def where_run(jobs: int, count: int) -> str:
    """How :func:`run_tasks` runs ``count`` tasks with ``jobs``, for a log line.

    ``"on 2 worker processes"`` or ``"serially (one job asked)"``.
    """
    why = serial_reason(jobs, count)
    return f"serially ({why})" if why else f"on {min(jobs, count)} worker processes"


def run_tasks(
    task: Callable[[int], T],
    count: int,
    jobs: int = 1,
    done: Callable[[int, T], None] | None = None,
) -> list[T]:
    """``[task(0), ..., task(count - 1)]``, on up to ``jobs`` forked worker processes.

    Args:
        task: called with a task index; its result must pickle (numbers, arrays, dataclasses).
        count: the number of tasks.
        jobs: worker processes (1: serially in this process; see the module for the others).
        done: called in this process with ``(index, result)`` as each task finishes, in the
            order they finish (index order when serial).

    Raises:
        WorkerError: a worker process ended without answering.
        Exception: what the task with the lowest index among those that raised raised.
    """
    if serial_reason(jobs, count):
        return _serially(task, count, done)
    if _TASK:
        raise RuntimeError("run_tasks is already running in this process")
    _TASK.append(task)
    for stream in (sys.stdout, sys.stderr):  # not copied into the children's buffers
        if stream is not None:
            stream.flush()
    context = mp.get_context("fork")
    workers: list[tuple[Any, Connection]] = []
    try:
        for _ in range(min(jobs, count)):
            try:
                workers.append(_started(context))
            except OSError as exc:  # out of processes or file descriptors: fewer workers
                LOGGER.warning("%d worker processes started of %d: %s", len(workers), jobs, exc)
                break
        if workers:
            return _collect(workers, count, done)
    finally:
        _TASK.clear()
        _stop(workers)
    return _serially(task, count, done)


def _serially(
    task: Callable[[int], T], count: int, done: Callable[[int, T], None] | None
) -> list[T]:
    """The tasks one after the other in this process."""
    results = []
    for index in range(count):
        results.append(task(index))
        if done is not None:
            done(index, results[-1])
    return results


def _started(context: Any) -> tuple[Any, Connection]:
    """A forked worker and our end of its pipe."""
    ours, theirs = context.Pipe()
    try:
        process = context.Process(target=_serve, args=(theirs,), daemon=True)
        process.start()
    except OSError:
        ours.close()
        raise
    finally:
        theirs.close()
    return process, ours


def _collect(
    workers: Sequence[tuple[Any, Connection]],
    count: int,
    done: Callable[[int, Any], None] | None,
) -> list[Any]:
    """Hand out the task indices in order, one at a time per worker; gather the answers.

    A worker that dies (while running a task, or before it is handed the next) counts as a
    failure of that task, under the same lowest-index rule as a task that raises.
    """
    results: list[Any] = [None] * count
    running: dict[int, int] = {}  # worker number -> task index
    failed: tuple[int, BaseException] | None = None
    following = 0

    def hand_out(number: int) -> tuple[int, BaseException] | None:
        nonlocal following
        process, connection = workers[number]
        index, following = following, following + 1
        try:
            connection.send(index)
        except OSError:  # it died after its last answer
            process.join()
            return _first(failed, index, WorkerError(index, process.exitcode))
        running[number] = index
        return failed

    for number in range(len(workers)):
        failed = hand_out(number)
    while running:
        ready = set(wait([o for n in running for o in (workers[n][1], workers[n][0].sentinel)]))
        for number in [n for n in running if ready & {workers[n][1], workers[n][0].sentinel}]:
            process, connection = workers[number]
            index = running.pop(number)
            try:
                ok, payload = connection.recv()
            except (EOFError, OSError):
                process.join()
                failed = _first(failed, index, WorkerError(index, process.exitcode))
                continue
            if not ok:
                failed = _first(failed, index, _rebuilt(payload))
            elif failed is None:
                results[index] = payload
                if done is not None:
                    done(index, payload)
            if following < count and failed is None:
                failed = hand_out(number)
        if failed is not None and all(i > failed[0] for i in running.values()):
            raise failed[1]  # the tasks still running come after it: a serial run never ran them
    if failed is not None:
        raise failed[1]
    return results


def _first(
    failed: tuple[int, BaseException] | None, index: int, error: BaseException
) -> tuple[int, BaseException]:
    """The failure with the lower task index: ``failed`` or task ``index``'s ``error``."""
    return (index, error) if failed is None or index < failed[0] else failed


def _stop(workers: Sequence[tuple[Any, Connection]]) -> None:
    """End and reap every worker: asked to leave, then SIGTERM, then SIGKILL."""
    for _, connection in workers:
        with contextlib.suppress(OSError):
            connection.send(None)
        connection.close()
    deadline = time.monotonic() + LEAVE_S
    for process, _ in workers:
        process.join(timeout=max(0.0, deadline - time.monotonic()))
        if process.is_alive():
            process.terminate()
            process.join(timeout=2.0)
        if process.is_alive():
            process.kill()
            process.join()
        process.close()


def _serve(connection: Connection) -> None:
    """A worker: answer task indices with ``(True, result)`` or ``(False, error)`` until told."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the caller handles Ctrl-C and ends us
    for name in ("SIGTERM", "SIGHUP"):
        if hasattr(signal, name):
            signal.signal(getattr(signal, name), signal.SIG_DFL)
    # Fresh standard streams: a thread of the caller (a progress display) may have held the
    # inherited ones' locks at the fork.
    sys.stdout = open(1, "w", buffering=1, closefd=False)  # noqa: SIM115
    sys.stderr = open(2, "w", buffering=1, closefd=False)  # noqa: SIM115
    if sys.stderr.isatty():  # the caller's progress bar owns the terminal: warnings only
        LOGGER.setLevel(max(LOGGER.getEffectiveLevel(), logging.WARNING))
    (task,) = _TASK
    with one_blas_thread():
        while True:
            try:
                index = connection.recv()
            except (EOFError, OSError):  # the caller is gone
                return
            if index is None:
                return
            try:
                connection.send((True, task(index)))
            except Exception as exc:  # the task's, or its result does not pickle
                connection.send((False, _portable(exc)))


def _portable(exc: Exception) -> tuple[type, tuple, dict[str, Any], str]:
    """An exception as (type, args, attributes, traceback text) for the caller.

    A RuntimeError with the same text when it cannot cross (an unpicklable type or attribute).
    """
    text = "".join(traceback.format_exception(exc))
    state = {k: v for k, v in vars(exc).items() if k != "__notes__"}
    payload = (type(exc), exc.args, state, text)
    try:
        pickle.loads(pickle.dumps(payload))
    except Exception:
        return (RuntimeError, (f"{type(exc).__name__}: {exc}",), {}, text)
    return payload


def _rebuilt(payload: tuple[type, tuple, dict[str, Any], str]) -> BaseException:
    """The exception :func:`_portable` described, its ``__init__`` not called again."""
    kind, args, state, text = payload
    exc = kind.__new__(kind, *args)
    exc.args = args
    exc.__dict__.update(state)
    exc.add_note(f"raised in a worker process:\n{text.rstrip()}")
    return exc
