"""A bound on how far the spacecraft turns from its start attitude on the way.

Antennas, sun sensors and solar arrays point where the spacecraft does: a motion that reaches
a goal a few degrees off may swing the spacecraft much further on the way (docs/method.md).
This constraint keeps the rotation angle of ``q(0)^-1 q(t)`` (the turn from the start
attitude, whatever axis) within ``max_angle`` at every instant. The rows are

    g = theta(s) - max_angle   (rad; feasible <= 0)

from the planner's own integration with its exact Jacobian (:mod:`..relative_attitude`),
asked a hair inside the bound (:data:`SOLVER_SLACK`). The dense check is independent of it
(:mod:`.attitude_check`: Pinocchio's centroidal map, Butcher's fifth-order Runge-Kutta method
on doubling grids, the largest sampled turns refined in time; the last two levels'
difference is its error estimate). A goal attitude beyond the bound is refused before any search
(:meth:`BaseSwing.at_attitude`). Scenario key and plan record::

    [constraints.base_swing]
    max_deg = 10.0                  # 0 < max < 180 [deg], from the start attitude
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ...errors import InputError, excerpt
from ...physics.attitude import relative_quat
from ...physics.turn_track import quaternion_turn
from ...robot.model import Robot
from ..paths import JointPolynomials
from ..relative_attitude import attitude_peaks, swing_rows
from ..residual import Problem
from .attitude_check import REFINED, attitude_track
from .base import DEFAULT_INSTANTS, Constraint, ConstraintRows, Excess, check_record_keys
from .slack import room_asked, tapered_slack

__all__ = ["SOLVER_SLACK", "BaseSwing", "degrees_apart"]

#: How far inside the bound the solvers' rows ask the turn to be (rad: 0.0057 deg): a start
#: path found on the bound at fixed instants peaked 2e-5 rad beyond it between them, and was
#: refused; less near the goal when it lies nearer the bound (:meth:`BaseSwing.solver_slack`).
SOLVER_SLACK = 1e-4


class BaseSwing(Constraint):
    """The spacecraft within ``max_angle`` (rad) of its start attitude at every instant.

    Args:
        max_angle: the largest turn allowed (rad), strictly between 0 and pi.
    """

    name = "base_swing"
    unit = "rad"
    tolerance = 1e-7

    def __init__(self, max_angle: float) -> None:
        if isinstance(max_angle, bool) or not 0.0 < float(max_angle) < math.pi:
            raise InputError(
                f"base_swing max angle must be between 0 and pi rad (exclusive), got "
                f"{excerpt(max_angle)}"
            )
        self.max_angle = float(max_angle)
        #: the bound as its record gave it (deg), recorded back as given
        self._max_deg: float | None = None

    # -- records ----------------------------------------------------------------------------

    def to_record(self) -> dict[str, Any]:
        """``max_deg``: the largest turn from the start attitude (deg)."""
        return {"max_deg": math.degrees(self.max_angle) if self._max_deg is None else self._max_deg}

    @classmethod
    def from_record(cls, record: Mapping[str, Any]) -> BaseSwing:
        """The bound its table describes (see the module docstring).

        Raises:
            InputError: an unknown or missing key, or a bad value, named.
        """
        check_record_keys("base_swing", record, ("max_deg",), ("max_deg",))
        value = record["max_deg"]
        if (
            isinstance(value, bool)
            or not isinstance(value, (int, float))
            or not 0 < value < 180
            or not math.radians(value) > 0.0  # a subnormal degree is 0 rad
        ):
            raise InputError(
                "base_swing max_deg must be a number between 0 and 180 (exclusive) [deg], got "
                f"{excerpt(value)}"
            )
        swing = cls(math.radians(value))
        swing._max_deg = float(value)
        return swing

    # -- the goal ---------------------------------------------------------------------------

    def at_attitude(self, relative: np.ndarray) -> Excess:
        """Its excess (rad) at an attitude ``relative`` to the start (the goal's, say)."""
        turn = float(quaternion_turn(np.asarray(relative, dtype=float)))
        said, bound = degrees_apart(turn, self.max_angle, self._max_deg)
        detail = f"it lies {said} deg from the start attitude, at most {bound} deg allowed"
        return Excess(turn - self.max_angle, 0.0, detail)

    def _said(self, turn: float, when: float) -> str:
        said, bound = degrees_apart(turn, self.max_angle, self._max_deg)
        return (
            f"the spacecraft {said} deg from its start attitude at t = {when:.4g} s, at most "
            f"{bound} deg allowed"
        )

    # -- the solvers' rows --------------------------------------------------------------------

    def rows(
        self, problem: Problem, beta: np.ndarray, instants: np.ndarray = DEFAULT_INSTANTS
    ) -> ConstraintRows:
        """``theta - max_angle`` (rad), a hair inside, and its exact Jacobian in beta.

        At the instants strictly between the ends: at the start the turn is 0, and at the
        end of a path at its goal it is the goal's, which no path changes (:meth:`at_attitude`
        judges it before any search). A path that need not reach the goal (a start path)
        holds its end by :meth:`end_rows`.
        """
        s = np.asarray(instants, dtype=float)
        s = s[(s > 0.0) & (s < 1.0)]  # the ends' turns: 0, and the goal's (checked)
        if not len(s):
            return ConstraintRows(np.zeros(0), np.zeros((0, problem.n_free)))
        found = swing_rows(problem, beta, s)
        bound = self.max_angle - self.solver_slack(problem, s)  # a hair inside
        return ConstraintRows(found.turns - bound, found.jacobian)

    def end_rows(self, problem: Problem, beta: np.ndarray) -> ConstraintRows:
        """The turn at the end of a path that need not reach the goal, a hair inside (rad).

        A start path found with the attitude ignored ends anywhere: continuation heads from
        its end attitude to the goal, and for a bound under 90 deg that way stays within it
        when both ends do (such a ball of attitudes is geodesically convex; beyond, each
        step's dense check decides). The room asked is the rows' away from the ends
        (:func:`.slack.room_asked`).
        """
        found = swing_rows(problem, beta, np.ones(1))
        asked = room_asked(*self._rooms(problem), SOLVER_SLACK)
        return ConstraintRows(found.turns - (self.max_angle - asked), found.jacobian)

    def solver_slack(self, problem: Problem, instants: np.ndarray) -> np.ndarray:
        """(K,) :data:`SOLVER_SLACK` (rad) at normalised ``instants``, tapered near the goal.

        Near a goal closer to the bound than twice that, to half the goal's room
        (:func:`.slack.tapered_slack`; none at a goal at or beyond the bound, which only
        ``reach`` heads for, stopping at the bound): no path ending there has more. At most
        half the bound anywhere (the start's room).
        """
        return tapered_slack(instants, *self._rooms(problem), SOLVER_SLACK)

    def _rooms(self, problem: Problem) -> tuple[float, float]:
        """How far inside the bound the start (turn 0) and the goal lie (rad)."""
        goal = relative_quat(problem.start_quaternion, problem.goal_quaternion)
        return self.max_angle, -self.at_attitude(goal).value

    def tight_instants(self, problem: Problem, beta: np.ndarray) -> np.ndarray:
        """The largest turns' instants, each refined in time (:func:`.attitude_peaks`)."""
        return attitude_peaks(problem, beta, REFINED, quaternion_turn)

    # -- finished paths -----------------------------------------------------------------------

    def critical_times(self, robot: Robot, path: JointPolynomials) -> np.ndarray:
        """Times (s) of the local maxima of the turn on the dense check's grid."""
        return attitude_track(robot, path).peak_times(quaternion_turn)

    def excess(self, robot: Robot, path: JointPolynomials) -> Excess:
        """The largest turn beyond ``max_angle`` (rad), with a step-doubling error estimate."""
        largest = attitude_track(robot, path).largest(quaternion_turn)
        if not math.isfinite(largest.value):  # too fast for the grid: it blew up
            return Excess(math.inf, 0.0, "the spacecraft's turn could not be integrated")
        detail = self._said(largest.value, largest.time)
        return Excess(largest.value - self.max_angle, largest.estimate, detail)

    def __repr__(self) -> str:
        return f"BaseSwing(max_angle={self.max_angle!r})"


def degrees_apart(turn: float, bound: float, given: float | None = None) -> tuple[str, str]:
    """A turn and the bound (rad) in degrees, the turn on its side of the bound.

    The bound as given (``given``, deg: as its record wrote it); the turn to 4 digits, or to
    as many as the bound shows when it shows more (trailing zeros kept: ``3.0000000`` beside
    ``2.9999999``), or as many more as keep it on its own side of the bound (a turn just
    beyond it is never shown at or below it).
    """
    limit = f"{math.degrees(bound) if given is None else given:.15g}"
    shown = len(limit.split("e")[0].replace("-", "").replace(".", "").lstrip("0"))
    style = "#" if shown > 4 else ""
    for digits in range(max(4, shown), 16):
        said = f"{math.degrees(turn):{style}.{digits}g}"
        if (float(said) > float(limit)) == (turn > bound) and (said == limit) <= (turn == bound):
            break
    return said, limit
