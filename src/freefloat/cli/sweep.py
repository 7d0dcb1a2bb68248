"""``freefloat sweep``: plan every combination of scenario values, one CSV row per job."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

from ..errors import InputError, InputLimitError
from .common import Commands, check_outputs

__all__ = ["MAX_WORKERS", "add_parser", "check", "run"]

#: Most local worker processes of ``sweep --workers``.
MAX_WORKERS = 1024


def add_parser(commands: Commands) -> argparse.ArgumentParser:
    """Add this command's sub-parser to ``commands``."""
    p_sweep = commands.add_parser(
        "sweep",
        help="plan every combination of scenario values and write one CSV row per job",
        description="Run a sweep file (a base scenario and axes of dotted keys into it, in the "
        "scenario's units: degrees) on local processes or a Dask cluster. Rows are written as "
        "jobs finish; re-running with the same output resumes. A failed job is a row, not an "
        "error.",
    )
    p_sweep.add_argument("sweep", help="sweep TOML file")
    p_sweep.add_argument("-o", "--output", required=True, metavar="CSV", help="results file")
    p_sweep.add_argument("--workers", type=int, help="local worker processes (default: all cores)")
    p_sweep.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run on a Dask distributed cluster, e.g. tcp://host:8786 "
        "(pip install 'freefloat[cluster]')",
    )
    p_sweep.add_argument("--plots", metavar="DIR", help="draw the feasibility map into DIR")
    p_sweep.set_defaults(func=run, check=check)
    return p_sweep


def check(args: argparse.Namespace) -> None:
    """Refuse a bad worker count or scheduler and unwritable outputs before any work."""
    if args.workers is not None and not 1 <= args.workers <= MAX_WORKERS:
        raise InputLimitError("--workers", args.workers, 1, MAX_WORKERS)
    if args.scheduler is not None and not args.scheduler.strip():
        raise InputError(
            "--scheduler is empty; give the Dask scheduler's address (tcp://host:8786), "
            "or leave the option out to run on local processes"
        )
    check_outputs(args, ("-o", "output"))
    check_outputs(args, ("--plots", "plots"), folder=True)


def run(args: argparse.Namespace) -> int:
    """Run the sweep file and print what its jobs became."""
    from ..files import check_output
    from ..sweep import SweepRow, SweepSpec, connect, plot_sweep, sweep
    from ..sweep.plots import check_plottable, plot_files

    spec = SweepSpec.from_toml(args.sweep)
    if args.plots:
        if spec.replay:
            raise InputError("--plots draws feasibility maps of plans; a replay sweep has none")
        check_plottable(spec)
        for path in plot_files(spec, args.plots):  # before any job runs
            check_output(path, "a figure")
    client = connect(args.scheduler) if args.scheduler is not None else None
    ran: list[object] = []
    try:
        rows = sweep(
            spec, workers=args.workers, client=client, output=args.output, on_row=ran.append
        )
    finally:
        if client is not None:
            client.close()
    if spec.replay:
        import numpy as np

        from ..robust.distribution import error_distribution
        from ..sweep.replay import ReplayRow
        from ..viz.robustness import distribution_lines

        print(f"freefloat sweep: {len(rows)} replays of {spec.scenario_path.name}")
        vectors = np.array(
            [
                [r.error_x_rad, r.error_y_rad, r.error_z_rad]
                for r in rows
                if isinstance(r, ReplayRow) and r.status == "replayed"
            ],
            dtype=float,
        )
        print("\n".join(distribution_lines(error_distribution(vectors), len(rows))))
        print(f"  results         {Path(args.output).resolve()}{_resumed(rows, ran)}")
        return 0
    counts = {s: sum(r.status == s for r in rows) for s in ("planned", "infeasible", "failed")}
    print(
        f"freefloat sweep: {len(rows)} jobs over {', '.join(spec.keys)}: "
        + ", ".join(f"{n} {s}" for s, n in counts.items())
    )
    print(f"  results         {Path(args.output).resolve()}{_resumed(rows, ran)}")
    if args.plots:
        written = plot_sweep(spec, [r for r in rows if isinstance(r, SweepRow)], args.plots)
        print(f"  plots           {', '.join(str(p) for p in written)}")
    return 0


def _resumed(rows: Sequence[object], ran: Sequence[object]) -> str:
    """`` (resumed: K of N jobs were in the file, M run now)``, or "" for a whole run."""
    kept = len(rows) - len(ran)
    return f" (resumed: {kept} of {len(rows)} jobs were in it, {len(ran)} run now)" if kept else ""
