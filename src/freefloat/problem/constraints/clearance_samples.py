"""Samples of clearance along a path: what the dense check measured, and its minima.

Helpers of :mod:`freefloat.problem.constraints.clearance` (the constraint's module stays a
readable size): the record of a path's measured samples with each pair's bounds there, and
the local minima of sampled values.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...robot.collision import Closest

__all__ = ["Measured", "local_minima", "lowest_minima", "pair_bounds"]


@dataclass(frozen=True)
class Measured:
    """The samples of a path the dense check measured, and what it bounded from them.

    Attributes:
        known: (S,) smallest distance over the pairs per sample (m; NaN where spared).
        lower: (S, P) lower bounds of every pair's distance per sample (m; NaN where spared).
        bound: a lower bound of the clearance along the whole path (m).
    """

    known: np.ndarray
    lower: np.ndarray
    bound: float


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
