"""Shortest joint-space path: the length of the curve the joints trace.

``L = int_0^1 sqrt(|q'(s)|^2 + eps^2) ds`` (rad; the duration does not matter), a smooth
approximation of ``int |q'| ds`` whose gradient exists everywhere, with
``eps = 1e-3 |q_goal - q_start|`` (or 1e-6 rad when the joints do not move); it overestimates
the length by at most ``eps``. The integrand is not polynomial: it is integrated by
Gauss-Legendre quadrature on ``nodes`` points, and :meth:`MinLength.error_estimate` compares with
twice as many.
"""

from __future__ import annotations

import numpy as np

from ..residual import Problem
from .base import Objective, ObjectiveValue, gauss_legendre

__all__ = ["MinLength"]


class MinLength(Objective):
    """Smoothed joint-space path length (rad; m for prismatic joints).

    Attributes:
        nodes: Gauss-Legendre nodes on [0, 1].
    """

    name = "min_length"
    unit = "rad"
    duration_power = 0
    exact = False
    description = "shortest joint-space path (smoothed: at most 1e-3 of the travel above it)"

    def __init__(self, nodes: int = 64) -> None:
        self.nodes = int(nodes)

    @staticmethod
    def smoothing(problem: Problem) -> float:
        """``eps`` (rad)."""
        travel = float(np.linalg.norm(problem.family.goal - problem.family.start))
        return 1e-3 * travel if travel > 0 else 1e-6

    def _evaluate(self, problem: Problem, beta: np.ndarray, nodes: int) -> ObjectiveValue:
        s, w = gauss_legendre(nodes)
        samples = problem.family.affine_samples(s)
        qs = samples.at(beta).qd
        speed = np.sqrt(np.einsum("ki,ki->k", qs, qs) + self.smoothing(problem) ** 2)
        value = float(w @ speed)
        gradient = np.einsum("k,ki,kif->f", w / speed, qs, samples.dqs)
        return ObjectiveValue(value, gradient)

    def evaluate(self, problem: Problem, beta: np.ndarray) -> ObjectiveValue:
        """Value and exact gradient of the quadrature (rad)."""
        return self._evaluate(problem, beta, self.nodes)

    def error_estimate(self, problem: Problem, beta: np.ndarray) -> float:
        """Difference from the quadrature on twice the nodes (rad)."""
        fine = self._evaluate(problem, beta, 2 * self.nodes).value
        return abs(fine - self.evaluate(problem, beta).value)
