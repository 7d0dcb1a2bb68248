"""Step doubling for the integrating checks of :mod:`freefloat.verify.checks`.

A check integrates on M and 2 M steps and takes the difference of the two results as the
error estimate of the finer one; :func:`_decided` says when that estimate can be trusted and
the verdict stands. :func:`_rk5_attitude` is the attitude check's integrator (Butcher's
fifth-order Runge-Kutta method, :mod:`freefloat.physics.runge_kutta`, batched, independent of
the planner's Magnus scheme).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..physics.attitude import geodesic_angle, ordered_product
from ..physics.runge_kutta import QUARTERS, step_matrices
from ..plans.format import Plan
from ..robot.model import Robot

__all__ = [
    "CONVERGED_FRACTION",
    "MAX_REPLAY_STEPS",
    "ROUNDING_FLOOR",
    "TORQUE_PERTURBATION",
    "AttitudeLevel",
    "attitude_by_doubling",
    "motion_speed",
    "perturbed_torques",
    "wrapped_joints",
]

#: A numerical check refines (doubles its steps) until its verdict no longer depends on its own
#: error, or until its error estimate is below this fraction of its tolerance.
CONVERGED_FRACTION = 0.1

#: A step-doubling difference at or below this fraction of the tolerance is at rounding: it
#: need not shrink further to be trusted.
ROUNDING_FLOOR = 1e-3 * CONVERGED_FRACTION
#: A refusal's difference at or below this fraction of the tolerance, two levels running,
#: need not shrink again for the refusal to stand (such a sequence is done converging).
SETTLED_FLOOR = 1e-5

#: Default cap on the replay's Runge-Kutta steps (see :func:`verify_plan`).
MAX_REPLAY_STEPS = 8192

#: Steps of the first, coarsest level of the step-doubling checks.
_FIRST_REPLAY_STEPS = 8
_FIRST_ATTITUDE_STEPS = 8
_MAX_ATTITUDE_STEPS = 1 << 14
#: Largest rotation (rad) of a joint or the base in one step before a check trusts its steps.
_MAX_TURN = 0.25
#: Before a replay refuses a plan, its torques are offset by this fraction of each joint's
#: largest and the replay run again: how far its end moves joins its error estimate.
TORQUE_PERTURBATION = 1e-12


def _decided(
    value: float,
    estimate: float,
    previous: float,
    tolerance: float,
    turn: float,
    earlier: float | None = None,
) -> bool:
    """Whether a step-doubling check's verdict stands whatever its numerical error.

    ``estimate`` is the difference between the results on M and 2 M steps, ``previous`` the
    one between M / 2 and M, ``earlier`` the one between M / 4 and M / 2 (inf while not
    known; None: not asked for). It bounds the error of the finer result only once the scheme
    converges at its order (fifth: the difference shrinks about 32-fold per doubling), so the
    verdict is trusted only once the steps resolve the motion (``turn``, the largest rotation
    in one step, rad, at most :data:`_MAX_TURN`) and the difference has shrunk at least
    8-fold since the doubling before (a first difference, with nothing before it, never
    suffices) or is already below rounding; then the check is decided when the estimate is
    small against the tolerance (and the value within it) or the value is clear of the
    tolerance by more than the estimate. To refuse, the value must exceed the tolerance by
    more than the estimate, the estimate must also be small against the value, and the
    difference must have shrunk 8-fold over the doubling before as well (or have been at
    rounding already, :data:`SETTLED_FLOOR` of the tolerance, after a difference that was a
    number): an erratic sequence (an
    open-loop replay whose error grows without bound, say) can shrink once by chance.
    """
    # a first difference (``previous`` inf) has not shrunk yet: it bounds nothing on its own
    shrunk = math.isfinite(previous) and estimate <= previous / 8.0
    floor = ROUNDING_FLOOR * tolerance
    converging = shrunk or estimate <= floor
    if turn > _MAX_TURN or not converging:
        return False
    small = estimate <= CONVERGED_FRACTION * tolerance
    if value + estimate <= tolerance or (small and value <= tolerance):
        return True
    settled = (
        earlier is None
        # the difference before was at rounding already, after one that was a number
        or (math.isfinite(earlier) and previous <= SETTLED_FLOOR * tolerance)
        or (math.isfinite(earlier) and previous <= earlier / 8.0)
    )
    return settled and value - estimate > tolerance and estimate <= CONVERGED_FRACTION * value


def wrapped_joints(robot: Robot, delta: np.ndarray) -> np.ndarray:
    """Joint differences (rad or m; any leading shape), continuous joints wrapped to (-pi, pi]."""
    out = np.array(delta, dtype=float)
    turn = np.vectorize(lambda value: math.remainder(value, 2.0 * math.pi), otypes=[float])
    for i, joint in enumerate(robot.joints):
        if joint.kind == "continuous":
            out[..., i] = turn(out[..., i])
    return out


def perturbed_torques(torques: np.ndarray) -> np.ndarray:
    """``torques`` (K, N; N m or N) offset by :data:`TORQUE_PERTURBATION` of each joint's largest.

    Alternate joints in opposite senses: about a thousand times the torques' own rounding.
    """
    signs = np.where(np.arange(torques.shape[1]) % 2 == 0, 1.0, -1.0)
    return torques + TORQUE_PERTURBATION * np.abs(torques).max(axis=0) * signs


def motion_speed(plan: Plan) -> float:
    """The largest joint rate or base angular speed of the plan's samples (rad/s or m/s).

    Times a step's duration, the largest turn in one step (``turn`` of :func:`_decided`).
    """
    samples = plan.samples
    return max(
        float(np.abs(np.asarray(samples.qd, float)).max()),
        float(np.linalg.norm(np.asarray(samples.base_angular_velocity, float), axis=1).max()),
        0.0,
    )


def _finite(x: float) -> float:
    """``x``, or infinity for NaN (a blown-up coarse level differs from anything by inf)."""
    return x if not math.isnan(x) else math.inf


def _rk5_attitude(start: np.ndarray, omega: np.ndarray, duration: float) -> np.ndarray:
    """Final attitude of ``y' = 0.5 y (x) omega(t)`` by Butcher's fifth-order method, uniform grid.

    The equation is linear in ``y`` and ``omega(t)`` is known beforehand, so every step is a
    4 x 4 matrix (built in one batch) and their product is taken by pairwise reduction.

    Args:
        start: attitude ``[x, y, z, w]`` at t = 0.
        omega: (4 M + 1, 3) base angular velocity (rad/s) at ``k duration / (4 M)``.
        duration: time span (s).
    """
    steps = (len(omega) - 1) // 4
    stage_omega = omega[4 * np.arange(steps)[:, None] + np.array(QUARTERS)[None, :]]
    phi = step_matrices(stage_omega, np.full(steps, duration / steps))
    end = ordered_product(phi) @ start
    return end / np.linalg.norm(end)


def _refine(
    table: np.ndarray | None, steps: int, duration: float, fill: Callable[[np.ndarray], np.ndarray]
) -> np.ndarray:
    """Values at ``k duration / (4 steps)``, k = 0..4 steps, reusing a table of half as many."""
    t = np.linspace(0.0, duration, 4 * steps + 1)
    if table is None:
        return fill(t)
    out = np.empty((len(t), table.shape[1]))
    out[0::2] = table
    out[1::2] = fill(t[1::2])
    return out


@dataclass(frozen=True)
class AttitudeLevel:
    """The last level of an attitude integration by step doubling.

    Attributes:
        attitude: final attitude ``[x, y, z, w]`` on ``steps`` steps.
        estimate: geodesic angle between it and the level of half as many steps (rad).
        previous: the same difference one level before (rad; inf at the first).
        steps: Runge-Kutta steps of the last level.
        turn: largest base rotation in one step (rad).
    """

    attitude: np.ndarray
    estimate: float
    previous: float
    steps: int
    turn: float


def attitude_by_doubling(
    start: np.ndarray,
    omega_at: Callable[[np.ndarray], np.ndarray],
    duration: float,
    first_steps: int,
    max_steps: int,
    done: Callable[[AttitudeLevel], bool],
) -> AttitudeLevel:
    """Integrate the base attitude (:func:`_rk5_attitude`), doubling the steps.

    Starts on ``first_steps`` steps and doubles (reusing every rate already computed) until
    ``done`` accepts a level or ``max_steps`` is reached.

    Args:
        start: attitude ``[x, y, z, w]`` at t = 0.
        omega_at: base angular velocity (rad/s) at an array of times (s), shape (K, 3).
        duration: time span (s).
        first_steps: steps of the coarsest level.
        max_steps: the most steps.
        done: whether a level settles the caller's question.
    """
    steps = first_steps
    omega = _refine(None, steps, duration, omega_at)
    coarse = _rk5_attitude(start, omega, duration)
    previous = math.inf
    while True:
        steps *= 2
        omega = _refine(omega, steps, duration, omega_at)
        fine = _rk5_attitude(start, omega, duration)
        turn = float(np.linalg.norm(omega, axis=1).max()) * duration / steps  # rad a step
        level = AttitudeLevel(fine, geodesic_angle(coarse, fine), previous, steps, turn)
        if steps >= max_steps or done(level):
            return level
        coarse, previous = fine, level.estimate
