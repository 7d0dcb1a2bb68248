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

#: Newton steps in time from a sampled extreme to the joint's (:meth:`tight_instants`).
NEWTON_STEPS = 2


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

    def tight_instants(self, problem: Problem, beta: np.ndarray) -> np.ndarray:
        """Each limited joint's largest and smallest value on the path, found cheaply.

        From the sampled extreme at the default instants, :data:`NEWTON_STEPS` Newton steps in
        time to the zero of the joint's rate, kept between the neighbouring samples. Near an
        extreme the value is stationary, so the instants' error costs the rows only its square.
        """
        joints = problem.robot.joints
        limited = [i for i, j in enumerate(joints) if math.isfinite(j.lower) or j.upper < math.inf]
        if not limited:
            return np.zeros(0)
        grid = DEFAULT_INSTANTS
        sampled = problem.family.evaluate(beta, grid).q[:, limited]
        k = np.concatenate([np.argmax(sampled, axis=0), np.argmin(sampled, axis=0)])
        column = np.array(limited * 2)
        lo, hi = grid[np.maximum(k - 1, 0)], grid[np.minimum(k + 1, len(grid) - 1)]
        s = grid[k]
        for _ in range(NEWTON_STEPS):
            at = problem.family.evaluate(beta, s)
            rate, curvature = at.qd[np.arange(len(s)), column], at.qdd[np.arange(len(s)), column]
            with np.errstate(divide="ignore", invalid="ignore"):
                moved = s - rate / curvature
            s = np.where(np.isfinite(moved), np.clip(moved, lo, hi), s)
        return np.unique(s)

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
            for over, t, value, side, limit in (
                (hi - joint.upper, t_hi, hi, "upper", joint.upper),
                (joint.lower - lo, t_lo, lo, "lower", joint.lower),
            ):
                if over > worst:
                    shown, bound = (_shown(joint.angular, v) for v in (value, limit))
                    worst = over
                    detail = (
                        f"joint {joint.name!r} at t = {t:.4g} s ({shown}, {side} limit {bound})"
                    )
        if worst == -math.inf:
            return Excess(0.0, 0.0, "no joint has finite limits")
        return Excess(worst, 0.0, detail)


def _shown(angular: bool, value: float) -> str:
    """A joint value (rad or m) for a message: in deg for a turning joint, else in m."""
    return f"{math.degrees(value):.5g} deg" if angular else f"{value:.5g} m"
