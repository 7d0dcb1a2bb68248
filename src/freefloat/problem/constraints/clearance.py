"""Clearance: every checked pair of bodies stays at least a margin apart along the path.

The pairs and their signed distances come from the robot's collision model (convex hulls,
coal's GJK/EPA; see :mod:`freefloat.robot.collision`). Obstacles are fixed to the spacecraft,
so clearance is a function of the joints alone.

For the solvers, each instant contributes one row: the margin minus the smallest distance over
the pairs there (m), with its gradient from the witness points of that pair and the joint
Jacobians, chained with the path's linear dependence on ``beta``. The rows ask for a little
more than the margin (:data:`SOLVER_SLACK`) so that the dips between instants stay outside it.

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
from .base import Constraint, ConstraintRows, Excess

__all__ = ["SOLVER_SLACK", "Clearance"]

#: Extra clearance the solvers ask for beyond the margin, between constraint instants (m).
SOLVER_SLACK = 2e-3
#: Instants at which the solvers impose clearance (normalised time s = t / T).
SOLVER_INSTANTS = np.linspace(0.0, 1.0, 241)


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
        self._memo: tuple[Problem, tuple[bytes, bytes], ConstraintRows] | None = None

    def __repr__(self) -> str:
        return f"Clearance(margin={self.margin:g} m, {self.model.n_pairs} pairs)"

    def applies_to(self, robot: Robot) -> bool:
        """True when the collision model has pairs to check."""
        return self.model.n_pairs > 0

    def rows(
        self, problem: Problem, beta: np.ndarray, instants: np.ndarray = SOLVER_INSTANTS
    ) -> ConstraintRows:
        """``margin + slack - min_pair d(q(s))`` at each instant (m) and its exact gradient."""
        instants = np.asarray(instants, dtype=float)
        beta = np.asarray(beta, dtype=float)
        key = (instants.tobytes(), beta.tobytes())
        if self._memo is not None and self._memo[0] is problem and self._memo[1] == key:
            return self._memo[2]
        base, dq, _ = problem.family.linear_map(instants)
        q = base.q + dq @ beta
        values = np.empty(len(instants))
        jacobian = np.zeros((len(instants), problem.n_free))
        for k, joints in enumerate(q):
            distance, gradient, _ = self.model.closest(joints)
            values[k] = self.margin + SOLVER_SLACK - distance
            jacobian[k] = -gradient @ dq[k]
        rows = ConstraintRows(values, jacobian)
        self._memo = (problem, key, rows)  # solvers ask for values, then Jacobian, at one beta
        return rows

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
            values = self.model.distances(joints).values
            k = int(np.argmin(values))
            return float(values[k]), k

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


def clearance_at(model: CollisionModel, joints: Sequence[float] | np.ndarray) -> tuple[float, str]:
    """Smallest clearance (m) at one configuration and the pair that has it."""
    values = model.distances(np.asarray(joints, dtype=float)).values
    k = int(np.argmin(values))
    return float(values[k]), model.names[k]
