"""Least effort: the integral of the squared joint torques of the free-floating dynamics.

``E = int_0^T |tau(t)|^2 dt`` (N^2 m^2 s), with ``tau`` the joint torques of the zero-momentum
motion (:mod:`freefloat.physics.torque_derivatives`). With ``s = t / T`` the torques are
``tau(t) = tau_1(s) / T^2``, ``tau_1`` the torques of the same path run in one second, so
``E = T^-3 int_0^1 |tau_1(s)|^2 ds``: the best path does not depend on the duration.

The integrand is smooth but not polynomial; it is integrated by Gauss-Legendre quadrature on
``nodes`` points, with the exact gradient of that quadrature: ``dtau/dbeta`` by the chain rule
through Pinocchio's analytic RNEA derivatives (``q``, ``q'`` and ``q''`` are affine in
``beta``). :meth:`MinEffort.error_estimate` compares with twice as many nodes.
"""

from __future__ import annotations

import numpy as np

from ...physics.joint_torques import joint_torques_batch
from ...physics.torque_derivatives import torques_and_derivatives
from ..residual import Problem
from .base import Objective, ObjectiveValue, gauss_legendre

__all__ = ["MinEffort"]


class MinEffort(Objective):
    """Integral of |tau|^2 over the motion (N^2 m^2 s; N^2 s for prismatic joints).

    Attributes:
        nodes: Gauss-Legendre nodes on [0, 1].
    """

    name = "min_effort"
    unit = "N^2 m^2 s"
    duration_power = 3
    exact = False
    description = "least effort: least integral of squared joint torques"

    def __init__(self, nodes: int = 32) -> None:
        self.nodes = int(nodes)

    def _torques(
        self, problem: Problem, beta: np.ndarray, nodes: int
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Weights, torques (T = 1 s) and their beta-derivatives at the Gauss nodes."""
        s, w = gauss_legendre(nodes)
        samples = problem.family.affine_samples(s)
        path = samples.at(beta)
        found = torques_and_derivatives(problem.mmap, path.q, path.qd, path.qdd)
        dtau = (
            np.einsum("kij,kjf->kif", found.d_q, samples.dq)
            + np.einsum("kij,kjf->kif", found.d_qd, samples.dqs)
            + np.einsum("kij,kjf->kif", found.d_qdd, samples.dqss)
        )
        return w, found.tau, dtau

    def _evaluate(
        self, problem: Problem, beta: np.ndarray, nodes: int, gradient: bool = True
    ) -> ObjectiveValue:
        scale = problem.duration**-3
        if not gradient:
            s, w = gauss_legendre(nodes)
            path = problem.family.affine_samples(s).at(beta)
            tau = joint_torques_batch(problem.mmap, path.q, path.qd, path.qdd)
            return ObjectiveValue(
                scale * float(np.einsum("k,ki,ki->", w, tau, tau)), np.zeros(problem.n_free)
            )
        w, tau, dtau = self._torques(problem, beta, nodes)
        value = scale * float(np.einsum("k,ki,ki->", w, tau, tau))
        grad = 2.0 * scale * np.einsum("k,ki,kif->f", w, tau, dtau)
        return ObjectiveValue(value, grad)

    def metric(self, problem: Problem, beta: np.ndarray) -> np.ndarray:
        """Weighted ``dtau/dbeta`` at the nodes (the Gauss-Newton factor of the Hessian)."""
        w, _, dtau = self._torques(problem, beta, self.nodes)
        scale = problem.duration**-1.5
        return (scale * np.sqrt(w)[:, None, None] * dtau).reshape(-1, problem.n_free)

    def evaluate(self, problem: Problem, beta: np.ndarray) -> ObjectiveValue:
        """Value and exact gradient of the quadrature (N^2 m^2 s)."""
        return self._evaluate(problem, beta, self.nodes)

    def error_estimate(self, problem: Problem, beta: np.ndarray) -> float:
        """Difference from the quadrature on twice the nodes (N^2 m^2 s)."""
        fine = self._evaluate(problem, beta, 2 * self.nodes, gradient=False).value
        return abs(fine - self._evaluate(problem, beta, self.nodes, gradient=False).value)
