"""CSV export: one row per instant, one header row naming every column with its unit.

Columns: ``t [s]``; per joint ``q_<joint>``, ``qd_<joint>``, ``qdd_<joint>``, ``tau_<joint>``
(rad, rad/s, rad/s^2, N m for revolute and continuous joints; m, m/s, m/s^2, N for prismatic
ones); ``base_qx``, ``base_qy``, ``base_qz``, ``base_qw`` (unit quaternion of the base
attitude, inertial frame); ``base_x``, ``base_y``, ``base_z`` [m] and ``ee_x``, ``ee_y``,
``ee_z`` [m] (inertial frame, origin at the system centre of mass). Numbers are written with
17 significant digits (``repr`` round trip).
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from ..files import atomic_write
from ..plans.format import Plan
from .trajectory import Trajectory

__all__ = ["columns", "write", "write_csv"]


def _units(kind: str) -> tuple[str, str, str, str]:
    if kind == "prismatic":
        return "m", "m/s", "m/s^2", "N"
    return "rad", "rad/s", "rad/s^2", "N m"


def columns(traj: Trajectory) -> list[str]:
    """The header row: column names with units in brackets."""
    names = ["t [s]"]
    for prefix, position in (("q", 0), ("qd", 1), ("qdd", 2), ("tau", 3)):
        names += [
            f"{prefix}_{joint} [{_units(kind)[position]}]"
            for joint, kind in zip(traj.joints, traj.kinds, strict=True)
        ]
    names += [f"base_q{c} [1]" for c in "xyzw"]
    names += [f"base_{c} [m]" for c in "xyz"]
    names += [f"ee_{c} [m]" for c in "xyz"]
    for frame in traj.end_effectors[1:]:  # further end effectors, by frame name
        names += [f"ee_{frame}_{c} [m]" for c in "xyz"]
    return names


def write(traj: Trajectory, path: str | Path, plan: Plan) -> Path:
    """The export registry's entry: :func:`write_csv` of the plan's trajectory."""
    return write_csv(traj, path)


def write_csv(traj: Trajectory, path: str | Path) -> Path:
    """Write the trajectory as CSV atomically; return the absolute path."""
    table = np.column_stack(
        [
            traj.t,
            traj.q,
            traj.qd,
            traj.qdd,
            traj.tau,
            traj.base_quaternion_xyzw,
            traj.base_position,
            traj.end_effector_position,
            *traj.end_effector_paths[1:],
        ]
    )

    def write(tmp: Path) -> None:
        with open(tmp, "w", encoding="utf-8", newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(columns(traj))
            for row in table:
                writer.writerow([repr(float(v)) for v in row])

    return atomic_write(path, write, suffix=".csv")
