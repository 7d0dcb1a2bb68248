"""Plan the worked example (planar spacecraft, two-link arm, base yaw -50 deg to 0 deg in 10 s).

Usage: python examples/plan_worked_example.py [OUT_DIR]   (default: ./freefloat-examples)
Writes OUT_DIR/worked_example.plan.json and prints the result in degrees.
"""

from __future__ import annotations

import sys
from pathlib import Path

import freefloat as ff


def main(out: Path) -> None:
    """Plan the worked example into ``out``."""
    scenario = ff.Scenario.from_toml(ff.default_scenario_path())
    plan = ff.plan(scenario)  # raises a FreeFloatError if no verified plan exists
    path = plan.save(out / "worked_example.plan.json")
    yaw = [plan.base.start_zyx_deg[0], plan.base.achieved_zyx_deg[0]]
    print(f"base yaw {yaw[0]:.3f} deg -> {yaw[1]:.6f} deg in {plan.duration:g} s")
    print(
        f"attitude error {plan.base.attitude_error_rad:.2e} rad; verified: "
        f"{plan.verification.passed}"
    )
    beta = plan.free_parameters["q2"][0]  # the plan's basis (docs/paths.md), rad
    b26 = plan.path().monomials()[1, 6]  # the paper's t^6 coefficient of q2, rad/s^6
    print(f"free parameter beta = {beta:.9e} rad (b26 = {b26:.6e} rad/s^6)")
    print(f"wrote {path}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "freefloat-examples"))
