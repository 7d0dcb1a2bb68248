"""Exports of a plan for other tools: CSV, MCAP (Foxglove) and ROS 2 bags (a leaf: reads a plan).

:func:`export` writes one file (a folder for a ROS 2 bag) from a :class:`~freefloat.Plan`.
Each format is one module with a ``write(traj, path, plan) -> Path`` function, named in
:data:`EXPORTS` (imported when used: some need packages that cost start-up time).
Without a rate the plan's own samples are written as they are; with ``rate`` (Hz) every
quantity is recomputed at that rate from the plan's polynomials and robot
(:mod:`freefloat.export.trajectory`). No ROS installation is needed.
"""

from __future__ import annotations

import importlib
from pathlib import Path

from ..errors import InputError
from ..plans.format import Plan
from .trajectory import Trajectory, from_samples, resample, trajectory

__all__ = ["EXPORTS", "Trajectory", "export", "from_samples", "resample", "trajectory"]

#: Export formats by name: the module (in this package) whose ``write`` writes it.
EXPORTS: dict[str, str] = {
    "csv": "csv_file",
    "mcap": "mcap_file",
    "ros2-bag": "ros2_bag",
}


def export(plan: Plan, path: str | Path, fmt: str, rate: float | None = None) -> Path:
    """Write ``plan`` to ``path`` in format ``fmt``; return the absolute path written.

    Args:
        plan: the plan.
        path: the file to write (a folder for ``ros2-bag``).
        fmt: one of :data:`EXPORTS`.
        rate: resample at this rate (Hz) instead of writing the plan's samples.

    Raises:
        InputError: unknown format, bad rate; nothing is written.
    """
    if fmt not in EXPORTS:
        raise InputError(f"unknown export format {fmt!r}; valid: {', '.join(EXPORTS)}")
    module = importlib.import_module(f".{EXPORTS[fmt]}", __name__)
    traj = trajectory(plan, rate)
    written: Path = module.write(traj, path, plan)
    return written
