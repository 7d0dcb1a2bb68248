"""Tasks on forked worker processes (freefloat.parallel): order, errors, cleanup, fallbacks."""

from __future__ import annotations

import multiprocessing as mp
import os
import signal
import time
from pathlib import Path

import pytest

import freefloat as ff
from freefloat import parallel
from freefloat.errors import CollisionError
from freefloat.parallel import WorkerError, check_jobs, run_tasks, serial_reason


def _children() -> list[tuple[int, str]]:
    """(pid, state) of every process whose parent is this one, read from /proc (zombies too)."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:  # ended meanwhile
            continue
        fields = stat[stat.rindex(")") + 2 :].split()  # after "pid (name) "
        if int(fields[1]) == os.getpid():
            found.append((int(entry.name), fields[0]))
    return found


@pytest.fixture
def new_children():
    """A function listing the children (pid, state) started since the test began."""
    before = {pid for pid, _ in _children()}
    return lambda: [(pid, state) for pid, state in _children() if pid not in before]


needs_fork = pytest.mark.skipif(
    parallel.serial_reason(2, 2) != "" or not Path("/proc").is_dir(),
    reason="forked workers and /proc (Linux)",
)


@needs_fork
def test_results_come_in_task_order_from_other_processes(new_children) -> None:
    finished: list[int] = []

    def task(i: int) -> tuple[int, int]:
        time.sleep(0.05 * (i % 3))  # finishing out of order; no result depends on it
        return i * i, os.getpid()

    results = run_tasks(task, 7, jobs=2, done=lambda i, r: finished.append(i))
    assert [r[0] for r in results] == [i * i for i in range(7)]
    pids = {r[1] for r in results}
    assert os.getpid() not in pids and len(pids) == 2  # two workers, none of them us
    assert sorted(finished) == list(range(7))
    assert not new_children()


def test_one_job_runs_in_this_process_in_order() -> None:
    finished: list[int] = []
    results = run_tasks(lambda i: (i, os.getpid()), 4, jobs=1, done=lambda i, r: finished.append(i))
    assert results == [(i, os.getpid()) for i in range(4)] and finished == [0, 1, 2, 3]


@needs_fork
def test_the_lowest_failing_task_raises_its_own_error_and_no_worker_is_left(new_children) -> None:
    """Tasks 1 and 4 raise; 4 finishes first, yet task 1's error is raised, as serially."""

    def task(i: int) -> int:
        if i == 1:
            time.sleep(0.3)
            raise CollisionError("t = 1 s", "link_a / link_b", -0.01, 0.02)
        if i == 4:
            raise CollisionError("t = 4 s", "link_c / link_d", -0.04, 0.02)
        return i

    with pytest.raises(CollisionError) as info:
        run_tasks(task, 8, jobs=3)
    with pytest.raises(CollisionError) as serial:
        run_tasks(task, 8, 1)
    assert str(info.value) == str(serial.value) and "t = 1 s" in str(info.value)
    assert vars(info.value) == {**vars(serial.value), "__notes__": info.value.__notes__}
    assert "raised in a worker process" in info.value.__notes__[0]
    assert not new_children()


@needs_fork
def test_an_error_that_cannot_cross_becomes_a_runtime_error_with_its_text(new_children) -> None:
    class LocalError(Exception):  # a local class does not pickle
        pass

    def task(i: int) -> int:
        if i == 2:
            raise LocalError("only here")
        return i

    with pytest.raises(RuntimeError) as info:
        run_tasks(task, 4, jobs=2)
    assert str(info.value) == "LocalError: only here"
    with pytest.raises(Exception, match="pickle"):  # a result that does not pickle
        run_tasks(lambda i: lambda: i, 3, jobs=2)
    assert not new_children()


@needs_fork
def test_a_worker_that_dies_is_a_worker_error_and_the_others_are_reaped(new_children) -> None:
    def task(i: int) -> int:
        if i == 3:
            os.kill(os.getpid(), signal.SIGKILL)
        time.sleep(0.05)
        return i

    with pytest.raises(WorkerError) as info:
        run_tasks(task, 10, jobs=2)
    assert info.value.task == 3 and info.value.exitcode == -signal.SIGKILL
    assert isinstance(info.value, ff.FreeFloatError)
    assert not new_children()


@needs_fork
def test_a_worker_that_dies_between_tasks_is_a_worker_error(new_children) -> None:
    """A worker killed after its answer, before it is handed the next task: the hand-out
    fails, and that is a WorkerError naming the task (not a broken pipe)."""
    import threading

    def task(i: int) -> int:
        if i == 0:  # answer, then die while the caller is still busy with the answer
            threading.Timer(0.1, lambda: os.kill(os.getpid(), signal.SIGKILL)).start()
        return i

    with pytest.raises(WorkerError) as info:
        run_tasks(task, 4, jobs=2, done=lambda i, r: time.sleep(0.3))
    assert info.value.exitcode == -signal.SIGKILL
    assert info.value.task in (2, 3)  # the task it would have been handed next
    assert str(info.value) == (
        f"a worker process ended (exit code -9) at task {info.value.task}; --jobs 1 runs "
        "every task in this process"
    )
    assert not new_children()


@needs_fork
def test_a_lower_task_error_wins_over_a_later_worker_death(new_children) -> None:
    """Task 0 raises slowly while task 1's worker dies at once: task 0's error is raised, as
    a serial run would raise it."""

    def task(i: int) -> int:
        if i == 0:
            time.sleep(0.3)
            raise CollisionError("start", "a / b", 0.001, 0.01)
        if i == 1:
            os.kill(os.getpid(), signal.SIGKILL)
        return i

    with pytest.raises(CollisionError):
        run_tasks(task, 4, jobs=2)
    assert not new_children()


@needs_fork
def test_ctrl_c_in_the_caller_ends_every_worker_and_workers_ignore_it(new_children) -> None:
    handlers = run_tasks(lambda i: signal.getsignal(signal.SIGINT) is signal.SIG_IGN, 2, jobs=2)
    assert handlers == [True, True]

    def interrupted(i: int, result: int) -> None:
        raise KeyboardInterrupt

    def slow(i: int) -> int:
        time.sleep(0.2 if i == 0 else 30.0)  # the second would outlast the test if left
        return i

    clock = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        run_tasks(slow, 4, jobs=2, done=interrupted)
    assert time.perf_counter() - clock < 10.0  # the busy worker was terminated, not awaited
    assert not new_children()


@needs_fork
def test_serial_where_workers_cannot_be_forked(monkeypatch) -> None:
    assert serial_reason(2, 1) == "one task" and serial_reason(1, 5) == "one job asked"
    assert serial_reason(2, 5) == ""
    assert parallel.where_run(8, 3) == "on 3 worker processes"  # at most one per task
    assert parallel.where_run(1, 3) == "serially (one job asked)"
    context = mp.get_context("fork")
    answer = context.Queue()

    def inside_a_daemon() -> None:
        pids = {pid for pid in run_tasks(lambda i: os.getpid(), 3, jobs=2)}
        answer.put((serial_reason(2, 3), pids == {os.getpid()}))

    daemon = context.Process(target=inside_a_daemon, daemon=True)
    daemon.start()
    why, in_itself = answer.get(timeout=60)
    daemon.join()
    assert why == "a daemonic process cannot start workers" and in_itself
    monkeypatch.setattr(parallel.sys, "platform", "darwin")
    assert serial_reason(2, 3) == "workers are forked on Linux only"
    assert {pid for pid in run_tasks(lambda i: os.getpid(), 3, jobs=2)} == {os.getpid()}


@needs_fork
def test_when_no_worker_can_start_the_tasks_run_here(monkeypatch, new_children) -> None:
    def refused(context):
        raise OSError(11, "Resource temporarily unavailable")

    warned: list[str] = []
    monkeypatch.setattr(parallel, "_started", refused)
    monkeypatch.setattr(parallel.LOGGER, "warning", lambda text, *args: warned.append(text % args))
    assert run_tasks(lambda i: (i, os.getpid()), 3, jobs=2) == [(i, os.getpid()) for i in range(3)]
    assert warned == [
        "0 worker processes started of 2: [Errno 11] Resource temporarily unavailable"
    ]
    assert not new_children()


def test_jobs_are_checked_in_one_line() -> None:
    check_jobs(None)
    check_jobs(1)
    for bad, text in (
        (0, "jobs = 0 is outside the supported range [1, 1024]"),
        (1025, "--jobs = 1025 is outside the supported range [1, 1024]"),
        (2.5, "jobs = 2.5 is outside the supported range [1, 1024]; a whole number of worker"),
        (True, "jobs = True is outside the supported range [1, 1024]; a whole number"),
    ):
        with pytest.raises(ff.InputLimitError) as info:
            check_jobs(bad, "--jobs" if bad == 1025 else "jobs")
        assert str(info.value).startswith(text) and "\n" not in str(info.value)


def test_default_jobs_are_the_usable_cores_at_most_one_per_task() -> None:
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    assert parallel.usable_cores() == cores
    assert parallel.default_jobs(1) == 1
    assert parallel.default_jobs(1000) == cores
