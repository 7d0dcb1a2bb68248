"""One replay job: a fixed plan run in a model with other mass properties; where it ends.

The plan's joint paths are kept (the arm's servos track them); the job's inertial values are
put into the plan's URDF and the base attitude is integrated along those paths
(:func:`freefloat.robust.replay.replay_attitude`, Runge-Kutta, not the planner's scheme). The row
holds the final attitude error (rad) and its rotation vector (goal frame), so that a sweep of
random draws gives the error's distribution. Each worker process keeps the plans it has read.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, fields, replace
from typing import ClassVar

from ..errors import FreeFloatError
from ..plans.format import Plan
from ..plans.robot_copy import plan_robot
from ..robot.model import Robot
from ..robust.inertial import perturbed_robot, robot_text
from ..robust.replay import replay_attitude
from .spec import Job, Value

__all__ = ["REPLAY_STATUSES", "ReplayRow", "run_replay_job"]

#: The outcomes of a replay job.
REPLAY_STATUSES = ("replayed", "failed")

#: Plans read by this process: (plan, its robot, its URDF text), by path.
_PLANS: dict[str, tuple[Plan, Robot, str]] = {}


@dataclass(frozen=True)
class ReplayRow:
    """The outcome of one replay job (one CSV row).

    Attributes:
        index: the job's position.
        values: one value per axis (kg, m, kg m^2).
        status: ``replayed`` or ``failed``.
        attitude_error_rad: angle from the goal attitude to the one reached (rad).
        error_x_rad: the error's rotation vector, x (rad, goal frame); y and z likewise.
        integration_error_rad: the replay's own error estimate (rad).
        total_time_s: wall time of the job (s); a timing, not part of the result.
        message: why a job failed; empty when replayed.
    """

    #: the statuses a row can have
    statuses: ClassVar[tuple[str, ...]] = ("replayed", "failed")

    index: int
    values: tuple[Value, ...]
    status: str
    attitude_error_rad: float | None = None
    error_x_rad: float | None = None
    error_y_rad: float | None = None
    error_z_rad: float | None = None
    integration_error_rad: float | None = None
    total_time_s: float | None = None
    message: str = ""

    @staticmethod
    def result_columns() -> tuple[str, ...]:
        """The CSV columns after the axis values, in order."""
        return tuple(f.name for f in fields(ReplayRow) if f.name not in ("index", "values"))

    def without_timings(self) -> ReplayRow:
        """This row with its timing column cleared (for comparing runs)."""
        return replace(self, total_time_s=None)


def _plan(path: str) -> tuple[Plan, Robot, str]:
    if path not in _PLANS:
        plan = Plan.load(path)  # checked against the schema when the sweep was read
        robot = plan_robot(plan)
        _PLANS[path] = (plan, robot, robot_text(robot))
    return _PLANS[path]


def run_replay_job(job: Job) -> ReplayRow:
    """Replay the job's plan in its changed model; never raises (a failure is a row)."""
    started = time.perf_counter()
    try:
        plan, robot, text = _plan(str(job.source))
        model = perturbed_robot(robot, job.changes, text) if job.changes else robot
        outcome = replay_attitude(plan, model)
    except FreeFloatError as exc:
        return ReplayRow(
            job.index,
            job.values,
            "failed",
            total_time_s=time.perf_counter() - started,
            message=" ".join(str(exc).split()),
        )
    x, y, z = (float(v) for v in outcome.error_rotvec)
    return ReplayRow(
        job.index,
        job.values,
        "replayed",
        attitude_error_rad=outcome.error_rad,
        error_x_rad=x,
        error_y_rad=y,
        error_z_rad=z,
        integration_error_rad=outcome.estimate_rad,
        total_time_s=time.perf_counter() - started,
    )
