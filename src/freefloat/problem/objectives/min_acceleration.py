"""Smoothest joint motion: the integral of the squared joint accelerations.

``J = int_0^T |qddot(t)|^2 dt = T^-3 int_0^1 |q''(s)|^2 ds`` (rad^2/s^3). The path is polynomial
and affine in ``beta``, so ``J`` is quadratic in ``beta``; Gauss-Legendre quadrature with as
many nodes as the highest degree integrates it exactly (the integrand has degree
``2 (degree - 2)``): no sampling error. For the plain quintic path of every joint,
``J = (120 / 7) |q_goal - q_start|^2 / T^3``.
"""

from __future__ import annotations

import numpy as np

from ..residual import Problem
from .base import Objective, ObjectiveValue, gauss_legendre

__all__ = ["MinAcceleration"]


class MinAcceleration(Objective):
    """Integral of |qddot|^2 over the motion (rad^2/s^3; m^2/s^3 for prismatic joints), exact."""

    name = "min_acceleration"
    unit = "rad^2/s^3"
    duration_power = 3
    description = "smoothest joint motion: least integral of squared joint accelerations"

    def evaluate(self, problem: Problem, beta: np.ndarray) -> ObjectiveValue:
        """Exact value and gradient (a quadratic form in ``beta``)."""
        s, w = gauss_legendre(max(problem.family.degrees))
        samples = problem.family.affine_samples(s)
        qss = samples.at(beta).qdd  # (K, N)
        scale = problem.duration**-3
        value = scale * float(np.einsum("k,ki,ki->", w, qss, qss))
        gradient = 2.0 * scale * np.einsum("k,ki,kif->f", w, qss, samples.dqss)
        return ObjectiveValue(value, gradient)

    def metric(self, problem: Problem, beta: np.ndarray) -> np.ndarray:
        """Weighted ``dq''/dbeta`` at the nodes: exactly half the Hessian's square root."""
        s, w = gauss_legendre(max(problem.family.degrees))
        dqss = problem.family.affine_samples(s).dqss
        scale = problem.duration**-1.5
        return (scale * np.sqrt(w)[:, None, None] * dqss).reshape(-1, problem.n_free)
