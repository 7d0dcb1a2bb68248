"""The objective interface: what "best" means when many paths reach the goal attitude.

With more free coefficients than attitude equations, a whole family of paths reaches the goal;
an objective picks one. Each objective is a function of the free coefficients ``beta`` with an
exact gradient, evaluated at the problem's duration ``T`` in physical units. Every objective
here scales with the duration as a power, ``J_T = J_1 T^-p`` (the path shape does not depend on
``T``), so the path that is best at one duration is best at every duration. Solvers receive one
objective; adding one means one new module with a subclass, plus its name in :mod:`.registry`.
"""

from __future__ import annotations

import abc
import functools
from dataclasses import dataclass

import numpy as np

from ..residual import Problem

__all__ = ["Objective", "ObjectiveValue", "gauss_legendre"]


@dataclass(frozen=True)
class ObjectiveValue:
    """An objective's value and exact gradient at one ``beta``.

    Attributes:
        value: the objective (in the objective's unit, at the problem's duration).
        gradient: (n_free,) exact ``dJ/dbeta``.
    """

    value: float
    gradient: np.ndarray


class Objective(abc.ABC):
    """One objective (see the module docstring).

    Attributes:
        name: identifier used in scenarios, on the command line and in plans.
        unit: unit of the value.
        duration_power: ``p`` in ``J_T = J_1 T^-p``.
        exact: whether the value is exact (no quadrature error).
        description: one line for the reader.
    """

    name: str = "objective"
    unit: str = "1"
    duration_power: int = 0
    exact: bool = True
    description: str = ""

    @abc.abstractmethod
    def evaluate(self, problem: Problem, beta: np.ndarray) -> ObjectiveValue:
        """Value and exact gradient at ``beta`` (problem's duration)."""

    def error_estimate(self, problem: Problem, beta: np.ndarray) -> float:
        """Numerical error of :meth:`evaluate`'s value (unit); 0 when exact."""
        return 0.0

    def metric(self, problem: Problem, beta: np.ndarray) -> np.ndarray | None:
        """A matrix ``M`` with ``M^T M`` close to half the Hessian at ``beta``, or None.

        Objectives that are sums of squares give the Jacobian of their weighted residuals
        (the Gauss-Newton approximation); solvers use it to scale their coordinates.
        """
        return None

    @property
    def nodes_used(self) -> int:
        """Quadrature nodes of the value (0 when exact or none are needed)."""
        return int(getattr(self, "nodes", 0))

    def refined(self) -> Objective:
        """The same objective with twice the quadrature nodes (itself when exact)."""
        if self.exact:
            return self
        return type(self)(nodes=2 * self.nodes_used)  # type: ignore[call-arg]

    def converged(
        self, problem: Problem, beta: np.ndarray, relative: float = 1e-9, max_nodes: int = 512
    ) -> Objective:
        """This objective, or one with more nodes, converged at ``beta``.

        Converged: its error estimate is below ``relative`` times its value (or it has
        ``max_nodes`` nodes).
        """
        objective: Objective = self
        while not objective.exact and objective.nodes_used < max_nodes:
            value = abs(objective.evaluate(problem, beta).value)
            if objective.error_estimate(problem, beta) <= relative * max(value, 1e-300):
                break
            objective = objective.refined()
        return objective

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


@functools.lru_cache(maxsize=32)
def gauss_legendre(count: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on [0, 1] (exact for polynomials of degree < 2 count).

    The arrays are shared between callers: read-only.
    """
    x, w = np.polynomial.legendre.leggauss(int(count))
    nodes, weights = 0.5 * (x + 1.0), 0.5 * w
    nodes.flags.writeable = False
    weights.flags.writeable = False
    return nodes, weights
