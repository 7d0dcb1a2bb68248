"""SLSQP's coordinates for :mod:`.optimise`: the objective and the attitude residual in ``z``.

``beta = beta0 + S z``, with ``S`` (:func:`scaled_coordinates`) such that the objective divided
by its value at ``beta0`` has a Hessian close to the identity; :class:`Evaluations` gives SLSQP
the objective, its gradient, the residual and its Jacobian in ``z``, remembered for the last
few points and counted against a budget of objective evaluations (a count).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import Any

import numpy as np

from ..problem.objectives import Objective, gauss_legendre
from ..problem.residual import Problem
from ..progress import heartbeat

__all__ = ["BudgetSpentError", "Evaluations", "scaled_coordinates"]


class BudgetSpentError(Exception):
    """The objective evaluation budget of one call is spent."""


def scaled_coordinates(
    problem: Problem, objective: Objective, beta: np.ndarray, value: float
) -> np.ndarray:
    """``S`` in which the objective divided by ``value`` has a Hessian near the identity.

    With the objective's metric ``M`` at ``beta`` (its Gauss-Newton factor: ``2 M^T M`` is
    close to the Hessian), ``S^T (M^T M + r^2 A^T A) S = value / 2 I``, where ``A`` is the
    weighted second-derivative map of the basis (exact Gauss-Legendre integration) and ``r`` a
    small multiple that keeps the matrix positive definite where ``M`` is rank deficient.
    Without a metric (``min_length``), ``S^T A^T A S`` is ``value / |A|^2 I``: the acceleration
    norm, scaled to the value. Built from the QR factors of the stacked matrices, not from a
    Cholesky factor of the product: that squares the condition number of a high-degree
    monomial basis.
    """
    s, w = gauss_legendre(max(problem.family.degrees))
    dqss = problem.family.affine_samples(s).dqss
    accel = (np.sqrt(w)[:, None, None] * dqss).reshape(-1, problem.n_free)
    metric = objective.metric(problem, beta)
    if metric is None:
        stacked = accel * np.sqrt(max(value, 1e-300) / max(_norm2(accel), 1e-300))
    else:
        weight = 1e-3 * np.sqrt(_norm2(metric) / max(_norm2(accel), 1e-300))
        stacked = np.vstack([metric, weight * accel]) / np.sqrt(max(0.5 * value, 1e-300))
    r = np.linalg.qr(stacked, mode="r")
    return np.linalg.solve(r, np.eye(problem.n_free))


def _norm2(matrix: np.ndarray) -> float:
    """Squared Frobenius norm."""
    return float(np.sum(matrix * matrix))


def _where(name: str, spent: int, budget: int) -> str:
    """A progress line of the minimisation (evaluations are counts)."""
    return f"minimise {name}: {spent} of at most {budget} objective evaluations at this level"


class Evaluations:
    """The objective and the attitude residual in scaled coordinates ``z``.

    ``beta = beta0 + S z``; the objective at T = 1 s divided by ``scale``. Values are kept for
    the last few points; objective evaluations are counted against a budget (a count).
    """

    def __init__(
        self,
        problem: Problem,
        unit: Problem,
        objective: Objective,
        beta0: np.ndarray,
        s_mat: np.ndarray,
        scale: float,
        budget: int,
    ) -> None:
        self.problem, self.unit, self.objective = problem, unit, objective
        self.beta0, self.s_mat, self.scale, self.budget = beta0, s_mat, scale, budget
        self.memo: dict[bytes, Any] = {}
        self.spent = 0  # objective evaluations so far
        self.start = 1.0  # the objective at beta0 divided by scale

    def to_beta(self, z: np.ndarray) -> np.ndarray:
        """``beta0 + S z`` (rad or m)."""
        return self.beta0 + self.s_mat @ z

    def _cached(self, kind: str, z: np.ndarray, make: Callable[[np.ndarray], Any]) -> Any:
        key = kind.encode() + np.asarray(z, dtype=float).tobytes()
        if key not in self.memo:
            if kind == "j":
                self.spent += 1
                if self.spent > self.budget:
                    raise BudgetSpentError
                heartbeat(partial(_where, self.objective.name, self.spent, self.budget))
            if len(self.memo) > 64:
                self.memo.clear()
            self.memo[key] = make(self.to_beta(z))
        return self.memo[key]

    def _objective(self, z: np.ndarray) -> Any:
        return self._cached("j", z, lambda b: self.objective.evaluate(self.unit, b))

    def fun(self, z: np.ndarray) -> float:
        """The objective at ``z`` divided by the scale (unitless)."""
        return float(self._objective(z).value) / self.scale

    def grad(self, z: np.ndarray) -> np.ndarray:
        """The gradient of :meth:`fun` in ``z``."""
        return np.asarray(self.s_mat.T @ self._objective(z).gradient) / self.scale

    def h(self, z: np.ndarray) -> np.ndarray:
        """The attitude residual at ``z`` (rad)."""
        return np.asarray(self._cached("h", z, self.problem.residual_and_jacobian)[0])

    def dh(self, z: np.ndarray) -> np.ndarray:
        """The residual's Jacobian in ``z`` (rad per unit of ``z``)."""
        return np.asarray(self._cached("h", z, self.problem.residual_and_jacobian)[1] @ self.s_mat)
