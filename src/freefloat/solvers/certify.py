"""Certify the attitude integration at a root: refine the grid until its error is negligible."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..problem.residual import Problem
from .newton import polish

__all__ = ["Certified", "certify"]


@dataclass(frozen=True)
class Certified:
    """A root on a grid fine enough for it.

    Attributes:
        problem: the problem on that grid (a copy when the grid was refined).
        beta: the root, polished on that grid.
        residual: its attitude residual (rad).
        integration_error: the grid's error estimate at the root (rad).
        passed: whether the error is below a tenth of the tolerance and the residual below it.
    """

    problem: Problem
    beta: np.ndarray
    residual: float
    integration_error: float
    passed: bool


def certify(problem: Problem, beta: np.ndarray, residual: float, tolerance: float) -> Certified:
    """Refine the integration grid at a root until its error is negligible.

    Up to three refinements, until the error is below a tenth of ``tolerance`` (rad); the root
    (with attitude residual ``residual``, rad) is polished on each finer grid.
    """
    certified = problem
    error = certified.integration_error(beta)
    for _ in range(3):
        if error <= 0.1 * tolerance:
            break
        certified = certified.with_steps(certified.steps_for(beta))
        beta, vector = polish(certified, beta, tolerance)
        residual = float(np.linalg.norm(vector))
        error = certified.integration_error(beta)
    passed = error <= 0.1 * tolerance and residual < tolerance
    return Certified(certified, beta, residual, error, passed)
