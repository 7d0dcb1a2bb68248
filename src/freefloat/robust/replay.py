"""Replay a plan's fixed joint paths in a (possibly perturbed) model: where does the base end?

The joints follow the plan's polynomials exactly (the arm's servos track them); the base
turns as the model's momentum map says. The attitude is integrated with the verifier's
fifth-order Runge-Kutta method on the quaternion equation in seconds
(:mod:`freefloat.verify.stepping`), not with the planner's Magnus scheme, and its step count
doubles until its own estimate (the change on doubling) is small against the error it
measures.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..physics.attitude import geodesic_angle, relative_rotvec
from ..physics.momentum import MomentumMap
from ..plans.format import Plan
from ..robot.model import Robot
from ..verify.path_eval import file_path
from ..verify.stepping import AttitudeLevel, attitude_by_doubling

__all__ = ["ReplayOutcome", "replay_attitude"]

#: Steps of the first level, and the cap, of the replay's step doubling.
FIRST_STEPS, MAX_STEPS = 16, 1 << 14
#: The replay stops doubling once its estimate is below this fraction of the error (or below
#: :data:`ABSOLUTE_FLOOR` rad) and shrank at least 8-fold on the last doubling.
RELATIVE_ACCURACY = 1e-4
ABSOLUTE_FLOOR = 1e-12


@dataclass(frozen=True)
class ReplayOutcome:
    """The base attitude at the end of a replayed plan.

    Attributes:
        quaternion: reached attitude ``[x, y, z, w]``.
        error_rotvec: rotation vector from the goal to the reached attitude (rad, goal frame).
        error_rad: its angle (rad).
        estimate_rad: the integration's own error estimate (rad): the change on doubling.
        steps: Runge-Kutta steps of the result.
    """

    quaternion: np.ndarray
    error_rotvec: np.ndarray
    error_rad: float
    estimate_rad: float
    steps: int


def replay_attitude(
    plan: Plan, robot: Robot, start_quaternion: np.ndarray | None = None
) -> ReplayOutcome:
    """Integrate the base attitude along the plan's joint paths in ``robot``'s model.

    Args:
        plan: the plan (its polynomials, duration and goal attitude are used).
        robot: the model to replay in (the plan's robot, or one with other inertial values);
            its joints must be the plan's.
        start_quaternion: base attitude at t = 0 ``[x, y, z, w]``; default the plan's.
    """
    mmap = MomentumMap(robot)
    path = file_path(plan)  # the file's own definition of its paths, as verification reads it
    duration = plan.duration
    start = np.asarray(
        plan.base.start_quaternion_xyzw if start_quaternion is None else start_quaternion, float
    )
    start = start / np.linalg.norm(start)
    goal = np.asarray(plan.base.target_quaternion_xyzw, dtype=float)

    def omega_at(t: np.ndarray) -> np.ndarray:
        q, qd, _ = path(t)
        return mmap.base_rates(q, qd).omega

    def accurate(level: AttitudeLevel) -> bool:
        error = geodesic_angle(level.attitude, goal)
        small = level.estimate <= max(ABSOLUTE_FLOOR, RELATIVE_ACCURACY * error)
        shrunk = math.isfinite(level.previous) and level.estimate <= level.previous / 8.0
        return small and shrunk  # a first difference, with none before it, never suffices

    level = attitude_by_doubling(start, omega_at, duration, FIRST_STEPS, MAX_STEPS, accurate)
    fine = level.attitude
    rotvec = relative_rotvec(goal, fine)
    return ReplayOutcome(fine, rotvec, float(np.linalg.norm(rotvec)), level.estimate, level.steps)
