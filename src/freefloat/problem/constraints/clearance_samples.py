"""Samples of clearance along a path: what the dense check measured, and its minima.

Helpers of :mod:`freefloat.problem.constraints.clearance` (the constraint's module stays a
readable size): the record of a path's measured samples with each pair's bounds there, and
the local minima of sampled values, and the bound of the clearance between two samples.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...robot.collision import Closest
from ...robot.motion_bound import BOUND_SLACK
from ..paths import JointPolynomials
from ..rate_bounds import rate_bounds

__all__ = [
    "Measured",
    "bound_between",
    "local_minima",
    "lowest_minima",
    "pair_bounds",
    "undecided",
]


@dataclass(frozen=True)
class Measured:
    """The samples of a path the dense check measured, and what it bounded from them.

    Attributes:
        known: (S,) smallest distance over the pairs per sample (m; NaN where spared).
        lower: (S, P) lower bounds of every pair's distance per sample (m; NaN where spared).
        bound: a lower bound of the clearance along the whole path (m; -inf when none was
            sought: a sample already below the limit asked for).
        pairs: (S,) the closest pair per sample (-1 where spared).
    """

    known: np.ndarray
    lower: np.ndarray
    bound: float
    pairs: np.ndarray


def pair_bounds(found: Closest) -> np.ndarray:
    """(B, P) the pairs' lower bounds (m) of a batch of queries."""
    assert found.lower is not None
    return found.lower


def lowest_minima(values: np.ndarray) -> list[int]:
    """Indices of the two lowest local minima of ``values`` (or the two lowest apart)."""
    n = len(values)
    minima = local_minima(values)
    order = [int(k) for k in minima[np.argsort(np.asarray(values)[minima], kind="stable")]]
    if len(order) < 2:
        far = [int(k) for k in np.argsort(values, kind="stable") if abs(int(k) - order[0]) > 2]
        order.append(far[0] if far else (order[0] + n // 2) % n)
    return order[:2]


def local_minima(values: np.ndarray) -> np.ndarray:
    """Indices of the local minima of ``values`` (an end counts against its one neighbour)."""
    left = np.concatenate([[np.inf], values[:-1]])
    right = np.concatenate([values[1:], [np.inf]])
    return np.flatnonzero((values <= left) & (values <= right))


def bound_between(
    path: JointPolynomials,
    weights: np.ndarray,
    t0: np.ndarray,
    t1: np.ndarray,
    lower0: np.ndarray,
    lower1: np.ndarray,
) -> np.ndarray:
    """Lower bounds (m) of the clearance over ``[t0, t1]`` (s), from bounds at both ends.

    ``lower0``, ``lower1``: (I, P) lower bounds of every pair's distance at ``t0`` and ``t1``
    (m; the measured distance where measured). Per pair: their mean less half the time between
    them times how fast that pair's distance can change there (its motion ``weights``, P x N m
    per rad, times bounds of the joint rates); the clearance's bound is the smallest.
    """
    speed = rate_bounds(path, t0, t1) @ weights.T  # (I, P), m/s
    per_pair = 0.5 * (lower0 + lower1 - speed * (t1 - t0)[:, None])
    per_pair = np.nan_to_num(per_pair, nan=-math.inf)  # no bound: nothing spared
    return np.min(per_pair, axis=1) - BOUND_SLACK


def undecided(
    path: JointPolynomials,
    weights: np.ndarray,
    ends: np.ndarray,
    table: np.ndarray,
    limit: float,
) -> np.ndarray:
    """Which intervals may dip below ``limit`` (m) unseen.

    ``ends``: rows t0, t1 (s), v0, v1 (m), and the rows of ``table`` (pair bounds, m) at both
    ends. Both ends measured and above ``limit`` (a sample below it is a dip seen), and the
    bound between them (:func:`bound_between`) below it.
    """
    seen = ~np.isnan(ends[2]) & ~np.isnan(ends[3]) & (ends[2] >= limit) & (ends[3] >= limit)
    bound = np.full(ends.shape[1], math.inf)
    if np.any(seen):
        first, second = ends[4, seen].astype(int), ends[5, seen].astype(int)
        bound[seen] = bound_between(
            path, weights, ends[0, seen], ends[1, seen], table[first], table[second]
        )
    return bound < limit
