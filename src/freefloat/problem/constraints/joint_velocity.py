"""Joint velocity limits from the URDF along the whole path.

Joint rates are ``dq/dt = (dq/ds) / T``: affine in the free coefficients, so the limits are
linear inequalities in ``beta`` at any instant. The dense check is exact: the extremes of the
rate polynomial are at the ends or at real roots of the acceleration (rad/s, or m/s).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ...errors import VelocityLimitError
from ...robot.model import Robot
from ..paths import JointPolynomials
from ..residual import Problem
from .base import DEFAULT_INSTANTS, ConstraintRows, DurationScaledLimit, Excess, LimitPeak

__all__ = ["JointVelocityLimits"]


#: Relative difference of a path's evaluated ends below which a joint does not travel (its
#: goal is its start: a loop's 1e-15 rad would say "no path can in under 2e-15 s").
_ROUNDING = 1e-12


class JointVelocityLimits(DurationScaledLimit):
    """Every joint's rate stays within ``+-velocity_limit`` of its URDF (rad/s or m/s)."""

    name = "joint_velocity_limits"
    unit = "rad/s|m/s"
    tolerance = 1e-9
    affine = True
    power = 1

    def applies_to(self, robot: Robot) -> bool:
        """True when some joint has a finite velocity limit."""
        return any(math.isfinite(j.velocity_limit) for j in robot.joints)

    def rows(
        self, problem: Problem, beta: np.ndarray, instants: np.ndarray = DEFAULT_INSTANTS
    ) -> ConstraintRows:
        """``+-qdot_i(t) - limit_i`` at the instants (rad/s or m/s)."""
        base, _, dqs = problem.family.linear_map(np.asarray(instants, dtype=float))
        scale = 1.0 / problem.duration
        rate = (base.qd + dqs @ np.asarray(beta, dtype=float)) * scale
        values, rows = [], []
        for i, joint in enumerate(problem.robot.joints):
            if math.isfinite(joint.velocity_limit):
                values += [rate[:, i] - joint.velocity_limit, -rate[:, i] - joint.velocity_limit]
                rows += [dqs[:, i, :] * scale, -dqs[:, i, :] * scale]
        if not values:
            return ConstraintRows(np.zeros(0), np.zeros((0, problem.n_free)))
        return ConstraintRows(np.concatenate(values), np.concatenate(rows))

    def critical_times(self, robot: Robot, path: JointPolynomials) -> np.ndarray:
        """Times (s) of each limited joint's extremes along the path."""
        times = []
        for i, joint in enumerate(robot.joints):
            if math.isfinite(joint.velocity_limit):
                (_, t_lo), (_, t_hi) = path.extremes(i, 1)
                times += [t_lo, t_hi]
        return np.array(times)

    def excess(self, robot: Robot, path: JointPolynomials) -> Excess:
        """Exact largest rate beyond a limit (rad/s or m/s), from the rate's extremes."""
        worst, detail = -math.inf, ""
        for i, joint in enumerate(robot.joints):
            if not math.isfinite(joint.velocity_limit):
                continue
            (lo, t_lo), (hi, t_hi) = path.extremes(i, 1)
            peak, t = (hi, t_hi) if abs(hi) >= abs(lo) else (lo, t_lo)
            over = abs(peak) - joint.velocity_limit
            if over > worst:
                worst, detail = over, f"joint {joint.name!r} at t = {t:.4g} s"
        if worst == -math.inf:
            return Excess(0.0, 0.0, "no joint has a velocity limit")
        return Excess(worst, 0.0, detail)

    def worst(self, robot: Robot, path: JointPolynomials) -> LimitPeak | None:
        """The joint whose exact peak rate (rad/s or m/s) is the largest fraction of its limit."""
        worst: LimitPeak | None = None
        ends = path.positions(np.array([0.0, path.duration]))
        least = 0.0  # each joint travels at least its span: at its limit, this long (s)
        for i, joint in enumerate(robot.joints):
            if math.isfinite(joint.velocity_limit):
                (lo, _), (hi, _) = path.extremes(i, 1)
                rate = max(abs(lo), abs(hi))
                fraction = rate / joint.velocity_limit
                span = float(ends[1, i] - ends[0, i])
                if joint.kind == "continuous":  # the goal is also reached the other way round
                    span = math.remainder(span, 2.0 * math.pi)
                if abs(span) <= _ROUNDING * max(1.0, abs(float(ends[0, i]))):
                    span = 0.0  # a loop (or whole turns): the ends agree to rounding alone
                least = max(least, abs(span) / joint.velocity_limit)
                if worst is None or fraction > worst.fraction:
                    worst = LimitPeak(
                        joint, rate, joint.velocity_limit, fraction, path.duration * fraction
                    )
        return None if worst is None else replace(worst, least_duration=least)

    def error(self, peak: LimitPeak) -> VelocityLimitError:
        """:class:`VelocityLimitError` naming the joint, its rate and the shortest duration."""
        return VelocityLimitError(
            peak.joint.name,
            peak.peak,
            peak.limit,
            peak.shortest_duration,
            peak.joint.unit,
            peak.least_duration,
        )
