"""Joint position limits from the URDF along the whole path.

A joint's value is affine in the free coefficients, so the limits at any instant are linear
inequalities in ``beta``. The dense check is exact: the extremes of a polynomial are at the
ends or at real roots of its derivative (rad, or m for prismatic joints).
"""

from __future__ import annotations

import math

import numpy as np

from ...robot.model import Robot
from ..paths import JointPolynomials
from ..residual import Problem
from .base import DEFAULT_INSTANTS, Constraint, ConstraintRows, Excess

__all__ = ["JointPositionLimits"]


class JointPositionLimits(Constraint):
    """Every joint stays within its URDF ``[lower, upper]`` (rad or m) at every instant."""

    name = "joint_position_limits"
    unit = "rad|m"
    tolerance = 1e-9
    affine = True

    def applies_to(self, robot: Robot) -> bool:
        """True when some joint has a finite limit."""
        return any(math.isfinite(j.lower) or math.isfinite(j.upper) for j in robot.joints)

    def rows(
        self, problem: Problem, beta: np.ndarray, instants: np.ndarray = DEFAULT_INSTANTS
    ) -> ConstraintRows:
        """``q_i(s) - upper_i`` and ``lower_i - q_i(s)`` at the instants (rad or m)."""
        base, dq, _ = problem.family.linear_map(np.asarray(instants, dtype=float))
        q = base.q + dq @ np.asarray(beta, dtype=float)
        values, rows = [], []
        for i, joint in enumerate(problem.robot.joints):
            if math.isfinite(joint.upper):
                values.append(q[:, i] - joint.upper)
                rows.append(dq[:, i, :])
            if math.isfinite(joint.lower):
                values.append(joint.lower - q[:, i])
                rows.append(-dq[:, i, :])
        if not values:
            return ConstraintRows(np.zeros(0), np.zeros((0, problem.n_free)))
        return ConstraintRows(np.concatenate(values), np.concatenate(rows))

    def critical_times(self, robot: Robot, path: JointPolynomials) -> np.ndarray:
        """Times (s) of each limited joint's extremes along the path."""
        times = []
        for i, joint in enumerate(robot.joints):
            if math.isfinite(joint.lower) or math.isfinite(joint.upper):
                (_, t_lo), (_, t_hi) = path.extremes(i, 0)
                times += [t_lo, t_hi]
        return np.array(times)

    def excess(self, robot: Robot, path: JointPolynomials) -> Excess:
        """Exact largest excursion beyond a limit (rad or m), from the polynomials' extremes."""
        worst, detail = -math.inf, ""
        for i, joint in enumerate(robot.joints):
            if not (math.isfinite(joint.lower) or math.isfinite(joint.upper)):
                continue
            (lo, t_lo), (hi, t_hi) = path.extremes(i, 0)
            for over, t in ((hi - joint.upper, t_hi), (joint.lower - lo, t_lo)):
                if over > worst:
                    worst, detail = over, f"joint {joint.name!r} at t = {t:.4g} s"
        if worst == -math.inf:
            return Excess(0.0, 0.0, "no joint has finite limits")
        return Excess(worst, 0.0, detail)
