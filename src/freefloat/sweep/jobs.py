"""One sweep job: plan one scenario of the sweep and reduce the outcome to a :class:`SweepRow`.

:func:`run_job` never raises: a refused or failed plan is a row with its status and the
one-line message. Each process keeps the robots it has loaded (:data:`_ROBOTS`), so that the
per-robot work (model, planar bounds, identified planar map) is done once per worker.
"""

from __future__ import annotations

import json
import logging
import math
import threading
import time
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from typing import Any, ClassVar

import numpy as np

from ..errors import FreeFloatError, InfeasibleError, UnitsWarning
from ..physics.turn_track import quaternion_turn
from ..pipeline import SPIN_WARNING, plan
from ..plans.format import Plan
from ..problem.constraints.attitude_check import attitude_track
from ..problem.scenario import Scenario
from ..progress import LOGGER
from ..robot.model import Robot
from ..robust.inertial import perturbed_robot
from .replay import ReplayRow, run_replay_job
from .spec import Job, Value

__all__ = ["STATUSES", "TIMING_COLUMNS", "JobOutcome", "SweepRow", "run_job", "run_job_collecting"]

#: The outcomes of a job.
STATUSES = ("planned", "infeasible", "failed")

#: Columns that measure time: they change from run to run and are not part of a sweep's result
#: (:meth:`SweepRow.without_timings` clears them).
TIMING_COLUMNS = ("solve_time_s", "total_time_s")

#: Robots loaded by this process, by their scenario definition (robot, end effector, folder).
_ROBOTS: dict[str, Robot] = {}


@dataclass(frozen=True)
class SweepRow:
    """The outcome of one job (one CSV row).

    Attributes:
        index: the job's position in the product of the axes.
        values: one value per axis, in the scenario file's units (degrees for angles).
        status: ``planned``, ``infeasible`` (outside the planar bounds) or ``failed``.
        attitude_error_rad: angle between achieved and goal attitude (rad); planned only.
        free_parameter_norm: Euclidean norm of all free coefficients (rad): the RMS deviation
            of the joint paths from the quintic (docs/paths.md).
        path_length: summed joint travel of the chosen path (rad, plus m for prismatic).
        peak_torque: largest joint torque magnitude along the samples (N m, or N).
        largest_excursion_deg: the farthest a turning joint goes beyond the interval between
            its start and goal values (deg, from the exact extremes; 360 and more: a full turn
            or more, which the sweep warns of once for all its jobs); planned only.
        largest_turn_deg: the largest turn of the spacecraft from its start attitude on the
            way (deg; the dense, independent integration of the base_swing check, refined in
            time: never a sample's); planned only.
        objective: what the path minimises (``min_norm``, ``min_effort`` ...); planned only.
        objective_value: its value along the plan (the objective's unit, e.g. N^2 m^2 s).
        requested_yaw_change_deg: planar robots: the requested base yaw change (deg).
        yaw_change_min_deg: planar robots: lower end of the reachable interval (deg).
        yaw_change_max_deg: planar robots: upper end of the reachable interval (deg).
        solve_time_s: solver wall time (s); a timing, not part of the result.
        total_time_s: wall time of the whole job (s); a timing, not part of the result.
        message: the one-line message of a refusal or failure; empty when planned.
    """

    #: the statuses a row can have
    statuses: ClassVar[tuple[str, ...]] = STATUSES

    index: int
    values: tuple[Value, ...]
    status: str
    attitude_error_rad: float | None = None
    free_parameter_norm: float | None = None
    path_length: float | None = None
    peak_torque: float | None = None
    largest_excursion_deg: float | None = None
    largest_turn_deg: float | None = None
    objective: str = ""
    objective_value: float | None = None
    requested_yaw_change_deg: float | None = None
    yaw_change_min_deg: float | None = None
    yaw_change_max_deg: float | None = None
    solve_time_s: float | None = None
    total_time_s: float | None = None
    message: str = ""

    @staticmethod
    def result_columns() -> tuple[str, ...]:
        """The CSV columns after the axis values, in order."""
        return tuple(f.name for f in fields(SweepRow) if f.name not in ("index", "values"))

    def without_timings(self) -> SweepRow:
        """This row with its timing columns cleared (for comparing runs)."""
        return replace(self, solve_time_s=None, total_time_s=None)


def _one_line(text: str) -> str:
    return " ".join(text.split())


def _robot_key(data: Mapping[str, Any], job: Job) -> str:
    goal = data.get("goal")
    frames = goal.get("end_effectors") if isinstance(goal, Mapping) else None
    robot = data.get("robot")
    locked_at_start = isinstance(robot, Mapping) and "lock" in robot  # start values lock joints
    return json.dumps(
        [
            robot,
            data.get("end_effector"),
            data.get("end_effectors"),
            sorted(frames) if isinstance(frames, Mapping) else None,
            data.get("start") if locked_at_start else None,
            data.get("payload"),
            str(job.relative_to),
        ],
        sort_keys=True,
        default=str,
    )


def _scenario(job: Job) -> Scenario:
    """The job's scenario, on this process's copy of its robot."""
    key = _robot_key(job.data, job)
    scenario = Scenario.from_dict(
        job.data, relative_to=job.relative_to, source=job.source, known=_ROBOTS.get(key)
    )
    robot = _ROBOTS.setdefault(key, scenario.robot)
    return scenario if robot is scenario.robot else replace(scenario, robot=robot)


def _planned(job: Job, result: Plan, robot: Robot, started: float) -> SweepRow:
    free = [c for values in result.free_parameters.values() for c in values]
    chosen = [
        s.path_length
        for s in result.solver.solutions
        if s.free_parameters == result.free_parameters
    ]
    lengths = chosen or [s.path_length for s in result.solver.solutions]
    tau = np.asarray(result.samples.tau, dtype=float)
    feasibility = result.feasibility
    bounds = feasibility.yaw_change_bounds_deg
    return SweepRow(
        index=job.index,
        values=job.values,
        status="planned",
        attitude_error_rad=float(result.base.attitude_error_rad),
        free_parameter_norm=float(math.sqrt(sum(c * c for c in free))),
        path_length=float(lengths[0]) if lengths else None,
        peak_torque=float(np.max(np.abs(tau))) if tau.size else None,
        largest_excursion_deg=_turning_excursion(result),
        largest_turn_deg=_largest_turn(result, robot),
        objective=result.objective.name,
        objective_value=result.objective.value,
        requested_yaw_change_deg=feasibility.requested_yaw_change_deg,
        yaw_change_min_deg=None if bounds is None else float(bounds[0]),
        yaw_change_max_deg=None if bounds is None else float(bounds[1]),
        solve_time_s=float(result.solver.wall_time_s),
        total_time_s=time.perf_counter() - started,
    )


def _largest_turn(result: Plan, robot: Robot) -> float | None:
    """The spacecraft's largest turn from its start attitude along the plan (deg), or None.

    :func:`~freefloat.problem.constraints.attitude_check.attitude_track`: Pinocchio's
    centroidal map integrated by RK5 on doubling grids, its largest peaks refined in time (a
    few ms, against a plan's hundreds), as the ``base_swing`` check finds it. None (an empty
    cell) when that fails or overflows: a statistic of a verified plan, never its refusal.
    """
    try:
        largest = attitude_track(robot, result.path()).largest(quaternion_turn)
    except (FreeFloatError, ArithmeticError, ValueError, np.linalg.LinAlgError):
        return None
    return math.degrees(largest.value) if math.isfinite(largest.value) else None


def _turning_excursion(result: Plan) -> float | None:
    """The largest excursion beyond its span of a turning joint (deg); None if none is known."""
    if result.quality is None:
        return None
    kinds = dict(zip(result.robot.joints, result.robot.joint_kinds, strict=False))
    beyond = [
        value
        for name, value in result.quality.excursion_beyond_span.items()
        if kinds.get(name, "revolute") != "prismatic"
    ]
    return float(max(beyond)) if beyond else None


def _planar_feasibility(scenario: Scenario) -> dict[str, Any]:
    """Requested yaw change and planar bounds (deg) of a planar scenario; empty otherwise."""
    from ..problem.build import problem_from_scenario

    try:
        problem = problem_from_scenario(scenario.resolved(), check_bounds=False)
    except FreeFloatError:
        return {}
    if problem.bounds is None or problem.yaw_change is None:
        return {}
    lo, hi = problem.bounds.interval(problem.family.goal - problem.family.start)
    return {
        "requested_yaw_change_deg": math.degrees(problem.yaw_change),
        "yaw_change_min_deg": math.degrees(lo),
        "yaw_change_max_deg": math.degrees(hi),
    }


def run_job(job: Job) -> SweepRow | ReplayRow:
    """Plan (or replay) one job; return its row. Never raises (a failure is a row)."""
    if job.replay:
        return run_replay_job(job)
    started = time.perf_counter()
    with warnings.catch_warnings():
        # a diverging solver attempt may overflow; its outcome is in the row, not a warning
        warnings.simplefilter("ignore", RuntimeWarning)
        # said once per axis value when the sweep is read, not once per job
        warnings.simplefilter("ignore", UnitsWarning)
        return _run(job, started)


@dataclass(frozen=True)
class JobOutcome:
    """A job's row and the distinct warnings the package logged while it ran.

    A worker process does not print its warnings: the sweep says each distinct one once, on
    the caller's warning path (``freefloat: warning: ...`` at the command line).
    """

    row: SweepRow | ReplayRow
    warnings: tuple[str, ...] = ()


class _Collector(logging.Handler):
    """Keeps the package's warnings of the job each thread is running, instead of printing."""

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.local = threading.local()

    def emit(self, record: logging.LogRecord) -> None:
        messages = getattr(self.local, "messages", None)
        if record.msg == SPIN_WARNING:  # in the row's largest_excursion_deg: said once per sweep
            return
        if messages is not None and record.getMessage() not in messages:
            messages.append(record.getMessage())


_COLLECTOR = _Collector()


def run_job_collecting(job: Job) -> JobOutcome:
    """:func:`run_job` in a worker process, its warnings collected rather than printed.

    The first call makes the collector the only handler of the package's logger in this
    process: call it in worker processes only. Never raises.
    """
    if LOGGER.handlers != [_COLLECTOR]:
        LOGGER.handlers[:] = [_COLLECTOR]
        LOGGER.propagate = False
    _COLLECTOR.local.messages = []
    try:
        row = run_job(job)
    finally:
        messages, _COLLECTOR.local.messages = _COLLECTOR.local.messages, None
    return JobOutcome(row, tuple(messages))


def _run(job: Job, started: float) -> SweepRow:
    scenario: Scenario | None = None
    try:
        scenario = _scenario(job)
        if job.changes:  # the robot with other mass properties: plan in that model
            changed = perturbed_robot(scenario.robot, job.changes, scenario.robot_text)
            scenario = replace(scenario, robot=changed)
        return _planned(job, plan(scenario, samples=job.samples), scenario.robot, started)
    except InfeasibleError as exc:
        lo, hi = exc.bounds_deg
        return SweepRow(
            job.index,
            job.values,
            "infeasible",
            requested_yaw_change_deg=exc.requested_deg,
            yaw_change_min_deg=lo,
            yaw_change_max_deg=hi,
            total_time_s=time.perf_counter() - started,
            message=_one_line(str(exc)),
        )
    except Exception as exc:  # a bad job must not stop the sweep
        known = isinstance(exc, FreeFloatError)
        message = str(exc) if known else f"internal error: {type(exc).__name__}: {exc}"
        extra = _planar_feasibility(scenario) if scenario is not None else {}
        return SweepRow(
            job.index,
            job.values,
            "failed",
            total_time_s=time.perf_counter() - started,
            message=_one_line(message),
            **extra,
        )
