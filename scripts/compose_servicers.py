"""Regenerate the shipped servicer URDFs in robots/ (maintenance script).

Each is an example-robot-data arm on a 0.6 m, 100 kg box spacecraft, mounted on the +x face.
Run from the repository root: python scripts/compose_servicers.py
"""

from __future__ import annotations

from pathlib import Path

from freefloat.robot.compose import ServicerSpec, compose_servicer

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
}


def main() -> None:
    for name, spec in SERVICERS.items():
        path = compose_servicer(spec, ROBOTS / f"{name}.urdf")
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
