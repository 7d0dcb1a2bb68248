"""The distribution of final attitude errors over many replays (a Monte Carlo study)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ErrorDistribution", "error_distribution"]


@dataclass(frozen=True)
class ErrorDistribution:
    """The final attitude error over replays (rad).

    Attributes:
        count: replays.
        mean: mean error angle.
        std: its standard deviation (sample, N - 1; 0 for one replay).
        median: median error angle.
        p95: 95th percentile (linear interpolation).
        largest: largest error angle.
        covariance: 3 x 3 sample covariance of the error rotation vectors (rad^2).
    """

    count: int
    mean: float
    std: float
    median: float
    p95: float
    largest: float
    covariance: np.ndarray


def error_distribution(vectors: np.ndarray) -> ErrorDistribution | None:
    """The distribution of error rotation vectors (K, 3) (rad); None when there are none."""
    vectors = np.asarray(vectors, dtype=float).reshape(-1, 3)
    if not len(vectors):
        return None
    angles = np.linalg.norm(vectors, axis=1)
    several = len(vectors) > 1
    return ErrorDistribution(
        count=len(vectors),
        mean=float(angles.mean()),
        std=float(angles.std(ddof=1)) if several else 0.0,
        median=float(np.median(angles)),
        p95=float(np.percentile(angles, 95)),
        largest=float(angles.max()),
        covariance=np.atleast_2d(np.cov(vectors.T)) if several else np.zeros((3, 3)),
    )
