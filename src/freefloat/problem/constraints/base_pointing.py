"""A pointing cone: an axis of the spacecraft stays within a half-angle of a fixed direction.

An antenna, a star tracker or a sun sensor fixed to the spacecraft must keep pointing near a
direction fixed in space while the arm moves: its boresight ``a`` (spacecraft frame) must stay
within ``half_angle`` of the direction ``d``, given in the spacecraft's frame at the start
(default: ``a`` itself, where the boresight pointed at the start). Turning about the boresight
is free, unlike the swing bound (:mod:`.base_swing`). With ``r(s)`` the attitude relative to
the start and ``v = R(r) a`` the boresight in the start frame, the rows are the angle

    g = atan2(|d x v|, d . v) - half_angle   (rad; feasible <= 0)

with the exact Jacobian ``dg = -(a x R^T d) . delta / sin(angle)`` for a body-frame
perturbation ``delta`` of ``r`` (:mod:`..relative_attitude`; 0 where the boresight is on the
direction, deep inside), asked :data:`SOLVER_SLACK` inside the cone. In radians, not as the
cosine gap, so that the tolerance means the same at every half-angle (a cosine gap of 1e-9
is 2.6 deg at a half-angle of 180 deg).
The dense check is independent (:mod:`.attitude_check`). A start or goal attitude outside the
cone is refused before any search. Scenario key and plan record::

    [constraints.base_pointing]
    axis = [1.0, 0.0, 0.0]          # the boresight, in the spacecraft frame
    direction = [1.0, 0.0, 0.0]     # optional: in the spacecraft frame at the start (default axis)
    half_angle_deg = 5.0            # 0 < half-angle < 180 [deg]
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ...errors import InputError, excerpt
from ...physics.attitude import quat_to_matrix, relative_quat
from ...robot.model import Robot
from ..paths import JointPolynomials
from ..relative_attitude import attitude_peaks, relative_rows
from ..residual import Problem
from .attitude_check import REFINED, attitude_track
from .base import DEFAULT_INSTANTS, Constraint, ConstraintRows, Excess, check_record_keys
from .base_swing import degrees_apart
from .end_effector_cone import unit_vector
from .slack import room_asked, tapered_slack

__all__ = ["SOLVER_SLACK", "BasePointing"]

#: How far inside the cone the rows ask the boresight to be (rad, 0.0057 deg), less near the
#: start or goal when it lies nearer the edge (:meth:`BasePointing.solver_slack`).
SOLVER_SLACK = 1e-4
#: Keys of the scenario table and the plan record.
_KEYS = ("axis", "direction", "half_angle_deg")


class BasePointing(Constraint):
    """The spacecraft's ``axis`` within ``half_angle`` (rad) of ``direction`` at every instant.

    Args:
        axis: (3,) the boresight in the spacecraft frame (normalised here).
        direction: (3,) the direction in the spacecraft frame at the start (normalised here);
            None: ``axis``.
        half_angle: cone half-angle (rad), strictly between 0 and pi.
    """

    name = "base_pointing"
    unit = "rad"
    tolerance = 1e-7

    def __init__(
        self, axis: Sequence[float], direction: Sequence[float] | None, half_angle: float
    ) -> None:
        self.axis = unit_vector(_listed(axis), "axis", self.name)
        given = axis if direction is None else direction
        self.direction = unit_vector(_listed(given), "direction", self.name)
        if isinstance(half_angle, bool) or not 1e-6 <= float(half_angle) <= math.pi - 1e-6:
            raise InputError(
                "base_pointing half-angle must be between 1e-6 and pi - 1e-6 rad, got "
                f"{excerpt(half_angle)}"
            )
        self.half_angle = float(half_angle)
        self._half_angle_deg: float | None = None

    # -- records ----------------------------------------------------------------------------

    def to_record(self) -> dict[str, Any]:
        """``axis``, ``direction`` (unit vectors, start frame) and ``half_angle_deg`` (deg)."""
        half = (
            math.degrees(self.half_angle) if self._half_angle_deg is None else self._half_angle_deg
        )
        return {
            "axis": self.axis.tolist(),
            "direction": self.direction.tolist(),
            "half_angle_deg": half,
        }

    @classmethod
    def from_record(cls, record: Mapping[str, Any]) -> BasePointing:
        """The cone its table describes (see the module docstring).

        Raises:
            InputError: an unknown or missing key, or a bad value, named.
        """
        check_record_keys("base_pointing", record, _KEYS, ("axis", "half_angle_deg"))
        half = record["half_angle_deg"]
        if (
            isinstance(half, bool)
            or not isinstance(half, (int, float))
            or not 0 < half < 180
            or not 1e-6 <= math.radians(half) <= math.pi - 1e-6
        ):
            raise InputError(
                "base_pointing half_angle_deg must be a number between 0 and 180 (exclusive; "
                f"at least 1e-6 rad from either) [deg], got {excerpt(half)}"
            )
        cone = cls(record["axis"], record.get("direction"), math.radians(half))
        cone._half_angle_deg = float(half)
        return cone

    # -- attitudes --------------------------------------------------------------------------

    def _angles(self, relative: np.ndarray) -> np.ndarray:
        """The boresight's angle from the direction (rad) at (K, 4) relative attitudes."""
        pointing = quat_to_matrix(np.atleast_2d(relative)) @ self.axis
        across = np.linalg.norm(np.cross(pointing, self.direction), axis=-1)
        return np.arctan2(across, pointing @ self.direction)

    def _gaps(self, relative: np.ndarray) -> np.ndarray:
        """The angle beyond the half-angle (rad) at (K, 4) relative attitudes."""
        return self._angles(relative) - self.half_angle

    def _said(self, angle: float, when: float | None = None) -> str:
        at = "" if when is None else f" at t = {when:.4g} s"
        said, bound = degrees_apart(angle, self.half_angle, self._half_angle_deg)
        return f"the boresight {said} deg from the direction{at}, at most {bound} deg allowed"

    def at_attitude(self, relative: np.ndarray) -> Excess:
        """Its excess (rad) at an attitude ``relative`` to the start (the start's or goal's)."""
        angle = float(self._angles(np.asarray(relative, dtype=float))[0])
        return Excess(angle - self.half_angle, 0.0, self._said(angle))

    def restarted(self, turn: np.ndarray) -> BasePointing:
        """The cone for a motion that starts ``turn`` (``q_old^-1 q_new``) away.

        The same direction in space, given in the new start frame; the axis is the
        spacecraft's own, and the half-angle as recorded (deg).
        """
        direction = quat_to_matrix(np.asarray(turn, dtype=float)).T @ self.direction
        cone = type(self)(self.axis.tolist(), direction.tolist(), self.half_angle)
        cone._half_angle_deg = self._half_angle_deg
        return cone

    # -- the solvers' rows --------------------------------------------------------------------

    def solver_slack(self, problem: Problem, instants: np.ndarray) -> np.ndarray:
        """(K,) :data:`SOLVER_SLACK` (rad) at normalised ``instants``, tapered near the ends.

        Near the start or goal when it is closer to the edge than twice that, to half its
        room; at most half the roomier end's anywhere (:func:`.slack.tapered_slack`).
        """
        return tapered_slack(instants, *self._rooms(problem), SOLVER_SLACK)

    def end_rows(self, problem: Problem, beta: np.ndarray) -> ConstraintRows:
        """The angle at the end of a path that need not reach the goal, a hair inside (rad).

        A start path found with the attitude ignored ends anywhere, and continuation heads
        from its end attitude to the goal: that path's end is held inside by the room the
        rows ask away from the ends (:func:`.slack.room_asked`). (The boresight's way between
        two attitudes inside the cone may still leave it: each step's dense check decides.)
        """
        asked = room_asked(*self._rooms(problem), SOLVER_SLACK)
        return self._angle_rows(problem, beta, np.ones(1), np.full(1, asked))

    def _rooms(self, problem: Problem) -> tuple[float, float]:
        """How far inside the cone the start and the goal boresights lie (rad)."""
        goal = relative_quat(problem.start_quaternion, problem.goal_quaternion)
        rooms = -self._gaps(np.stack([np.array([0.0, 0.0, 0.0, 1.0]), goal]))
        return float(rooms[0]), float(rooms[1])

    def rows(
        self, problem: Problem, beta: np.ndarray, instants: np.ndarray = DEFAULT_INSTANTS
    ) -> ConstraintRows:
        """``angle - (half_angle - slack)`` (rad) strictly between the ends, exact Jacobian.

        The ends' attitudes are fixed (and checked); a path that need not reach the goal (a
        start path) holds its end by :meth:`end_rows`.
        """
        s = np.asarray(instants, dtype=float)
        s = s[(s > 0.0) & (s < 1.0)]  # the ends' attitudes are fixed (and checked)
        return self._angle_rows(problem, beta, s, self.solver_slack(problem, s))

    def _angle_rows(
        self, problem: Problem, beta: np.ndarray, s: np.ndarray, slack: np.ndarray
    ) -> ConstraintRows:
        """``angle - (half_angle - slack)`` (rad) at normalised ``s``, exact Jacobian in beta."""
        if not len(s):
            return ConstraintRows(np.zeros(0), np.zeros((0, problem.n_free)))
        found = relative_rows(problem, beta, s)
        rotations = quat_to_matrix(found.relative)
        local = np.einsum("mji,j->mi", rotations, self.direction)  # R^T d
        lever = np.cross(self.axis[None, :], local)  # a x R^T d: d(d . v) = lever . delta
        angles = self._angles(found.relative)
        sine = np.sin(angles)
        scale = np.divide(-1.0, sine, out=np.zeros_like(sine), where=sine > 1e-12)
        values = angles - (self.half_angle - slack)
        return ConstraintRows(values, scale[:, None] * np.einsum("mi,mif->mf", lever, found.body))

    def tight_instants(self, problem: Problem, beta: np.ndarray) -> np.ndarray:
        """The largest gaps' instants, each refined in time (:func:`.attitude_peaks`)."""
        return attitude_peaks(problem, beta, REFINED, self._gaps)

    # -- finished paths -----------------------------------------------------------------------

    def critical_times(self, robot: Robot, path: JointPolynomials) -> np.ndarray:
        """Times (s) of the local maxima of the gap on the dense check's grid."""
        return attitude_track(robot, path).peak_times(self._gaps)

    def excess(self, robot: Robot, path: JointPolynomials) -> Excess:
        """The largest angle beyond the half-angle (rad), with a step-doubling error estimate."""
        largest = attitude_track(robot, path).largest(self._gaps)
        if not math.isfinite(largest.value):
            return Excess(math.inf, 0.0, "the spacecraft's attitude could not be integrated")
        detail = self._said(largest.value + self.half_angle, largest.time)
        return Excess(largest.value, largest.estimate, detail)

    def __repr__(self) -> str:
        return (
            f"BasePointing(axis={self.axis.tolist()}, direction={self.direction.tolist()}, "
            f"half_angle={self.half_angle!r})"
        )


def _listed(value: Any) -> Any:
    """A sequence as a list (a numpy array too), anything else as it is (to be refused)."""
    return list(value) if isinstance(value, (list, tuple, np.ndarray)) else value
