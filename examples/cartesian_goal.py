"""Plan to an end-effector position instead of goal joints (inverse kinematics of the system).

Usage: python examples/cartesian_goal.py [OUT_DIR]   (default: ./freefloat-examples)
Writes OUT_DIR/cartesian.toml and OUT_DIR/cartesian.plan.json; prints the goal joints chosen
and the end-effector error.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

import freefloat as ff

SCENARIO = """
robot = "{urdf}"
duration = 10.0                                # s
[start]
joints = {{ q1 = 80.0, q2 = 30.0 }}              # deg
base_zyx_deg = [-50.0, 0.0, 0.0]
[goal]
end_effector_xyz = [1.70, -0.30, 0.0]          # m, from the system centre of mass
base_zyx_deg = [0.0, 0.0, 0.0]
[path]
extra = {{ q2 = 1 }}
"""


def main(out: Path) -> None:
    """Plan to the end-effector goal and report the joints chosen."""
    urdf = ff.default_scenario_path().parents[1] / "planar_2dof.urdf"
    out.mkdir(parents=True, exist_ok=True)
    toml = out / "cartesian.toml"
    toml.write_text(SCENARIO.format(urdf=urdf.as_posix()))
    plan = ff.plan(ff.Scenario.from_toml(toml))
    goal = [math.degrees(q) for q in plan.request.goal_joints]
    miss = np.linalg.norm(np.array(plan.samples.end_effector_position[-1]) - [1.70, -0.30, 0.0])
    print("goal joints chosen [deg]:", ", ".join(f"{q:.4f}" for q in goal))
    print(f"end-effector position error {miss:.2e} m; verified: {plan.verification.passed}")
    print(f"wrote {plan.save(out / 'cartesian.plan.json')}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "freefloat-examples"))
