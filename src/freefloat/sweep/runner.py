"""Running a sweep: local processes or a Dask cluster; CSV output written as jobs finish.

The output is one CSV row per job (:mod:`.results`). Rows are appended as jobs finish, one
whole line per write, so
an interrupted run leaves complete rows (a torn last line is dropped on the next run). A
re-run with the same output skips the jobs whose rows are there (same index and axis values)
and, when every job has a row, rewrites the file sorted by index (atomically). The file is
then the same whatever the number of workers or the backend, except the timing columns
:data:`~freefloat.sweep.jobs.TIMING_COLUMNS`.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from ..errors import InputError
from ..progress import LOGGER
from .jobs import _ROBOTS, JobOutcome, run_job_collecting
from .results import Appender, Row, inputs_digest, read_rows, write_rows
from .spec import Job, SweepSpec

__all__ = ["BLAS_ENV", "HANDSHAKE_GRACE", "connect", "sweep"]


#: One BLAS thread per worker: the solvers' floating-point results depend on the number of
#: BLAS threads, so every worker (local or Dask, whose nanny sets the same) uses one; with one
#: process per core this is also the fastest.
BLAS_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def _init_worker(parent: int) -> None:
    """Start a local worker process with an empty robot cache, watching the sweep's process.

    ``parent``: the process running the sweep. A worker's own parent is the fork server, which
    outlives a sweep killed outright (SIGKILL, which nothing can catch): the worker would
    finish its job and wait for the next for ever. It leaves when the sweep's process is gone.
    """
    _ROBOTS.clear()
    if os.name == "posix":  # signal 0 probes a process there (elsewhere it is a Ctrl-C)
        threading.Thread(
            target=_leave_with, args=(parent,), name="freefloat-watch", daemon=True
        ).start()


def _leave_with(parent: int, every: float = 1.0) -> None:
    """Exit this worker (status 1) once process ``parent`` is gone; poll every ``every`` s."""
    while True:
        time.sleep(every)
        try:
            os.kill(parent, 0)
        except ProcessLookupError:
            os._exit(1)
        except PermissionError:  # there, but not ours to signal (a sandbox): still alive
            continue
        if _zombie(parent):  # killed and not yet reaped by its own parent
            os._exit(1)


def _zombie(pid: int) -> bool:
    """Whether process ``pid`` has ended and waits to be reaped (Linux's /proc; else False)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "Z"
    except (OSError, IndexError):
        return False


@contextmanager
def _blas_env() -> Iterator[None]:
    """Set :data:`BLAS_ENV` while worker processes start (they read it when numpy loads)."""
    saved = {k: os.environ.get(k) for k in BLAS_ENV}
    os.environ.update(BLAS_ENV)
    try:
        yield
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


def _local(jobs: Sequence[Job], workers: int) -> Iterator[JobOutcome]:
    """Run the jobs on fresh worker processes (forkserver, else spawn); rows as they finish.

    Even one worker is a separate process, so that no state of the caller (its BLAS threads,
    loaded robots) changes a result.
    """
    if not jobs:
        return
    method = "forkserver" if "forkserver" in mp.get_all_start_methods() else "spawn"
    context = mp.get_context(method)
    if method == "forkserver":
        context.set_forkserver_preload(["freefloat.sweep.jobs"])
    with _blas_env():
        pool = ProcessPoolExecutor(
            max_workers=min(workers, len(jobs)),
            mp_context=context,
            initializer=_init_worker,
            initargs=(os.getpid(),),
        )
        futures = [pool.submit(run_job_collecting, job) for job in jobs]
    try:
        for future in as_completed(futures):
            yield future.result()
    finally:
        for future in futures:
            future.cancel()
        pool.shutdown(wait=True, cancel_futures=True)


def _worker_env() -> dict[str, str | None]:
    return {k: os.environ.get(k) for k in BLAS_ENV}


def _check_dask(client: Any) -> None:
    """Refuse Dask workers that do not run with :data:`BLAS_ENV` or run several threads.

    A worker process keeps one collision model per robot and its last distances (the bound of
    which pairs can be the closest): jobs in two threads of one process would share them.
    """
    workers = client.scheduler_info().get("workers", {})
    for address, info in workers.items():
        threads = info.get("nthreads", 1)
        if threads != 1:
            raise InputError(
                f"Dask worker {address} runs {threads} threads; freefloat needs one thread per "
                "worker process (`dask worker ... --nthreads 1`, or LocalCluster("
                "threads_per_worker=1))"
            )
    for address, env in client.run(_worker_env).items():
        if env != BLAS_ENV:
            raise InputError(
                f"Dask worker {address} does not run with one BLAS thread ({env}); start "
                "workers with their nanny (the default of `dask worker`) or with "
                + " ".join(f"{k}=1" for k in BLAS_ENV)
            )


def _dask(jobs: Sequence[Job], client: Any) -> Iterator[JobOutcome]:
    from distributed import as_completed as dask_completed

    futures = client.map(run_job_collecting, list(jobs), pure=False)
    try:
        for future in dask_completed(futures):
            yield future.result()
    finally:
        client.cancel(futures)


def connect(address: str, timeout: float = 10.0) -> Any:
    """A Dask ``distributed.Client`` connected to the scheduler at ``address``.

    Raises:
        InputError: Dask is not installed (``pip install 'freefloat[cluster]'``) or the
            scheduler does not answer within ``timeout`` (s).
    """
    try:
        from distributed import Client
    except ImportError:
        raise InputError(
            "--scheduler needs Dask distributed: pip install 'freefloat[cluster]'"
        ) from None
    outcome: dict[str, Any] = {}
    lock = threading.Lock()

    def attempt() -> None:
        try:
            client = Client(address, timeout=timeout)
        except Exception as exc:  # whatever the far end did (garbage read as a message
            outcome["error"] = exc  # length gives a MemoryError), it is named below
            return
        with lock:
            if outcome.get("abandoned"):  # answered after the caller gave up: not leaked
                client.close()
            else:
                outcome["client"] = client

    # Dask's timeout covers the connection, not its handshake: a server that accepts and then
    # says nothing (a web server, say) would hold the call for ever
    thread = threading.Thread(target=attempt, name="freefloat-connect", daemon=True)
    thread.start()
    thread.join(timeout + HANDSHAKE_GRACE)
    with lock:
        outcome["abandoned"] = True
        if "client" in outcome:
            return outcome["client"]
    reason = outcome.get("error") or TimeoutError(
        f"no Dask handshake within {timeout + HANDSHAKE_GRACE:g} s (is it a Dask scheduler?)"
    )
    raise InputError(f"cannot connect to the Dask scheduler {address!r}: {reason}")


#: Seconds beyond the connection timeout that the scheduler's handshake may take.
HANDSHAKE_GRACE = 5.0


def sweep(
    spec: SweepSpec | str | Path,
    workers: int | None = None,
    client: Any = None,
    output: str | Path | None = None,
    progress: bool | None = None,
    on_row: Callable[[Row], None] | None = None,
) -> list[Row]:
    """Run every job of a sweep; return the rows sorted by job index.

    Args:
        spec: a :class:`SweepSpec` or the path of a sweep file.
        workers: local worker processes (default: all cores), each with one BLAS thread.
            Ignored with ``client``.
        client: a Dask ``distributed.Client``; the jobs run on its cluster.
        output: CSV file written as jobs finish; rows already there are kept (resume).
        progress: a progress bar on stderr; default: only when stderr is a terminal.
        on_row: called with each new row as it finishes.

    Raises:
        FreeFloatError: a bad sweep or output file (before any job runs). Jobs never raise:
            a failed job is a row with status ``failed``.
    """
    if not isinstance(spec, SweepSpec):
        spec = SweepSpec.from_toml(spec)
    if workers is None:
        workers = os.cpu_count() or 1
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InputError(f"workers must be an integer >= 1, got {workers!r}")
    if client is not None:
        _check_dask(client)
    inputs = inputs_digest(spec) if output is not None else ""  # loads the robot: once
    done = read_rows(spec, output, inputs) if output is not None else {}
    todo = [job for job in spec.jobs() if job.index not in done]
    rows = dict(done)
    appender = Appender(spec, Path(output), done, inputs) if output is not None else None
    show = sys.stderr.isatty() if progress is None else progress
    from tqdm import tqdm

    bar = tqdm(
        total=spec.size, initial=len(done), disable=not show, unit="job", desc="sweep", leave=True
    )
    try:
        stream = _dask(todo, client) if client is not None else _local(todo, workers)
        said: set[str] = set()
        for outcome in stream:
            for message in outcome.warnings:  # each distinct warning once per sweep
                if message not in said:
                    said.add(message)
                    LOGGER.warning("%s", message)
            row = outcome.row
            rows[row.index] = row
            if appender is not None:
                appender.add(row)
            if on_row is not None:
                on_row(row)
            bar.update(1)
    finally:
        bar.close()
        if appender is not None:
            appender.close()
    ordered = [rows[i] for i in sorted(rows)]
    if output is not None:
        write_rows(spec, output, ordered, inputs)
    _warn_spun(ordered)
    return ordered


def _warn_spun(rows: Sequence[Row]) -> None:
    """Say once for the whole sweep which planned jobs turn a joint a full turn or more.

    Each job's plan would warn of it with its own figures (a line per job); the rows carry
    them in ``largest_excursion_deg`` (deg).
    """
    spun = [
        (row.index, excursion / 360.0)
        for row in rows
        if (excursion := getattr(row, "largest_excursion_deg", None)) is not None
        and excursion >= 360.0
    ]
    if not spun:
        return
    shown = ", ".join(str(index) for index, _ in spun[:10]) + (", ..." if len(spun) > 10 else "")
    LOGGER.warning(
        "%d planned job(s) turn a joint a full turn or more beyond its start-goal span (jobs "
        "%s; at most %.3g turns; column largest_excursion_deg): if the real joints cannot turn "
        "freely (cables, hard stops), give them limits in the URDF",
        len(spun),
        shown,
        max(turns for _, turns in spun),
    )
