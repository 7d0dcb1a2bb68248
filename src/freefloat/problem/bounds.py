"""Reachable yaw change of a planar free floater (docs/method.md section 6).

For a planar system ``dyaw = sum_i g_i(q) dq_i`` with ``g_i`` the z row of ``F1``. Each
``g_i`` is bounded over the configurations the joints can take (their limits; a full turn for
continuous joints). For a joint moving monotonically by ``dq_i`` its contribution lies between
``g_i,min dq_i`` and ``g_i,max dq_i`` (ends swapped when ``dq_i < 0``); the sum of these
intervals is the (open) interval of yaw changes a simple point-to-point motion can reach.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..physics.momentum import MomentumMap, cached_planar_axis
from ..physics.planar_map import PlanarMap, cached_identify
from ..robot.content_cache import RobotCache
from .quasi_random import unit_points

__all__ = ["PlanarBounds", "joint_ranges", "planar_bounds"]


@dataclass(frozen=True)
class PlanarBounds:
    """Extremes of the planar gains ``g_i = dyaw / dq_i`` over the configuration space.

    Attributes:
        g_min: per joint, the smallest gain (rad of yaw per rad, or per m for prismatic).
        g_max: per joint, the largest gain (same units).
    """

    g_min: np.ndarray
    g_max: np.ndarray

    def interval(self, delta_q: np.ndarray) -> tuple[float, float]:
        """Open interval (rad) of yaw changes reachable when the joints move by ``delta_q``."""
        lo = np.minimum(self.g_min * delta_q, self.g_max * delta_q)
        hi = np.maximum(self.g_min * delta_q, self.g_max * delta_q)
        return float(lo.sum()), float(hi.sum())


def cached_planar_bounds(mmap: MomentumMap) -> PlanarBounds:
    """:func:`planar_bounds` computed once per robot content (they depend on the robot alone).

    The planar axis and map are the robot's own, derived from it (kept per content too), so
    everything the bounds depend on is in the content key.

    Raises:
        ValueError: the robot is not planar.
    """
    robot = mmap.robot

    def compute() -> PlanarBounds:
        axis = cached_planar_axis(robot)
        if axis is None:
            raise ValueError("planar bounds of a robot whose base does not turn about one axis")
        return planar_bounds(mmap, axis=axis, planar_map=cached_identify(robot))

    return _BOUNDS.get(robot, compute)


#: Planar bounds, computed once per robot content.
_BOUNDS: RobotCache[PlanarBounds] = RobotCache()


def joint_ranges(mmap: MomentumMap) -> np.ndarray:
    """(N, 2) ranges to explore per joint: limits, or one full turn for continuous joints."""
    ranges = []
    for joint in mmap.robot.joints:
        if math.isfinite(joint.lower) and math.isfinite(joint.upper):
            ranges.append((joint.lower, joint.upper))
        else:
            ranges.append((-math.pi, math.pi))
    return np.array(ranges)


def planar_bounds(
    mmap: MomentumMap,
    samples: int = 4096,
    seed: int = 0,
    axis: np.ndarray | None = None,
    planar_map: PlanarMap | None = None,
) -> PlanarBounds:
    """Extremes of each gain ``g_i(q)`` for a planar robot.

    The gains are sampled on a grid (up to two joints) or at evenly spread points
    (:func:`.quasi_random.unit_points`), and the best samples are refined with bounded
    quasi-Newton searches, so the extremes are accurate to the optimiser's tolerance (about
    1e-10).

    Args:
        mmap: momentum map of a planar robot.
        samples: number of configurations sampled before refinement.
        seed: shift of the evenly spread points (:func:`.quasi_random.unit_points`).
        axis: the planar axis (base frame); default base z.
        planar_map: the robot's cosine-polynomial gains, to evaluate them vectorised.
    """
    ranges = joint_ranges(mmap)
    n = len(ranges)
    per_axis = round(samples ** (1.0 / n))
    if n <= 2:
        axes = [np.linspace(lo, hi, per_axis) for lo, hi in ranges]
        points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, n)
    else:
        unit = unit_points(samples, n, seed)
        points = ranges[:, 0] + unit * (ranges[:, 1] - ranges[:, 0])
    n_axis = np.array([0.0, 0.0, 1.0]) if axis is None else np.asarray(axis, dtype=float)

    def gain(q: np.ndarray) -> np.ndarray:
        if planar_map is not None:
            return planar_map.gains(q)
        return np.asarray(n_axis @ mmap.f1(q))

    if planar_map is not None:
        gains = planar_map.gains(points)
    else:
        gains = np.array([gain(p) for p in points])
    # Continuous joints are periodic: let the refinement cross +-pi.
    limits = [
        (None, None) if joint.kind == "continuous" else (float(lo), float(hi))
        for joint, (lo, hi) in zip(mmap.robot.joints, ranges, strict=True)
    ]

    lower = np.array([-np.inf if lim[0] is None else lim[0] for lim in limits])
    upper = np.array([np.inf if lim[1] is None else lim[1] for lim in limits])

    def refine(i: int, sign: float) -> float:
        start = points[np.argmin(sign * gains[:, i])]
        if planar_map is not None:
            # Exact gradients of the cosine-polynomial gains: a projected gradient search
            # (no SciPy: it is slow to import, and the gains are smooth and cheap).
            def signed(q: np.ndarray) -> tuple[float, np.ndarray]:
                values, slopes = planar_map.gains_and_derivatives(q)
                return sign * values[i], sign * slopes[i]

            value = _projected_descent(signed, start, lower, upper)
            return float(min(sign * gains[:, i].min(), value) * sign)
        from scipy import optimize  # imported when first used

        result = optimize.minimize(
            lambda q: sign * gain(q)[i],
            start,
            method="L-BFGS-B",
            bounds=limits,
            options={"ftol": 1e-15, "gtol": 1e-12},
        )
        return float(min(sign * gains[:, i].min(), result.fun) * sign)

    g_min = np.array([refine(i, 1.0) for i in range(n)])
    g_max = np.array([refine(i, -1.0) for i in range(n)])
    return PlanarBounds(g_min=g_min, g_max=g_max)


def _projected_descent(
    function: Callable[[np.ndarray], tuple[float, np.ndarray]],
    start: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    iterations: int = 500,
) -> float:
    """Smallest value of a smooth function in a box, from ``start``.

    ``function`` gives the value and its gradient at a point. Projected gradient steps with
    Barzilai-Borwein lengths and backtracking; stops when a step changes the value by less than
    1e-15 (a fixed count of iterations at most, so the answer is deterministic).
    """
    x = np.clip(np.asarray(start, dtype=float), lower, upper)
    f, g = function(x)
    step = 1e-2
    for _ in range(iterations):
        while True:
            trial = np.clip(x - step * g, lower, upper)
            f_trial, g_trial = function(trial)
            if f_trial <= f - 1e-4 * float(g @ (x - trial)) or step < 1e-14:
                break
            step *= 0.5
        if step < 1e-14:
            break
        s, y = trial - x, g_trial - g
        done = abs(f - f_trial) < 1e-15 and float(np.abs(s).max()) < 1e-9
        x, f, g = trial, f_trial, g_trial
        if done:
            break
        curvature = float(s @ y)
        step = float(s @ s) / curvature if curvature > 1e-300 else 2.0 * step
    return float(f)
