"""The points an SLSQP run evaluated, and the best of them within its rows.

SLSQP can stop short, as "Inequality constraints incompatible", after passing points that
lower the objective far below its start while keeping every row: clearance rows, whose closest
pair changes from one point to the next, make the linearised rows inconsistent (ETS-VII under
``min_effort``: a point at a quarter of the start's effort within every row, then a stop with
its last point deep in collision). A :class:`Journal` wraps the functions SLSQP is given and
notes, per point, the objective and the smallest value of each inequality function;
:meth:`Journal.best` lists the points within every row, lowest objective first. They lie near
the root set, not on it (SLSQP keeps ``h = 0`` only to first order): the caller polishes them
onto it and checks them like any result.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Journal"]

Function = Callable[[np.ndarray], object]


@dataclass
class Journal:
    """What an SLSQP run met: per point (scaled coordinates ``z``), objective and rows.

    Attributes:
        rows: the number of inequality functions (each noted at every point it is asked at).
        points: the points met, by their bytes.
        objective: the objective at each point (the run's scaled value, unitless).
        lowest: per point, the smallest value of each inequality function asked there (>= 0
            within a row, SLSQP's sign; their units).
    """

    rows: int
    points: dict[bytes, np.ndarray] = field(default_factory=dict)
    objective: dict[bytes, float] = field(default_factory=dict)
    lowest: dict[bytes, dict[int, float]] = field(default_factory=dict)

    def _note(self, z: np.ndarray) -> bytes:
        key = np.asarray(z, dtype=float).tobytes()
        if key not in self.points:
            self.points[key] = np.array(z, dtype=float)
        return key

    def objective_of(self, fun: Callable[[np.ndarray], float]) -> Callable[[np.ndarray], float]:
        """``fun`` (the objective), its values noted."""

        def noted(z: np.ndarray) -> float:
            value = fun(z)
            self.objective[self._note(z)] = float(value)
            return value

        return noted

    def inequality(self, index: int, fun: Function) -> Callable[[np.ndarray], object]:
        """The ``index``-th inequality function ``fun``, the smallest of its values noted."""

        def noted(z: np.ndarray) -> object:
            values = fun(z)
            smallest = float(np.min(np.asarray(values, dtype=float), initial=math.inf))
            self.lowest.setdefault(self._note(z), {})[index] = smallest
            return values

        return noted

    def best(self, below: float, count: int) -> list[np.ndarray]:
        """Up to ``count`` points within every row, objective below ``below``, lowest first.

        ``below``: in the objective's own scale (the run's scaled value, unitless). A point
        counts only where the objective is known and every inequality function was asked
        (with none, every such point), none negative or not a number.
        """
        within = []
        for key, value in self.objective.items():
            rows = self.lowest.get(key, {})
            if len(rows) < self.rows or not value < below:  # False for NaN
                continue
            if all(v >= 0.0 for v in rows.values()):  # False for NaN
                within.append((value, key))
        within.sort(key=lambda item: item[0])
        return [self.points[key] for _, key in within[:count]]
