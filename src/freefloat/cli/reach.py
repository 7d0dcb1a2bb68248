"""``freefloat reach``: the drift attitude and the attitudes a simple motion can reach."""

from __future__ import annotations

import argparse
import math

from ..errors import CollisionError, EndpointError, InputLimitError, JointLimitError
from ..parallel import MAX_JOBS, check_jobs
from ..problem.limits import check_number
from ..reachable import DEFAULT_BUDGET as DEFAULT_REACH_BUDGET
from ..solvers.reach import DirectionReach
from .common import MAX_BUDGET, Commands, check_figure, load_scenario

__all__ = ["MAX_TRAVEL", "add_jobs", "add_parser", "check", "direction_line", "run"]

#: Largest ``reach --travel`` (joint travel over the start-goal span).
MAX_TRAVEL = 100.0


def add_parser(commands: Commands) -> argparse.ArgumentParser:
    """Add this command's sub-parser to ``commands``."""
    p_reach = commands.add_parser(
        "reach",
        help="print the drift attitude and the attitudes a simple motion can reach",
        description="Where the plain quintic path leaves the spacecraft (the drift attitude), "
        "an outer bound on the turn of every simple motion (joint travel at most --travel times "
        "its start-goal span; 1: every joint monotone), and per direction the largest turn from "
        "the drift attitude reached by a solved path, with the goal attitude to paste into the "
        "scenario (docs/reach.md). The scenario's goal attitude is ignored.",
    )
    p_reach.add_argument(
        "scenario",
        nargs="?",
        help="scenario TOML file, or a shipped scenario's name (default: worked example)",
    )
    p_reach.add_argument(
        "--travel",
        type=float,
        default=1.0,
        metavar="K",
        help="outer bound for joint travel at most K x the start-goal span (default 1: monotone)",
    )
    p_reach.add_argument(
        "--budget",
        type=int,
        default=DEFAULT_REACH_BUDGET,
        help="residual evaluations per continuation pass of the inner estimate (a direction "
        "makes one pass, more where it confirms its turn or imposes clearance; "
        f"default {DEFAULT_REACH_BUDGET}; a count); 0: the drift attitude and the outer bound "
        "only (well under a second)",
    )
    add_jobs(p_reach)
    p_reach.add_argument("--plot", metavar="FILE", help="also draw it (PNG, SVG or PDF)")
    p_reach.set_defaults(func=run, check=check)
    return p_reach


def add_jobs(parser: argparse.ArgumentParser) -> None:
    """``--jobs N`` of reach and bounds: worker processes for the directions."""
    parser.add_argument(
        "--jobs",
        type=int,
        metavar="N",
        help="worker processes for the directions (default: the usable cores, at most one per "
        f"direction; 1: in this process; at most {MAX_JOBS}). The numbers printed are the same, "
        "bit for bit, whatever N; forked on Linux, serial where fork is not available",
    )


def direction_line(d: DirectionReach) -> str:
    """One direction done, for the progress lines: its axis, turn (deg) and evaluations."""
    axis = " ".join(f"{x:+.2f}" for x in d.axis)
    return f"axis {axis}: {math.degrees(d.reached):.3f} deg ({d.evaluations} evaluations)"


def check(args: argparse.Namespace) -> None:
    """Refuse bad numbers and an unwritable figure before any work (docs/limits.md)."""
    check_number(args.travel, "--travel", MAX_TRAVEL, low=1.0)
    if not 0 <= args.budget <= MAX_BUDGET:
        raise InputLimitError("--budget", args.budget, 0, MAX_BUDGET)
    check_jobs(args.jobs, "--jobs")
    check_figure(args)


def run(args: argparse.Namespace) -> int:
    """Print the drift attitude, the outer bound and the reached attitudes."""
    from ..progress import counted
    from ..reachable import reachable
    from ..solvers.reach import default_directions
    from ..viz.reach_text import reach_lines

    scenario = load_scenario(args.scenario)
    try:
        with counted("reach", len(default_directions())) as advance:
            report = reachable(
                scenario,
                travel_factor=args.travel,
                budget=args.budget,
                progress=lambda i, n, d: advance(direction_line(d)),
                jobs=args.jobs,
            )
    except (JointLimitError, CollisionError, EndpointError) as exc:  # the file's ends, named first
        if scenario.source is None:
            raise
        raise exc.naming(scenario.source) from None
    print("\n".join(reach_lines(report, scenario.robot)))
    if args.plot:
        from ..viz.reach_plot import save_reach_figure

        written = save_reach_figure(report.estimate(), args.plot, title=report.robot)
        print(f"figure: {written.resolve()}")
    return 0
