"""Running a sweep: local processes or a Dask cluster; CSV output written as jobs finish.

The output is one CSV row per job: ``index``, one column per axis (the axis key), then the
columns of :class:`SweepRow`. Rows are appended as jobs finish, one whole line per write, so
an interrupted run leaves complete rows (a torn last line is dropped on the next run). A
re-run with the same output skips the jobs whose rows are there (same index and axis values)
and, when every job has a row, rewrites the file sorted by index (atomically). The file is
then the same whatever the number of workers or the backend, except the timing columns
:data:`~freefloat.sweep.jobs.TIMING_COLUMNS`.
"""

from __future__ import annotations

import csv
import io
import math
import multiprocessing as mp
import os
import sys
import threading
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from contextlib import contextmanager
from dataclasses import fields
from pathlib import Path
from typing import Any

from ..errors import InputError, ScenarioError
from ..files import atomic_write_text
from ..progress import LOGGER
from ..verify.plan_checks import TOLERANCES
from .jobs import _ROBOTS, JobOutcome, SweepRow, run_job_collecting
from .replay import ReplayRow
from .spec import Job, SweepSpec

__all__ = ["connect", "read_rows", "row_class", "sweep"]


def _cell(value: Any) -> str:
    """CSV text of a value: floats round-trip exactly (shortest repr); None is empty."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    return str(value)


def row_class(spec: SweepSpec) -> type[SweepRow] | type[ReplayRow]:
    """The rows a sweep gives: :class:`SweepRow` (plans) or :class:`ReplayRow` (replays)."""
    return ReplayRow if spec.replay else SweepRow


Row = SweepRow | ReplayRow


def _header(spec: SweepSpec) -> list[str]:
    return ["index", *spec.keys, *row_class(spec).result_columns()]


def _line(cells: Sequence[str]) -> str:
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerow(cells)
    return buffer.getvalue()


def _row_cells(row: Row) -> list[str]:
    return [
        str(row.index),
        *(_cell(v) for v in row.values),
        *(_cell(getattr(row, name)) for name in row.result_columns()),
    ]


def _parse_row(cells: Sequence[str], job: Job, kind: type[Row], where: str) -> Row:
    """One row of a results file read back, each cell as the runner writes it.

    Raises:
        ScenarioError: a number that is not one (or not finite), a status the rows never
            have, or a planned row whose attitude error no plan has (the file was edited).
    """
    values: dict[str, Any] = {}
    for f, text in zip(fields(kind)[2:], cells, strict=True):
        if f.name in ("status", "message", "objective"):
            values[f.name] = text
            continue
        try:
            values[f.name] = float(text) if text else None
        except ValueError:
            values[f.name] = math.nan
        if values[f.name] is not None and not math.isfinite(values[f.name]):
            raise ScenarioError(f"{where}: {f.name} {text!r} is not a finite number{_EDITED}")
    row = kind(index=job.index, values=job.values, **values)
    if row.status not in kind.statuses:
        raise ScenarioError(
            f"{where}: status {row.status!r} is none of {', '.join(kind.statuses)}{_EDITED}"
        )
    error = row.attitude_error_rad
    if row.status == "planned" and (error is None or error > PLANNED_ATTITUDE_RAD):
        raise ScenarioError(
            f"{where}: a planned row whose attitude error {_text_of(error)} rad exceeds the "
            f"{PLANNED_ATTITUDE_RAD:g} rad every plan keeps{_EDITED}"
        )
    return row


#: The largest attitude error (rad) of a planned row: what verification holds a plan to.
PLANNED_ATTITUDE_RAD = TOLERANCES["attitude_independent_rad"]
_EDITED = " (an edited file?); choose another output file or delete it"


def _text_of(value: float | None) -> str:
    """A row's number as the file has it, or "none"."""
    return "none" if value is None else repr(value)


def read_rows(spec: SweepSpec, output: str | Path) -> dict[int, Row]:
    """The rows of an existing output file, by job index (resume); empty if there is none.

    Raises:
        ScenarioError: the file holds another sweep (other columns or job values).
    """
    path = Path(output)
    if not path.is_file():
        return {}
    text = path.read_text(encoding="utf-8-sig")  # a spreadsheet may have added a BOM
    if text and not text.endswith("\n"):  # a torn last line of an interrupted run
        text = text[: text.rfind("\n") + 1]
    lines = list(csv.reader(io.StringIO(text)))
    if not lines:
        return {}
    header = _header(spec)
    if lines[0] != header:
        raise ScenarioError(
            f"{path} holds another sweep (columns {', '.join(lines[0][:6])}...); choose another "
            "output file or delete it"
        )
    jobs = spec.jobs()
    rows: dict[int, Row] = {}
    n_axes = len(spec.axes)
    for number, cells in enumerate(lines[1:], start=2):
        if len(cells) != len(header) or not cells[0].isdigit() or int(cells[0]) >= len(jobs):
            raise ScenarioError(f"{path} line {number} is not a row of this sweep")
        job = jobs[int(cells[0])]
        if cells[1 : 1 + n_axes] != [_cell(v) for v in job.values]:
            raise ScenarioError(
                f"{path} line {number} has other axis values than job {job.index}; choose "
                "another output file or delete it"
            )
        where = f"{path} line {number}"
        rows[job.index] = _parse_row(cells[1 + n_axes :], job, row_class(spec), where)
    return rows


def write_rows(spec: SweepSpec, output: str | Path, rows: Sequence[Row]) -> Path:
    """Write the whole output file atomically, rows sorted by index."""
    text = _line(_header(spec)) + "".join(
        _line(_row_cells(r)) for r in sorted(rows, key=lambda r: r.index)
    )
    return atomic_write_text(output, text)


class _Appender:
    """Appends whole rows to the output file (one ``write`` per row, ``O_APPEND``)."""

    def __init__(self, spec: SweepSpec, path: Path, rows: dict[int, Row]) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        if not path.is_file() or not rows:
            write_rows(spec, path, [])
        else:  # drop a torn last line before appending
            write_rows(spec, path, list(rows.values()))
        self._fd = os.open(path, os.O_WRONLY | os.O_APPEND)

    def add(self, row: Row) -> None:
        os.write(self._fd, _line(_row_cells(row)).encode("utf-8"))

    def close(self) -> None:
        os.close(self._fd)


#: One BLAS thread per worker: the solvers' floating-point results depend on the number of
#: BLAS threads, so every worker (local or Dask, whose nanny sets the same) uses one; with one
#: process per core this is also the fastest.
BLAS_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def _init_worker() -> None:
    """Start a local worker process with an empty robot cache."""
    _ROBOTS.clear()


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
            max_workers=min(workers, len(jobs)), mp_context=context, initializer=_init_worker
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
    done = read_rows(spec, output) if output is not None else {}
    todo = [job for job in spec.jobs() if job.index not in done]
    rows = dict(done)
    appender = _Appender(spec, Path(output), done) if output is not None else None
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
        write_rows(spec, output, ordered)
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
