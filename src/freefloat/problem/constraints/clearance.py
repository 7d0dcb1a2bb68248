"""Clearance: every checked pair of bodies stays at least a margin apart along the path.

The pairs and their signed distances come from the robot's collision model (convex hulls,
coal's GJK/EPA; see :mod:`freefloat.robot.collision`). Obstacles are fixed to the spacecraft,
so clearance is a function of the joints alone.

For the solvers, each instant contributes one row: the margin minus the smallest distance over
the pairs there (m), with its gradient from the witness points of that pair and the joint
Jacobians, chained with the path's linear dependence on ``beta``. The instants are a uniform
grid refined around the minima of clearance, and the rows ask for a little more than the
margin (:data:`SOLVER_SLACK`) so that the dips between instants stay outside it.

The dense check samples the whole path, refines every near-minimum by a bounded scalar search
in time, and estimates its own error by step doubling (the same search on half the samples).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.optimize import minimize_scalar

from ...robot.collision import CollisionModel
from ...robot.model import Robot
from ..paths import JointPolynomials
from ..residual import Problem
from .base import DEFAULT_INSTANTS, Constraint, ConstraintRows, Excess

__all__ = ["REFINE", "SOLVER_SLACK", "Clearance", "clearance_at"]

#: Extra clearance the solvers ask for beyond the margin, between constraint instants (m).
SOLVER_SLACK = 2e-3
#: Extra instants per grid interval next to a local minimum of clearance.
REFINE = 3


class Clearance(Constraint):
    """Every checked pair at least ``margin`` apart (m) at every instant of the path.

    Args:
        model: the robot's collision model (pairs, obstacles).
        margin: required clearance (m), >= 0.
    """

    name = "clearance"
    unit = "m"
    tolerance = 1e-6
    affine = False

    def __init__(self, model: CollisionModel, margin: float = 0.01) -> None:
        if not (math.isfinite(margin) and margin >= 0.0):
            raise ValueError(f"clearance margin must be a finite number >= 0 m, got {margin!r}")
        self.model = model
        self.margin = float(margin)
        self._memo: tuple[Problem, bytes, ConstraintRows] | None = None

    def __repr__(self) -> str:
        return f"Clearance(margin={self.margin:g} m, {self.model.n_pairs} pairs)"

    def applies_to(self, robot: Robot) -> bool:
        """True when the collision model has pairs to check."""
        return self.model.n_pairs > 0

    def rows(
        self, problem: Problem, beta: np.ndarray, instants: np.ndarray = DEFAULT_INSTANTS
    ) -> ConstraintRows:
        """``margin + slack - min_pair d(q(s))`` (m) and its exact gradient, one row an instant.

        Clearance picks its own instants: the uniform grid :data:`DEFAULT_INSTANTS` (the
        ``instants`` asked for are thinned to it, since other constraints' tightest instants
        say nothing of clearance), plus :data:`REFINE` instants in each grid interval next to
        each of the two lowest local minima of clearance on that grid: a fixed number of rows,
        as SLSQP needs.
        """
        beta = np.asarray(beta, dtype=float)
        key = beta.tobytes()
        if self._memo is not None and self._memo[0] is problem and self._memo[1] == key:
            return self._memo[2]
        grid = DEFAULT_INSTANTS
        base, dq, _ = problem.family.linear_map(grid)
        q = base.q + dq @ beta
        coarse = np.array([self.model.closest_value(x)[0] for x in q])
        chosen = np.concatenate([grid, *(self._refinement(grid, k) for k in _lowest(coarse))])
        base, dq, _ = problem.family.linear_map(chosen)
        q = base.q + dq @ beta
        values = np.empty(len(chosen))
        jacobian = np.zeros((len(chosen), problem.n_free))
        for k, joints in enumerate(q):
            distance, gradient, _ = self.model.closest(joints)
            values[k] = self.margin + SOLVER_SLACK - distance
            jacobian[k] = -gradient @ dq[k]
        rows = ConstraintRows(values, jacobian)
        self._memo = (problem, key, rows)  # solvers ask for values, then Jacobian, at one beta
        return rows

    @staticmethod
    def _refinement(grid: np.ndarray, k: int) -> np.ndarray:
        """:data:`REFINE` instants on each side of grid point ``k``, none on the grid."""
        lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
        return np.linspace(lo, hi, 2 * REFINE + 2)[1:-1]

    def critical_times(self, robot: Robot, path: JointPolynomials) -> np.ndarray:
        """The times (s) of the smallest clearance along ``path``, refined between samples."""
        if self.model.n_pairs == 0:
            return np.zeros(0)
        return np.array([self.smallest(path, 201)[1]])

    def smallest(self, path: JointPolynomials, samples: int) -> tuple[float, float, int]:
        """Smallest clearance along ``path`` (m), its time (s) and pair, from ``samples``.

        Every sampled local minimum within 1 cm of the smallest is refined by a bounded
        scalar search between its neighbouring samples.
        """
        t = np.linspace(0.0, path.duration, samples)
        q = path.evaluate(t).q

        def lowest(joints: np.ndarray) -> tuple[float, int]:
            return self.model.closest_value(joints)

        sampled = np.array([lowest(x)[0] for x in q])
        best = float(sampled.min())
        best_t = float(t[int(np.argmin(sampled))])
        best_pair = lowest(q[int(np.argmin(sampled))])[1]
        interior = np.flatnonzero(
            (sampled <= np.roll(sampled, 1)) & (sampled <= np.roll(sampled, -1))
        )
        candidates = set(interior.tolist()) | {0, samples - 1}
        for k in sorted(candidates):
            if sampled[k] > best + 0.01:
                continue
            lo, hi = t[max(k - 1, 0)], t[min(k + 1, samples - 1)]
            result = minimize_scalar(
                lambda s: lowest(path.evaluate(np.array([s])).q[0])[0],
                bounds=(lo, hi),
                method="bounded",
                options={"xatol": 1e-9 * max(1.0, path.duration)},
            )
            if float(result.fun) < best:
                best, best_t = float(result.fun), float(result.x)
                best_pair = lowest(path.evaluate(np.array([best_t])).q[0])[1]
        return best, best_t, best_pair

    def excess(self, robot: Robot, path: JointPolynomials) -> Excess:
        """``margin - smallest clearance`` along the path (m), with its own error estimate."""
        if self.model.n_pairs == 0:
            return Excess(-math.inf, 0.0, "no pairs to check")
        fine = self.smallest(path, 1001)
        coarse = self.smallest(path, 501)
        clearance, when, pair = fine
        estimate = abs(coarse[0] - fine[0])
        detail = (
            f"min clearance {clearance:.6g} m ({self.model.names[pair]}) at t = {when:.4g} s, "
            f"margin {self.margin:g} m"
        )
        return Excess(self.margin - clearance, estimate, detail)

    def violation(self, problem: Problem, beta: np.ndarray) -> Excess:
        """The excess of the problem's path at ``beta`` for solvers (201 samples, refined).

        Verification uses :meth:`excess` (twice as dense, with its error estimate).
        """
        if self.model.n_pairs == 0:
            return Excess(-math.inf, 0.0, "no pairs to check")
        clearance, when, pair = self.smallest(problem.polynomials(beta), 201)
        detail = (
            f"min clearance {clearance:.6g} m ({self.model.names[pair]}) at t = {when:.4g} s, "
            f"margin {self.margin:g} m"
        )
        return Excess(self.margin - clearance, 0.0, detail)


def _lowest(values: np.ndarray) -> list[int]:
    """Indices of the two lowest local minima of ``values`` (or the two lowest apart)."""
    n = len(values)
    left = np.concatenate([[np.inf], values[:-1]])
    right = np.concatenate([values[1:], [np.inf]])
    minima = np.flatnonzero((values <= left) & (values <= right))
    order = [int(k) for k in minima[np.argsort(values[minima], kind="stable")]]
    if len(order) < 2:
        far = [int(k) for k in np.argsort(values, kind="stable") if abs(int(k) - order[0]) > 2]
        order.append(far[0] if far else (order[0] + n // 2) % n)
    return order[:2]


def clearance_at(model: CollisionModel, joints: Sequence[float] | np.ndarray) -> tuple[float, str]:
    """Smallest clearance (m) at one configuration and the pair that has it."""
    values = model.distances(np.asarray(joints, dtype=float)).values
    k = int(np.argmin(values))
    return float(values[k]), model.names[k]
