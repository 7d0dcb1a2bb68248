"""Evenly spread points in the unit cube, for sampling a joint box before refinement.

The additive recurrence with the generalised golden ratio (a Kronecker sequence): point ``k``
is ``frac(offset + k alpha)`` with ``alpha_j = phi^-(j + 1)``, ``phi`` the positive root of
``x^(d + 1) = x + 1``. Its points fill the cube with low discrepancy in any dimension, every
prefix too, and cost one array product: no random state, so the same points on any machine,
and nothing slow to import (SciPy's quasi-Monte Carlo module takes about 0.3 s to load, a
tenth of a ``freefloat reach``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["unit_points"]


def _golden(dimensions: int) -> float:
    """The positive root of ``x^(d + 1) = x + 1`` (d = ``dimensions``), by Newton from 2."""
    x = 2.0
    for _ in range(60):  # converges in well under 60 steps from above
        step = (x ** (dimensions + 1) - x - 1.0) / ((dimensions + 1) * x**dimensions - 1.0)
        x -= step
        if abs(step) < 1e-16:
            break
    return x


def unit_points(count: int, dimensions: int, seed: int = 0) -> np.ndarray:
    """(``count``, ``dimensions``) points in ``[0, 1)^dimensions``, evenly spread.

    Args:
        count: number of points (>= 0).
        dimensions: dimension of the cube (>= 1).
        seed: shifts the sequence (another seed, of either sign, other points of the same
            quality in every dimension); the points are a function of the three arguments
            alone.
    """
    if count < 0 or dimensions < 1:
        raise ValueError(f"need count >= 0 and dimensions >= 1, got {count}, {dimensions}")
    alpha = _golden(dimensions) ** -np.arange(1, dimensions + 1, dtype=float)
    offset = np.mod(0.5 + seed * np.sqrt(_primes(dimensions)), 1.0)  # irrational per dimension
    k = np.arange(count, dtype=float)[:, None]
    return np.mod(offset + k * alpha, 1.0)


def _primes(count: int) -> np.ndarray:
    """The first ``count`` primes (as floats)."""
    found: list[int] = []
    candidate = 2
    while len(found) < count:
        if all(candidate % p for p in found if p * p <= candidate):
            found.append(candidate)
        candidate += 1
    return np.array(found, dtype=float)
