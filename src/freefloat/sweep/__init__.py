"""Sweeps: many plans over a grid of scenario values (feasibility maps, design studies).

:class:`SweepSpec` reads a sweep file (a base scenario and axes of dotted keys into it);
:func:`sweep` runs every job on local processes or a Dask cluster and returns one
:class:`SweepRow` per job; :func:`plot_sweep` draws the feasibility map (matplotlib, imported
when called).
"""

from .jobs import STATUSES, TIMING_COLUMNS, SweepRow, run_job
from .plots import plot_sweep
from .results import read_rows, write_rows
from .runner import connect, sweep
from .spec import Axis, Job, SweepSpec

__all__ = [
    "STATUSES",
    "TIMING_COLUMNS",
    "Axis",
    "Job",
    "SweepRow",
    "SweepSpec",
    "connect",
    "plot_sweep",
    "read_rows",
    "run_job",
    "sweep",
    "write_rows",
]
