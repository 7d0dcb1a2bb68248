"""How far the spacecraft has turned from its start attitude, along a known joint motion.

The spacecraft's turn from its start attitude at time ``t`` is the angle of the relative
rotation ``r(t) = q(0)^-1 q(t)``, which starts at the identity and follows the body-frame rate
alone: ``r' = 0.5 r (x) [omega(t), 0]``. It does not depend on the start attitude. Here ``r``
is integrated with Butcher's fifth-order Runge-Kutta method (:mod:`.runge_kutta`) on a uniform
grid, every step one 4 x 4 matrix, from angular velocities the caller computes (the
verification's: Pinocchio's centroidal map, :meth:`~.momentum.MomentumMap.pinocchio_rates`);
the planner's Magnus scheme is not used. Between grid points, :func:`relative_between` integrates
from the step's start to any instant, so that a caller can refine a largest turn in time.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .runge_kutta import QUARTERS, step_matrices

__all__ = [
    "RatesAt",
    "TurnTrack",
    "quaternion_turn",
    "relative_between",
    "track_turn",
]

#: Angular velocity (rad/s, base frame), (K, 3), at an array of K times (s).
RatesAt = Callable[[np.ndarray], np.ndarray]


def quaternion_turn(r: np.ndarray) -> np.ndarray:
    """Rotation angle (rad, in [0, pi]) of quaternions ``[x, y, z, w]`` (..., 4), normalised."""
    r = np.asarray(r, dtype=float)
    vector = np.linalg.norm(r[..., :3], axis=-1)
    return 2.0 * np.arctan2(vector, np.abs(r[..., 3]))


@dataclass(frozen=True)
class TurnTrack:
    """The relative attitude at the ends of uniform steps.

    Attributes:
        times: the steps' ends, ``steps + 1`` instants from 0 to the duration (s).
        relative: (steps + 1, 4) ``r(t) = q(0)^-1 q(t)``, ``[x, y, z, w]``, normalised.
        turns: (steps + 1,) rotation angle of each (rad).
        rates: (4 steps + 1, 3) the angular velocities used, at the quarters of the steps
            (rad/s), for a finer level to reuse.
    """

    times: np.ndarray
    relative: np.ndarray
    turns: np.ndarray
    rates: np.ndarray

    @property
    def steps(self) -> int:
        """Number of steps."""
        return len(self.times) - 1


def track_turn(
    omega_at: RatesAt, duration: float, steps: int, coarser: TurnTrack | None = None
) -> TurnTrack:
    """The relative attitude at the ends of ``steps`` uniform RK5 steps over ``duration`` (s).

    ``coarser``: a track on ``steps / 2`` steps whose rates are reused (only the new quarter
    instants are evaluated).
    """
    quarters = np.linspace(0.0, duration, 4 * steps + 1)
    if coarser is not None and 2 * coarser.steps == steps:
        rates = np.empty((len(quarters), 3))
        rates[0::2] = coarser.rates
        rates[1::2] = omega_at(quarters[1::2])
    else:
        rates = np.asarray(omega_at(quarters), dtype=float)
    stage = rates[4 * np.arange(steps)[:, None] + np.array(QUARTERS)[None, :]]
    relative = np.empty((steps + 1, 4))
    y = np.array([0.0, 0.0, 0.0, 1.0])
    relative[0] = y
    # steps too long for the rates overflow: the turns are then not numbers (the caller's)
    with np.errstate(over="ignore", invalid="ignore"):
        for k, matrix in enumerate(step_matrices(stage, np.full(steps, duration / steps))):
            y = matrix @ y
            relative[k + 1] = y
        relative /= np.linalg.norm(relative, axis=1, keepdims=True)
    times = quarters[0::4]
    return TurnTrack(times, relative, quaternion_turn(relative), rates)


def relative_between(omega_at: RatesAt, track: TurnTrack, t: float, duration: float) -> np.ndarray:
    """The relative attitude ``[x, y, z, w]`` at time ``t`` (s).

    Integrated from the track's last step end before ``t``, by as many RK5 steps as make
    each no wider than the track's own, so its error is of the track's order.
    """
    width = duration / track.steps
    k = min(max(math.floor(t / width), 0), track.steps - 1)
    start = float(track.times[k])
    span = t - start
    if span <= 0.0:
        return np.array(track.relative[k])
    pieces = max(1, math.ceil(span / width - 1e-9))
    h = span / pieces
    quarters = start + h * np.arange(4 * pieces + 1) / 4.0
    rates = np.asarray(omega_at(quarters), dtype=float)
    stage = rates[4 * np.arange(pieces)[:, None] + np.array(QUARTERS)[None, :]]
    y = track.relative[k]
    with np.errstate(over="ignore", invalid="ignore"):
        for matrix in step_matrices(stage, np.full(pieces, h)):
            y = matrix @ y
        return y / np.linalg.norm(y)
