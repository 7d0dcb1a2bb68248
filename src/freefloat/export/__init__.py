"""Exports of a plan for other tools: CSV, MCAP (Foxglove) and ROS 2 bags (a leaf: reads a plan).

:func:`export` writes one file (a folder for a ROS 2 bag) from a :class:`~freefloat.Plan`.
Each format is one module with a ``write(traj, path, plan) -> Path`` function, named in
:data:`EXPORTS` (imported when used: some need packages that cost start-up time); another
package adds a format with a ``freefloat.exports`` entry point naming its ``write`` function
(:mod:`freefloat.plugins`).
Without a rate the plan's own samples are written as they are; with ``rate`` (Hz) every
quantity is recomputed at that rate from the plan's polynomials and robot
(:mod:`freefloat.export.trajectory`). No ROS installation is needed.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from pathlib import Path

from ..errors import InputError
from ..plans.format import Plan
from ..plugins import Registry, plugin_function
from .trajectory import Trajectory, from_samples, resample, trajectory

__all__ = ["EXPORTS", "Trajectory", "export", "from_samples", "resample", "trajectory"]

#: A format's writer: ``write(traj, path, plan) -> Path`` (the absolute path written).
Writer = Callable[[Trajectory, Path, Plan], Path]


def _builtin(module: str) -> Writer:
    """The ``write`` of a module of this package, imported when first called."""

    def write(traj: Trajectory, path: Path, plan: Plan) -> Path:
        written: Path = importlib.import_module(f".{module}", __name__).write(traj, path, plan)
        return written

    write.__qualname__ = f"{module}.write"
    return write


#: Export formats by name: their writers (the built-ins' modules imported when used).
EXPORTS: Registry[Writer] = Registry(
    "export format",
    {"csv": _builtin("csv_file"), "mcap": _builtin("mcap_file"), "ros2-bag": _builtin("ros2_bag")},
    plugin_function("export format"),
)


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
    traj = trajectory(plan, rate)
    return Path(EXPORTS[fmt](traj, Path(path), plan))
