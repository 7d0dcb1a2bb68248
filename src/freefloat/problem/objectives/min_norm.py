"""The paper's objective: the smallest free coefficients.

``J = sum_k beta_k^2`` (rad^2, or m^2 for prismatic joints): the squared norm of the free
coefficients of the normalised path. It does not depend on the duration. It has no physical
meaning (it depends on how the polynomial basis is scaled), but it is the planner's default,
so plans made before objectives existed are unchanged.
"""

from __future__ import annotations

import numpy as np

from ..residual import Problem
from .base import Objective, ObjectiveValue

__all__ = ["MinNorm"]


class MinNorm(Objective):
    """Squared norm of the free coefficients (rad^2); the default."""

    name = "min_norm"
    unit = "rad^2"
    duration_power = 0
    description = "smallest free coefficients (the paper's choice)"

    def evaluate(self, problem: Problem, beta: np.ndarray) -> ObjectiveValue:
        """``beta . beta`` and ``2 beta``."""
        beta = np.asarray(beta, dtype=float)
        return ObjectiveValue(float(beta @ beta), 2.0 * beta)

    def metric(self, problem: Problem, beta: np.ndarray) -> np.ndarray:
        """The identity (the Hessian is 2 I)."""
        return np.eye(problem.n_free)
