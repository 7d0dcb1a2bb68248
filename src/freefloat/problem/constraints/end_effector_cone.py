"""A pointing cone: a tool axis of the end effector stays within a half-angle of a direction.

A camera or a tool on the end effector must keep pointing at something fixed to the
spacecraft (a docked client, a tool changer, an antenna): the unit ``axis`` fixed in the
end-effector frame, seen from the spacecraft (base) frame, ``v(q) = R(q) a``, must stay within
``half_angle`` of the unit ``direction`` ``d`` fixed in the base frame. The rows are

    g = cos(half_angle) - d . v(q)   (unitless; feasible <= 0)

with the exact gradient ``dg/dq_j = -w_j . (v x d)``, ``w_j`` the angular column of joint ``j``
of the end effector's Jacobian in base-frame axes, chained with the path's affine dependence on
``beta``. The cosine form is smooth everywhere (the angle itself is not at the cone's axis).
The solvers' rows use a half-angle a hair smaller (:data:`SOLVER_SLACK`, less when an end of
the path lies nearer the edge), so that the path between their instants stays inside; the
dense check and verification use the cone itself.

The dense check samples the finished path (:data:`VERIFY_SAMPLES` instants of Pinocchio's
frame placements), refines each sampled local maximum of ``g`` by a bounded scalar search in
time, and estimates its own error by step doubling (the same search on every other sample).
Scenario key and plan record::

    [constraints.end_effector_cone]
    axis = [1.0, 0.0, 0.0]          # in the end-effector frame (normalised when read)
    direction = [1.0, 1.0, 0.0]     # in the spacecraft (base) frame (normalised when read)
    half_angle_deg = 60.0           # 0 < half-angle < 180 [deg]
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from ...errors import InputError, excerpt
from ...robot.model import Robot
from ..limits import finite_number
from ..paths import JointPolynomials
from ..residual import Problem
from ..scalar_minimum import scalar_minimum
from .base import DEFAULT_INSTANTS, Constraint, ConstraintRows, Excess, check_record_keys
from .slack import tapered_slack

__all__ = ["SOLVER_SLACK", "VERIFY_SAMPLES", "EndEffectorCone", "unit_vector"]

#: Samples of the dense verification check (every sampled local maximum is then refined).
VERIFY_SAMPLES = 801
#: How far inside the cone the solvers' rows ask the axis to be (rad: 0.017 deg), so that the
#: path between their instants stays inside (a root 0.01 deg out between them was refused);
#: less near the start or goal when it lies nearer the edge (:meth:`EndEffectorCone._slack`).
SOLVER_SLACK = 3e-4
#: Keys of the scenario table and the plan record.
_KEYS = ("axis", "direction", "half_angle_deg")


def unit_vector(value: Any, key: str, constraint: str = "end_effector_cone") -> np.ndarray:
    """``value`` as a unit vector: 3 finite numbers, not all 0 (normalised).

    Raises:
        InputError: naming ``constraint``'s ``key`` and what is valid.
    """
    if (
        not isinstance(value, Sequence)
        or isinstance(value, str)
        or len(value) != 3
        or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in value)
    ):
        raise InputError(f"{constraint} {key} must be 3 numbers [x, y, z], got {excerpt(value)}")
    if not all(finite_number(x) for x in value):  # an integer beyond the floats too
        raise InputError(f"{constraint} {key} must be finite numbers, got {excerpt(value)}")
    vector = np.array(value, dtype=float)
    largest = float(np.abs(vector).max())
    if largest == 0.0:
        raise InputError(f"{constraint} {key} must be a non-zero vector, got {excerpt(value)}")
    vector = vector / largest  # scaled first: [1e300, 1e300, 0] has no float norm
    norm = float(np.linalg.norm(vector))
    return vector / norm


class EndEffectorCone(Constraint):
    """The end effector's ``axis`` within ``half_angle`` (rad) of ``direction`` (base frame).

    Args:
        axis: (3,) direction in the end-effector frame (normalised here).
        direction: (3,) direction in the spacecraft (base) frame (normalised here).
        half_angle: cone half-angle (rad), strictly between 0 and pi.
    """

    name = "end_effector_cone"
    unit = "1"
    tolerance = 1e-9
    affine = False

    def __init__(
        self, axis: Sequence[float], direction: Sequence[float], half_angle: float
    ) -> None:
        self.axis = unit_vector(list(axis), "axis")
        self.direction = unit_vector(list(direction), "direction")
        if not 0.0 < half_angle < math.pi:
            raise InputError(
                "end_effector_cone half-angle must be between 0 and pi rad (exclusive), got "
                f"{excerpt(half_angle)}"
            )
        self.half_angle = float(half_angle)
        #: the half-angle as its record gave it (deg), recorded back as given: a round trip
        #: through radians would turn 60 into 59.99999999999999
        self._half_angle_deg: float | None = None

    # -- records ----------------------------------------------------------------------------

    def to_record(self) -> dict[str, Any]:
        """``axis``, ``direction`` (unit vectors) and ``half_angle_deg`` (deg)."""
        return {
            "axis": self.axis.tolist(),
            "direction": self.direction.tolist(),
            "half_angle_deg": (
                math.degrees(self.half_angle)
                if self._half_angle_deg is None
                else self._half_angle_deg
            ),
        }

    @classmethod
    def from_record(cls, record: Mapping[str, Any]) -> EndEffectorCone:
        """The cone its table describes (see the module docstring).

        Raises:
            InputError: an unknown or missing key, or a bad value, named.
        """
        check_record_keys("end_effector_cone", record, _KEYS, _KEYS)
        half = record["half_angle_deg"]
        if isinstance(half, bool) or not isinstance(half, (int, float)) or not 0 < half < 180:
            raise InputError(
                "end_effector_cone half_angle_deg must be a number between 0 and 180 "
                f"(exclusive) [deg], got {excerpt(half)}"
            )
        cone = cls(record["axis"], record["direction"], math.radians(half))
        cone._half_angle_deg = float(half)
        return cone

    # -- geometry ---------------------------------------------------------------------------

    def _gap(self, robot: Robot, path: JointPolynomials, t: np.ndarray) -> np.ndarray:
        """``g`` (unitless) at times ``t`` (s) of a finished path, from frame placements."""
        model, data = robot.model, robot.model.createData()
        frame, cos = robot.end_effector_frame, math.cos(self.half_angle)
        out = []
        for joints in path.positions(np.atleast_1d(t)):
            pin.framesForwardKinematics(model, data, robot.configuration(joints))
            out.append(cos - self.direction @ (data.oMf[frame].rotation @ self.axis))
        return np.array(out)

    def at_rest(self, robot: Robot, joints: np.ndarray) -> Excess:
        """``g`` at the configuration ``joints`` (rad or m), the tool axis's angle named."""
        angle = self._angle(robot, joints)
        degrees, half = math.degrees(angle), math.degrees(self.half_angle)
        detail = (
            f"{robot.end_effector}'s axis {degrees:.4g} deg from the direction "
            f"(half-angle {half:.4g} deg)"
        )
        return Excess(math.cos(self.half_angle) - math.cos(angle), 0.0, detail)

    def _slack(self, problem: Problem, instants: np.ndarray) -> np.ndarray:
        """(K,) how far inside the rows ask at normalised ``instants`` (rad).

        :data:`SOLVER_SLACK`, tapered near the start or the goal (which every path keeps) when
        that is nearer the edge, to half its room; at most half the roomier end's anywhere
        (a tool axis that cannot leave the rim has none); 0 at an end outside
        (:func:`.slack.tapered_slack`).
        """
        start, goal = (
            self.half_angle - self._angle(problem.robot, np.asarray(ends, dtype=float))
            for ends in (problem.family.start, problem.family.goal)
        )
        return tapered_slack(instants, start, goal, SOLVER_SLACK)

    def _angle(self, robot: Robot, joints: np.ndarray) -> float:
        """The tool axis's angle from the direction at the configuration ``joints`` (rad)."""
        model, data = robot.model, robot.model.createData()
        pin.framesForwardKinematics(model, data, robot.configuration(joints))
        pointing = data.oMf[robot.end_effector_frame].rotation @ self.axis
        return math.acos(float(np.clip(self.direction @ pointing, -1.0, 1.0)))

    def rows(
        self, problem: Problem, beta: np.ndarray, instants: np.ndarray = DEFAULT_INSTANTS
    ) -> ConstraintRows:
        """``cos(half_angle - slack) - d . v`` at the instants (:meth:`_slack`), exact Jacobian."""
        robot = problem.robot
        model, data = robot.model, robot.model.createData()
        frame = robot.end_effector_frame
        instants = np.asarray(instants, dtype=float)
        samples = problem.family.affine_samples(instants)
        q = samples.at(beta).q
        columns = [joint.idx_v for joint in robot.joints]
        cos = np.cos(self.half_angle - self._slack(problem, instants))  # a hair inside
        values = np.empty(len(q))
        gradients = np.empty((len(q), robot.n))
        for k, joints in enumerate(q):
            config = robot.configuration(joints)
            pin.computeJointJacobians(model, data, config)
            pin.updateFramePlacements(model, data)
            pointing = data.oMf[frame].rotation @ self.axis
            jacobian = pin.getFrameJacobian(model, data, frame, pin.LOCAL_WORLD_ALIGNED)
            values[k] = cos[k] - self.direction @ pointing
            gradients[k] = -(jacobian[3:6, columns].T @ np.cross(pointing, self.direction))
        return ConstraintRows(values, np.einsum("ki,kif->kf", gradients, samples.dq))

    # -- finished paths ---------------------------------------------------------------------

    def _worst(self, robot: Robot, path: JointPolynomials, samples: int) -> tuple[float, float]:
        """Largest ``g`` and its time (s): sampled, each local maximum refined in time."""
        t = np.linspace(0.0, path.duration, samples)
        g = self._gap(robot, path, t)
        best, when = float(g.max()), float(t[int(np.argmax(g))])
        inner = np.flatnonzero((g[1:-1] >= g[:-2]) & (g[1:-1] >= g[2:])) + 1
        for k in inner[np.argsort(g[inner])[::-1][:8]]:
            found = scalar_minimum(
                lambda x: -float(self._gap(robot, path, np.array([x]))[0]),
                float(t[k - 1]),
                float(t[k + 1]),
                1e-10 * path.duration,
            )
            if -found.value > best:
                best, when = -found.value, found.x
        return best, when

    def critical_times(self, robot: Robot, path: JointPolynomials) -> np.ndarray:
        """Times (s) of the local maxima of ``g`` on a grid of :data:`VERIFY_SAMPLES` // 4."""
        t = np.linspace(0.0, path.duration, VERIFY_SAMPLES // 4)
        g = self._gap(robot, path, t)
        inner = np.flatnonzero((g[1:-1] >= g[:-2]) & (g[1:-1] >= g[2:])) + 1
        return t[inner]

    def excess(self, robot: Robot, path: JointPolynomials) -> Excess:
        """Largest ``g`` along the path, with a step-doubling error estimate (unitless)."""
        fine, when = self._worst(robot, path, VERIFY_SAMPLES)
        coarse, _ = self._worst(robot, path, VERIFY_SAMPLES // 2 + 1)
        angle = math.degrees(math.acos(max(-1.0, min(1.0, math.cos(self.half_angle) - fine))))
        detail = (
            f"{robot.end_effector}'s axis {angle:.4g} deg from the direction (half-angle "
            f"{math.degrees(self.half_angle):.4g} deg) at t = {when:.4g} s"
        )
        return Excess(fine, abs(fine - coarse), detail)

    def __repr__(self) -> str:
        return (
            f"EndEffectorCone(axis={self.axis.tolist()}, direction={self.direction.tolist()}, "
            f"half_angle={self.half_angle!r})"
        )
