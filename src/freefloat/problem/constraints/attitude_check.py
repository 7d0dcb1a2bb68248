"""The dense, independent check of a constraint of the spacecraft's attitude along a path.

The attitude relative to the start, ``r(t) = q(0)^-1 q(t)``, is integrated without the
planner's model: Pinocchio's centroidal map gives the angular velocity (zero momentum) and
Butcher's fifth-order Runge-Kutta method integrates it on uniform grids
(:mod:`freefloat.physics.turn_track`), doubled until the relative attitudes at the coarser level's
step ends move by less than :data:`SETTLED`. A quantity of the attitude (a turn, a pointing
gap; larger is worse) is then sampled at the step ends of the last two levels, and each of
its local maxima that may hold the largest value (:func:`_candidates`) refined in time by a
bounded scalar search; the
difference between the two levels' largest values is the check's error estimate.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ...physics.momentum import MomentumMap
from ...physics.turn_track import RatesAt, TurnTrack, relative_between, track_turn
from ...robot.model import Robot
from ..paths import JointPolynomials
from ..scalar_minimum import scalar_minimum

__all__ = ["CANDIDATES", "REFINED", "AttitudeTrack", "Largest", "attitude_track", "local_maxima"]

#: Steps of the first level, and the most it doubles to.
FIRST_STEPS, MAX_STEPS = 64, 8192
#: Doubling stops when no relative attitude at the coarser level's step ends moves by more
#: than this (quaternion components): the integration has converged there.
SETTLED = 1e-11
#: Largest sampled local maxima refined in time, at least (a count); more when more lie
#: within what the quantity can gain between samples, up to :data:`CANDIDATES`.
REFINED = 3
CANDIDATES = 16

#: A quantity of the relative attitude: (K, 4) quaternions to K values (larger is worse).
Quantity = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class Largest:
    """The largest value of a quantity along the path.

    Attributes:
        value: the largest value (the quantity's unit); inf when the integration blew up.
        time: where (s).
        estimate: the difference to the coarser level's (same unit): its error estimate.
    """

    value: float
    time: float
    estimate: float


@dataclass(frozen=True)
class AttitudeTrack:
    """The last two levels of the independent integration along one path.

    Attributes:
        coarse: the level of half as many steps.
        fine: the last level.
        rates: the angular velocity the levels integrate (rad/s at times in s).
        duration: the path's duration (s).
    """

    coarse: TurnTrack
    fine: TurnTrack
    rates: RatesAt
    duration: float

    @property
    def finite(self) -> bool:
        """Whether the last level is finite (a step too long for the rates blows up)."""
        return bool(np.all(np.isfinite(self.fine.relative)))

    def largest(self, quantity: Quantity) -> Largest:
        """The quantity's largest value on the fine level, refined, and its error estimate."""
        if not self.finite:
            return Largest(math.inf, 0.0, 0.0)
        value, when = self._largest(self.fine, quantity)
        rough, _ = self._largest(self.coarse, quantity)
        return Largest(value, when, abs(value - rough))

    def peak_times(self, quantity: Quantity) -> np.ndarray:
        """Times (s) of the quantity's local maxima on the fine level's step ends."""
        return self.fine.times[local_maxima(quantity(self.fine.relative))]

    def _largest(self, track: TurnTrack, quantity: Quantity) -> tuple[float, float]:
        values = quantity(track.relative)
        best = int(np.argmax(values))
        value, when = float(values[best]), float(track.times[best])
        for k in _candidates(values):
            low, high = float(track.times[k - 1]), float(track.times[k + 1])
            found = scalar_minimum(
                lambda t: -float(quantity(self._at(track, t)[None])[0]),
                low,
                high,
                1e-9 * self.duration,
            )
            if -found.value > value:
                value, when = -found.value, found.x
        return value, when

    def _at(self, track: TurnTrack, t: float) -> np.ndarray:
        return relative_between(self.rates, track, t, self.duration)


def attitude_track(robot: Robot, path: JointPolynomials) -> AttitudeTrack:
    """The independent integration of the relative attitude along ``path``, doubled."""
    mmap = MomentumMap(robot)

    def omega_at(t: np.ndarray) -> np.ndarray:
        samples = path.evaluate(t)
        return mmap.pinocchio_rates(samples.q, samples.qd)

    coarse = track_turn(omega_at, path.duration, FIRST_STEPS)
    while True:
        fine = track_turn(omega_at, path.duration, 2 * coarse.steps, coarse)
        moved = float(np.abs(fine.relative[::2] - coarse.relative).max())  # the shared ends
        if not moved > SETTLED or fine.steps >= MAX_STEPS:  # NaN: no use going on
            return AttitudeTrack(coarse, fine, omega_at, path.duration)
        coarse = fine


def _candidates(values: np.ndarray) -> np.ndarray:
    """The sampled local maxima that may hold the largest value between the samples.

    Those within four of the largest second differences of the largest sample (a smooth
    quantity gains at most an eighth of one between samples), at most :data:`CANDIDATES`,
    and never fewer than :data:`REFINED` (the largest first).
    """
    peaks = local_maxima(values)
    if not len(peaks):
        return peaks
    rise = 4.0 * float(np.abs(np.diff(values, 2)).max(initial=0.0))
    close = peaks[values[peaks] >= float(values.max()) - rise]
    return peaks[: min(CANDIDATES, max(REFINED, len(close)))]


def local_maxima(values: np.ndarray) -> np.ndarray:
    """Indices of interior local maxima, largest first."""
    inner = np.flatnonzero((values[1:-1] >= values[:-2]) & (values[1:-1] >= values[2:])) + 1
    return inner[np.argsort(values[inner])[::-1]]
