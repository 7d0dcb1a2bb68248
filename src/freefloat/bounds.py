"""Reachable yaw change of a planar free floater (method.md section 6).

For a planar system ``dyaw = sum_i g_i(q) dq_i`` with ``g_i`` the z row of ``F1``. Each
``g_i`` is bounded over the configurations the joints can take (their limits; a full turn for
continuous joints). For a joint moving monotonically by ``dq_i`` its contribution lies between
``g_i,min dq_i`` and ``g_i,max dq_i`` (ends swapped when ``dq_i < 0``); the sum of these
intervals is the (open) interval of yaw changes a simple point-to-point motion can reach.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize
from scipy.stats import qmc

from .momentum import MomentumMap

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


def joint_ranges(mmap: MomentumMap) -> np.ndarray:
    """(N, 2) ranges to explore per joint: limits, or one full turn for continuous joints."""
    ranges = []
    for joint in mmap.robot.joints:
        if math.isfinite(joint.lower) and math.isfinite(joint.upper):
            ranges.append((joint.lower, joint.upper))
        else:
            ranges.append((-math.pi, math.pi))
    return np.array(ranges)


def planar_bounds(mmap: MomentumMap, samples: int = 4096, seed: int = 0) -> PlanarBounds:
    """Extremes of each gain ``g_i(q)`` for a planar robot.

    The gains are sampled on a grid (up to two joints) or a scrambled Sobol set, and the best
    samples are refined with bounded quasi-Newton searches, so the extremes are accurate to
    the optimiser's tolerance (about 1e-10).

    Args:
        mmap: momentum map of a planar robot.
        samples: number of configurations sampled before refinement.
        seed: seed of the Sobol scrambling (the result is deterministic for a seed).
    """
    ranges = joint_ranges(mmap)
    n = len(ranges)
    per_axis = round(samples ** (1.0 / n))
    if n <= 2:
        axes = [np.linspace(lo, hi, per_axis) for lo, hi in ranges]
        points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, n)
    else:
        unit = qmc.Sobol(n, scramble=True, seed=seed).random(samples)
        points = ranges[:, 0] + unit * (ranges[:, 1] - ranges[:, 0])
    gains = np.array([mmap.f1(p)[2] for p in points])
    # Continuous joints are periodic: let the refinement cross +-pi.
    limits = [
        (None, None) if joint.kind == "continuous" else (float(lo), float(hi))
        for joint, (lo, hi) in zip(mmap.robot.joints, ranges, strict=True)
    ]

    def refine(i: int, sign: float) -> float:
        start = points[np.argmin(sign * gains[:, i])]
        result = minimize(
            lambda q: sign * mmap.f1(q)[2, i],
            start,
            method="L-BFGS-B",
            bounds=limits,
            options={"ftol": 1e-15, "gtol": 1e-12},
        )
        return float(min(sign * gains[:, i].min(), result.fun) * sign)

    g_min = np.array([refine(i, 1.0) for i in range(n)])
    g_max = np.array([refine(i, -1.0) for i in range(n)])
    return PlanarBounds(g_min=g_min, g_max=g_max)
