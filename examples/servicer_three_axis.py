"""Compose a servicer (a UR5 on a 100 kg, 0.6 m box) and plan a three-axis attitude goal.

Usage: python examples/servicer_three_axis.py [OUT_DIR]   (default: ./freefloat-examples)
Writes OUT_DIR/ur5_servicer.urdf and OUT_DIR/ur5_three_axis.plan.json.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import freefloat as ff
from freefloat.robot.compose import ServicerSpec, compose_servicer


def main(out: Path) -> None:
    """Compose the servicer into ``out`` and plan its three-axis goal."""
    spec = ServicerSpec(
        arm="ur5",  # an example-robot-data arm
        base_mass=100.0,  # kg
        base_size=(0.6, 0.6, 0.6),  # m
        mount=(0.3, 0.0, 0.0),  # m, in the spacecraft frame
        mount_rpy=(0.0, math.radians(90.0), 0.0),  # rad
    )
    robot = ff.load_robot(compose_servicer(spec, out / "ur5_servicer.urdf"))
    deg = math.radians
    start = dict(
        zip(robot.joint_names, [0.0, deg(-90), deg(90), deg(-90), deg(-90), 0.0], strict=True)
    )
    goal = dict(
        zip(
            robot.joint_names,
            [deg(57.3), deg(-57.3), deg(68.8), deg(-68.8), deg(-57.3), deg(28.6)],
            strict=True,
        )
    )
    scenario = ff.Scenario(
        robot,
        duration=20.0,  # s
        start_joints=start,
        goal_joints=goal,
        goal_attitude=ff.quat_from_zyx(deg(-7.6), deg(-1.8), deg(-8.3)),  # yaw, pitch, roll
    )
    plan = ff.plan(scenario)
    path = plan.save(out / "ur5_three_axis.plan.json")
    print(
        "base yaw, pitch, roll reached [deg]:",
        ", ".join(f"{a:.4f}" for a in plan.base.achieved_zyx_deg),
    )
    print(
        f"attitude error {plan.base.attitude_error_rad:.2e} rad; free coefficients "
        f"{plan.solver.freedom}; verified: {plan.verification.passed}"
    )
    print(f"wrote {path}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "freefloat-examples"))
