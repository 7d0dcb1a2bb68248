"""The robustness commands' library side: a plan file in, typed results out."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..errors import PlanFileError
from ..physics.attitude import geodesic_angle, quat_from_zyx
from ..plans.format import Plan
from ..plans.schema import load_plan_file
from ..robot.model import Robot, load_robot
from .correction import correcting_plan
from .sensitivity import attitude_sensitivity
from .uncertainty import AttitudeSpread, Uncertainty, spread

__all__ = ["correct_plan", "plan_robot", "plan_sensitivity"]


def plan_robot(plan: Plan) -> Robot:
    """The plan's robot, loaded from its URDF; its joints must be the plan's.

    Raises:
        PlanFileError: the URDF's joints are not the plan's.
    """
    robot = load_robot(plan.robot.urdf, plan.robot.end_effector)
    if robot.joint_names != list(plan.robot.joints):
        raise PlanFileError(
            f"the plan's joints {plan.robot.joints} do not match the URDF's {robot.joint_names}"
        )
    return robot


def plan_sensitivity(path: str | Path, uncertainty: Uncertainty) -> tuple[Plan, AttitudeSpread]:
    """The plan file at ``path`` and its first-order attitude error under ``uncertainty``."""
    plan = load_plan_file(path)
    return plan, spread(attitude_sensitivity(plan, plan_robot(plan)), uncertainty)


def correct_plan(path: str | Path, measured_zyx_deg: Sequence[float]) -> tuple[Plan, float]:
    """The correcting plan for the plan file at ``path`` from a measured attitude.

    Args:
        path: the plan that ran.
        measured_zyx_deg: the spacecraft's measured yaw, pitch, roll (deg).

    Returns:
        The correcting plan and the angle it turns the spacecraft back by (rad).
    """
    plan = load_plan_file(path)
    yaw, pitch, roll = (np.radians(float(a)) for a in measured_zyx_deg)
    measured = quat_from_zyx(yaw, pitch, roll)
    goal = np.asarray(plan.base.target_quaternion_xyzw, dtype=float)
    result = correcting_plan(plan, plan_robot(plan), measured)
    return result, geodesic_angle(measured, goal)
