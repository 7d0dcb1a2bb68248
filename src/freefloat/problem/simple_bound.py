"""Outer bound on the base turn of a *simple* motion of a spatial (or planar) free floater.

The base angular velocity is ``omega = F1(q) qdot`` (base frame, rad/s), so along any joint
path the base turns by at most ``integral |omega| dt <= sum_i G_i L_i``, where ``L_i`` is the
travel of joint ``i`` (the integral of ``|qdot_i|``, rad or m) and ``G_i`` the largest norm
of the column ``F1[:, i](q)`` over the configurations the path can visit (rad of base turn per
rad or m of joint travel). A simple motion is one with ``L_i <= k |goal_i - start_i|`` for a
stated ``k >= 1``: ``k = 1`` is every joint monotone between start and goal (as the quintic
path is), and then the path stays in the box spanned by start and goal; with ``k > 1`` a joint
may leave that box by ``(k - 1) |goal_i - start_i| / 2`` on either side (within its limits).

The geodesic angle between the start attitude and the end attitude is at most the length of
the attitude's path, so ``B = sum_i G_i L_i`` bounds how far from the start attitude any simple
motion leaves the spacecraft. ``G_i`` is the largest value found by sampling the box (evenly
spread points, :func:`.quasi_random.unit_points`) and refining the best sample of each joint
by a projected gradient ascent within the box (the column's analytic derivative,
:meth:`~freefloat.physics.momentum.MomentumMap.base_rates`; a count of steps) and a few
projected Newton steps where the maximum is concave: a maximum
estimated, not certified (a narrow peak between samples could be missed), so the bound is as
good as that search. Cyclic back-and-forth motions
(``k`` large) can turn the base further; the bound says nothing about them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..physics.attitude import quat_exp, quat_log, quat_multiply
from ..physics.momentum import MomentumMap
from .quasi_random import unit_points

__all__ = [
    "SimpleMotionBound",
    "first_crossing",
    "inertia_ratio",
    "simple_motion_bound",
    "turn_limit",
]

#: Configurations sampled in the box before refinement.
SAMPLES = 256
#: Gradient steps tried per refined joint gain (a count; all joints' searches in one batch).
REFINE_STEPS = 200
#: Projected Newton steps after the gradient ascent, per joint gain (a count).
NEWTON_STEPS = 8
#: Forward-difference step of the Hessian, in unit coordinates.
DIFFERENCE = 1e-6
#: First step of a gradient search, as a fraction of the unit box's diagonal.
FIRST_STEP = 0.25
#: A search stops once its step falls below this (unit coordinates).
SMALLEST_STEP = 1e-9


@dataclass(frozen=True)
class SimpleMotionBound:
    """How far a simple motion can turn the base, and from what.

    Attributes:
        travel_factor: ``k``: every joint travels at most ``k`` times its start-goal span.
        travel: per joint, the travel allowed (rad or m).
        box: (N, 2) per joint, the values a path of that travel can visit (rad or m).
        gains: per joint, the largest ``|F1[:, i](q)|`` found over the box (rad per rad or m).
        bound: ``sum_i gains_i travel_i``: largest turn from the start attitude (rad).
    """

    travel_factor: float
    travel: np.ndarray
    box: np.ndarray
    gains: np.ndarray
    bound: float


def _box(mmap: MomentumMap, start: np.ndarray, goal: np.ndarray, factor: float) -> np.ndarray:
    """(N, 2) values reachable with travel ``factor |goal - start|`` (clipped to the limits)."""
    lo, hi = np.minimum(start, goal), np.maximum(start, goal)
    slack = 0.5 * (factor - 1.0) * (hi - lo)
    lower = np.array([j.lower for j in mmap.robot.joints])
    upper = np.array([j.upper for j in mmap.robot.joints])
    return np.stack(
        [
            np.maximum(lo - slack, np.minimum(lower, lo)),
            np.minimum(hi + slack, np.maximum(upper, hi)),
        ],
        axis=1,
    )


def simple_motion_bound(
    mmap: MomentumMap,
    start: np.ndarray,
    goal: np.ndarray,
    travel_factor: float = 1.0,
    samples: int = SAMPLES,
    seed: int = 0,
) -> SimpleMotionBound:
    """The bound ``B`` (rad) on the base turn of every motion with travel ``<= k`` x span.

    Args:
        mmap: the robot's momentum map.
        start: start joint values (rad or m).
        goal: goal joint values (rad or m).
        travel_factor: ``k >= 1`` (1: every joint monotone between start and goal).
        samples: configurations sampled in the box before refinement.
        seed: shift of the evenly spread points (:func:`.quasi_random.unit_points`).
    """
    if not travel_factor >= 1.0:
        raise ValueError(f"travel_factor must be at least 1, got {travel_factor}")
    start, goal = np.asarray(start, dtype=float), np.asarray(goal, dtype=float)
    box = _box(mmap, start, goal, travel_factor)
    travel = travel_factor * np.abs(goal - start)
    unit = unit_points(samples, len(start), seed)
    points = np.vstack([start, goal, box[:, 0] + unit * (box[:, 1] - box[:, 0])])
    norms = np.linalg.norm(mmap.base_rates(points, np.zeros_like(points)).f1, axis=1)  # (K, N)
    moving = np.flatnonzero(travel > 0.0)  # a joint that does not move adds nothing
    gains = norms.max(axis=0)
    if len(moving):
        found = _ascended(mmap, points[np.argmax(norms[:, moving], axis=0)], moving, box)
        gains[moving] = np.maximum(gains[moving], found)
    return SimpleMotionBound(
        travel_factor=float(travel_factor),
        travel=travel,
        box=box,
        gains=gains,
        bound=float(gains @ travel),
    )


def _column_norms(
    mmap: MomentumMap, joints: np.ndarray, columns: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Row ``k``: ``|F1[:, columns[k]](joints[k])|`` (rad per rad or m) and its gradient.

    The column is the base rate of a unit rate of that joint, so its derivative over the
    joints is the analytic ``d omega / d q`` at those rates (per rad or m).
    """
    rates = np.zeros_like(joints)
    rates[np.arange(len(columns)), columns] = 1.0
    found = mmap.base_rates(joints, rates, derivatives=True)
    norms = np.linalg.norm(found.omega, axis=1)
    assert found.domega_dq is not None
    slope = np.einsum("ki,kij->kj", found.omega, found.domega_dq)
    return norms, slope / np.maximum(norms, 1e-300)[:, None]


def _held(unit: np.ndarray, climb: np.ndarray) -> np.ndarray:
    """Coordinates at a face of the unit box whose gradient ``climb`` points out of it."""
    return ((unit <= 0.0) & (climb < 0.0)) | ((unit >= 1.0) & (climb > 0.0))


def _ascended(
    mmap: MomentumMap, joints: np.ndarray, columns: np.ndarray, box: np.ndarray
) -> np.ndarray:
    """Per row, the largest ``|F1[:, columns[k]]|`` a projected gradient ascent finds.

    Each row climbs from ``joints[k]`` within ``box`` in unit coordinates (the box scaled to
    the unit cube, so radians and metres weigh alike) along its gradient, less the parts that
    point out of the box at a face it lies on, clipped to the box. A step is taken when it
    raises the norm, else halved; after a step the next one's length is the Barzilai-Borwein
    estimate of the curvature met (secant), which keeps long ridges from costing many short
    steps. :data:`REFINE_STEPS` batched evaluations at most, fewer once every step is below
    :data:`SMALLEST_STEP`. Deterministic.
    """
    low, width = box[:, 0], box[:, 1] - box[:, 0]
    unit = np.where(width > 0.0, (joints - low) / np.where(width > 0.0, width, 1.0), 0.0)
    values, slope = _column_norms(mmap, joints, columns)
    climb = slope * width  # d norm / d unit coordinate
    scale = np.linalg.norm(climb, axis=1)
    factor = FIRST_STEP * math.sqrt(len(low)) / np.where(scale > 0.0, scale, 1.0)
    for _ in range(REFINE_STEPS):
        ahead = np.where(_held(unit, climb), 0.0, climb)
        trial = np.clip(unit + factor[:, None] * ahead, 0.0, 1.0)
        moved = trial - unit
        active = np.linalg.norm(moved, axis=1) >= SMALLEST_STEP
        if not active.any():
            break
        rows = np.flatnonzero(active)  # only the searches still moving are evaluated
        tried, tried_slope = _column_norms(mmap, low + trial[rows] * width, columns[rows])
        moved, tried_climb = moved[rows], tried_slope * width
        curvature = -np.einsum("kj,kj->k", moved, tried_climb - climb[rows])  # > 0: concave
        secant = np.einsum("kj,kj->k", moved, moved) / np.where(curvature > 0.0, curvature, 1.0)
        better = tried > values[rows]
        factor[rows] = np.where(
            better, np.where(curvature > 0.0, secant, 2.0 * factor[rows]), 0.5 * factor[rows]
        )
        kept = rows[better]
        unit[kept], values[kept], climb[kept] = trial[kept], tried[better], tried_climb[better]
    for k in range(len(columns)):  # the ridge's last stretch: Newton steps on the free faces
        values[k] = _polished(mmap, int(columns[k]), unit[k], float(values[k]), climb[k], box)
    return values


def _polished(
    mmap: MomentumMap,
    column: int,
    unit: np.ndarray,
    value: float,
    climb: np.ndarray,
    box: np.ndarray,
) -> float:
    """The norm after up to :data:`NEWTON_STEPS` projected Newton steps from ``unit``.

    Unit coordinates as in :func:`_ascended`; ``climb`` is the norm's gradient there. The
    Hessian comes from forward differences of the analytic gradient (one batch per step);
    the joints free to move are those not held at a face by their gradient. A Newton step is
    taken only where the Hessian is negative definite on them and the step raises the norm
    (halved up to four times); otherwise the search ends. Returns the best norm found.
    """
    low, width = box[:, 0], box[:, 1] - box[:, 0]
    n = len(unit)
    for _ in range(NEWTON_STEPS):
        free = (width > 0.0) & ~_held(unit, climb)
        if not free.any():
            break
        shift = np.where(unit + DIFFERENCE <= 1.0, DIFFERENCE, -DIFFERENCE)
        shifted = unit[None, :] + np.diag(shift)
        _, slopes = _column_norms(mmap, low + shifted * width, np.full(n, column))
        hessian = (slopes * width - climb[None, :]) / shift[:, None]
        block = -0.5 * (hessian + hessian.T)[np.ix_(free, free)]
        try:
            lower = np.linalg.cholesky(block)  # negative definite: a maximum's neighbourhood
        except np.linalg.LinAlgError:
            break
        step = np.zeros(n)
        step[free] = np.linalg.solve(lower.T, np.linalg.solve(lower, climb[free]))
        for _ in range(5):
            trial = np.clip(unit + step, 0.0, 1.0)
            tried, tried_slope = _column_norms(
                mmap, (low + trial * width)[None, :], np.array([column])
            )
            if tried[0] > value:
                unit, value, climb = trial, float(tried[0]), tried_slope[0] * width
                break
            step *= 0.5
        else:
            break
    return value


def turn_limit(drift: np.ndarray, axis: np.ndarray, bound: float) -> float:
    """Largest turn (rad) about ``axis`` from the drift attitude within ``bound`` of the start.

    ``drift`` is the rotation from the start attitude to the drift attitude (``[x, y, z, w]``)
    and ``axis`` a unit axis in the base frame at the drift attitude: the first ``theta >= 0``
    where ``angle(drift exp(theta axis)) = bound``. The angle is 1-Lipschitz in ``theta``, so
    stepping by the remaining room never jumps over the first crossing.
    """
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)

    def room(theta: float) -> float:
        turned = quat_multiply(drift, quat_exp(theta * axis))
        return bound - float(np.linalg.norm(quat_log(turned)))

    return first_crossing(room, math.pi)


def first_crossing(room: Callable[[float], float], most: float) -> float:
    """The first ``theta >= 0`` (rad, at most ``most``) where ``room(theta)`` reaches 0.

    ``room`` must change by at most the change in ``theta`` (1-Lipschitz): stepping by the
    room left never jumps over the first crossing. 0 when ``room(0) < 0``; at most 200 steps.
    """
    theta, left = 0.0, room(0.0)
    if left < 0.0:
        return 0.0
    for _ in range(200):
        if left < 1e-12 or theta >= most:
            break
        theta += left
        left = room(theta)
    return min(theta, most)


def inertia_ratio(mmap: MomentumMap, joints: np.ndarray) -> float:
    """Spacecraft over arm rotational inertia about the system CM at ``joints`` (traces).

    The spacecraft is the URDF's root body; the arm is every other body (a captured payload
    included). Both inertias are taken about the system's centre of mass, base frame.
    """
    model, data = mmap.model, mmap.data
    q = mmap.robot.configuration(np.asarray(joints, dtype=float))
    pin.forwardKinematics(model, data, q)
    com = pin.centerOfMass(model, data, q)
    traces = []
    for index in range(1, model.njoints):
        inertia = data.oMi[index].act(model.inertias[index])
        offset = np.asarray(inertia.lever) - com
        about_cm = inertia.inertia + inertia.mass * (
            offset @ offset * np.eye(3) - np.outer(offset, offset)
        )
        traces.append(float(np.trace(about_cm)))
    base, arm = traces[0], sum(traces[1:])
    return base / arm if arm > 0.0 else math.inf
