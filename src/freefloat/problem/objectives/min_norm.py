"""The paper's objective, the smallest free coefficients: the smallest deviation from the quintic.

``J = sum_k beta_k^2`` (rad^2, or m^2 for prismatic joints). In the orthonormal path basis
(:mod:`freefloat.problem.basis`) this is exactly ``int_0^1 |q(s) - q_quintic(s)|^2 ds``: the
squared L2 deviation of the joint paths from the plain quintic, over normalised time. It does
not depend on the duration; ``sqrt(J)`` is the RMS joint-space distance from the quintic (plans
print it in degrees). It is the planner's default: of all paths that reach the goal attitude,
the one that departs least from the smooth quintic, which is what keeps joints from swinging
far beyond their start-goal spans.
"""

from __future__ import annotations

import numpy as np

from ..residual import Problem
from .base import Objective, ObjectiveValue

__all__ = ["MinNorm"]


class MinNorm(Objective):
    """Squared L2 deviation from the quintic, ``|beta|^2`` (rad^2); the default."""

    name = "min_norm"
    unit = "rad^2"
    duration_power = 0
    description = "smallest deviation from the quintic (the paper's minimum norm, L2 over time)"

    def evaluate(self, problem: Problem, beta: np.ndarray) -> ObjectiveValue:
        """``beta . beta`` and ``2 beta``."""
        beta = np.asarray(beta, dtype=float)
        return ObjectiveValue(float(beta @ beta), 2.0 * beta)

    def metric(self, problem: Problem, beta: np.ndarray) -> np.ndarray:
        """The identity (the Hessian is 2 I)."""
        return np.eye(problem.n_free)
