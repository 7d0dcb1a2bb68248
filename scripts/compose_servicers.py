"""Regenerate the shipped servicer URDFs in robots/ (maintenance script).

Each is an example-robot-data arm on a 0.6 m, 100 kg box spacecraft, mounted on the +x face;
the dual servicer carries two UR5 arms side by side on that face (prefixes ``left_`` at
y = +0.2 m and ``right_`` at y = -0.2 m), with its SRDF (each arm's pairs, prefixed) beside it.
Each robot is named as its file. Run from the repository root: python scripts/compose_servicers.py
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from freefloat.robot.compose import ArmSpec, ServicerSpec, compose_servicer

ROBOTS = Path(__file__).resolve().parents[1] / "robots"

SERVICERS = {
    # 7 joints: Franka Emika Panda, fingers locked.
    "panda_servicer": ServicerSpec(
        "panda",
        100.0,
        (0.6, 0.6, 0.6),
        mount=(0.3, 0.0, 0.0),
        mount_rpy=(0.0, 1.5707963267948966, 0.0),
    ),
    # 6 joints: Universal Robots UR5.
    "ur5_servicer": ServicerSpec(
        "ur5",
        100.0,
        (0.6, 0.6, 0.6),
        mount=(0.3, 0.0, 0.0),
        mount_rpy=(0.0, 1.5707963267948966, 0.0),
    ),
    # 12 joints: two UR5 arms on one box.
    "dual_ur5_servicer": ServicerSpec(
        "ur5",
        100.0,
        (0.6, 0.6, 0.6),
        mount=(0.3, 0.2, 0.0),
        mount_rpy=(0.0, 1.5707963267948966, 0.0),
        prefix="left_",
        more_arms=(
            ArmSpec(
                "ur5",
                mount=(0.3, -0.2, 0.0),
                mount_rpy=(0.0, 1.5707963267948966, 0.0),
                prefix="right_",
            ),
        ),
    ),
}


def main() -> None:
    for name, spec in SERVICERS.items():
        path = compose_servicer(replace(spec, name=name), ROBOTS / f"{name}.urdf")
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
