"""The objective interface: what "best" means when many paths reach the goal attitude.

With more free coefficients than attitude equations, a whole family of paths reaches the goal;
an objective picks one. Each objective is a function of the free coefficients ``beta`` with an
exact gradient, evaluated at the problem's duration ``T`` in physical units. Every objective
here scales with the duration as a power, ``J_T = J_1 T^-p`` (the path shape does not depend on
``T``), so the path that is best at one duration is best at every duration. Solvers receive one
objective; adding one means one new module with a subclass, plus its name in :mod:`.registry`.

An objective writes and reads its own parameters (:meth:`Objective.to_record`,
:meth:`Objective.from_record`; the quadrature is not a parameter: a plan records it apart), so
a plan names its objective completely and ``freefloat verify`` rebuilds it from the registry.
"""

from __future__ import annotations

import abc
import copy
import functools
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import InputError
from ..residual import Problem

__all__ = ["Level", "Objective", "ObjectiveValue", "gauss_legendre"]

#: Longest ``Level.note`` kept (characters): the plan file's limit.
MAX_NOTE = 200


@dataclass(frozen=True)
class ObjectiveValue:
    """An objective's value and exact gradient at one ``beta``.

    Attributes:
        value: the objective (in the objective's unit, at the problem's duration).
        gradient: (n_free,) exact ``dJ/dbeta``.
    """

    value: float
    gradient: np.ndarray


@dataclass(frozen=True)
class Level:
    """One freedom level an objective was minimised with (the minimiser's result, as stored).

    Attributes:
        freedom: free coefficients per joint.
        value: the objective at that level's best root (the objective's unit).
        iterations: SLSQP iterations spent.
        note: why the level kept its starting path, when it did (cut to :data:`MAX_NOTE`
            characters).
    """

    freedom: dict[str, int]
    value: float
    iterations: int
    note: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "note", self.note[:MAX_NOTE])


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

    def with_nodes(self, nodes: int) -> Objective:
        """A copy on ``nodes`` quadrature nodes, other parameters kept (itself when exact)."""
        if self.exact:
            return self
        out = copy.copy(self)
        out.nodes = int(nodes)  # type: ignore[attr-defined]
        return out

    def refined(self) -> Objective:
        """The same objective with twice the quadrature nodes (itself when exact)."""
        return self.with_nodes(2 * self.nodes_used)

    def to_record(self) -> dict[str, Any]:
        """The objective's parameters, JSON-ready, as a plan writes them (default: none).

        ``type(self).from_record(self.to_record())`` is the same objective (quadrature aside).
        """
        return {}

    @classmethod
    def from_record(cls, record: Mapping[str, Any]) -> Objective:
        """The objective its parameters describe (as :meth:`to_record` writes them).

        Raises:
            InputError: an unknown, missing or bad parameter, named, with what is valid.
        """
        if record:
            raise InputError(
                f"objective {cls.name!r} takes no parameters, got {', '.join(map(repr, record))}"
            )
        return cls()

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
