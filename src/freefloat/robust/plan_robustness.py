"""A plan's robustness to its mass properties: its record, and the commands' library side.

:func:`plan_spread` is the first-order final attitude error of a plan under an uncertainty
(:mod:`freefloat.problem.uncertainty`); :func:`with_robustness` puts that figure into the plan
(its ``robustness`` record, format ``freefloat.plan/5``); :func:`plan_sensitivity` and
:func:`correct_plan` take a plan file, as the commands ``sensitivity`` and ``correct`` do.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..physics.attitude import geodesic_angle, quat_from_zyx
from ..plans.format import Plan
from ..plans.guarantees import RobustnessReport
from ..plans.robot_copy import plan_robot
from ..plans.schema import load_plan_file
from ..plans.versions import FORMAT
from ..problem.inertial_sensitivity import attitude_sensitivity
from ..problem.uncertainty import DEFAULT_UNCERTAINTY, AttitudeSpread, Uncertainty, spread
from ..robot.model import Robot
from ..robot.payload import held_payload
from ..solvers.options import DEFAULT_TOLERANCE
from ..verify.recompute import problem_from_plan
from .correction import correcting_plan

__all__ = ["Correction", "correct_plan", "plan_sensitivity", "plan_spread", "with_robustness"]


def plan_spread(
    plan: Plan, robot: Robot, uncertainty: Uncertainty = DEFAULT_UNCERTAINTY
) -> AttitudeSpread:
    """The plan's first-order final attitude error under ``uncertainty`` (rad).

    The sensitivity is exact along the plan's joint paths, on its own integration grid.
    """
    problem, beta = problem_from_plan(plan, robot)
    return spread(attitude_sensitivity(problem, beta), uncertainty)


def with_robustness(
    plan: Plan, robot: Robot, uncertainty: Uncertainty = DEFAULT_UNCERTAINTY
) -> Plan:
    """The plan with its ``robustness`` record (format ``freefloat.plan/5``).

    Raises:
        InputError: ``uncertainty`` gives a payload sizes of its own, which the record (one
            size per kind for every body) cannot state.
    """
    if uncertainty.payload is not None:
        raise InputError(
            "a plan's robustness record states one uncertainty for every body; a payload's own "
            "is for freefloat sensitivity (plan_spread), not the record"
        )
    found = plan_spread(plan, robot, uncertainty)
    record = RobustnessReport(
        mass_fraction=uncertainty.mass_fraction,
        com_m=uncertainty.com_m,
        inertia_fraction=uncertainty.inertia_fraction,
        rms_rad=found.rms,
        worst_rad=found.worst,
    )
    return replace(plan, robustness=record, format=FORMAT)


def plan_sensitivity(
    path: str | Path | Plan, uncertainty: Uncertainty
) -> tuple[Plan, AttitudeSpread]:
    """The plan (or the plan file at ``path``) and its first-order attitude error.

    ``uncertainty``: the sizes of the mass-property errors.

    Raises:
        InputError: ``uncertainty`` gives a payload sizes of its own and the plan's robot
            holds no captured payload (before any work).
    """
    plan = path if isinstance(path, Plan) else load_plan_file(path)
    robot = plan_robot(plan)
    if uncertainty.payload is not None and held_payload(robot) is None:  # before any work
        raise InputError(
            "--payload-* options need a plan whose robot holds a captured payload ([payload] "
            "in the scenario, or freefloat compose --payload-mass); this one holds none"
        )
    return plan, plan_spread(plan, robot, uncertainty)


@dataclass(frozen=True)
class Correction:
    """What ``freefloat correct`` found for a measured attitude.

    Attributes:
        turn: the angle from the measured attitude to the plan's goal (rad).
        tolerance: the attitude tolerance a correcting plan is solved to (rad).
        plan: the correcting plan; None when ``turn`` is within ``tolerance`` (the spacecraft
            is at its goal as closely as a plan would bring it: nothing to correct).
    """

    turn: float
    tolerance: float
    plan: Plan | None


def correct_plan(path: str | Path | Plan, measured_zyx_deg: Sequence[float]) -> Correction:
    """The correction for the plan (or plan file at ``path``) from a measured attitude.

    Args:
        path: the plan that ran, or its file.
        measured_zyx_deg: the spacecraft's measured yaw, pitch, roll (deg).

    Raises:
        InputError, SolverError: as :func:`~.correction.correcting_plan`.
    """
    plan = path if isinstance(path, Plan) else load_plan_file(path)
    yaw, pitch, roll = (np.radians(float(a)) for a in measured_zyx_deg)
    measured = quat_from_zyx(yaw, pitch, roll)
    goal = np.asarray(plan.base.target_quaternion_xyzw, dtype=float)
    turn, tolerance = geodesic_angle(measured, goal), DEFAULT_TOLERANCE
    if turn <= tolerance:  # the path that stays put already ends there
        return Correction(turn, tolerance, None)
    return Correction(turn, tolerance, correcting_plan(plan, plan_robot(plan), measured))
