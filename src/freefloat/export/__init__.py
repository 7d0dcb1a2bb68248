"""Exports of a plan for other tools: CSV, MCAP (Foxglove) and ROS 2 bags (a leaf: reads a plan).

:func:`export` writes one file (a folder for a ROS 2 bag) from a :class:`~freefloat.Plan`.
Without a rate the plan's own samples are written as they are; with ``rate`` (Hz) every
quantity is recomputed at that rate from the plan's polynomials and robot
(:mod:`freefloat.export.trajectory`). No ROS installation is needed.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import InputError
from ..plans.format import Plan
from .trajectory import Trajectory, from_samples, resample, trajectory

__all__ = ["FORMATS", "Trajectory", "export", "from_samples", "resample", "trajectory"]

#: Export formats by name.
FORMATS = ("csv", "mcap", "ros2-bag")


def export(plan: Plan, path: str | Path, fmt: str, rate: float | None = None) -> Path:
    """Write ``plan`` to ``path`` in format ``fmt``; return the absolute path written.

    Args:
        plan: the plan.
        path: the file to write (a folder for ``ros2-bag``).
        fmt: one of :data:`FORMATS`.
        rate: resample at this rate (Hz) instead of writing the plan's samples.

    Raises:
        InputError: unknown format, bad rate; nothing is written.
    """
    if fmt not in FORMATS:
        raise InputError(f"unknown export format {fmt!r}; valid: {', '.join(FORMATS)}")
    traj = trajectory(plan, rate)
    if fmt == "csv":
        from .csv_file import write_csv

        return write_csv(traj, path)
    if fmt == "mcap":
        from .mcap_file import write_mcap

        return write_mcap(traj, path, plan.robot.urdf, plan.robot.urdf_text)
    from .ros2_bag import write_bag

    return write_bag(traj, path, plan.robot.urdf, plan.robot.urdf_text)
